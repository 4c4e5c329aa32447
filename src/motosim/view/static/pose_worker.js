// The rider's view's pose socket in a worker (see pose.js): the newest pose into shared
// memory, the rest (status, clock offset, arrival times) to the page every 50 ms.
import { poseSlots, poseSocket } from './pose.js';

let slots = null, send = null, news = { ages: [] }, dirty = false;
onmessage = (event) => {
  const m = event.data;
  if (m.buffer) {
    slots = poseSlots(m.buffer);
    send = poseSocket(m.url, (e) => {
      if (e.message) {
        slots.write(e.message);
        news.status = e.message.status; news.poses = (news.poses || 0) + 1;
        if (e.message.clock != null) news.ages.push([e.message.clock, e.message.sent, e.received]);
      } else {
        Object.assign(news, e);
      }
      dirty = true;
    });
  } else if (m.frames && send) {
    postMessage({ reported: send(m.frames) ? m.frames.length : 0 });
  }
};
setInterval(() => {
  if (dirty) { postMessage(news); news = { ages: [] }; dirty = false; }
}, 50);

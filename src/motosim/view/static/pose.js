// The pose socket (/ws/pose), shared by the rider's view's page and its worker.
//
// In a worker (when the page is cross-origin isolated, so SharedArrayBuffer exists), messages
// are handled at once even while the page's thread is busy drawing a frame; the newest pose
// goes into shared memory under a sequence lock, and the page reads it at the start of each
// frame. Without isolation the page runs the same code itself. Times are absolute
// (performance.timeOrigin + performance.now() [ms]), the same in the page and the worker.
export const POSE = ['t', 'x', 'y', 'psi', 'phi', 'delta', 'v_x', 'theta_h', 'theta', 'clock', 'deadline'];
export const SLOTS = POSE.length;
const now = () => performance.timeOrigin + performance.now();

// writer/reader of the newest pose in `buffer`: an Int32 sequence (odd while being written),
// then SLOTS float64 values (NaN where the message has none)
export function poseSlots(buffer) {
  const seq = new Int32Array(buffer, 0, 2), values = new Float64Array(buffer, 8, SLOTS);
  return {
    write(message) {
      Atomics.add(seq, 0, 1);
      const p = message.pose || {};
      for (let k = 0; k < 8; k++) values[k] = p[POSE[k]] ?? NaN;
      values[8] = message.clock ?? NaN; values[9] = message.deadline ?? NaN;
      Atomics.add(seq, 0, 1);
    },
    // the pose as an object, or null if none is newer than `since` (or one is being written)
    read(since) {
      const s = Atomics.load(seq, 0);
      if (s === since || s % 2 === 1 || s === 0) return null;  // the same, busy, or none yet
      const copy = Array.from(values);
      if (Atomics.load(seq, 0) !== s) return null;
      const pose = {};
      POSE.forEach((name, k) => { pose[name] = Number.isNaN(copy[k]) ? null : copy[k]; });
      return { seq: s, pose };
    },
  };
}

// Connect to /ws/pose (reconnecting); `on` gets {pose message, received [ms]}, {status},
// {offset [s], rtt [ms]}, {closed}. Returns send(frames): report drawn frames to the server.
export function poseSocket(url, on) {
  let socket = null, rtt = null;
  const ping = () => {
    if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ ping: now() }));
  };
  function connect() {
    const ws = new WebSocket(url);
    socket = ws;
    ws.onopen = () => { for (let k = 0; k < 5; k++) setTimeout(ping, 50 * k); };
    ws.onmessage = (event) => {
      const message = JSON.parse(event.data);
      if (message.pong !== undefined) {
        const back = now(), trip = back - message.pong;
        if (rtt === null || trip <= rtt) {
          rtt = trip;
          on({ offset: message.server - (message.pong + back) / 2000, rtt });
        }
        return;
      }
      on({ message, received: now() });
    };
    ws.onclose = () => {
      socket = null; rtt = null; on({ closed: true }); setTimeout(connect, 1000);
    };
  }
  connect();
  setInterval(ping, 1000);
  return (frames) => {
    if (socket && socket.readyState === WebSocket.OPEN) { socket.send(JSON.stringify({ frames })); return true; }
    return false;
  };
}

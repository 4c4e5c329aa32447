// The rider's view: a three.js scene of the road, seen from the rider's eye, posed by
// /ws/pose. Frames: motosim's ground frame (x forward at the start, y right, z down) maps to
// three.js (X = x, Y = up, Z = y), a proper rotation; yaw psi is -psi - pi/2 about Y for a
// camera looking down its -Z axis; roll phi (right side down) is -phi about the view axis.
import * as THREE from 'three';
import { poseSlots, poseSocket } from './pose.js';

const EYE = 1.2;          // m, eye height above the road when upright
const token = new URLSearchParams(location.search).get('token') || '';
const $ = (id) => document.getElementById(id);
const stats = { frames: 0, rendered: 0, fps: 0, poses: 0, lastPose: null, status: null, ready: false,
  offset: null, rtt: null, lags: [], ages: [], reported: 0 };
window.motosimStats = stats;
for (const a of document.querySelectorAll('a')) a.href += location.search;

const info = await (await fetch('/api/info')).json();
document.title = `${info.title}: the rider's view`;

const canvas = $('scene');
const params = new URLSearchParams(location.search);
// Antialiasing is off unless ?antialias=1 (MSAA halves the frame rate of a software
// renderer). The render scale (pixel ratio) is ?scale= when given; otherwise it starts at the
// screen's and steps down (x0.75, to 0.5 at the least) after each two measured seconds in a row
// below MIN_FPS, and never steps back up (no oscillation between two scales).
const MIN_FPS = 30, MIN_SCALE = 0.5;
const antialias = params.get('antialias') === '1';
const fixedScale = Number(params.get('scale')) > 0 ? Number(params.get('scale')) : null;
const renderer = new THREE.WebGLRenderer({
  canvas,
  antialias,
  preserveDrawingBuffer: params.get('readback') === '1',  // for tests that read pixels back
});
renderer.setPixelRatio(fixedScale ?? Math.min(window.devicePixelRatio, 2));
// Colours are given as the sRGB values to show and written as they are (no conversion from
// linear light in each pixel's shader: its pow() is most of a software renderer's per-pixel
// cost); `srgb(hex)` makes such a colour.
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
const srgb = (hex) => new THREE.Color().setHex(hex, THREE.LinearSRGBColorSpace);
Object.assign(stats, { antialias, scale: renderer.getPixelRatio(), adaptive: fixedScale === null });
// ?sync=1 reads one pixel back after each frame, which waits until the frame is rendered: the
// frame rate is then that of finished frames, not of frames handed to the GPU (for the bench)
const sync = params.get('sync') === '1', gl = renderer.getContext(), pixel = new Uint8Array(4);
let slowSeconds = 0;
function adapt(fps) {
  if (fixedScale !== null) return;
  slowSeconds = fps < MIN_FPS ? slowSeconds + 1 : 0;
  const ratio = renderer.getPixelRatio();
  if (slowSeconds >= 2 && ratio > MIN_SCALE) {
    const next = ratio * 0.75;  // 1 -> 0.75 -> 0.5 on a plain screen
    renderer.setPixelRatio(next < MIN_SCALE + 0.1 ? MIN_SCALE : next);
    stats.scale = renderer.getPixelRatio();
    slowSeconds = 0;
  }
}
stats.adapt = adapt;  // a test feeds it frame rates
const scene = new THREE.Scene();
const sky = srgb(0x9cc3e6);
scene.background = sky;
// Nothing is drawn beyond FAR metres: the fog reaches the sky's colour there, so the cut does
// not show, and the road's chunks farther away (or behind the eye) are culled whole.
const FAR = 600;
scene.fog = new THREE.Fog(sky, 120, FAR);
const camera = new THREE.PerspectiveCamera(70, 1, 0.1, FAR);
camera.rotation.order = 'YXZ';
Object.assign(stats, { camera, renderer, scene });

// --- road ----------------------------------------------------------------------------
const road = info.road;
const n = road.x.length;
const tx = [], ty = [], s = [0];
for (let i = 0; i < n; i++) {
  const j = Math.min(i + 1, n - 1), k = Math.max(i - 1, 0);
  const dx = road.x[j] - road.x[k], dy = road.y[j] - road.y[k];
  const d = Math.hypot(dx, dy) || 1;
  tx.push(dx / d); ty.push(dy / d);
  if (i > 0) s.push(s[i - 1] + Math.hypot(road.x[i] - road.x[i - 1], road.y[i] - road.y[i - 1]));
}
// point at lateral offset (right positive) from centre-line point i, in three.js coordinates
const at = (i, offset, height) =>
  [road.x[i] - offset * ty[i], height, road.y[i] + offset * tx[i]];

// The world is flat and the eye above it, so the flat layers (ground, shoulders, asphalt,
// lines) are painted in order without the depth buffer (no z-fighting between coplanar
// layers, whatever the GPU's depth precision) and the upright objects drawn after them.
// The road is cut into chunks of CHUNK segments; each chunk is two draw calls (its flat
// layers as one mesh of coloured triangles drawn in the order they were appended, its posts
// and trees as one mesh), and three.js skips the chunks outside the view (behind the eye or
// beyond FAR): a frame costs the road in sight, not the whole road (a software renderer's
// time goes mostly to the triangles it sets up).
const CHUNK = 75;
const chunks = Math.max(1, Math.ceil((n - 1) / CHUNK));
const chunkOf = (i) => Math.min(Math.floor(i / CHUNK), chunks - 1);
function coloured(pos, col) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
  geometry.setAttribute('color', new THREE.Float32BufferAttribute(col, 3));
  return geometry;
}
function quad(pos, col, color, a, b, c, d) {  // a quad a b c d (a-b and c-d across)
  for (const p of [a, b, c, b, d, c]) { pos.push(...p); col.push(color.r, color.g, color.b); }
}
const flatMaterial = new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide,
  depthTest: false, depthWrite: false });
let cx = 0, cy = 0;
for (let i = 0; i < n; i++) { cx += road.x[i] / n; cy += road.y[i] / n; }
{
  const G = 6000, pos = [], col = [];  // m, half the ground's side
  quad(pos, col, srgb(0x5d8a3a), [cx - G, -0.02, cy - G], [cx + G, -0.02, cy - G],
    [cx - G, -0.02, cy + G], [cx + G, -0.02, cy + G]);
  const ground = new THREE.Mesh(coloured(pos, col), flatMaterial);
  ground.renderOrder = -2;
  ground.frustumCulled = false;  // it surrounds the eye
  scene.add(ground);
}
const w = road.width / 2;
const layers = [  // left and right offsets [m], height [m], colour
  [-w - 1.5, w + 1.5, 0.0, 0x8a8a7a],                    // shoulders
  [-w, w, 0.01, 0x3c3c40],                               // asphalt
  [-w + 0.25, -w + 0.4, 0.02, 0xf4f4f4],                 // left edge line
  [w - 0.4, w - 0.25, 0.02, 0xf4f4f4],                   // right edge line
  [-0.075, 0.075, 0.02, 0xf4f4f4, (i) => (s[i] % 9) < 3],  // dashed centre line: 3 m in 9 m
].map(([left, right, height, color, keep]) =>
  [left, right, height, srgb(color), keep || (() => true)]);
for (let c = 0; c < chunks; c++) {
  const pos = [], col = [];
  const last = Math.min((c + 1) * CHUNK, n - 1);
  for (const [left, right, height, color, keep] of layers) {
    for (let i = c * CHUNK; i < last; i++) {
      if (keep(i)) {
        quad(pos, col, color, at(i, left, height), at(i, right, height), at(i + 1, left, height),
          at(i + 1, right, height));
      }
    }
  }
  const mesh = new THREE.Mesh(coloured(pos, col), flatMaterial);
  mesh.renderOrder = -1;  // after the ground; the chunks do not overlap
  scene.add(mesh);
}

// --- speed and distance cues: posts every 25 m, trees at seeded random places ------------
let seed = 12345;
const random = () => ((seed = (seed * 16807) % 2147483647) / 2147483647);
// the vertices and colours of several coloured parts, each raised by its height [m]
function parts(...list) {
  const pos = [], col = [];
  for (const [geometry, color, dy] of list) {
    const flatGeometry = geometry.toNonIndexed();
    flatGeometry.translate(0, dy, 0);
    const c = srgb(color);
    const p = flatGeometry.getAttribute('position');
    for (let k = 0; k < p.count; k++) {
      pos.push(p.getX(k), p.getY(k), p.getZ(k)); col.push(c.r, c.g, c.b);
    }
  }
  return { pos, col };
}
const post = parts([new THREE.BoxGeometry(0.12, 1.0, 0.12), 0xf0f0f0, 0.5],   // white post
  [new THREE.BoxGeometry(0.13, 0.12, 0.13), 0xd02020, 1.05]);                 // red top
const tree = parts([new THREE.CylinderGeometry(0.15, 0.2, 2.0, 5), 0x6b4a2b, 1.0],  // trunk
  [new THREE.ConeGeometry(1.6, 5.0, 7), 0x2f6a2a, 4.0]);                           // crown
const objects = Array.from({ length: chunks }, () => ({ pos: [], col: [] }));
function place(kind, i, x, z, scale) {  // a copy of kind's vertices, scaled, at (x, 0, z)
  const { pos, col } = objects[chunkOf(i)];
  for (let k = 0; k < kind.pos.length; k += 3) {
    pos.push(x + scale * kind.pos[k], scale * kind.pos[k + 1], z + scale * kind.pos[k + 2]);
  }
  col.push(...kind.col);
}
let next = 0, nextTree = 0;
for (let i = 0; i < n; i++) {
  if (s[i] >= next) {
    for (const side of [-1, 1]) {
      const [x, , z] = at(i, side * (w + 1.0), 0);
      place(post, i, x, z, 1);
    }
    next += 25;
  }
  if (s[i] >= nextTree) {
    const side = random() < 0.5 ? -1 : 1;
    const scale = 0.7 + 0.8 * random();
    const [x, , z] = at(i, side * (w + 6 + 30 * random()), 0);
    place(tree, i, x, z, scale);
    nextTree += 12 + 20 * random();
  }
}
const objectMaterial = new THREE.MeshBasicMaterial({ vertexColors: true });
for (const { pos, col } of objects) {
  if (pos.length) scene.add(new THREE.Mesh(coloured(pos, col), objectMaterial));
}

// --- the motorcycle's cockpit: tank, fork, headlight shell, instruments and the handlebar --
// In the camera's frame (X right, Y up, -Z ahead), so it stays below the eye. The cockpit
// leans with the motorcycle: when the horizon does not roll (the toggle off) it rolls by phi
// in the view instead. The handlebar turns by theta_h about the steering axis, raked back by
// RAKE; theta_h and phi positive steer and lean to the right (motosim's axes: z down).
const RAKE = 0.45;  // rad, steering axis from the vertical (about 26 deg)
const cockpit = new THREE.Group();
const steering = new THREE.Group();  // at the steering head, its Y axis the steering axis
const bars = new THREE.Group();      // turns by theta_h about steering's Y axis
{
  const mesh = (geometry, color) => new THREE.Mesh(geometry,
    new THREE.MeshBasicMaterial({ color: srgb(color) }));
  const add = (parent, object, x, y, z, rx = 0, ry = 0, rz = 0) => {
    object.position.set(x, y, z); object.rotation.set(rx, ry, rz); parent.add(object);
    return object;
  };
  add(cockpit, mesh(new THREE.BoxGeometry(0.36, 0.16, 0.42), 0xb3202a), 0, -0.46, -0.44, 0.35);  // tank
  add(cockpit, mesh(new THREE.BoxGeometry(0.24, 0.05, 0.36), 0xd8343f), 0, -0.37, -0.46, 0.35);  // its top
  add(steering, mesh(new THREE.BoxGeometry(0.22, 0.08, 0.08), 0x1c1c1c), 0, 0.07, -0.04);  // instruments
  add(steering, mesh(new THREE.BoxGeometry(0.08, 0.055, 0.01), 0xe8e8d0), -0.05, 0.075, 0.0);  // dials
  add(steering, mesh(new THREE.BoxGeometry(0.08, 0.055, 0.01), 0xe8e8d0), 0.05, 0.075, 0.0);
  add(steering, mesh(new THREE.CylinderGeometry(0.13, 0.1, 0.16, 10), 0x2a2a2a),
    0, -0.05, -0.1, Math.PI / 2);  // headlight shell
  for (const side of [-1, 1]) {  // fork tubes, clamped below the bar
    add(steering, mesh(new THREE.CylinderGeometry(0.022, 0.022, 0.5, 8), 0x9a9a9a),
      side * 0.12, -0.25, 0.0);
  }
  add(bars, mesh(new THREE.CylinderGeometry(0.013, 0.013, 0.62, 8), 0xc8c8c8),
    0, 0, 0, 0, 0, Math.PI / 2);  // the bar across
  for (const side of [-1, 1]) {
    add(bars, mesh(new THREE.CylinderGeometry(0.02, 0.02, 0.13, 8), 0x111111),
      side * 0.29, 0, 0, 0, 0, Math.PI / 2);  // grips
    add(bars, mesh(new THREE.BoxGeometry(0.08, 0.015, 0.02), 0x444444),
      side * 0.2, 0.005, 0.06, 0, side * 0.3, 0);  // levers
  }
  add(bars, mesh(new THREE.BoxGeometry(0.12, 0.04, 0.06), 0x333333), 0, 0, 0);  // top clamp
  steering.add(bars);
  add(cockpit, steering, 0, -0.34, -0.78, -RAKE);
  for (const part of [cockpit, steering, bars]) part.traverse((o) => { o.renderOrder = 1; });
  camera.add(cockpit);
  scene.add(camera);
  stats.cockpit = cockpit; stats.bars = bars;
}

// --- pose, and the lag of each frame behind the loop --------------------------------------
// A pose stamped with the loop's clock (`clock`: when the loop wrote it, the machine's
// monotonic clock [s]) lets the page measure how far behind the loop each frame is: the
// server answers pings with its monotonic time, and the ping with the shortest round trip
// gives the offset from absolute page time (performance.timeOrigin + now() [ms]) to that
// clock. Each drawn frame is reported as [sample, drawn] (both on the loop's clock [s]) once
// a second over the pose socket (GET /api/lag sums them up). For tests and the bench,
// motosimStats.lags keeps [sample [s], drawn [absolute ms], the sample's deadline [s]],
// motosimStats.offset maps them, and motosimStats.ages has, for each pose, [written, sent [s],
// received [absolute ms]]. The socket lives in a worker when the page is cross-origin
// isolated (the server says so): a frame then draws the newest pose even if the page's
// thread was busy when it came (motosimStats.worker).
const absolute = () => performance.timeOrigin + performance.now();
let pose = { t: 0, x: road.x[Math.min(25, n - 1)], y: road.y[Math.min(25, n - 1)], psi: 0,
  phi: 0, delta: 0, v_x: 0, theta_h: 0, theta: 0, clock: null, deadline: null };
let status = info.status, pending = [], report, readPose = () => {};
const url = `ws://${location.host}/ws/pose`;
function got(e) {  // what the socket reports, in the page or from the worker
  if (e.offset !== undefined) { stats.offset = e.offset; stats.rtt = e.rtt; }
  if (e.closed) { stats.rtt = null; show('state', 'disconnected'); }
  if (e.status) { status = e.status; stats.status = status; }
  if (e.poses) stats.poses += e.poses;
  if (e.ages && stats.ages.length < 100000) stats.ages.push(...e.ages);
  if (e.reported) stats.reported += e.reported;
}
stats.worker = window.crossOriginIsolated === true && typeof SharedArrayBuffer !== 'undefined';
if (stats.worker) {
  const buffer = new SharedArrayBuffer(8 + 8 * 16), slots = poseSlots(buffer);
  const worker = new Worker('/static/pose_worker.js', { type: 'module' });
  worker.onmessage = (event) => got(event.data);
  worker.postMessage({ buffer, url });
  report = (frames) => worker.postMessage({ frames });
  let seq = -1;
  readPose = () => {
    const next = slots.read(seq);
    if (next) { seq = next.seq; pose = next.pose; stats.lastPose = pose; }
  };
} else {
  const send = poseSocket(url, (e) => {
    if (e.message) {
      const m = e.message;
      if (m.pose) { pose = { ...m.pose, clock: m.clock ?? null, deadline: m.deadline ?? null }; stats.lastPose = pose; }
      got({ status: m.status, poses: 1, ages: m.clock != null ? [[m.clock, m.sent, e.received]] : [] });
    } else {
      got(e);
    }
  });
  report = (frames) => got({ reported: send(frames) ? frames.length : 0 });
}
setInterval(() => {
  if (pending.length && stats.offset !== null) {
    const offset = stats.offset;
    report(pending.map(([c, d]) => [c, d / 1000 + offset]));
  }
  pending = [];
}, 1000);

function aim() {
  const roll = rollToggle.checked ? (pose.phi || 0) : 0;
  const psi = pose.psi || 0, phi = pose.phi || 0;
  // the eye leans with the motorcycle about the contact line
  const right = EYE * Math.sin(phi), up = EYE * Math.cos(phi);
  camera.position.set(pose.x - right * Math.sin(psi), up, pose.y + right * Math.cos(psi));
  // the motorcycle's pitch (theta nose up, recorded by the multibody model) tilts the eye
  camera.rotation.set(-0.04 + (pose.theta || 0), -psi - Math.PI / 2, -roll);
  cockpit.rotation.z = -(phi - roll);  // the motorcycle's lean that the view does not show
  bars.rotation.y = -(pose.theta_h || 0);
}

function resize() {
  const width = canvas.clientWidth, height = canvas.clientHeight;
  if (canvas.width !== Math.round(width * renderer.getPixelRatio())) {
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
  }
}

const deg = (r) => (r == null ? 0 : (r * 180) / Math.PI).toFixed(1);
// the page's text changes only when its value does (no style or layout work otherwise)
const shown = new Map();
function show(id, text) {
  if (shown.get(id) !== text) { shown.set(id, text); $(id).textContent = text; }
}
const bar = $('bar'), rollToggle = $('roll-toggle'), seek = $('seek');
let barAngle = null;
let fpsFrames = 0, fpsSince = performance.now();
// A frame is rendered only when what it shows changed (a new pose, the size, the horizon
// toggle): a paused replay or an idle run costs the machine nothing. Every frame still
// counts in the lag (the screen shows the last rendered pose) and in the frame rate.
let shownKey = '';
function frame(now) {
  readPose(); resize();
  const key = `${pose.t} ${pose.x} ${pose.y} ${pose.psi} ${pose.phi} ${pose.theta_h} ${rollToggle.checked} ${canvas.width} ${canvas.height}`;
  if (key !== shownKey) {
    shownKey = key;
    aim();
    renderer.render(scene, camera);
    if (sync) gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    stats.rendered++;
  }
  if (pose.clock != null) {
    const drawn = absolute();
    pending.push([pose.clock, drawn]);
    if (stats.lags.length < 100000) stats.lags.push([pose.clock, drawn, pose.deadline]);
  }
  stats.frames++; fpsFrames++; stats.ready = true;
  if (now - fpsSince >= 1000) {
    stats.fps = (1000 * fpsFrames) / (now - fpsSince);
    show('fps', stats.fps.toFixed(0));
    fpsFrames = 0; fpsSince = now;
    adapt(stats.fps);
  }
  show('speed', ((pose.v_x || 0) * 3.6).toFixed(0));
  show('steer', deg(pose.delta));
  show('handlebar', deg(pose.theta_h));
  show('roll', deg(pose.phi));
  const angle = deg(pose.theta_h);
  if (angle !== barAngle) { barAngle = angle; bar.style.transform = `rotate(${angle}deg)`; }
  if (status) {
    show('state', status.state);
    show('clock', `${(status.t || 0).toFixed(1)} s`);
    show('play', status.state === 'playing' || status.state === 'running'
      ? (info.replay ? 'Pause' : 'Stop') : (info.replay ? 'Play' : 'Arm'));
    if (status.duration && !seeking && seek.max !== String(status.duration)) {
      seek.max = status.duration;
    }
    if (status.duration && !seeking) seek.value = status.t;
  }
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);

// --- controls (POST with the token) ---------------------------------------------------------
async function command(body) {
  const response = await fetch('/api/control', {
    method: 'POST', headers: { 'Content-Type': 'application/json', 'X-Motosim-Token': token },
    body: JSON.stringify(body),
  });
  const answer = await response.json();
  if (!response.ok) show('state', answer.error);
  return answer;
}
let seeking = false;
$('play').onclick = () => command({
  action: status && (status.state === 'playing' || status.state === 'running') ? 'stop' : 'arm',
});
$('seek').oninput = () => { seeking = true; };
$('seek').onchange = async () => {
  await command({ action: 'seek', t: Number($('seek').value) }); seeking = false;
};
$('rate').onchange = () => command({ action: 'rate', rate: Number($('rate').value) });
if (!info.replay) { $('seek').disabled = true; $('rate').disabled = true; }

// The dashboard: plots of the run's signals on plain canvases, the run's state, the safety
// stage's state and fault, the loop's timing, and its controls (with the token). A live run
// scrolls the last WINDOW seconds of /ws/signals and has Arm and Stop; a replay plots the whole
// recorded run at once (GET /api/replay), a cursor at the replay time, and has Play/Pause and
// a position slider instead (a recording cannot be armed).
const WINDOW = 10;  // s of history shown
const token = new URLSearchParams(location.search).get('token') || '';
const $ = (id) => document.getElementById(id);
const stats = { messages: 0, rows: 0, draws: 0, state: null, lastControl: null, panels: {},
  safety: null, faultTime: null, replay: false, cursor: null };
window.motosimDash = stats;
for (const a of document.querySelectorAll('a')) a.href += location.search;

const DEG = 180 / Math.PI, MS = 1e3;
// [signal, scale, colour]; a panel none of whose signals the feed has says where they come from
const PANELS = [
  { id: 'torque', title: 'rider torque [N m]', lines: [['tau_r', 1, '#d62728'], ['tau_r_hat', 1, '#1f77b4']] },
  { id: 'steer', title: 'steer and handlebar [deg]', lines: [['delta', DEG, '#2ca02c'], ['theta_h', DEG, '#9467bd']] },
  { id: 'roll', title: 'roll [deg]', lines: [['phi', DEG, '#ff7f0e']] },
  { id: 'speed', title: 'speed [km/h]', lines: [['v_x', 3.6, '#17becf']] },
  { id: 'timing', title: 'loop timing [ms], peak per 5 ms',
    lines: [['period', MS, '#1f77b4'], ['compute', MS, '#d62728'], ['wake', MS, '#2ca02c']],
    missing: 'the real-time loop (motosim run --view)' },
  { id: 'missed', title: 'missed deadlines', lines: [['missed', 1, '#d62728']], step: true,
    missing: 'the real-time loop (motosim run --view)' },
  { id: 'safety', title: 'safety state (0 idle 1 fade-in 2 running 3 fault 4 stopping), fault code',
    lines: [['state', 1, '#2ca02c'], ['fault', 1, '#d62728']], step: true,
    missing: 'the safety stage (motosim run --view)' },
  { id: 'platform', title: 'platform commands [deg]',
    lines: [['phi_s', DEG, '#ff7f0e'], ['theta_s', DEG, '#1f77b4'], ['psi_s', DEG, '#2ca02c'], ['phi_vis', DEG, '#7f7f7f']],
    missing: 'the cueing (motosim view RUN --cueing DIR)' },
  { id: 'lateral', title: 'lateral error [m]', lines: [['e_y', 1, '#8c564b']] },
  { id: 'current', title: 'motor current [A]', lines: [['i_m', 1, '#7f7f7f']] },
];

const info = await (await fetch('/api/info')).json();
$('title').textContent = info.title;
const panels = PANELS.map((p) => ({ ...p, lines: p.lines.filter(([n]) => info.dashboard.includes(n)) }))
  .filter((p) => p.lines.length || p.missing);
for (const p of panels) {
  p.canvas = document.createElement('canvas');
  p.canvas.setAttribute('data-panel', p.id);
  p.canvas.setAttribute('data-title', p.title);
  $('plots').append(p.canvas);
  stats.panels[p.id] = { lines: p.lines.map(([n]) => n), points: 0, lastT: null };
}
const recorded = info.recorded;  // a replay of motosim run: what timing.json says
if (recorded) {
  $('safety').textContent = `${recorded.state} at the end, fault ${recorded.fault} (${recorded.fault_reason})`;
  const tm = recorded.timing || {};
  const ms = (v) => (v == null ? '-' : (v * MS).toFixed(3));
  $('loop').textContent = `${tm.served} periods at ${tm.rate} Hz, missed ${tm.missed}; ` +
    `wake-up p99 ${ms(tm.wake_p99)} ms, compute p99 ${ms(tm.compute_p99)} ms (recorded)`;
}
let t = [], columns = {}, dirty = true;
const clear = () => {
  t = []; columns = {}; for (const n of info.dashboard) columns[n] = []; dirty = true;
};
clear();
const replay = info.replay === true;
stats.replay = replay;
let cursor = null;  // the replay time on the recording's clock [s]
if (replay) {
  $('live-controls').hidden = true;
  $('replay-controls').hidden = false;
  const whole = await (await fetch('/api/replay')).json();
  const ti = whole.names.indexOf('t');
  for (const row of whole.rows) {
    t.push(row[ti]);
    whole.names.forEach((n, j) => columns[n].push(row[j]));
  }
  stats.rows = whole.rows.length;
  if (info.status && info.status.duration) $('position').max = info.status.duration;
}
let dragging = false;

function showStatus(status) {
  stats.state = status.state;
  $('state').textContent = status.state;
  $('clock').textContent = (status.t || 0).toFixed(1);
  if (replay) {
    const now = (t.length ? t[0] : 0) + (status.t || 0);
    if (now !== cursor) { cursor = now; stats.cursor = now; dirty = true; }
    $('play').textContent = status.state === 'playing' ? 'Pause' : 'Play';
    if (!dragging) $('position').value = status.t || 0;
    $('position-text').textContent = `${(status.t || 0).toFixed(1)} of ${(status.duration || 0).toFixed(1)} s`;
  }
  if (status.safety) {
    const s = status.safety;
    const when = stats.faultTime == null ? '' : ` at t = ${stats.faultTime.toFixed(3)} s`;
    stats.safety = s;
    $('safety').textContent = s.fault === 'NONE' ? `${s.state}, no fault`
      : `${s.state}, fault ${s.fault}${when}: ${s.reason}`;
    $('safety').className = s.fault === 'NONE' ? '' : 'fault';
  } else if (!recorded) {
    $('safety').textContent = 'no safety stage in this feed';
  }
  if (status.missed != null) $('loop').textContent = `missed ${status.missed} deadlines`;
  else if (!recorded) $('loop').textContent = 'no real-time loop in this feed';
}

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws/signals`);
  ws.onmessage = (event) => {
    const m = JSON.parse(event.data);
    if (replay) {  // the whole run is plotted: only the replay time moves
      stats.messages++;
      showStatus(m.status);
      return;
    }
    if (m.start_over) clear();
    const ti = m.names.indexOf('t'), fi = m.names.indexOf('fault');
    for (const row of m.rows) {
      t.push(row[ti]);
      m.names.forEach((n, j) => columns[n].push(row[j]));
      if (fi >= 0 && stats.faultTime == null && row[fi] > 0) stats.faultTime = row[ti];
    }
    if (m.rows.length) dirty = true;
    const cut = t.findIndex((v) => v >= t[t.length - 1] - WINDOW);
    if (cut > 0) { t = t.slice(cut); for (const n in columns) columns[n] = columns[n].slice(cut); }
    stats.messages++; stats.rows += m.rows.length;
    showStatus(m.status);
  };
  ws.onclose = () => { $('state').textContent = 'disconnected'; setTimeout(connect, 1000); };
}
connect();

function draw(p) {
  const c = p.canvas, ratio = window.devicePixelRatio || 1;
  const W = Math.round(c.clientWidth * ratio), H = Math.round(c.clientHeight * ratio);
  if (c.width !== W || c.height !== H) { c.width = W; c.height = H; }
  const g = c.getContext('2d');
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  const w = c.clientWidth, h = c.clientHeight, left = 48, top = 18, bottom = 18;
  g.clearRect(0, 0, w, h);
  g.fillStyle = '#222'; g.font = '12px sans-serif';
  g.fillText(p.title, left, 13);
  if (!p.lines.length) {
    g.fillStyle = '#888'; g.fillText(`not in this feed: from ${p.missing}`, left, h / 2);
    return;
  }
  if (t.length < 2) return;
  const t1 = t[t.length - 1], t0 = replay ? t[0] : t1 - WINDOW, span = t1 - t0 || 1;
  let lo = Infinity, hi = -Infinity;
  for (const [n, k] of p.lines) for (const v of columns[n]) if (v !== null) {
    lo = Math.min(lo, v * k); hi = Math.max(hi, v * k);
  }
  if (!isFinite(lo)) return;
  if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
  const pad = 0.08 * (hi - lo); lo -= pad; hi += pad;
  const X = (v) => left + ((v - t0) / span) * (w - left - 6);
  const Y = (v) => top + (1 - (v - lo) / (hi - lo)) * (h - top - bottom);
  g.strokeStyle = '#ddd'; g.beginPath();
  for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) { g.moveTo(left, Y(v)); g.lineTo(w - 6, Y(v)); }
  g.stroke();
  g.fillStyle = '#555';
  const digits = Math.min(6, Math.max(0, 1 - Math.floor(Math.log10(hi - lo - 2 * pad))));
  for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) g.fillText(v.toFixed(digits), 2, Y(v) + 4);
  g.fillText(`${t1.toFixed(1)} s`, w - 50, h - 4);
  let points = 0;
  p.lines.forEach(([n, k, color], j) => {
    const values = columns[n];
    g.strokeStyle = color; g.lineWidth = 1.5; g.beginPath();
    let pen = false, last = 0;
    for (let i = 0; i < values.length; i++) {
      const v = values[i];
      if (v === null) { pen = false; continue; }
      const x = X(t[i]), y = Y(v * k);
      if (!pen) { g.moveTo(x, y); pen = true; } else {
        if (p.step) g.lineTo(x, last);
        g.lineTo(x, y);
      }
      last = y; points++;
    }
    g.stroke();
    g.fillStyle = color; g.fillText(n, w - 90 - 70 * (p.lines.length - 1 - j), 13);
  });
  if (replay && cursor !== null) {  // where the replay is
    g.strokeStyle = '#000'; g.lineWidth = 1; g.beginPath();
    g.moveTo(X(cursor), top); g.lineTo(X(cursor), h - bottom); g.stroke();
  }
  stats.panels[p.id].points = points;
  stats.panels[p.id].lastT = replay ? cursor : t1;
}

// redraw only when rows came in (the signals arrive at 30 Hz) or the page was resized
addEventListener('resize', () => { dirty = true; });
function frame() {
  if (dirty) { for (const p of panels) draw(p); stats.draws++; dirty = false; }
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);

async function command(action, extra = {}) {
  const response = await fetch('/api/control', {
    method: 'POST', headers: { 'Content-Type': 'application/json', 'X-Motosim-Token': token },
    body: JSON.stringify({ action, ...extra }),
  });
  const answer = await response.json();
  stats.lastControl = { action, status: response.status, answer };
  $('message').textContent = response.ok ? `${action}: ${answer.status.state}` : answer.error;
  if (response.ok) showStatus(answer.status);
}
$('arm').onclick = () => command('arm');
$('stop').onclick = () => command('stop');
$('play').onclick = () => command(stats.state === 'playing' ? 'stop' : 'arm');
$('position').oninput = () => { dragging = true; };
$('position').onchange = async () => {
  await command('seek', { t: Number($('position').value) });
  dragging = false;
};

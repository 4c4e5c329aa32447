// The dashboard: scrolling plots of /ws/signals on plain canvases, and the arm/stop buttons.
const WINDOW = 10;  // s of history shown
const token = new URLSearchParams(location.search).get('token') || '';
const $ = (id) => document.getElementById(id);
const stats = { messages: 0, rows: 0, draws: 0, state: null, lastControl: null };
window.motosimDash = stats;
for (const a of document.querySelectorAll('a')) a.href += location.search;

const DEG = 180 / Math.PI;
const PANELS = [
  { title: 'rider torque [N m]', lines: [['tau_r', 1, '#d62728'], ['tau_r_hat', 1, '#1f77b4']] },
  { title: 'steer and handlebar [deg]', lines: [['delta', DEG, '#2ca02c'], ['theta_h', DEG, '#9467bd']] },
  { title: 'roll [deg]', lines: [['phi', DEG, '#ff7f0e']] },
  { title: 'speed [km/h]', lines: [['v_x', 3.6, '#17becf']] },
  { title: 'lateral error [m]', lines: [['e_y', 1, '#8c564b']] },
  { title: 'motor current [A]', lines: [['i_m', 1, '#7f7f7f']] },
];

const info = await (await fetch('/api/info')).json();
$('title').textContent = info.title;
const panels = PANELS.map((p) => ({ ...p, lines: p.lines.filter(([n]) => info.dashboard.includes(n)) }))
  .filter((p) => p.lines.length);
for (const p of panels) {
  p.canvas = document.createElement('canvas');
  p.canvas.setAttribute('data-title', p.title);
  $('plots').append(p.canvas);
}
let t = [], columns = {};
const clear = () => { t = []; columns = {}; for (const n of info.dashboard) columns[n] = []; };
clear();

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws/signals`);
  ws.onmessage = (event) => {
    const m = JSON.parse(event.data);
    if (m.start_over) clear();
    const ti = m.names.indexOf('t');
    for (const row of m.rows) {
      t.push(row[ti]);
      m.names.forEach((n, j) => columns[n].push(row[j]));
    }
    const cut = t.findIndex((v) => v >= t[t.length - 1] - WINDOW);
    if (cut > 0) { t = t.slice(cut); for (const n in columns) columns[n] = columns[n].slice(cut); }
    stats.messages++; stats.rows += m.rows.length; stats.state = m.status.state;
    $('state').textContent = m.status.state;
    $('clock').textContent = (m.status.t || 0).toFixed(1);
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
  if (t.length < 2) return;
  const t1 = t[t.length - 1], t0 = t1 - WINDOW;
  let lo = Infinity, hi = -Infinity;
  for (const [n, k] of p.lines) for (const v of columns[n]) if (v !== null) {
    lo = Math.min(lo, v * k); hi = Math.max(hi, v * k);
  }
  if (!isFinite(lo)) return;
  if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
  const pad = 0.08 * (hi - lo); lo -= pad; hi += pad;
  const X = (v) => left + ((v - t0) / WINDOW) * (w - left - 6);
  const Y = (v) => top + (1 - (v - lo) / (hi - lo)) * (h - top - bottom);
  g.strokeStyle = '#ddd'; g.beginPath();
  for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) { g.moveTo(left, Y(v)); g.lineTo(w - 6, Y(v)); }
  g.stroke();
  g.fillStyle = '#555';
  const digits = Math.min(6, Math.max(0, 1 - Math.floor(Math.log10(hi - lo - 2 * pad))));
  for (const v of [lo + pad, (lo + hi) / 2, hi - pad]) g.fillText(v.toFixed(digits), 2, Y(v) + 4);
  g.fillText(`${t1.toFixed(1)} s`, w - 50, h - 4);
  p.lines.forEach(([n, k, color], j) => {
    g.strokeStyle = color; g.lineWidth = 1.5; g.beginPath();
    let pen = false;
    columns[n].forEach((v, i) => {
      if (v === null) { pen = false; return; }
      if (pen) g.lineTo(X(t[i]), Y(v * k)); else { g.moveTo(X(t[i]), Y(v * k)); pen = true; }
    });
    g.stroke();
    g.fillStyle = color; g.fillText(n, left + 200 + 70 * j, 13);
  });
}

function frame() { for (const p of panels) draw(p); stats.draws++; requestAnimationFrame(frame); }
requestAnimationFrame(frame);

async function command(action) {
  const response = await fetch('/api/control', {
    method: 'POST', headers: { 'Content-Type': 'application/json', 'X-Motosim-Token': token },
    body: JSON.stringify({ action }),
  });
  const answer = await response.json();
  stats.lastControl = { action, status: response.status, answer };
  $('message').textContent = response.ok ? `${action}: ${answer.status.state}` : answer.error;
}
$('arm').onclick = () => command('arm');
$('stop').onclick = () => command('stop');

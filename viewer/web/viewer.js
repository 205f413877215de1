// canhil's viewer page: the world from `canhil run` (live, over the WebSocket)
// or from a recording (`canhil view`, played here), drawn to scale; drags
// become the run's own commands (docs/viewer.md is the protocol).
import { makePlots } from './plots.js';

const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.search).get('token');
const withToken = (path) => (token ? `${path}${path.includes('?') ? '&' : '?'}token=${encodeURIComponent(token)}` : path);

const canvas = $('field');
const ctx = canvas.getContext('2d');
const eye = $('eye');
const eyeCtx = eye.getContext('2d');

let hello = null;        // the server's hello
let state = null;        // the latest live state, or the replay's state at the cursor
let socket = null;
let nextId = 1;
const pending = new Map();  // id -> resolve
const view = { cx: 0, cy: 0, scale: 30, fitted: false };
let drag = null;         // {kind, index, mode: 'move'|'turn'|'kick'|'pan', ...}
let dirty = true;
let lastDrawn = { robots: [], ball: null };
const frameTimes = [];
let plots = null;
let replay = null;       // {rows, columns, robots, events, t, playing, speed, duration}

// --- connection ---------------------------------------------------------------

function connect() {
  const url = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}${withToken('/ws')}`;
  socket = new WebSocket(url);
  socket.onopen = () => setStatus('connected');
  socket.onclose = () => {
    setStatus('disconnected — reconnecting', true);
    setTimeout(connect, 1000);
  };
  socket.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    if (msg.type === 'hello') onHello(msg);
    else if (msg.type === 'state') onState(msg);
    else if (msg.type === 'reply') onReply(msg);
    else if (msg.type === 'log') log(msg.text);
  };
}

function ask(command, args = {}) {
  return new Promise((resolve) => {
    if (!socket || socket.readyState !== WebSocket.OPEN) {
      log(`not connected: ${command} not sent`, true);
      resolve({ ok: false, error: 'not connected' });
      return;
    }
    const id = nextId++;
    pending.set(id, resolve);
    socket.send(JSON.stringify({ command, id, ...args }));
  });
}

function onReply(msg) {
  if (!msg.ok) log(`refused: ${msg.error}`, true);
  const resolve = pending.get(msg.id);
  if (resolve) {
    pending.delete(msg.id);
    resolve(msg);
  }
}

function setStatus(text, bad = false) {
  $('status').textContent = text;
  $('status').classList.toggle('bad', bad);
}

function log(text, error = false) {
  const li = document.createElement('li');
  li.textContent = text;
  if (error) li.className = 'error';
  $('log').appendChild(li);
  while ($('log').children.length > 200) $('log').firstChild.remove();
  $('log').scrollTop = $('log').scrollHeight;
}

// --- hello and state ------------------------------------------------------------

function onHello(h) {
  hello = h;
  if (!view.fitted) fit();
  const pick = $('robot-pick');
  pick.innerHTML = '';
  for (const r of h.robots) pick.add(new Option(`robot ${r.index}: agent ${r.agent}, ${r.interface}`, r.index));
  const live = h.mode === 'live';
  $('live-controls').hidden = !live;
  $('replay-controls').hidden = live;
  for (const b of document.querySelectorAll('#pause, #resume, #step, [data-speed]')) b.disabled = !h.virtual_time;
  const gs = $('game-state');
  gs.innerHTML = '';
  for (const g of h.game_states || []) gs.add(new Option(g, g));
  const fl = $('fault-list');
  fl.innerHTML = '';
  fl.add(new Option('pick a fault…', ''));
  for (const f of h.faults || []) fl.add(new Option(f, f));
  showSaves(h.saves || []);
  plots = makePlots($('plots'), h);
  if (!live) startReplay();
  dirty = true;
}

function onState(s) {
  state = s;
  const paused = s.paused ? 'paused' : s.speed === 0 ? 'max speed' : `${s.speed}x`;
  $('clock').textContent = `t = ${s.time_s.toFixed(2)} s · ${s.ended ? 'ended' : paused} · ` +
    `${s.real_time_factor.toFixed(1)}x real time · goals ${s.goals.length}`;
  $('pause').classList.toggle('on', s.paused);
  for (const b of document.querySelectorAll('[data-speed]')) b.classList.toggle('on', !s.paused && Number(b.dataset.speed) === s.speed);
  if (plots) plots.push(s, selectedRobot());
  if ($('follow-ball').checked) {
    view.cx = s.ball.x;
    view.cy = s.ball.y;
  }
  dirty = true;
}

function selectedRobot() {
  return Number($('robot-pick').value || 0);
}

function showSaves(list) {
  const ul = $('saves');
  ul.innerHTML = '';
  for (const s of list) {
    const li = document.createElement('li');
    li.textContent = `${s.name} (${s.kind})`;
    const b = document.createElement('button');
    b.textContent = 'load';
    b.onclick = () => ask('load', { name: s.name, kind: s.kind });
    li.appendChild(b);
    ul.appendChild(li);
  }
}

// --- the view -------------------------------------------------------------------

function resize() {
  const dpr = window.devicePixelRatio || 1;
  const r = canvas.getBoundingClientRect();
  canvas.width = Math.round(r.width * dpr);
  canvas.height = Math.round(r.height * dpr);
  dirty = true;
}

function fit() {
  if (!hello) return;
  const f = hello.field;
  const r = canvas.getBoundingClientRect();
  const w = f.length_m + 2 * (f.margin_m + f.goal_depth_m);
  const h = f.width_m + 2 * f.margin_m;
  view.scale = Math.min(r.width / w, r.height / h) * 0.97;
  view.cx = 0;
  view.cy = 0;
  view.fitted = true;
  dirty = true;
}

// World metres -> CSS pixels in the canvas, and back.
function toCanvas(x, y) {
  const r = canvas.getBoundingClientRect();
  return { x: r.width / 2 + (x - view.cx) * view.scale, y: r.height / 2 - (y - view.cy) * view.scale };
}
function toWorld(px, py) {
  const r = canvas.getBoundingClientRect();
  return { x: view.cx + (px - r.width / 2) / view.scale, y: view.cy - (py - r.height / 2) / view.scale };
}

function zoom(factor, px, py) {
  const before = toWorld(px, py);
  view.scale = Math.min(400, Math.max(5, view.scale * factor));
  const after = toWorld(px, py);
  view.cx += before.x - after.x;
  view.cy += before.y - after.y;
  dirty = true;
}

// --- drawing ---------------------------------------------------------------------

function draw() {
  const dpr = window.devicePixelRatio || 1;
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  const r = canvas.getBoundingClientRect();
  ctx.fillStyle = '#1b4d1e';
  ctx.fillRect(0, 0, r.width, r.height);
  if (!hello) return;
  drawField(hello.field);
  const s = state;
  if (!s) return;
  const drawn = { robots: [], ball: null };
  for (const [i, o] of (s.obstacles || []).entries()) {
    const p = dragged('obstacle', i) || o;
    const radius = hello.obstacles[i] ? hello.obstacles[i].radius_m : 0.25;
    disc(p.x, p.y, radius, '#111', '#555');
  }
  for (const [i, rb] of s.robots.entries()) {
    if (rb.odometry) ghost(rb.odometry, hello.robot_radius_m);
    const p = dragged('robot', i) || rb;
    robot(p, i);
    drawn.robots.push({ x: p.x, y: p.y, heading_deg: p.heading_deg });
  }
  if ($('show-vision').checked && s.vision) visionPoints(s);
  const b = dragged('ball', 0) || s.ball;
  ball(b);
  drawn.ball = { x: b.x, y: b.y };
  if (drag && drag.mode === 'kick') kickArrow();
  lastDrawn = drawn;
  drawEye(s);
}

function line(x1, y1, x2, y2) {
  const a = toCanvas(x1, y1), b = toCanvas(x2, y2);
  ctx.moveTo(a.x, a.y);
  ctx.lineTo(b.x, b.y);
}

function rect(x1, y1, x2, y2) {
  line(x1, y1, x2, y1);
  line(x2, y1, x2, y2);
  line(x2, y2, x1, y2);
  line(x1, y2, x1, y1);
}

function arc(x, y, radius, from, to) {
  const c = toCanvas(x, y);
  ctx.moveTo(c.x + radius * view.scale * Math.cos(from), c.y - radius * view.scale * Math.sin(from));
  ctx.arc(c.x, c.y, radius * view.scale, -from, -to, true);
}

function drawField(f) {
  const L = f.length_m / 2, W = f.width_m / 2, m = f.margin_m;
  const a = toCanvas(-L - m, W + m), b = toCanvas(L + m, -W - m);
  ctx.fillStyle = '#2e7d32';
  ctx.fillRect(a.x, a.y, b.x - a.x, b.y - a.y);
  ctx.strokeStyle = '#f4f4f4';
  ctx.lineWidth = Math.max(1, f.line_width_m * view.scale);
  ctx.beginPath();
  rect(-L, -W, L, W);
  line(0, -W, 0, W);
  arc(0, 0, f.centre_circle_radius_m, 0, 2 * Math.PI);
  for (const s of [-1, 1]) {
    rect(s * L, -f.penalty_area_width_m / 2, s * (L - f.penalty_area_depth_m), f.penalty_area_width_m / 2);
    rect(s * L, -f.goal_area_width_m / 2, s * (L - f.goal_area_depth_m), f.goal_area_width_m / 2);
    for (const t of [-1, 1]) {
      // The corner's quarter circle, inside the field.
      const R = f.corner_arc_radius_m;
      for (let k = 0; k < 8; k++) {
        const u0 = (k * Math.PI) / 16, u1 = ((k + 1) * Math.PI) / 16;
        line(s * (L - R * Math.cos(u0)), t * (W - R * Math.sin(u0)), s * (L - R * Math.cos(u1)), t * (W - R * Math.sin(u1)));
      }
    }
  }
  ctx.stroke();
  ctx.fillStyle = '#f4f4f4';
  for (const s of [-1, 1]) {
    const p = toCanvas(s * (L - f.penalty_mark_distance_m), 0);
    ctx.beginPath();
    ctx.arc(p.x, p.y, Math.max(2, 0.06 * view.scale), 0, 2 * Math.PI);
    ctx.fill();
  }
  // Goals: +x the opponent's (blue), -x own (yellow).
  for (const [s, colour] of [[1, '#58a6ff'], [-1, '#f2cc60']]) {
    const g1 = toCanvas(s * L, f.goal_width_m / 2), g2 = toCanvas(s * (L + f.goal_depth_m), -f.goal_width_m / 2);
    ctx.fillStyle = colour;
    ctx.globalAlpha = 0.55;
    ctx.fillRect(Math.min(g1.x, g2.x), g1.y, Math.abs(g2.x - g1.x), g2.y - g1.y);
    ctx.globalAlpha = 1;
  }
}

function disc(x, y, radius, fill, stroke) {
  const c = toCanvas(x, y);
  ctx.beginPath();
  ctx.arc(c.x, c.y, Math.max(2, radius * view.scale), 0, 2 * Math.PI);
  ctx.fillStyle = fill;
  ctx.fill();
  ctx.strokeStyle = stroke;
  ctx.lineWidth = 1.5;
  ctx.stroke();
}

function front(p) {
  const a = ((p.heading_deg + 90) * Math.PI) / 180;  // the robot's front is its +y axis
  return { x: Math.cos(a), y: Math.sin(a) };
}

function robot(p, i) {
  const radius = hello.robot_radius_m;
  disc(p.x, p.y, radius, '#0d1117', '#e6edf3');
  const d = front(p);
  ctx.beginPath();
  line(p.x, p.y, p.x + d.x * radius * 1.4, p.y + d.y * radius * 1.4);
  ctx.strokeStyle = '#ff9f43';
  ctx.lineWidth = Math.max(2, 0.05 * view.scale);
  ctx.stroke();
  const info = hello.robots[i] || { agent: i + 1, interface: '' };
  const c = toCanvas(p.x, p.y);
  ctx.font = `${Math.max(10, Math.min(16, 0.3 * view.scale))}px system-ui, sans-serif`;
  ctx.fillStyle = '#fff';
  ctx.textAlign = 'center';
  ctx.fillText(String(info.agent), c.x, c.y + 4);
  ctx.fillStyle = '#e8f5e9';
  ctx.fillText(info.interface, c.x, c.y - radius * view.scale - 4);
}

function ghost(p, radius) {
  const c = toCanvas(p.x, p.y);
  ctx.beginPath();
  ctx.setLineDash([4, 3]);
  ctx.arc(c.x, c.y, radius * view.scale, 0, 2 * Math.PI);
  const d = front(p);
  ctx.moveTo(c.x, c.y);
  ctx.lineTo(c.x + d.x * radius * view.scale, c.y - d.y * radius * view.scale);
  ctx.strokeStyle = 'rgba(255,255,255,0.55)';
  ctx.lineWidth = 1;
  ctx.stroke();
  ctx.setLineDash([]);
}

function ball(b) {
  const radius = hello.ball_radius_m;
  const air = b.z > radius + 0.02;
  if (air) {
    const s = toCanvas(b.x, b.y);
    ctx.beginPath();
    ctx.arc(s.x + 3, s.y + 3, Math.max(3, radius * view.scale), 0, 2 * Math.PI);
    ctx.fillStyle = 'rgba(0,0,0,0.35)';
    ctx.fill();
  }
  disc(b.x, b.y, Math.max(radius, 6 / view.scale), '#ff7f0e', '#fff');
  if (air) {
    const c = toCanvas(b.x, b.y);
    ctx.fillStyle = '#fff';
    ctx.font = '12px system-ui, sans-serif';
    ctx.fillText(`${b.z.toFixed(2)} m`, c.x + 14, c.y - 10);
  }
}

function visionPoints(s) {
  const v = s.vision;
  const rb = s.robots[v.robot];
  if (!rb) return;
  const a = (rb.heading_deg * Math.PI) / 180;
  const toW = ([x, y]) => ({ x: rb.x + x * Math.cos(a) - y * Math.sin(a), y: rb.y + x * Math.sin(a) + y * Math.cos(a) });
  for (const [list, colour] of [[v.lines, '#fff59d'], [v.obstacles, '#ff5252'], [v.balls, '#ffb74d']]) {
    ctx.fillStyle = colour;
    for (const p of list) {
      const c = toCanvas(toW(p).x, toW(p).y);
      ctx.fillRect(c.x - 1.5, c.y - 1.5, 3, 3);
    }
  }
}

// The robot's-eye view: what its vision reports, in its own frame, front up.
function drawEye(s) {
  eyeCtx.fillStyle = '#17301a';
  eyeCtx.fillRect(0, 0, eye.width, eye.height);
  const k = eye.width / 14;  // 7 m around the robot
  const cx = eye.width / 2, cy = eye.height / 2;
  eyeCtx.fillStyle = '#fff';
  eyeCtx.font = '11px system-ui, sans-serif';
  if (!s.vision || s.vision.robot !== selectedRobot()) {
    eyeCtx.fillText(hello.mode === 'live' ? 'tick "vision points" to see this robot\'s vision' : 'no vision in a recording', 8, 16);
    return;
  }
  for (const [list, colour] of [[s.vision.lines, '#fff59d'], [s.vision.obstacles, '#ff5252'], [s.vision.balls, '#ffb74d']]) {
    eyeCtx.fillStyle = colour;
    for (const [x, y] of list) eyeCtx.fillRect(cx + x * k - 1.5, cy - y * k - 1.5, 3, 3);
  }
  eyeCtx.beginPath();
  eyeCtx.arc(cx, cy, hello.robot_radius_m * k, 0, 2 * Math.PI);
  eyeCtx.moveTo(cx, cy);
  eyeCtx.lineTo(cx, cy - hello.robot_radius_m * k * 1.5);
  eyeCtx.strokeStyle = '#ff9f43';
  eyeCtx.stroke();
  eyeCtx.fillStyle = '#fff';
  eyeCtx.fillText(`t = ${s.vision.time_s.toFixed(2)} s, ${s.vision.lines.length} line points`, 8, eye.height - 8);
}

function kickArrow() {
  const b = state.ball;
  const from = toCanvas(b.x, b.y), to = toCanvas(drag.to.x, drag.to.y);
  ctx.beginPath();
  ctx.moveTo(from.x, from.y);
  ctx.lineTo(to.x, to.y);
  ctx.strokeStyle = '#ffeb3b';
  ctx.lineWidth = 3;
  ctx.stroke();
  const v = kickVelocity();
  ctx.fillStyle = '#ffeb3b';
  ctx.fillText(`${Math.hypot(v.vx, v.vy).toFixed(1)} m/s`, to.x + 8, to.y - 8);
}

function dragged(kind, index) {
  if (!drag || drag.kind !== kind || drag.index !== index || !drag.to) return null;
  if (drag.mode === 'move') {
    const base = kind === 'robot' ? state.robots[index] : kind === 'ball' ? state.ball : state.obstacles[index];
    return { ...base, x: drag.to.x, y: drag.to.y };
  }
  if (drag.mode === 'turn') return { ...state.robots[index], heading_deg: drag.heading_deg };
  return null;
}

// --- interaction ------------------------------------------------------------------

const KICK_PER_METRE = 2;  // m/s of ball speed per metre dragged
const KICK_MOST = 12;

function kickVelocity() {
  const b = state.ball;
  let vx = (drag.to.x - b.x) * KICK_PER_METRE, vy = (drag.to.y - b.y) * KICK_PER_METRE;
  const speed = Math.hypot(vx, vy);
  if (speed > KICK_MOST) {
    vx *= KICK_MOST / speed;
    vy *= KICK_MOST / speed;
  }
  return { vx, vy };
}

function pick(w, px, py) {
  if (!state) return null;
  const near = (x, y, radius) => {
    const c = toCanvas(x, y);
    return Math.hypot(c.x - px, c.y - py) <= Math.max(radius * view.scale, 12);
  };
  if (near(state.ball.x, state.ball.y, hello.ball_radius_m)) return { kind: 'ball', index: 0 };
  for (const [i, r] of state.robots.entries()) if (near(r.x, r.y, hello.robot_radius_m)) return { kind: 'robot', index: i };
  for (const [i, o] of state.obstacles.entries()) {
    if (near(o.x, o.y, hello.obstacles[i] ? hello.obstacles[i].radius_m : 0.25)) return { kind: 'obstacle', index: i };
  }
  return null;
}

function canvasPoint(e) {
  const r = canvas.getBoundingClientRect();
  return { px: e.clientX - r.left, py: e.clientY - r.top };
}

canvas.addEventListener('contextmenu', (e) => e.preventDefault());
canvas.addEventListener('mousedown', (e) => {
  const { px, py } = canvasPoint(e);
  const w = toWorld(px, py);
  const live = hello && hello.mode === 'live';
  const hit = live ? pick(w, px, py) : null;
  if (hit && hit.kind === 'ball' && (e.ctrlKey || e.altKey || e.metaKey)) drag = { ...hit, mode: 'kick', to: w };
  else if (hit && hit.kind === 'robot' && (e.button === 2 || e.shiftKey)) drag = { ...hit, mode: 'turn', heading_deg: state.robots[hit.index].heading_deg };
  else if (hit && e.button === 0) drag = { ...hit, mode: 'move', to: w };
  else drag = { mode: 'pan', px, py, cx: view.cx, cy: view.cy };
  e.preventDefault();
});
window.addEventListener('mousemove', (e) => {
  if (!drag) return;
  const { px, py } = canvasPoint(e);
  const w = toWorld(px, py);
  if (drag.mode === 'pan') {
    view.cx = drag.cx - (px - drag.px) / view.scale;
    view.cy = drag.cy + (py - drag.py) / view.scale;
    $('follow-ball').checked = false;
  } else if (drag.mode === 'turn') {
    const r = state.robots[drag.index];
    // The front (+y of the robot) toward the mouse: heading = that angle - 90 degrees.
    drag.heading_deg = (Math.atan2(w.y - r.y, w.x - r.x) * 180) / Math.PI - 90;
  } else {
    drag.to = w;
  }
  dirty = true;
});
window.addEventListener('mouseup', () => {
  if (!drag) return;
  const d = drag;
  drag = null;
  dirty = true;
  if (d.mode === 'pan' || !state) return;
  if (d.mode === 'kick') {
    const saved = drag;
    drag = d;
    const v = kickVelocity();
    drag = saved;
    ask('move_ball', { x: state.ball.x, y: state.ball.y, vx: v.vx, vy: v.vy });
  } else if (d.mode === 'turn') {
    const r = state.robots[d.index];
    ask('move_robot', { robot: d.index, x: r.x, y: r.y, heading_deg: d.heading_deg });
  } else if (d.kind === 'robot') {
    ask('move_robot', { robot: d.index, x: d.to.x, y: d.to.y, heading_deg: state.robots[d.index].heading_deg });
  } else if (d.kind === 'ball') {
    ask('move_ball', { x: d.to.x, y: d.to.y });
  } else if (d.kind === 'obstacle') {
    ask('move_obstacle', { obstacle: d.index, x: d.to.x, y: d.to.y });
  }
});
canvas.addEventListener('wheel', (e) => {
  const { px, py } = canvasPoint(e);
  zoom(e.deltaY < 0 ? 1.15 : 1 / 1.15, px, py);
  e.preventDefault();
}, { passive: false });
$('zoom-in').onclick = () => zoom(1.3, canvas.clientWidth / 2, canvas.clientHeight / 2);
$('zoom-out').onclick = () => zoom(1 / 1.3, canvas.clientWidth / 2, canvas.clientHeight / 2);
$('zoom-fit').onclick = () => { $('follow-ball').checked = false; fit(); };
$('follow-ball').onchange = () => { dirty = true; };

$('pause').onclick = () => ask('pause');
$('resume').onclick = () => ask('resume');
$('step').onclick = () => ask('step', { count: 1 });
for (const b of document.querySelectorAll('[data-speed]')) {
  b.onclick = async () => {
    await ask('speed', { factor: Number(b.dataset.speed) });
    if (state && state.paused) ask('resume');
  };
}
$('send-game-state').onclick = () => ask('coach', { game_state: $('game-state').value });
$('fault-list').onchange = () => { $('fault-text').value = $('fault-list').value; };
$('inject').onclick = () => { if ($('fault-text').value) ask('fault', { rule: $('fault-text').value }); };
$('save').onclick = async () => {
  const name = $('save-name').value.trim();
  if (!name) return log('give the save a name', true);
  const r = await ask('save', { name, kind: $('save-kind').value });
  if (r.ok) log(`saved to ${r.path}`);
  const list = await ask('saves');
  if (list.ok) showSaves(list.saves);
};
$('show-vision').onchange = () => ask('watch_vision', { robot: $('show-vision').checked ? selectedRobot() : null });
$('robot-pick').onchange = () => {
  if ($('show-vision').checked) ask('watch_vision', { robot: selectedRobot() });
  if (plots) plots.reset();
};

// --- replay ------------------------------------------------------------------------

async function startReplay() {
  const data = await (await fetch(withToken('/api/replay'))).json();
  replay = { ...data, t: 0, playing: false, speed: 1, duration: data.rows[data.rows.length - 1][0], lastFetch: -1 };
  $('scrub').max = 1000;
  setReplayTime(0);
}

function rowAt(t) {
  const rows = replay.rows;
  let lo = 0, hi = rows.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (rows[mid][0] <= t) lo = mid; else hi = mid - 1;
  }
  const a = rows[lo], b = rows[Math.min(lo + 1, rows.length - 1)];
  const k = b[0] > a[0] ? Math.min(1, Math.max(0, (t - a[0]) / (b[0] - a[0]))) : 0;
  return a.map((v, i) => v + (b[i] - v) * k);
}

function replayState(t) {
  const row = rowAt(t);
  const robots = [];
  for (let r = 0; r < replay.robots; r++) {
    const o = 4 + 6 * r;
    robots.push({ x: row[o], y: row[o + 1], heading_deg: row[o + 2], odometry: { x: row[o + 3], y: row[o + 4], heading_deg: row[o + 5] } });
  }
  return {
    time_s: t, ball: { x: row[1], y: row[2], z: row[3] }, robots, obstacles: [],
    goals: replay.events.filter((e) => e.kind === 'goal' && e.time_s <= t),
  };
}

function setReplayTime(t) {
  replay.t = Math.max(0, Math.min(replay.duration, t));
  state = replayState(replay.t);
  $('scrub').value = Math.round((replay.t / (replay.duration || 1)) * 1000);
  $('replay-time').textContent = `t = ${replay.t.toFixed(2)} s of ${replay.duration.toFixed(2)} s`;
  $('clock').textContent = `replay · t = ${replay.t.toFixed(2)} s · ${replay.playing ? `${replay.speed}x` : 'paused'}`;
  if (plots) plots.push(state, selectedRobot());
  dirty = true;
  fetchFrames();
}

let framesTimer = null;
function fetchFrames() {
  if (!hello || !hello.has_trace || framesTimer) return;
  framesTimer = setTimeout(async () => {
    framesTimer = null;
    const t = replay.t;
    const frames = await (await fetch(withToken(`/api/frames?from=${(t - 0.1).toFixed(4)}&to=${(t + 0.1).toFixed(4)}`))).json();
    const body = $('frames').tBodies[0];
    body.innerHTML = '';
    for (const f of frames.slice(0, 120)) {
      const tr = body.insertRow();
      if (Math.abs(f.time_s - t) < 0.005) tr.className = 'cursor';
      for (const v of [f.time_s.toFixed(4), f.interface, f.signals]) tr.insertCell().textContent = v;
    }
  }, 150);
}

function jump(kind) {
  const next = replay.events.find((e) => e.kind === kind && e.time_s > replay.t + 1e-6);
  if (next) setReplayTime(next.time_s);
  else log(`no ${kind} after t = ${replay.t.toFixed(2)} s`);
}

$('play').onclick = () => { replay.playing = true; replay.wall = performance.now(); };
$('stop').onclick = () => { replay.playing = false; setReplayTime(replay.t); };
$('replay-speed').onchange = () => { replay.speed = Number($('replay-speed').value); };
$('scrub').oninput = () => setReplayTime((Number($('scrub').value) / 1000) * replay.duration);
$('next-goal').onclick = () => jump('goal');
$('next-kick').onclick = () => jump('kick');

// --- the loop ----------------------------------------------------------------------

function frame(now) {
  if (replay && replay.playing) {
    const dt = (now - replay.wall) / 1000;
    replay.wall = now;
    setReplayTime(replay.t + dt * replay.speed);
    if (replay.t >= replay.duration) replay.playing = false;
  }
  if (dirty) {
    dirty = false;
    draw();
    frameTimes.push(now);
    while (frameTimes.length && frameTimes[0] < now - 2000) frameTimes.shift();
  }
  requestAnimationFrame(frame);
}

window.addEventListener('resize', () => { resize(); fit(); });
resize();
connect();
requestAnimationFrame(frame);

// Read-only hooks for the browser tests (tests/browser/).
window.canhilView = {
  state: () => state,
  hello: () => hello,
  toScreen: (x, y) => {
    const c = toCanvas(x, y);
    const r = canvas.getBoundingClientRect();
    return { x: r.left + c.x, y: r.top + c.y };
  },
  drawn: () => lastDrawn,
  fps: () => (frameTimes.length < 2 ? 0 : ((frameTimes.length - 1) * 1000) / (frameTimes[frameTimes.length - 1] - frameTimes[0])),
  replayTime: () => (replay ? replay.t : null),
  setReplayTime: (t) => setReplayTime(t),
  play: (speed) => { replay.speed = speed; replay.playing = true; replay.wall = performance.now(); },
};

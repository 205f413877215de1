// canhil's viewer page: the world of `canhil run` live over the WebSocket, or
// a recording (`canhil view`) played here; drawn to scale, changed by hand.
// docs/viewer.md is the protocol. This module wires the parts together:
// protocol.js (the connection), field.js (drawing), interact.js (the mouse),
// plots.js (uPlot), replay.js (the timeline).

import { Connection, getJson, ballVelocity } from './protocol.js';
import { View, drawField, drawRobot, drawGhost, drawObstacle, drawBall, drawKick, drawVisionOnField, drawEye } from './field.js';
import { Interaction } from './interact.js';
import { livePlots, replayPlots } from './plots.js';
import { Replay } from './replay.js';

const $ = (id) => document.getElementById(id);
const canvas = $('field');
const ctx = canvas.getContext('2d');
const eye = $('eye');
const eyeCtx = eye.getContext('2d');

const view = new View();
let hello = null;
let live = null;          // the latest live state
let replay = null;        // the Replay in replay mode
let plots = null;
let fitted = false;
let autoFit = true;       // refit on resize until the user zooms or pans
let dirty = true;
let lastDrawn = { robots: [], ball: null };
const frameTimes = [];    // when each of the last 2 s of frames was drawn
let framesDrawn = 0;
let lastPlotDraw = 0;

const isLive = () => hello !== null && hello.mode !== 'replay';
const current = () => (replay ? replay.state : live);
const changed = () => { dirty = true; };
const selectedRobot = () => Number($('robot-pick').value || 0);

// --- the log ---------------------------------------------------------------------

function log(text, error = false) {
  const li = document.createElement('li');
  const when = document.createElement('span');
  when.className = 'when';
  when.textContent = new Date().toLocaleTimeString([], { hour12: false });
  li.append(when, document.createTextNode(text));
  if (error) li.className = 'error';
  const list = $('log');
  const atEnd = list.scrollTop + list.clientHeight >= list.scrollHeight - 4;
  list.appendChild(li);
  while (list.children.length > 300) list.firstChild.remove();
  if (atEnd || error) list.scrollTop = list.scrollHeight;
}
$('log-clear').onclick = () => { $('log').textContent = ''; };

// --- the connection ----------------------------------------------------------------

let lastConn = null;
const connection = new Connection({
  hello: onHello,
  state: onState,
  log: (text, error) => log(text, error),
  refused: (command, error) => log(`${command} refused: ${error}`, true),
  status: (kind, text) => {
    const el = $('conn');
    el.className = `chip conn-${kind}`;
    el.textContent = text;
    $('overlay').hidden = kind !== 'closed';
    $('overlay').textContent = kind === 'closed' ? 'disconnected — reconnecting…' : '';
    if (kind === 'closed' && lastConn === 'open') log('disconnected from the server; reconnecting', true);
    if (kind === 'open' && lastConn === 'closed') log('connected again');
    if (kind !== 'connecting') lastConn = kind;
  },
});
const send = (command, args) => connection.ask(command, args);

function onHello(h) {
  const first = hello === null;
  hello = h;
  document.body.classList.toggle('replay', !isLive());
  $('mode').textContent = isLive() ? 'live' : 'replay';
  for (const el of document.querySelectorAll('.live-only')) el.hidden = !isLive();
  for (const el of document.querySelectorAll('.replay-only')) el.hidden = isLive();
  showEyeBox();

  const pick = $('robot-pick');
  const was = pick.value;
  pick.textContent = '';
  for (const r of h.robots || []) {
    const where = r.interface === `robot ${r.index}` ? r.interface : `${r.interface} (robot ${r.index})`;
    pick.add(new Option(`agent ${r.agent} · ${where}`, r.index));
  }
  if (was && Number(was) < (h.robots || []).length) pick.value = was;

  if (isLive()) setupLive(h);
  if (!fitted || first) fitView();
  if (isLive()) {
    plots = livePlots($('plots'), h);
    replay = null;
    if ($('show-vision').checked) send('watch_vision', { robot: selectedRobot() });
  } else {
    startReplay(h);
  }
  log(`${isLive() ? 'live run' : 'replay'}: ${(h.robots || []).length} robots, field ${h.field.length_m} × ${h.field.width_m} m`);
  dirty = true;
}

function setupLive(h) {
  const vt = Boolean(h.virtual_time);
  for (const b of document.querySelectorAll('#pause, #resume, #step, [data-speed]')) b.disabled = !vt;
  $('run-note').hidden = vt;
  const states = $('game-states');
  states.textContent = '';
  for (const g of h.game_states || []) {
    const b = document.createElement('button');
    b.textContent = g.replace(/_/g, ' ');
    b.title = `coach: ${g}`;
    b.dataset.state = g;
    b.onclick = () => send('coach', { game_state: g });
    states.appendChild(b);
  }
  const faults = $('fault-list');
  faults.textContent = '';
  faults.add(new Option('an example rule…', ''));
  for (const f of h.faults || []) faults.add(new Option(f, f));
  showSaves(h.saves || []);
}

function onState(s) {
  if (!hello || !isLive() || !s || !s.ball || !Array.isArray(s.robots)) return;
  live = s;
  interaction.stateArrived();
  if (plots) plots.push(s, selectedRobot());
  showStatus();
  dirty = true;
}

// --- the status line ----------------------------------------------------------------

// With two teams, the score: each team's goals are those in the goal it attacks.
function goalsText(goals) {
  const teams = (hello && hello.teams) || [];
  if (teams.length === 2) {
    const of = (t) => (goals || []).filter((g) => g.positive_x === t.attacks_positive_x).length;
    return `${teams[0].name} ${of(teams[0])} : ${of(teams[1])} ${teams[1].name}`;
  }
  if (!goals || !goals.length) return 'goals 0';
  const plus = goals.filter((g) => g.positive_x === true).length;
  const minus = goals.filter((g) => g.positive_x === false).length;
  return plus + minus === goals.length ? `goals ${goals.length} (+x ${plus} · −x ${minus})` : `goals ${goals.length}`;
}

function showStatus() {
  if (replay) {
    $('st-time').textContent = `t ${replay.t.toFixed(2)} s`;
    $('st-run').textContent = replay.playing ? `playing ${replay.speed}x` : 'paused';
    $('st-rtf').textContent = `of ${replay.end.toFixed(2)} s`;
    $('st-goals').textContent = goalsText(replay.state.goals);
    $('st-game').textContent = '';
    return;
  }
  const s = live;
  if (!s) return;
  $('st-time').textContent = `t ${s.time_s.toFixed(2)} s`;
  const speed = s.speed === 0 ? 'max speed' : `${s.speed}x`;
  $('st-run').textContent = s.ended ? 'ended' : s.paused ? `paused (${speed})` : speed;
  const rtf = typeof s.real_time_factor === 'number' && !s.paused && !s.ended;
  $('st-rtf').textContent = rtf ? `${s.real_time_factor.toFixed(2)}× real time` : '';
  $('st-goals').textContent = goalsText(s.goals);
  const game = s.coach ? s.coach.game_state : '';
  $('st-game').textContent = game ? `coach: ${game}` : '';
  $('pause').classList.toggle('on', Boolean(s.paused));
  $('resume').classList.toggle('on', !s.paused && !s.ended);
  for (const b of document.querySelectorAll('[data-speed]')) b.classList.toggle('on', Number(b.dataset.speed) === s.speed);
  for (const b of document.querySelectorAll('#game-states button')) b.classList.toggle('on', b.dataset.state === game);
}

// --- the view -------------------------------------------------------------------------

function sizeCanvas(target, cssWidth, cssHeight) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(cssWidth * dpr)), h = Math.max(1, Math.round(cssHeight * dpr));
  if (target.width !== w || target.height !== h) {
    target.width = w;
    target.height = h;
  }
  return dpr;
}

function resize() {
  const r = canvas.getBoundingClientRect();
  view.width = r.width;
  view.height = r.height;
  sizeCanvas(canvas, r.width, r.height);
  const e = eye.getBoundingClientRect();
  sizeCanvas(eye, e.width, e.height);
  if (hello && (!fitted || autoFit)) fitView();
  dirty = true;
}
new ResizeObserver(resize).observe($('canvas-box'));
new ResizeObserver(resize).observe(eye);

function fitView() {
  if (!hello || view.width < 10) return;
  view.fit(hello.field);
  fitted = true;
  dirty = true;
}

function zoomCentre(factor) {
  view.zoom(factor, view.width / 2, view.height / 2);
  autoFit = false;
  dirty = true;
}
$('zoom-in').onclick = () => zoomCentre(1.25);
$('zoom-out').onclick = () => zoomCentre(1 / 1.25);
$('zoom-fit').onclick = () => { $('follow-ball').checked = false; autoFit = true; fitView(); };
$('follow-ball').onchange = () => { if ($('follow-ball').checked) autoFit = false; dirty = true; };

const interaction = new Interaction(canvas, {
  view,
  state: () => (isLive() ? live : null),
  hello: () => hello,
  live: isLive,
  kickMode: () => $('kick-mode').checked,
  send,
  select: (i) => {
    if (String(i) === $('robot-pick').value) return;
    $('robot-pick').value = String(i);
    robotPicked();
  },
  changed,
  zoomed: () => { autoFit = false; },
  panned: () => { $('follow-ball').checked = false; autoFit = false; },
});

// --- drawing ----------------------------------------------------------------------------

function draw() {
  const dpr = window.devicePixelRatio || 1;
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  if (!hello) {
    ctx.fillStyle = '#15191d';
    ctx.fillRect(0, 0, view.width, view.height);
    return;
  }
  const s = current();
  if (s && $('follow-ball').checked && !interaction.active) {
    view.cx = s.ball.x;
    view.cy = s.ball.y;
  }
  drawField(ctx, view, hello.field);
  if (!s) return;
  const drawn = { robots: [], ball: null };
  (s.obstacles || []).forEach((o, i) => {
    const info = (hello.obstacles || [])[i] || { radius_m: 0.25, movable: false };
    const p = interaction.poseOf('obstacle', i, o);
    drawObstacle(ctx, view, p, info.radius_m, info.movable, interaction.isActive('obstacle', i));
  });
  const picked = selectedRobot();
  const vision = s.vision;
  if (vision && $('show-vision').checked && s.robots[vision.robot]) drawVisionOnField(ctx, view, vision, s.robots[vision.robot]);
  for (const r of s.robots) if (r.odometry) drawGhost(ctx, view, r.odometry, hello.robot_radius_m);
  s.robots.forEach((r, i) => {
    const p = interaction.poseOf('robot', i, r);
    const info = (hello.robots || [])[i] || { agent: i + 1, interface: '' };
    drawRobot(ctx, view, p, hello.robot_radius_m, info, { selected: i === picked, active: interaction.isActive('robot', i) });
    drawn.robots.push({ x: p.x, y: p.y, heading_deg: p.heading_deg });
  });
  const b = interaction.poseOf('ball', 0, s.ball);
  drawBall(ctx, view, b, hello.ball_radius_m, interaction.isActive('ball', 0));
  drawn.ball = { x: b.x, y: b.y };
  const kick = interaction.kick();
  if (kick) drawKick(ctx, view, kick.from, kick.velocity, kick.to);
  lastDrawn = drawn;
  if (!$('eye-box').hidden) drawEyeView(s);
}

// The robot's-eye view (bottom right of the top view while "vision points" is on).
function drawEyeView(s) {
  const dpr = window.devicePixelRatio || 1;
  const w = eye.width / dpr, h = eye.height / dpr;
  eyeCtx.setTransform(dpr, 0, 0, dpr, 0, 0);
  const picked = selectedRobot();
  const info = (hello.robots || [])[picked];
  let vision = null, message;
  if (!s.vision || s.vision.robot !== picked) message = 'waiting for its vision…';
  else {
    vision = s.vision;
    message = `${vision.lines.length} line · ${vision.obstacles.length} obstacle · ${vision.balls.length} ball points`;
  }
  $('eye-title').textContent = `what agent ${info ? info.agent : picked + 1} sees${vision ? ` · t ${vision.time_s.toFixed(2)} s` : ''}`;
  drawEye(eyeCtx, w, h, vision, hello.robot_radius_m, message);
}

function showEyeBox() {
  const on = isLive() && $('show-vision').checked;
  $('eye-box').hidden = !on;
  if (on) resize();
}

function frame(now) {
  if (replay && replay.tick(now)) {
    dirty = true;
    showStatus();
  }
  if (replay && plots && now - lastPlotDraw > 125 && replay.plotsStale) {
    lastPlotDraw = now;
    replay.plotsStale = false;
    plots.show(replay.plotSamples(selectedRobot()));
  }
  if (dirty || interaction.active) {
    dirty = false;
    draw();
    framesDrawn++;
    frameTimes.push(now);
    while (frameTimes.length && frameTimes[0] < now - 2000) frameTimes.shift();
  }
  requestAnimationFrame(frame);
}

// --- the controls (live) ---------------------------------------------------------------

$('pause').onclick = () => send('pause');
$('resume').onclick = () => send('resume');
$('step').onclick = () => send('step', { count: 1 });
for (const b of document.querySelectorAll('[data-speed]')) b.onclick = () => send('speed', { factor: Number(b.dataset.speed) });

$('fault-list').onchange = () => {
  if ($('fault-list').value) $('fault-text').value = $('fault-list').value;
};
async function inject() {
  const rule = $('fault-text').value.trim();
  if (!rule) return log('write a fault rule first (or pick an example)', true);
  const r = await send('fault', { rule });
  if (r.ok) log(`fault injected: ${rule}`);
}
$('inject').onclick = inject;
$('fault-text').onkeydown = (e) => { if (e.key === 'Enter') inject(); };

function showSaves(list) {
  const ul = $('saves');
  ul.textContent = '';
  if (!list.length) {
    const li = document.createElement('li');
    li.className = 'empty';
    li.textContent = 'nothing saved yet';
    ul.appendChild(li);
    return;
  }
  for (const s of list) {
    const li = document.createElement('li');
    const name = document.createElement('span');
    name.className = 'name';
    name.textContent = s.name;
    const kind = document.createElement('span');
    kind.className = 'kind';
    kind.textContent = s.kind;
    const b = document.createElement('button');
    b.textContent = 'load';
    b.dataset.name = s.name;
    b.dataset.kind = s.kind;
    b.onclick = async () => {
      const r = await send('load', { name: s.name, kind: s.kind });
      if (r.ok) log(`loaded ${s.kind} ${s.name}`);
    };
    li.append(name, kind, b);
    ul.appendChild(li);
  }
}

async function refreshSaves() {
  const r = await send('saves');
  if (r.ok && Array.isArray(r.saves)) showSaves(r.saves);
}
$('saves-refresh').onclick = refreshSaves;
async function save() {
  const name = $('save-name').value.trim();
  if (!/^[A-Za-z0-9_-][A-Za-z0-9_.-]{0,63}$/.test(name)) {
    return log('a save name is 1..64 letters, digits, "-", "_" or ".", not starting with "."', true);
  }
  const kind = $('save-kind').value;
  const r = await send('save', { name, kind });
  if (r.ok) log(`saved ${kind} ${name}${r.path ? ` (${r.path})` : ''}`);
  await refreshSaves();
}
$('save').onclick = save;
$('save-name').onkeydown = (e) => { if (e.key === 'Enter') save(); };

function robotPicked() {
  if (isLive() && $('show-vision').checked) send('watch_vision', { robot: selectedRobot() });
  if (plots && plots.reset) plots.reset();
  if (replay) replay.plotsStale = true;
  dirty = true;
}
$('robot-pick').onchange = robotPicked;
$('show-vision').onchange = () => {
  send('watch_vision', { robot: $('show-vision').checked ? selectedRobot() : null });
  showEyeBox();
  dirty = true;
};

// --- replay ------------------------------------------------------------------------------

async function startReplay(h) {
  const keep = replay ? replay.t : null;
  let data;
  try {
    data = await getJson('/api/replay');
  } catch (e) {
    log(`cannot load the recording: ${e.message}`, true);
    return;
  }
  if (!Array.isArray(data.rows) || !data.rows.length) {
    log('the recording has no rows', true);
    return;
  }
  const el = {
    scrub: $('rp-scrub'), play: $('rp-play'), speed: $('rp-speed'), nextGoal: $('rp-next-goal'), nextKick: $('rp-next-kick'),
    marks: $('rp-marks'), time: $('rp-time'), summary: $('rp-summary'), frames: $('frames'), framesNote: $('frames-note'),
  };
  const r = new Replay(data, h, el, {
    changed: () => {
      dirty = true;
      if (replay) replay.plotsStale = true;
      showStatus();
    },
    log,
  });
  replay = r;
  replay.plotsStale = true;
  plots = replayPlots($('plots'));
  if (keep !== null) r.seek(keep);
  showStatus();
  dirty = true;
}

// --- start --------------------------------------------------------------------------------

resize();
connection.open();
requestAnimationFrame(frame);

// Read-only hooks for the browser tests (tests/browser/).
window.canhilView = Object.freeze({
  /** The state drawn: the live stream's latest, or the replay's at the cursor. */
  state: () => current(),
  hello: () => hello,
  /** A world point in the page's (viewport) pixels, where page.mouse aims. */
  toScreen: (x, y) => {
    const c = view.toCanvas(x, y);
    const r = canvas.getBoundingClientRect();
    return { x: r.left + c.x, y: r.top + c.y };
  },
  /** What the last frame drew, in world coordinates. */
  drawn: () => ({ robots: lastDrawn.robots.map((r) => ({ ...r })), ball: lastDrawn.ball ? { ...lastDrawn.ball } : null }),
  /** Frames drawn per second over the last 2 s. */
  fps: () => {
    const now = performance.now();
    const recent = frameTimes.filter((t) => t >= now - 2000);
    return recent.length / 2;
  },
  /** Frames drawn since the page loaded. */
  framesDrawn: () => framesDrawn,
  replayTime: () => (replay ? replay.t : null),
  ballVelocity: () => (live ? ballVelocity(live) : null),
});

// The live plots, with uPlot (global `uPlot`, lib/uPlot.iife.min.js): the
// last 20 s of the stream's time. Points are kept at most every 50 ms of
// stream time and the charts redrawn at most 8 times a wall second, so a
// fast run costs the page no more than a slow one.

export const WINDOW_S = 20;
const EVERY_S = 0.05;
const REDRAW_MS = 125;
const PALETTE = ['#ff7f50', '#4fc3f7', '#9ccc65', '#ba68c8', '#ffd54f', '#4db6ac', '#f06292', '#a1887f', '#90a4ae', '#e57373'];

const axis = (extra = {}) => ({
  stroke: '#aeb9c4',
  grid: { stroke: 'rgba(255, 255, 255, 0.07)', width: 1 },
  ticks: { stroke: 'rgba(255, 255, 255, 0.15)', width: 1 },
  font: '11px system-ui, sans-serif',
  labelFont: '11px system-ui, sans-serif',
  ...extra,
});

// The x range: always WINDOW_S wide, ending at the newest point once there
// are WINDOW_S seconds of them (a steady axis from the start, then scrolling).
function xWindow(times) {
  if (!times.length) return { min: 0, max: WINDOW_S };
  const first = times[0], last = times[times.length - 1];
  const min = Math.max(first, last - WINDOW_S);
  return { min, max: min + WINDOW_S };
}

/** One chart in a card of its own; `series`: [{label, scale?, colour?}]. */
class Chart {
  constructor(parent, title, series, { yLabel = '', y2Label = null, yRange = null } = {}) {
    this.card = document.createElement('div');
    this.card.className = 'plot';
    parent.appendChild(this.card);
    this.data = [[], ...series.map(() => [])];
    const scales = { x: { time: false, auto: false, range: (u, min, max) => [min, max] } };
    scales.y = yRange ? { range: yRange } : { range: (u, min, max) => autoRange(min, max) };
    const axes = [axis({ label: 't (s)', size: 32, labelSize: 14 }), axis({ label: yLabel, scale: 'y', size: 46, labelSize: 14 })];
    if (y2Label) {
      scales.y2 = { range: (u, min, max) => autoRange(min, max) };
      axes.push(axis({ label: y2Label, scale: 'y2', side: 1, size: 46, labelSize: 14, grid: { show: false } }));
    }
    this.plot = new window.uPlot({
      title,
      width: this.width(),
      height: 170,
      scales,
      axes,
      legend: { live: false },
      cursor: { drag: { x: false, y: false } },
      series: [{ label: 't' }, ...series.map((s, i) => ({
        label: s.label,
        scale: s.scale || 'y',
        stroke: s.colour || PALETTE[i % PALETTE.length],
        width: 1.5,
        dash: s.dash,
        spanGaps: false,
        points: { show: false },
      }))],
    }, this.data, this.card);
    this.show();
  }

  width() {
    return Math.max(280, this.card.clientWidth - 8);
  }

  resize() {
    this.plot.setSize({ width: this.width(), height: 170 });
  }

  add(t, values) {
    this.data[0].push(t);
    values.forEach((v, i) => this.data[i + 1].push(v === undefined ? null : v));
    let drop = 0;
    while (drop < this.data[0].length && this.data[0][drop] < t - WINDOW_S) drop++;
    if (drop > 0) for (const d of this.data) d.splice(0, drop);
  }

  clear() {
    for (const d of this.data) d.length = 0;
  }

  show() {
    this.plot.batch(() => {
      this.plot.setData(this.data);
      this.plot.setScale('x', xWindow(this.data[0]));
    });
  }

  remove() {
    this.plot.destroy();
    this.card.remove();
  }
}

function autoRange(min, max) {
  if (min === null || max === null || !Number.isFinite(min) || !Number.isFinite(max)) return [0, 1];
  const lo = Math.min(0, min), hi = Math.max(max, lo + 0.1);
  return [lo, hi + (hi - lo) * 0.08];
}

function note(parent, text) {
  const div = document.createElement('div');
  div.className = 'plot note';
  div.textContent = text;
  parent.appendChild(div);
  return div;
}

/**
 * The live plots for `hello`'s robots in `parent`.
 * push(state, robot) adds a state; reset() empties them (another robot picked).
 */
export function livePlots(parent, hello) {
  parent.innerHTML = '';
  if (!window.uPlot) {
    note(parent, 'No plots: lib/uPlot.iife.min.js did not load (npm ci in viewer/web, then build).');
    return null;
  }
  const names = hello.robots.map((r) => `agent ${r.agent} (${r.interface})`);
  const ball = new Chart(parent, 'ball speed', [{ label: 'ball (m/s)' }], { yLabel: 'm/s' });
  const velocity = new Chart(parent, 'picked robot: commanded vs achieved', [
    { label: '|v| commanded', colour: '#ff7f50' },
    { label: '|v| achieved', colour: '#4fc3f7' },
    { label: 'w commanded', colour: '#ffd54f', scale: 'y2', dash: [5, 3] },
    { label: 'w achieved', colour: '#9ccc65', scale: 'y2', dash: [5, 3] },
  ], { yLabel: 'm/s', y2Label: 'rad/s' });
  const load = new Chart(parent, 'bus load per robot', names.map((label) => ({ label })), { yLabel: '%', yRange: (u, min, max) => [0, Math.max(10, (max || 0) * 1.15)] });
  let jitter = null, jitterNames = '', jitterNote = note(parent, 'period jitter: no bus figures in this run (real time, or none yet)');
  let latency = null, latencyNote = note(parent, 'handler latency: none reported yet');
  let lastT = null, lastDraw = 0;

  const charts = () => [ball, velocity, load, jitter, latency].filter(Boolean);

  function push(s, robot) {
    const t = s.time_s;
    if (lastT !== null && t < lastT) reset();  // a new run, or a load went back in time
    if (lastT !== null && t - lastT < EVERY_S) return;
    lastT = t;
    const v = s.ball_velocity || (typeof s.ball.vx === 'number' ? { x: s.ball.vx, y: s.ball.vy } : null);
    ball.add(t, [v ? Math.hypot(v.x, v.y) : null]);
    const r = s.robots[robot] || {};
    const cmd = r.commanded, got = r.achieved;
    velocity.add(t, [cmd ? Math.hypot(cmd.vx, cmd.vy) : null, got ? Math.hypot(got.vx, got.vy) : null,
      cmd ? cmd.w : null, got ? got.w : null]);
    const buses = s.buses || [];
    if (buses.length) load.add(t, hello.robots.map((_, i) => (buses[i] ? buses[i].load * 100 : null)));
    const bus = buses[robot];
    if (bus && bus.jitter_ms) {
      const msgs = Object.keys(bus.jitter_ms).sort();
      if (msgs.length && msgs.join() !== jitterNames) {
        if (jitter) jitter.remove();
        if (jitterNote) { jitterNote.remove(); jitterNote = null; }
        jitterNames = msgs.join();
        jitter = new Chart(parent, `agent ${hello.robots[robot].agent}: worst period jitter per message`,
          msgs.map((label) => ({ label })), { yLabel: 'ms' });
        parent.insertBefore(jitter.card, latency ? latency.card : latencyNote);
      }
      if (jitter) jitter.add(t, jitterNames.split(',').map((m) => bus.jitter_ms[m] ?? null));
    }
    const lat = s.handler_latency_ms;
    if (Array.isArray(lat) && lat.some((x) => x !== null && x !== undefined)) {
      if (!latency) {
        latencyNote.remove();
        latency = new Chart(parent, 'handler latency: frame to RTDB', names.map((label) => ({ label })), { yLabel: 'ms' });
      }
      latency.add(t, hello.robots.map((_, i) => lat[i] ?? null));
    }
    redraw();
  }

  // At most every REDRAW_MS; the last change is always drawn (a paused run sends no more).
  let pendingDraw = null;
  function redraw() {
    const now = performance.now();
    if (now - lastDraw >= REDRAW_MS) {
      lastDraw = now;
      for (const c of charts()) c.show();
    } else if (!pendingDraw) {
      pendingDraw = setTimeout(() => { pendingDraw = null; redraw(); }, REDRAW_MS - (now - lastDraw) + 1);
    }
  }

  function reset() {
    lastT = null;
    for (const c of charts()) { c.clear(); c.show(); }
    if (jitter) { jitter.remove(); jitter = null; jitterNames = ''; }
    if (!jitterNote) {
      jitterNote = note(parent, 'period jitter: waiting for the picked robot\'s bus figures');
      parent.insertBefore(jitterNote, latency ? latency.card : latencyNote);
    }
  }

  const observer = new ResizeObserver(() => { for (const c of charts()) c.resize(); });
  observer.observe(parent);
  return { push, reset };
}

/**
 * The replay's plots: the window up to the cursor, worked out from the
 * recorded rows (no velocities are recorded: speeds from the positions).
 * show(samples) with samples = {t: [], ball: [], truth: [], reported: []}.
 */
export function replayPlots(parent, robotLabel) {
  parent.innerHTML = '';
  if (!window.uPlot) {
    note(parent, 'No plots: lib/uPlot.iife.min.js did not load.');
    return null;
  }
  const ball = new Chart(parent, 'ball speed (from the log)', [{ label: 'ball (m/s)' }], { yLabel: 'm/s' });
  const robot = new Chart(parent, 'picked robot: speed (from the log)', [
    { label: '|v| world', colour: '#4fc3f7' }, { label: '|v| odometry', colour: '#ff7f50', dash: [5, 3] }], { yLabel: 'm/s' });
  note(parent, 'bus load, jitter and latency are live-only: record a trace and see the bus panel');
  const observer = new ResizeObserver(() => { ball.resize(); robot.resize(); });
  observer.observe(parent);
  return {
    show(samples) {
      ball.data = [samples.t, samples.ball];
      robot.data = [samples.t, samples.truth, samples.reported];
      ball.show();
      robot.show();
    },
    label: robotLabel,
  };
}

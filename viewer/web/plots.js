// The viewer's live plots, with uPlot: the last 20 s of the run's time.
const WINDOW_S = 20;
const EVERY_S = 0.05;  // at most one point per 50 ms of the run's time

function chart(parent, title, series, height = 170) {
  const div = document.createElement('div');
  div.className = 'plot';
  parent.appendChild(div);
  const colours = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b', '#e377c2', '#17becf'];
  const opts = {
    title,
    width: Math.max(360, div.clientWidth - 4),
    height,
    scales: { x: { time: false } },
    axes: [{ label: 't (s)' }, {}],
    series: [{ label: 't' }, ...series.map((s, i) => ({ label: s, stroke: colours[i % colours.length], width: 1.5 }))],
  };
  const data = [[], ...series.map(() => [])];
  return { plot: new window.uPlot(opts, data, div), data, div };
}

export function makePlots(parent, hello) {
  parent.innerHTML = '';
  if (!window.uPlot) {
    parent.textContent = 'plots need lib/uPlot.iife.min.js (run npm ci in viewer/web, then build)';
    return null;
  }
  const robots = hello.robots.map((r) => `agent ${r.agent}`);
  const charts = {
    ball: chart(parent, 'ball speed (m/s)', ['ball']),
    velocity: chart(parent, 'selected robot: commanded and achieved', ['|v| commanded (m/s)', '|v| achieved (m/s)', 'w commanded (rad/s)', 'w achieved (rad/s)']),
    load: chart(parent, 'bus load (fraction of 1 Mbit/s)', robots),
    latency: chart(parent, "handler latency, frame to RTDB (ms)", robots),
  };
  let jitter = null;
  let jitterNames = '';
  let lastT = -1;
  let lastBall = null;

  function add(c, t, values) {
    c.data[0].push(t);
    values.forEach((v, i) => c.data[i + 1].push(v));
    while (c.data[0].length && c.data[0][0] < t - WINDOW_S) for (const d of c.data) d.shift();
  }

  function push(s, robot) {
    const t = s.time_s;
    if (t < lastT) reset();  // a replay scrubbed back
    if (lastT >= 0 && t - lastT < EVERY_S) return;
    lastT = t;
    const b = s.ball, v = s.ball_velocity;
    // A recording has no velocities: the speed from the last point.
    const speed = v ? Math.hypot(v.x, v.y) : lastBall && t > lastBall.t ? Math.hypot(b.x - lastBall.x, b.y - lastBall.y) / (t - lastBall.t) : 0;
    lastBall = { t, x: b.x, y: b.y };
    add(charts.ball, t, [speed]);
    const r = s.robots[robot] || {};
    const cmd = r.commanded, got = r.achieved;
    add(charts.velocity, t, [cmd ? Math.hypot(cmd.vx, cmd.vy) : null, got ? Math.hypot(got.vx, got.vy) : null, cmd ? cmd.w : null, got ? got.w : null]);
    if (s.buses) add(charts.load, t, s.buses.map((x) => x.load));
    if (s.handler_latency_ms) add(charts.latency, t, s.handler_latency_ms);
    const bus = s.buses && s.buses[robot];
    if (bus) {
      const names = Object.keys(bus.jitter_ms).sort();
      if (names.join() !== jitterNames && names.length) {
        if (jitter) jitter.div.remove();
        jitter = chart(parent, 'selected robot: worst period deviation per message (ms)', names);
        jitterNames = names.join();
      }
      if (jitter) add(jitter, t, jitterNames.split(',').map((n) => bus.jitter_ms[n] ?? null));
    }
    for (const c of [charts.ball, charts.velocity, charts.load, charts.latency, jitter]) if (c) c.plot.setData(c.data);
  }

  function reset() {
    lastT = -1;
    lastBall = null;
    for (const c of [charts.ball, charts.velocity, charts.load, charts.latency, jitter]) {
      if (!c) continue;
      for (const d of c.data) d.length = 0;
      c.plot.setData(c.data);
    }
  }

  return { push, reset };
}

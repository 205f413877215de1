// Replay (`canhil view`): the world log's rows from /api/replay played in the
// page. The cursor's state is interpolated between the two rows around it
// (headings the short way round); the timeline has play and pause, a speed,
// the scrubber with the goals and kicks marked, and jumps to the next goal or
// kick; the bus panel lists the trace's frames within 0.1 s of the cursor.

import { getJson } from './protocol.js';
import { WINDOW_S } from './plots.js';

const FRAMES_AROUND_S = 0.1;
const FRAMES_SHOWN = 200;

function column(columns, name, fallback) {
  const i = columns.indexOf(name);
  return i >= 0 ? i : fallback;
}

/** Column indexes of the world log: {t, bx, by, bz, robots: [{x, y, h, rx, ry, rh}]}. */
export function layout(columns, robots) {
  const out = {
    t: column(columns, 'time_s', 0),
    bx: column(columns, 'ball_x_m', 1),
    by: column(columns, 'ball_y_m', 2),
    bz: column(columns, 'ball_z_m', 3),
    robots: [],
  };
  for (let k = 0; k < robots; k++) {
    const base = 4 + 6 * k;
    out.robots.push({
      x: column(columns, `robot${k}_x_m`, base),
      y: column(columns, `robot${k}_y_m`, base + 1),
      h: column(columns, `robot${k}_heading_deg`, base + 2),
      rx: column(columns, `robot${k}_reported_x_m`, -1),
      ry: column(columns, `robot${k}_reported_y_m`, -1),
      rh: column(columns, `robot${k}_reported_heading_deg`, -1),
    });
  }
  return out;
}

function lerp(a, b, k) {
  return a + (b - a) * k;
}

function lerpDeg(a, b, k) {
  let d = (b - a) % 360;
  if (d > 180) d -= 360;
  if (d < -180) d += 360;
  let h = a + d * k;
  if (h > 180) h -= 360;
  if (h <= -180) h += 360;
  return h;
}

export class Replay {
  /**
   * data: /api/replay's answer; hello: the server's; el: the timeline's and
   * the bus panel's elements; on: {changed(), log(text, error)}.
   */
  constructor(data, hello, el, on) {
    this.rows = data.rows.filter((r) => Array.isArray(r) && r.length > 0);
    this.columns = data.columns || [];
    this.robotCount = data.robots ?? (hello.robots || []).length;
    this.events = (data.events || []).slice().sort((a, b) => a.time_s - b.time_s);
    this.hello = hello;
    this.el = el;
    this.on = on;
    this.col = layout(this.columns, this.robotCount);
    this.start = this.rows.length ? this.rows[0][this.col.t] : 0;
    this.end = this.rows.length ? this.rows[this.rows.length - 1][this.col.t] : 0;
    this.t = this.start;
    this.playing = false;
    this.speed = 1;
    this.lastWall = null;
    this.state = this.stateAt(this.t);
    this.framesTimer = null;
    this.framesAt = null;
    this.setupTimeline();
    this.seek(this.start);
  }

  /** The index of the last row at or before t. */
  rowIndex(t) {
    const rows = this.rows, c = this.col.t;
    let lo = 0, hi = rows.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (rows[mid][c] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  /** The world at time t, shaped like a live state. */
  stateAt(t) {
    const col = this.col;
    const robots = [];
    if (!this.rows.length) return { time_s: t, ball: { x: 0, y: 0, z: 0 }, robots, obstacles: [], goals: [] };
    const i = this.rowIndex(t);
    const a = this.rows[i], b = this.rows[Math.min(i + 1, this.rows.length - 1)];
    const span = b[col.t] - a[col.t];
    const k = span > 0 ? Math.min(1, Math.max(0, (t - a[col.t]) / span)) : 0;
    const at = (j) => lerp(a[j], b[j], k);
    for (const r of col.robots) {
      const pose = { x: at(r.x), y: at(r.y), heading_deg: lerpDeg(a[r.h], b[r.h], k) };
      pose.odometry = r.rx >= 0 ? { x: at(r.rx), y: at(r.ry), heading_deg: lerpDeg(a[r.rh], b[r.rh], k) } : null;
      robots.push(pose);
    }
    return {
      time_s: t,
      ball: { x: at(col.bx), y: at(col.by), z: col.bz < a.length ? at(col.bz) : 0 },
      robots,
      obstacles: [],
      goals: this.events.filter((e) => e.kind === 'goal' && e.time_s <= t + 1e-9),
    };
  }

  setupTimeline() {
    const el = this.el;
    el.scrub.min = String(this.start);
    el.scrub.max = String(Math.max(this.end, this.start + 1e-3));
    el.scrub.step = 'any';
    el.scrub.oninput = () => this.seek(Number(el.scrub.value));
    el.play.onclick = () => this.toggle();
    el.speed.onchange = () => { this.speed = Number(el.speed.value); this.showTime(); };
    el.nextGoal.onclick = () => this.jump('goal');
    el.nextKick.onclick = () => this.jump('kick');
    el.nextGoal.disabled = !this.events.some((e) => e.kind === 'goal');
    el.nextKick.disabled = !this.events.some((e) => e.kind === 'kick');
    // The events as marks over the scrubber; a click on one goes there.
    el.marks.innerHTML = '';
    const span = Math.max(this.end - this.start, 1e-3);
    for (const e of this.events) {
      const m = document.createElement('button');
      m.className = `mark ${e.kind}`;
      m.style.left = `${((e.time_s - this.start) / span) * 100}%`;
      m.title = `${e.time_s.toFixed(2)} s: ${e.text || e.kind}`;
      m.onclick = () => this.seek(e.time_s);
      el.marks.appendChild(m);
    }
    el.summary.textContent = `${this.rows.length} rows, ${this.robotCount} robot${this.robotCount === 1 ? '' : 's'}, ` +
      `${this.events.filter((e) => e.kind === 'goal').length} goals, ${this.events.filter((e) => e.kind === 'kick').length} kicks`;
  }

  toggle() {
    if (!this.playing && this.t >= this.end) this.seek(this.start);
    this.playing = !this.playing;
    this.lastWall = null;
    this.showTime();
  }

  jump(kind) {
    const next = this.events.find((e) => e.kind === kind && e.time_s > this.t + 1e-6);
    if (next) this.seek(next.time_s);
    else this.on.log(`no ${kind} after t = ${this.t.toFixed(2)} s`);
  }

  /** Puts the cursor at t (clamped to the log). */
  seek(t) {
    this.t = Math.min(this.end, Math.max(this.start, Number.isFinite(t) ? t : this.start));
    this.state = this.stateAt(this.t);
    this.el.scrub.value = String(this.t);
    this.showTime();
    this.requestFrames();
    this.on.changed();
  }

  showTime() {
    this.el.play.textContent = this.playing ? '❚❚ pause' : '▶ play';
    this.el.play.classList.toggle('on', this.playing);
    this.el.time.textContent = `${this.t.toFixed(2)} / ${this.end.toFixed(2)} s`;
  }

  /** Advances the cursor by the wall time since the last frame, when playing. */
  tick(now) {
    if (!this.playing) return false;
    if (this.lastWall === null) this.lastWall = now;
    const dt = (now - this.lastWall) / 1000;
    this.lastWall = now;
    this.seek(this.t + dt * this.speed);
    if (this.t >= this.end) {
      this.playing = false;
      this.showTime();
    }
    return true;
  }

  /** The bus panel: the trace's frames around the cursor, fetched at most ~6 times a second. */
  requestFrames() {
    if (this.hello.has_trace === false) {
      if (!this.el.frames.dataset.none) {
        this.el.frames.dataset.none = '1';
        this.el.framesNote.textContent = 'no trace recorded (canhil view … --trace FILE)';
      }
      return;
    }
    if (this.framesTimer) return;
    this.framesTimer = setTimeout(() => this.fetchFrames(), 160);
  }

  async fetchFrames() {
    const t = this.t;
    let frames;
    try {
      frames = await getJson(`/api/frames?from=${(t - FRAMES_AROUND_S).toFixed(4)}&to=${(t + FRAMES_AROUND_S).toFixed(4)}`);
    } catch (e) {
      this.el.framesNote.textContent = `no frames: ${e.message}`;
      this.framesTimer = null;
      return;
    }
    this.framesTimer = null;
    if (Math.abs(this.t - t) > 1e-9) this.requestFrames();  // the cursor moved meanwhile
    this.showFrames(Array.isArray(frames) ? frames : frames.frames || [], t);
  }

  showFrames(frames, t) {
    const body = this.el.frames.tBodies[0];
    body.textContent = '';
    let nearest = null, best = Infinity;
    for (const f of frames.slice(0, FRAMES_SHOWN)) {
      const tr = body.insertRow();
      const d = Math.abs(f.time_s - t);
      if (d < best) { best = d; nearest = tr; }
      // The decoded text starts with the message's name already; the raw bytes when undecoded.
      const name = f.name || `0x${Number(f.id).toString(16)}`;
      const text = f.signals ? (f.signals.startsWith(name) ? f.signals : `${name} ${f.signals}`) : `${name} ${f.data}`;
      const cells = [f.time_s.toFixed(4), f.interface, text];
      for (const v of cells) tr.insertCell().textContent = v;
      tr.title = `id 0x${Number(f.id).toString(16)} data ${f.data}`;
    }
    if (nearest) {
      nearest.className = 'cursor';
      const box = this.el.frames.parentElement;
      box.scrollTop = Math.max(0, nearest.offsetTop - box.clientHeight / 2);
    }
    this.el.frames.dataset.at = String(t);  // the cursor these frames are around
    this.el.framesNote.textContent = `${frames.length}${frames.length >= 500 ? '+' : ''} frames within ±${FRAMES_AROUND_S} s of ${t.toFixed(3)} s`;
  }

  /** Ball and robot speeds over the plot window up to the cursor, from the positions. */
  plotSamples(robot) {
    const out = { t: [], ball: [], truth: [], reported: [] };
    if (this.rows.length < 2) return out;
    const col = this.col, r = col.robots[robot];
    const last = this.rowIndex(this.t);
    let first = this.rowIndex(this.t - WINDOW_S);
    if (first < 1) first = 1;
    const stride = Math.max(1, Math.ceil((last - first + 1) / 400));
    for (let i = first; i <= last; i += stride) {
      const a = this.rows[i - 1], b = this.rows[i];
      const dt = b[col.t] - a[col.t];
      if (dt <= 0) continue;
      out.t.push(b[col.t]);
      out.ball.push(Math.hypot(b[col.bx] - a[col.bx], b[col.by] - a[col.by]) / dt);
      out.truth.push(r ? Math.hypot(b[r.x] - a[r.x], b[r.y] - a[r.y]) / dt : null);
      out.reported.push(r && r.rx >= 0 ? Math.hypot(b[r.rx] - a[r.rx], b[r.ry] - a[r.ry]) / dt : null);
    }
    return out;
  }
}

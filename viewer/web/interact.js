// The mouse on the top view: pick the robot, obstacle or ball under it, drag
// it (left button), turn a robot (right button, or shift), give the ball a
// velocity (ctrl or alt from the ball, or the kick mode), pan (the carpet, or
// the middle button anywhere), zoom (the wheel). Each drag becomes one of the
// run's commands on release; until the run's state shows it, the page keeps
// drawing the thing where it was dropped.

export const KICK_PER_METRE = 2;  // m/s of ball speed per metre dragged
export const KICK_MOST = 12;      // m/s
const PICK_MIN_PX = 12;           // small things (the ball) stay pickable zoomed out
const CLICK_PX = 3;               // a press that moved less is a click, not a drag
const SETTLE_MS = 1500;

/** The velocity a kick drag from `ball` to `to` gives: 2 m/s per metre, at most 12 m/s. */
export function kickVelocity(ball, to) {
  let vx = (to.x - ball.x) * KICK_PER_METRE, vy = (to.y - ball.y) * KICK_PER_METRE;
  const speed = Math.hypot(vx, vy);
  if (speed > KICK_MOST) {
    vx *= KICK_MOST / speed;
    vy *= KICK_MOST / speed;
  }
  return { vx, vy };
}

/** The heading (deg, +x axis from field +x) that puts a robot's front (+y) toward `to`. */
export function headingToward(from, to) {
  let h = (Math.atan2(to.y - from.y, to.x - from.x) * 180) / Math.PI - 90;
  if (h <= -180) h += 360;
  return h;
}

export class Interaction {
  /**
   * deps: {view, state(), hello(), live(), kickMode(), send(command, args) -> Promise<reply>,
   *        select(robotIndex), changed(), zoomed(), panned()}
   */
  constructor(canvas, deps) {
    this.canvas = canvas;
    this.deps = deps;
    this.drag = null;     // the gesture under way
    this.settle = null;   // {kind, index, pose, statesLeft, until}: a drop not yet in the state
    this.hover = null;
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('mousedown', (e) => this.down(e));
    window.addEventListener('mousemove', (e) => this.move(e));
    window.addEventListener('mouseup', (e) => this.up(e));
    canvas.addEventListener('wheel', (e) => {
      const p = this.point(e);
      deps.view.zoom(Math.exp(-Math.sign(e.deltaY) * 0.15), p.px, p.py);
      deps.zoomed();
      deps.changed();
      e.preventDefault();
    }, { passive: false });
  }

  get active() {
    return this.drag !== null;
  }

  point(e) {
    const r = this.canvas.getBoundingClientRect();
    return { px: e.clientX - r.left, py: e.clientY - r.top };
  }

  /** The thing under the canvas point, or null; `only` limits the kinds. */
  pick(px, py, only = null) {
    const s = this.deps.state(), h = this.deps.hello();
    if (!s || !h) return null;
    const view = this.deps.view;
    let best = null;
    const consider = (kind, index, x, y, radius, bias) => {
      if (only && !only.includes(kind)) return;
      const c = view.toCanvas(x, y);
      const d = Math.hypot(c.x - px, c.y - py);
      const reach = Math.max(radius * view.scale, PICK_MIN_PX);
      if (d > reach) return;
      const score = d / reach - bias;
      if (!best || score < best.score) best = { kind, index, score, x, y };
    };
    // The ball first when it is within reach: it is small and often beside a robot.
    consider('ball', 0, s.ball.x, s.ball.y, h.ball_radius_m, 1);
    s.robots.forEach((r, i) => consider('robot', i, r.x, r.y, h.robot_radius_m, 0));
    (s.obstacles || []).forEach((o, i) => {
      const info = (h.obstacles || [])[i];
      consider('obstacle', i, o.x, o.y, info ? info.radius_m : 0.25, 0);
    });
    return best;
  }

  down(e) {
    const { px, py } = this.point(e);
    const view = this.deps.view;
    const w = view.toWorld(px, py);
    const pan = () => ({ mode: 'pan', px, py, cx: view.cx, cy: view.cy, moved: false });
    if (e.button === 1 || !this.deps.live()) {
      this.drag = pan();
    } else {
      const kickWanted = e.button === 0 && (e.ctrlKey || e.altKey || e.metaKey || this.deps.kickMode());
      const turn = e.button === 2 || e.shiftKey;
      const kickHit = kickWanted ? this.pick(px, py, ['ball']) : null;
      const hit = kickHit || (turn ? this.pick(px, py, ['robot']) : this.pick(px, py));
      if (kickHit) {
        this.drag = { mode: 'kick', kind: 'ball', index: 0, to: w, sx: px, sy: py, moved: false };
      } else if (hit && turn) {
        const r = this.deps.state().robots[hit.index];
        this.drag = { mode: 'turn', kind: 'robot', index: hit.index, heading_deg: r.heading_deg, sx: px, sy: py, moved: false };
        this.deps.select(hit.index);
      } else if (hit && e.button === 0) {
        this.drag = { mode: 'move', kind: hit.kind, index: hit.index, to: { x: hit.x, y: hit.y },
          dx: hit.x - w.x, dy: hit.y - w.y, sx: px, sy: py, moved: false };
        if (hit.kind === 'robot') this.deps.select(hit.index);
      } else if (e.button === 0) {
        this.drag = pan();
      } else {
        return;
      }
    }
    this.canvas.style.cursor = 'grabbing';
    this.deps.changed();
    e.preventDefault();
  }

  move(e) {
    const { px, py } = this.point(e);
    const d = this.drag;
    if (!d) {
      // Only the cursor: say what a press here would do.
      if (e.target !== this.canvas || !this.deps.live()) return;
      const hit = this.pick(px, py);
      const kind = hit ? hit.kind : null;
      if (kind !== this.hover) {
        this.hover = kind;
        this.canvas.style.cursor = kind ? 'grab' : 'default';
      }
      return;
    }
    const view = this.deps.view;
    const w = view.toWorld(px, py);
    if (d.mode === 'pan') {
      view.cx = d.cx - (px - d.px) / view.scale;
      view.cy = d.cy + (py - d.py) / view.scale;
      d.moved = true;
      this.deps.panned();
    } else {
      if (Math.hypot(px - d.sx, py - d.sy) >= CLICK_PX) d.moved = true;
      if (d.mode === 'turn') {
        const r = this.deps.state().robots[d.index];
        const c = view.toCanvas(r.x, r.y);
        if (Math.hypot(px - c.x, py - c.y) > 4) d.heading_deg = headingToward(r, w);
      } else if (d.mode === 'kick') {
        d.to = w;
      } else {
        d.to = { x: w.x + d.dx, y: w.y + d.dy };
      }
    }
    this.deps.changed();
  }

  up() {
    const d = this.drag;
    if (!d) return;
    this.drag = null;
    this.canvas.style.cursor = 'default';
    this.hover = null;
    this.deps.changed();
    const s = this.deps.state();
    if (d.mode === 'pan' || !d.moved || !s) return;
    let command, args, pose = null;
    if (d.mode === 'kick') {
      const v = kickVelocity(s.ball, d.to);
      command = 'move_ball';
      args = { x: s.ball.x, y: s.ball.y, vx: v.vx, vy: v.vy };
    } else if (d.mode === 'turn') {
      const r = s.robots[d.index];
      command = 'move_robot';
      args = { robot: d.index, x: r.x, y: r.y, heading_deg: d.heading_deg };
      pose = { x: r.x, y: r.y, heading_deg: d.heading_deg };
    } else if (d.kind === 'robot') {
      const r = s.robots[d.index];
      command = 'move_robot';
      args = { robot: d.index, x: d.to.x, y: d.to.y, heading_deg: r.heading_deg };
      pose = { x: d.to.x, y: d.to.y, heading_deg: r.heading_deg };
    } else if (d.kind === 'ball') {
      command = 'move_ball';
      args = { x: d.to.x, y: d.to.y };
      pose = { x: d.to.x, y: d.to.y };
    } else {
      command = 'move_obstacle';
      args = { obstacle: d.index, x: d.to.x, y: d.to.y };
      pose = { x: d.to.x, y: d.to.y };
    }
    // Millimetres, hundredths of a degree: the pixel a drag ends on is no finer.
    for (const key of Object.keys(args)) {
      if (key === 'robot' || key === 'obstacle') continue;
      args[key] = Math.round(args[key] * (key === 'heading_deg' ? 100 : 1000)) / (key === 'heading_deg' ? 100 : 1000);
    }
    const settle = pose ? { kind: d.kind, index: d.index, pose, statesLeft: null, until: performance.now() + SETTLE_MS } : null;
    this.settle = settle;
    this.deps.send(command, args).then((reply) => {
      if (this.settle !== settle) return;
      if (reply.ok && settle) settle.statesLeft = 2;  // the next states but one have it
      else this.settle = null;
      this.deps.changed();
    });
  }

  /** Called on each new state: a drop shown until the state has it. */
  stateArrived() {
    const s = this.settle;
    if (!s) return;
    if (s.statesLeft !== null && --s.statesLeft <= 0) this.settle = null;
  }

  /** Where to draw thing (kind, index) instead of `base`, while dragged or settling. */
  poseOf(kind, index, base) {
    const d = this.drag;
    if (d && d.kind === kind && d.index === index) {
      if (d.mode === 'move') return { ...base, x: d.to.x, y: d.to.y };
      if (d.mode === 'turn') return { ...base, heading_deg: d.heading_deg };
    }
    const s = this.settle;
    if (s && s.kind === kind && s.index === index) {
      if (performance.now() > s.until) this.settle = null;
      else return { ...base, ...s.pose };
    }
    return base;
  }

  /** The kick under way: {from, to, velocity}, or null. */
  kick() {
    const d = this.drag, s = this.deps.state();
    if (!d || d.mode !== 'kick' || !s) return null;
    return { from: s.ball, to: d.to, velocity: kickVelocity(s.ball, d.to) };
  }

  /** Which thing is being dragged, for a highlight. */
  isActive(kind, index) {
    const d = this.drag;
    return d !== null && d.kind === kind && d.index === index;
  }
}

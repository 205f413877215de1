// Drawing: the top view of the field to scale, the things on it, and the
// robot's-eye view. World frame: metres, the field's centre at (0, 0), x
// along its length, y up on the screen. A robot's heading is the angle of its
// +x axis counter-clockwise from the field's +x; its front is its +y axis.

const DEG = Math.PI / 180;

export const COLOURS = {
  outside: '#15191d',
  carpet: '#2f7d34',
  carpetEdge: '#276b2c',
  line: '#f2f2f2',
  goalPositive: '#4f8fe8',  // +x: the opponent's goal
  goalNegative: '#e9c046',  // -x: your own
  robotBody: '#11161b',
  secondTeamBody: '#7a1f5c',  // the second team's robots (magenta, as the league's markers)
  robotRim: '#dfe6ec',
  robotFront: '#ff9f43',
  selected: '#5ee1ff',
  ghost: 'rgba(255, 255, 255, 0.6)',
  obstacle: '#050505',
  ball: '#ff7f0e',
  visionLine: '#fff59d',
  visionObstacle: '#ff4d4d',
  visionBall: '#ffb14d',
  kick: '#ffe14d',
};

/** The transform between world metres and the canvas' CSS pixels. */
export class View {
  constructor() {
    this.scale = 40;   // pixels per metre
    this.cx = 0;       // the world point at the canvas' centre
    this.cy = 0;
    this.width = 1;    // the canvas in CSS pixels
    this.height = 1;
  }

  toCanvas(x, y) {
    return { x: this.width / 2 + (x - this.cx) * this.scale, y: this.height / 2 - (y - this.cy) * this.scale };
  }

  toWorld(px, py) {
    return { x: this.cx + (px - this.width / 2) / this.scale, y: this.cy - (py - this.height / 2) / this.scale };
  }

  /** The whole carpet (field, margin, goals) in view. */
  fit(field) {
    const w = field.length_m + 2 * Math.max(field.margin_m, field.goal_depth_m) + 0.4;
    const h = field.width_m + 2 * field.margin_m + 0.4;
    this.scale = Math.max(2, Math.min(this.width / w, this.height / h));
    this.cx = 0;
    this.cy = 0;
  }

  /** Zooms by `factor` keeping the world point under (px, py) where it is. */
  zoom(factor, px, py) {
    const before = this.toWorld(px, py);
    this.scale = Math.min(800, Math.max(2, this.scale * factor));
    const after = this.toWorld(px, py);
    this.cx += before.x - after.x;
    this.cy += before.y - after.y;
  }
}

/** The robot's front (its +y axis) as a unit vector in the world. */
export function frontOf(headingDeg) {
  const a = (headingDeg + 90) * DEG;
  return { x: Math.cos(a), y: Math.sin(a) };
}

/** A point in a robot's frame (+y its front) in the world, with the robot's pose. */
export function robotToWorld(pose, px, py) {
  const a = pose.heading_deg * DEG;
  const c = Math.cos(a), s = Math.sin(a);
  return { x: pose.x + px * c - py * s, y: pose.y + px * s + py * c };
}

function pathLine(ctx, view, x1, y1, x2, y2) {
  const a = view.toCanvas(x1, y1), b = view.toCanvas(x2, y2);
  ctx.moveTo(a.x, a.y);
  ctx.lineTo(b.x, b.y);
}

function pathRect(ctx, view, x1, y1, x2, y2) {
  const a = view.toCanvas(Math.min(x1, x2), Math.max(y1, y2));
  const b = view.toCanvas(Math.max(x1, x2), Math.min(y1, y2));
  ctx.rect(a.x, a.y, b.x - a.x, b.y - a.y);
}

// An arc around the world point (x, y), angles in the world (counter-clockwise).
function pathArc(ctx, view, x, y, radius, from, to) {
  const c = view.toCanvas(x, y);
  const r = radius * view.scale;
  ctx.moveTo(c.x + r * Math.cos(from), c.y - r * Math.sin(from));
  ctx.arc(c.x, c.y, r, -from, -to, true);
}

/** The carpet with its margin, the lines and the goals, to scale. */
export function drawField(ctx, view, f) {
  ctx.fillStyle = COLOURS.outside;
  ctx.fillRect(0, 0, view.width, view.height);
  const L = f.length_m / 2, W = f.width_m / 2, m = f.margin_m;
  ctx.fillStyle = COLOURS.carpet;
  ctx.beginPath();
  pathRect(ctx, view, -L - m, -W - m, L + m, W + m);
  ctx.fill();
  ctx.strokeStyle = COLOURS.carpetEdge;
  ctx.lineWidth = 1;
  ctx.stroke();

  // Lines are line_width_m wide, centred on their nominal place.
  ctx.strokeStyle = COLOURS.line;
  ctx.lineWidth = Math.max(1, f.line_width_m * view.scale);
  ctx.beginPath();
  pathRect(ctx, view, -L, -W, L, W);
  pathLine(ctx, view, 0, -W, 0, W);
  pathArc(ctx, view, 0, 0, f.centre_circle_radius_m, 0, 2 * Math.PI);
  for (const s of [-1, 1]) {
    pathRect(ctx, view, s * L, -f.penalty_area_width_m / 2, s * (L - f.penalty_area_depth_m), f.penalty_area_width_m / 2);
    pathRect(ctx, view, s * L, -f.goal_area_width_m / 2, s * (L - f.goal_area_depth_m), f.goal_area_width_m / 2);
  }
  // Corner arcs: a quarter circle inside the field at each corner.
  const R = f.corner_arc_radius_m;
  pathArc(ctx, view, L, W, R, Math.PI, 1.5 * Math.PI);
  pathArc(ctx, view, -L, W, R, 1.5 * Math.PI, 2 * Math.PI);
  pathArc(ctx, view, -L, -W, R, 0, 0.5 * Math.PI);
  pathArc(ctx, view, L, -W, R, 0.5 * Math.PI, Math.PI);
  ctx.stroke();

  ctx.fillStyle = COLOURS.line;
  const spot = Math.max(1.5, 0.075 * view.scale);
  for (const p of [[0, 0], [L - f.penalty_mark_distance_m, 0], [-(L - f.penalty_mark_distance_m), 0]]) {
    const c = view.toCanvas(p[0], p[1]);
    ctx.beginPath();
    ctx.arc(c.x, c.y, spot, 0, 2 * Math.PI);
    ctx.fill();
  }

  // The goals behind the goal lines: the net's floor tinted, the frame drawn.
  for (const [s, colour] of [[1, COLOURS.goalPositive], [-1, COLOURS.goalNegative]]) {
    const gw = f.goal_width_m / 2;
    ctx.beginPath();
    pathRect(ctx, view, s * L, -gw, s * (L + f.goal_depth_m), gw);
    ctx.globalAlpha = 0.35;
    ctx.fillStyle = colour;
    ctx.fill();
    ctx.globalAlpha = 1;
    ctx.beginPath();
    pathLine(ctx, view, s * L, gw, s * (L + f.goal_depth_m), gw);
    pathLine(ctx, view, s * (L + f.goal_depth_m), gw, s * (L + f.goal_depth_m), -gw);
    pathLine(ctx, view, s * (L + f.goal_depth_m), -gw, s * L, -gw);
    ctx.strokeStyle = colour;
    ctx.lineWidth = Math.max(2, 0.08 * view.scale);
    ctx.stroke();
  }
}

function label(ctx, text, x, y, size, colour = '#fff') {
  ctx.font = `${size}px system-ui, sans-serif`;
  const w = ctx.measureText(text).width;
  ctx.fillStyle = 'rgba(10, 14, 18, 0.6)';
  ctx.fillRect(x - w / 2 - 3, y - size + 1, w + 6, size + 3);
  ctx.fillStyle = colour;
  ctx.textAlign = 'center';
  ctx.textBaseline = 'alphabetic';
  ctx.fillText(text, x, y);
}

/** A robot: its body (the second team's magenta), a wedge at its front, its agent number, its interface under it. */
export function drawRobot(ctx, view, pose, radius, info, { selected = false, active = false } = {}) {
  const c = view.toCanvas(pose.x, pose.y);
  const r = Math.max(6, radius * view.scale);
  ctx.beginPath();
  ctx.arc(c.x, c.y, r, 0, 2 * Math.PI);
  ctx.fillStyle = info.team === 1 ? COLOURS.secondTeamBody : COLOURS.robotBody;
  ctx.fill();
  ctx.lineWidth = selected || active ? 3 : 1.5;
  ctx.strokeStyle = selected || active ? COLOURS.selected : COLOURS.robotRim;
  ctx.stroke();

  // The front: a wedge from the rim toward the centre, along the robot's +y.
  const d = frontOf(pose.heading_deg);
  const fx = d.x, fy = -d.y;  // on the screen, y grows downward
  const tip = { x: c.x + fx * r, y: c.y + fy * r };
  const back = { x: c.x + fx * r * 0.35, y: c.y + fy * r * 0.35 };
  const side = r * 0.42;
  ctx.beginPath();
  ctx.moveTo(tip.x, tip.y);
  ctx.lineTo(back.x - fy * side, back.y + fx * side);
  ctx.lineTo(back.x + fy * side, back.y - fx * side);
  ctx.closePath();
  ctx.fillStyle = COLOURS.robotFront;
  ctx.fill();

  // The agent number in the middle, on the body's back half when the robot is small.
  const size = Math.round(Math.max(10, Math.min(18, r * 0.8)));
  ctx.font = `bold ${size}px system-ui, sans-serif`;
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  ctx.fillStyle = '#fff';
  const nx = c.x - fx * r * 0.3, ny = c.y - fy * r * 0.3;
  ctx.fillText(String(info.agent), nx, ny);
  if (info.interface) label(ctx, info.interface, c.x, c.y + r + Math.max(11, size * 0.8) + 2, Math.max(10, Math.min(13, size * 0.75)), '#e8f5e9');
}

/** A robot's odometry pose: a dashed outline with its front marked. */
export function drawGhost(ctx, view, pose, radius) {
  const c = view.toCanvas(pose.x, pose.y);
  const r = Math.max(6, radius * view.scale);
  const d = frontOf(pose.heading_deg);
  ctx.beginPath();
  ctx.setLineDash([5, 4]);
  ctx.arc(c.x, c.y, r, 0, 2 * Math.PI);
  ctx.moveTo(c.x + d.x * r * 0.3, c.y - d.y * r * 0.3);
  ctx.lineTo(c.x + d.x * r * 1.25, c.y - d.y * r * 1.25);
  ctx.strokeStyle = COLOURS.ghost;
  ctx.lineWidth = 1.2;
  ctx.stroke();
  ctx.setLineDash([]);
}

export function drawObstacle(ctx, view, p, radius, movable, active = false) {
  const c = view.toCanvas(p.x, p.y);
  ctx.beginPath();
  ctx.arc(c.x, c.y, Math.max(4, radius * view.scale), 0, 2 * Math.PI);
  ctx.fillStyle = COLOURS.obstacle;
  ctx.fill();
  ctx.lineWidth = active ? 3 : 1.2;
  ctx.strokeStyle = active ? COLOURS.selected : movable ? '#6b7580' : '#2a2f35';
  ctx.stroke();
}

/**
 * The ball; in the air (z > radius + 2 cm) with its shadow on the ground
 * (thrown toward the lower right, farther the higher it is) and its height.
 */
export function drawBall(ctx, view, b, radius, active = false) {
  const c = view.toCanvas(b.x, b.y);
  const r = Math.max(4, radius * view.scale);
  const z = typeof b.z === 'number' ? b.z : radius;
  if (z > radius + 0.02) {
    const off = Math.min(60, (z - radius) * view.scale * 0.6 + 3);
    ctx.beginPath();
    ctx.ellipse(c.x + off, c.y + off, r * 1.05, r * 0.8, 0, 0, 2 * Math.PI);
    ctx.fillStyle = 'rgba(0, 0, 0, 0.38)';
    ctx.fill();
    ctx.beginPath();
    ctx.setLineDash([2, 3]);
    ctx.moveTo(c.x, c.y);
    ctx.lineTo(c.x + off, c.y + off);
    ctx.strokeStyle = 'rgba(0, 0, 0, 0.45)';
    ctx.lineWidth = 1;
    ctx.stroke();
    ctx.setLineDash([]);
    label(ctx, `${z.toFixed(2)} m`, c.x + r + 24, c.y - r - 4, 12, '#fff');
  }
  ctx.beginPath();
  ctx.arc(c.x, c.y, r, 0, 2 * Math.PI);
  ctx.fillStyle = COLOURS.ball;
  ctx.fill();
  ctx.lineWidth = active ? 2.5 : 1;
  ctx.strokeStyle = active ? COLOURS.selected : '#fff3e0';
  ctx.stroke();
}

/** The kick being dragged: an arrow from the ball, with the speed it gives. */
export function drawKick(ctx, view, from, velocity, to) {
  const a = view.toCanvas(from.x, from.y), b = view.toCanvas(to.x, to.y);
  const len = Math.hypot(b.x - a.x, b.y - a.y);
  if (len < 2) return;
  const ux = (b.x - a.x) / len, uy = (b.y - a.y) / len;
  ctx.beginPath();
  ctx.moveTo(a.x, a.y);
  ctx.lineTo(b.x, b.y);
  ctx.moveTo(b.x, b.y);
  ctx.lineTo(b.x - ux * 12 - uy * 6, b.y - uy * 12 + ux * 6);
  ctx.moveTo(b.x, b.y);
  ctx.lineTo(b.x - ux * 12 + uy * 6, b.y - uy * 12 - ux * 6);
  ctx.strokeStyle = COLOURS.kick;
  ctx.lineWidth = 3;
  ctx.stroke();
  label(ctx, `${Math.hypot(velocity.vx, velocity.vy).toFixed(1)} m/s`, b.x + ux * 30, b.y + uy * 30 + 4, 13, COLOURS.kick);
}

/** One robot's vision points on the field, from its frame to the world with its pose. */
export function drawVisionOnField(ctx, view, vision, pose) {
  const sets = [[vision.lines, COLOURS.visionLine, 2], [vision.obstacles, COLOURS.visionObstacle, 3], [vision.balls, COLOURS.visionBall, 4]];
  for (const [points, colour, half] of sets) {
    ctx.fillStyle = colour;
    for (const p of points || []) {
      const w = robotToWorld(pose, p[0], p[1]);
      const c = view.toCanvas(w.x, w.y);
      ctx.fillRect(c.x - half, c.y - half, 2 * half, 2 * half);
    }
  }
}

/**
 * The robot's-eye view: its vision in its own frame, front up, `rangeM` metres
 * from the centre to the nearest edge, with 1 m rings.
 */
export function drawEye(ctx, width, height, vision, robotRadius, message, rangeM = 6) {
  ctx.fillStyle = '#183a1c';
  ctx.fillRect(0, 0, width, height);
  const cx = width / 2, cy = height / 2;
  const k = Math.min(width, height) / 2 / rangeM;
  ctx.strokeStyle = 'rgba(255, 255, 255, 0.13)';
  ctx.lineWidth = 1;
  ctx.beginPath();
  for (let m = 1; m <= rangeM + 2; m++) {
    ctx.moveTo(cx + m * k, cy);
    ctx.arc(cx, cy, m * k, 0, 2 * Math.PI);
  }
  ctx.moveTo(cx, 0);
  ctx.lineTo(cx, height);
  ctx.moveTo(0, cy);
  ctx.lineTo(width, cy);
  ctx.stroke();
  if (vision) {
    const sets = [[vision.lines, COLOURS.visionLine, 1.5], [vision.obstacles, COLOURS.visionObstacle, 2.5], [vision.balls, COLOURS.visionBall, 3.5]];
    for (const [points, colour, half] of sets) {
      ctx.fillStyle = colour;
      for (const p of points || []) ctx.fillRect(cx + p[0] * k - half, cy - p[1] * k - half, 2 * half, 2 * half);
    }
  }
  const r = Math.max(5, robotRadius * k);
  ctx.beginPath();
  ctx.arc(cx, cy, r, 0, 2 * Math.PI);
  ctx.fillStyle = COLOURS.robotBody;
  ctx.fill();
  ctx.strokeStyle = COLOURS.robotRim;
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(cx, cy - r);
  ctx.lineTo(cx - r * 0.45, cy - r * 0.3);
  ctx.lineTo(cx + r * 0.45, cy - r * 0.3);
  ctx.closePath();
  ctx.fillStyle = COLOURS.robotFront;
  ctx.fill();
  ctx.font = '11px system-ui, sans-serif';
  ctx.textAlign = 'left';
  ctx.textBaseline = 'alphabetic';
  ctx.fillStyle = '#dfe';
  ctx.fillText('front ↑   1 m rings', 6, 14);
  if (message) {
    ctx.fillStyle = '#fff';
    ctx.textAlign = 'center';
    ctx.fillText(message, cx, height - 10);
  }
}

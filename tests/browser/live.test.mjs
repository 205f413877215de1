// The viewer page against a live `canhil run` (virtual time), in headless
// chromium: what it draws is where the world has it; a drag moves a robot in
// the physics world; a ctrl-drag gives the ball the velocity the page sent;
// pause and step advance exactly one EC; a scenario saved from the page loads
// back. Every test starts its own canhil and reads the world back through a
// WebSocket of its own (`snapshot`), not through the page.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import {
  SOURCE, sharedBrowser, startCanhil, openPage, shot, Control, dragWorld, dist, sleep, workDir, bodyColour, magenta,
} from './support.mjs';

const FIVE = join(SOURCE, 'emulator/scenarios/five_robots.toml');
const TWO_TEAMS = join(SOURCE, 'emulator/scenarios/two_teams.toml');
const shared = sharedBrowser();

// A paused, long virtual-time run with its viewer on a free port, the page
// open on it and the test's own connection.
async function live(extra = [], { config = FIVE, beforeLoad = null } = {}) {
  const dir = workDir('live');
  const args = ['run', '--virtual-time', '--duration', '600', '--view-port', '0', '--no-control', ...extra];
  if (config) args.push('--config', config);
  const run = await startCanhil(args, dir);
  shared.cleanup(run.stop);
  const page = await openPage(shared.browser, run.url, { beforeLoad });
  shared.cleanup(() => page.close());
  const control = await Control.open(run.url, page);
  shared.cleanup(() => control.close());
  return { run, page, control, dir };
}

const drawn = (page) => page.evaluate(() => window.canhilView.drawn());
const pageState = (page) => page.evaluate(() => {
  const s = window.canhilView.state();
  return { time_s: s.time_s, steps: s.steps, paused: s.paused };
});

function assertDrawnAt(d, s, tolerance) {
  assert.equal(d.robots.length, s.robots.length, 'every robot drawn');
  s.robots.forEach((r, i) => {
    assert.ok(dist(d.robots[i], r) <= tolerance,
      `robot ${i} drawn at (${d.robots[i].x.toFixed(3)}, ${d.robots[i].y.toFixed(3)}), world (${r.x.toFixed(3)}, ${r.y.toFixed(3)})`);
    const dh = Math.abs(((d.robots[i].heading_deg - r.heading_deg + 540) % 360) - 180);
    assert.ok(dh <= 1, `robot ${i} drawn heading ${d.robots[i].heading_deg}, world ${r.heading_deg}`);
  });
  assert.ok(d.ball && dist(d.ball, s.ball) <= tolerance,
    `ball drawn at ${JSON.stringify(d.ball)}, world (${s.ball.x}, ${s.ball.y})`);
}

// Waits until the page has drawn the state of the run's time `t`.
async function pageAt(page, t) {
  await page.waitForFunction((want) => Math.abs(window.canhilView.state().time_s - want) < 1e-9, { timeout: 10000 }, t);
  await sleep(100);  // one animation frame or more
}

test('1. the page loads and draws the robots and the ball where the world has them', async () => {
  const { page, control } = await live(['--paused']);
  const hello = await page.evaluate(() => window.canhilView.hello());
  assert.equal(hello.mode, 'live');
  assert.equal(hello.robots.length, 5);
  let s = await control.snapshot();
  await pageAt(page, s.time_s);
  await shot(page, '1-loaded');
  assertDrawnAt(await drawn(page), s, 0.05);
  // Run 3 s of virtual time: the robots move, the page follows.
  await control.must('step', { count: Math.round(3 / hello.ec_s) });
  s = await control.until((x) => x.time_s >= 2.99, 'three seconds stepped');
  s = await control.snapshot();
  await pageAt(page, s.time_s);
  assertDrawnAt(await drawn(page), s, 0.05);
  await shot(page, '1-after-3s');
  // The labels: agent and interface, from the hello.
  assert.deepEqual(hello.robots.map((r) => r.interface), ['vcan0', 'vcan1', 'vcan2', 'vcan3', 'vcan4']);
  assert.deepEqual(page.errors, []);
});

test('2. a mouse drag of a robot moves it in the physics world; a right-drag turns it', async () => {
  const { page, control } = await live(['--paused']);
  const s0 = await control.snapshot();
  await pageAt(page, s0.time_s);
  const target = { x: 1, y: -3 };
  const drag = await dragWorld(page, s0.robots[0], target);
  await sleep(100);
  // While dragging the page draws the robot under the mouse, before any command.
  const during = await drawn(page);
  assert.ok(dist(during.robots[0], target) < 0.1, `drawn during the drag at ${JSON.stringify(during.robots[0])}`);
  assert.ok(dist((await control.snapshot()).robots[0], s0.robots[0]) < 0.01, 'the world has not moved it yet');
  await shot(page, '2-dragging');
  await drag.release();
  const s1 = await control.until((x) => dist(x.robots[0], target) < 0.15, 'robot 0 near the drop point');
  assert.ok(dist(s1.robots[0], target) < 0.15);
  await pageAt(page, s1.time_s);
  await shot(page, '2-dropped');
  // Right button: its front (+y) follows the mouse; toward field +y is heading 0.
  const turn = await dragWorld(page, s1.robots[0], { x: s1.robots[0].x, y: s1.robots[0].y + 2 }, { button: 'right' });
  await turn.release();
  const s2 = await control.until((x) => Math.abs(x.robots[0].heading_deg) < 3, 'robot 0 turned to face +y');
  assert.ok(dist(s2.robots[0], target) < 0.15, 'turning left it in place');
  // An obstacle (the movable keeper) dragged as well.
  const keeper = s2.obstacles[4];
  const spot = { x: keeper.x - 1.5, y: keeper.y - 1 };
  const od = await dragWorld(page, keeper, spot);
  await od.release();
  await control.until((x) => dist(x.obstacles[4], spot) < 0.15, 'obstacle 4 near its drop point');
  assert.deepEqual(page.errors, []);
});

// Records what the page sends on its WebSocket (page side, before its scripts run).
function recordSent() {
  window.__sent = [];
  const send = WebSocket.prototype.send;
  WebSocket.prototype.send = function recorded(data) {
    try { window.__sent.push(JSON.parse(data)); } catch { /* not ours */ }
    return send.call(this, data);
  };
}

test('3. a ctrl-drag from the ball gives it the velocity the page sent', async () => {
  const { page, control } = await live(['--paused'], { beforeLoad: recordSent });
  const s0 = await control.snapshot();
  await pageAt(page, s0.time_s);
  const ball = s0.ball;
  // 1.5 m along +x and 1 m along +y from the ball: 2 m/s per metre -> (3, 2) m/s.
  const drag = await dragWorld(page, ball, { x: ball.x + 1.5, y: ball.y + 1.0 }, { modifier: 'Control' });
  await sleep(100);
  await shot(page, '3-kick-arrow');
  await drag.release();
  await page.waitForFunction(() => window.__sent.some((m) => m.command === 'move_ball'), { timeout: 5000 });
  const sent = await page.evaluate(() => window.__sent.filter((m) => m.command === 'move_ball').pop());
  assert.ok(Math.abs(sent.x - ball.x) <= 0.001 && Math.abs(sent.y - ball.y) <= 0.001, `sent from the ball's place: ${JSON.stringify(sent)}`);
  assert.ok(Math.hypot(sent.vx - 3, sent.vy - 2) < 0.15, `the page sent (${sent.vx}, ${sent.vy}) m/s for a (1.5, 1) m drag`);
  const ec = (await page.evaluate(() => window.canhilView.hello())).ec_s;
  await control.must('step', { count: 1 });
  const s1 = await control.until((x) => x.time_s >= s0.time_s + ec * 0.5, 'one step');
  const v = s1.ball_velocity || { x: s1.ball.vx, y: s1.ball.vy };
  const speed = Math.hypot(v.x, v.y), sentSpeed = Math.hypot(sent.vx, sent.vy);
  const angle = (Math.atan2(v.y, v.x) * 180) / Math.PI, sentAngle = (Math.atan2(sent.vy, sent.vx) * 180) / Math.PI;
  console.log(`kick: sent ${sentSpeed.toFixed(3)} m/s at ${sentAngle.toFixed(1)} deg; after one step ${speed.toFixed(3)} m/s at ${angle.toFixed(1)} deg`);
  assert.ok(Math.abs(angle - sentAngle) <= 10, `direction ${angle} deg, sent ${sentAngle} deg`);
  assert.ok(Math.abs(speed - sentSpeed) <= 0.15 * sentSpeed, `speed ${speed} m/s, sent ${sentSpeed} m/s`);
  await control.must('step', { count: 20 });
  await sleep(300);
  await shot(page, '3-ball-rolling');
  assert.deepEqual(page.errors, []);
});

test('4. pause, then each step advances exactly one EC', async () => {
  const { page, control } = await live(['--speed', '1']);
  const hello = await page.evaluate(() => window.canhilView.hello());
  assert.equal(hello.virtual_time, true);
  assert.equal(await page.$eval('#step', (b) => b.disabled), false);
  await page.click('#pause');
  await page.waitForFunction(() => window.canhilView.state().paused === true, { timeout: 10000 });
  // Paused: the steps counter stands still.
  let s = await control.snapshot();
  await sleep(400);
  const still = await control.snapshot();
  assert.equal(still.steps, s.steps, 'paused: no steps');
  assert.equal(still.time_s, s.time_s);
  for (let k = 1; k <= 3; k++) {
    await page.click('#step');
    const next = await control.until((x) => x.steps > s.steps, `step ${k}`);
    await sleep(300);  // nothing more comes
    const settled = await control.snapshot();
    assert.equal(settled.steps, s.steps + 1, `step ${k}: steps ${s.steps} -> ${settled.steps}`);
    assert.equal(settled.steps, next.steps);
    assert.ok(Math.abs(settled.time_s - (s.time_s + hello.ec_s)) < 1e-9,
      `step ${k}: time ${s.time_s} -> ${settled.time_s}, EC ${hello.ec_s}`);
    await pageAt(page, settled.time_s);
    const shown = await pageState(page);
    assert.equal(shown.steps, settled.steps, 'the page shows the step');
    s = settled;
  }
  const status = await page.$eval('#st-time', (e) => e.textContent);
  assert.equal(status, `t ${s.time_s.toFixed(2)} s`);
  await shot(page, '4-stepped');
  assert.deepEqual(page.errors, []);
});

test('5. a scenario saved from the page loads back', async () => {
  const { page, control, dir } = await live(['--paused', '--save-dir', 'saves']);
  const s0 = await control.snapshot();
  await pageAt(page, s0.time_s);
  const saved = { x: 2, y: 2 };
  let d = await dragWorld(page, s0.robots[0], saved);
  await d.release();
  await control.until((x) => dist(x.robots[0], saved) < 0.15, 'robot 0 at (2, 2)');
  await page.type('#save-name', 't1');
  await page.select('#save-kind', 'scenario');
  await page.click('#save');
  await page.waitForSelector('#saves button[data-name="t1"][data-kind="scenario"]', { timeout: 10000 });
  assert.ok(existsSync(join(dir, 'saves', 't1.toml')), 'the scenario file written');
  const list = await control.must('saves');
  assert.ok(list.saves.some((x) => x.name === 't1' && x.kind === 'scenario'));
  // Elsewhere, then load t1: back at the saved place.
  const s1 = await control.snapshot();
  await pageAt(page, s1.time_s);
  d = await dragWorld(page, s1.robots[0], { x: -3, y: -4 });
  await d.release();
  await control.until((x) => dist(x.robots[0], { x: -3, y: -4 }) < 0.15, 'robot 0 moved away');
  await shot(page, '5-before-load');
  await page.click('#saves button[data-name="t1"][data-kind="scenario"]');
  const s2 = await control.until((x) => dist(x.robots[0], saved) < 0.15, 'robot 0 back at the saved place');
  await pageAt(page, s2.time_s);
  assertDrawnAt(await drawn(page), s2, 0.05);
  await shot(page, '5-loaded');
  const logText = await page.$eval('#log', (e) => e.textContent);
  assert.match(logText, /loaded scenario t1/);
  assert.deepEqual(page.errors, []);
});

test('an error reply shows in the log', async () => {
  const { page } = await live(['--paused']);
  await page.type('#fault-text', 'no-such-rule');
  await page.click('#inject');
  await page.waitForSelector('#log li.error', { timeout: 10000 });
  const text = await page.$eval('#log li.error', (e) => e.textContent);
  assert.match(text, /fault refused/);
  assert.deepEqual(page.errors, []);
});

test('two teams: the second team\'s robots in magenta, the score in the bar', async () => {
  const { page, control } = await live(['--paused'], { config: TWO_TEAMS });
  const hello = await page.evaluate(() => window.canhilView.hello());
  assert.equal(hello.teams.length, 2);
  const teamOf = hello.robots.map((r) => r.team);
  assert.ok(teamOf.includes(0) && teamOf.includes(1), `teams of the robots: ${teamOf}`);
  const s0 = await control.snapshot();
  await pageAt(page, s0.time_s);
  for (let i = 0; i < s0.robots.length; ++i) {
    const colour = await bodyColour(page, hello, s0.robots[i]);
    assert.equal(magenta(colour), teamOf[i] === 1, `robot ${i} (team ${teamOf[i]}) drawn ${colour}`);
  }
  const bar = () => page.$eval('#st-goals', (e) => e.textContent);
  const [a, b] = hello.teams;
  assert.equal(await bar(), `${a.name} 0 : 0 ${b.name}`);
  // A ball rolled into the goal the first team attacks: 1 : 0.
  const x = (a.attacks_positive_x ? 1 : -1) * (hello.field.length_m / 2 - 0.3);
  await control.must('move_ball', { x, y: 0, z: hello.ball_radius_m, vx: a.attacks_positive_x ? 3 : -3, vy: 0, vz: 0 });
  await control.must('step', { count: 50 });
  await control.until((w) => w.goals.length === 1, 'the goal counted');
  await page.waitForFunction((want) => document.getElementById('st-goals').textContent === want, { timeout: 10000 },
    `${a.name} 1 : 0 ${b.name}`);
  await shot(page, 'two-teams');
  assert.deepEqual(page.errors, []);
});

test('the view: wheel and buttons zoom, the middle button pans, follow the ball; a stopped server shows as disconnected', async () => {
  const { run, page, control } = await live(['--paused']);
  const s0 = await control.snapshot();
  await pageAt(page, s0.time_s);
  const scale = () => page.evaluate(() => {
    const a = window.canhilView.toScreen(0, 0), b = window.canhilView.toScreen(1, 0);
    return b.x - a.x;
  });
  const at = (x, y) => page.evaluate((px, py) => window.canhilView.toScreen(px, py), x, y);
  const k0 = await scale();
  assert.ok(k0 > 20, `${k0} pixels per metre at the start`);
  // The whole field in view at the start.
  const box = await (await page.$('#field')).boundingBox();
  const hello = await page.evaluate(() => window.canhilView.hello());
  const corner = await at(hello.field.length_m / 2, hello.field.width_m / 2);
  assert.ok(corner.x < box.x + box.width && corner.y > box.y, 'the field\'s corner in view');
  const p = await at(2, 1);
  await page.mouse.move(p.x, p.y);
  await page.mouse.wheel({ deltaY: -100 });
  await page.mouse.wheel({ deltaY: -100 });
  await sleep(100);
  const k1 = await scale();
  assert.ok(k1 > k0 * 1.2, `wheel up zooms in: ${k0} -> ${k1}`);
  const p1 = await at(2, 1);
  assert.ok(Math.hypot(p1.x - p.x, p1.y - p.y) < 1.5, 'the point under the mouse stays under it');
  await page.click('#zoom-out');
  assert.ok((await scale()) < k1, 'the - button zooms out');
  await page.click('#zoom-in');
  // Middle button: pan by 120 px to the right, 40 down.
  const o0 = await at(0, 0);
  await page.mouse.move(box.x + 200, box.y + 200);
  await page.mouse.down({ button: 'middle' });
  await page.mouse.move(box.x + 260, box.y + 220);
  await page.mouse.move(box.x + 320, box.y + 240);
  await page.mouse.up({ button: 'middle' });
  const o1 = await at(0, 0);
  assert.ok(Math.abs(o1.x - o0.x - 120) < 2 && Math.abs(o1.y - o0.y - 40) < 2, `panned by (${o1.x - o0.x}, ${o1.y - o0.y})`);
  assert.ok(dist((await control.snapshot()).robots[0], s0.robots[0]) < 1e-6, 'panning moved nothing in the world');
  // Follow the ball: it goes to the middle of the view.
  await page.click('#follow-ball');
  await sleep(100);
  const b = await at(s0.ball.x, s0.ball.y);
  assert.ok(Math.abs(b.x - (box.x + box.width / 2)) < 2 && Math.abs(b.y - (box.y + box.height / 2)) < 2, 'the ball in the middle');
  await shot(page, 'view-zoomed-following');
  await page.click('#zoom-fit');
  assert.deepEqual(page.errors, []);
  // The server goes away: the page says so, and keeps trying.
  await run.stop();
  await page.waitForSelector('#conn.conn-closed', { timeout: 10000 });
  assert.equal(await page.$eval('#overlay', (e) => e.hidden), false);
  assert.match(await page.$eval('#conn', (e) => e.textContent), /disconnected/);
  await shot(page, 'view-disconnected');
  // A run on the same port again: the page reconnects by itself and shows the new world.
  const port = new URL(run.url).port;
  const again = await startCanhil(['run', '--virtual-time', '--duration', '600', '--view-port', port, '--no-control', '--paused'], workDir('again'));
  shared.cleanup(again.stop);
  await page.waitForSelector('#conn.conn-open', { timeout: 15000 });
  await page.waitForFunction(() => window.canhilView.hello().robots.length === 1, { timeout: 10000 });
  assert.equal(await page.$eval('#overlay', (e) => e.hidden), true);
  const againControl = await Control.open(again.url, page);
  shared.cleanup(() => againControl.close());
  const s = await againControl.snapshot();
  await pageAt(page, s.time_s);
  assertDrawnAt(await drawn(page), s, 0.05);
  await shot(page, 'view-reconnected');
  // While the server was away, each of the page's attempts may have made the
  // browser log a refused connection to that same address; nothing else.
  const refused = new RegExp(`^console: WebSocket connection to 'ws://127\\.0\\.0\\.1:${port}/ws' failed: .*ERR_CONNECTION_REFUSED$`);
  assert.deepEqual(page.errors.filter((e) => !refused.test(e)), []);
});

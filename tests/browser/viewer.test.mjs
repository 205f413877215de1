// The viewer page in a real browser: Debian's chromium, headless, driven by
// puppeteer-core, against `canhil run` and `canhil view`. What the page draws
// is read back (window.canhilView) and compared with the world as the run's
// own snapshot has it; a drag moves the robot in the physics world; a ctrl-
// drag gives the ball its velocity; pause and step advance exactly one EC;
// a saved scenario loads back; the replay's scrubber shows the recorded
// positions; ten robots are drawn at 30 frames per second or more.
// Screenshots of every step go to $CANHIL_BROWSER_OUT.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { mkdtempSync, mkdirSync, writeFileSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import puppeteer from 'puppeteer-core';

const CANHIL = process.env.CANHIL;
if (!CANHIL) throw new Error('set CANHIL to the canhil binary');
const OUT = process.env.CANHIL_BROWSER_OUT || mkdtempSync(join(tmpdir(), 'canhil-browser-'));
mkdirSync(OUT, { recursive: true });
const WORK = mkdtempSync(join(tmpdir(), 'canhil-browser-work-'));
const SOURCE = new URL('../../', import.meta.url).pathname;

let browser;
const children = [];

before(async () => {
  browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', `--user-data-dir=${mkdtempSync(join(tmpdir(), 'chromium-'))}`],
  });
});

after(async () => {
  for (const c of children) c.kill('SIGINT');
  if (browser) await browser.close();
  console.log(`screenshots in ${OUT}`);
});

// Starts canhil and waits for "WHO: viewer at URL".
function start(args) {
  return new Promise((resolve, reject) => {
    const child = spawn(CANHIL, args, { cwd: WORK, env: { ...process.env, RTDB_KEY: String(0x5f000000 + ((process.pid & 0xfff) << 8)) } });
    children.push(child);
    let out = '';
    const timer = setTimeout(() => reject(new Error(`no viewer address from canhil ${args.join(' ')}:\n${out}`)), 60000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/viewer at (http:\/\/\S+)/);
      if (m) {
        clearTimeout(timer);
        resolve({ child, url: m[1], output: () => out });
      }
    });
    child.stderr.on('data', (d) => { out += d; });
    child.on('exit', (code) => reject(new Error(`canhil ended (${code}) before its viewer was up:\n${out}`)));
  });
}

async function open(url) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 950 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.canhilView && window.canhilView.hello() && window.canhilView.state());
  page.errors = errors;
  return page;
}

async function shot(page, name) {
  const path = join(OUT, `${name}.png`);
  await page.screenshot({ path });
  console.log(`screenshot ${path}`);
}

// A command on the page's own connection's terms, from a second WebSocket in the page.
async function ask(page, request) {
  return page.evaluate((req) => new Promise((resolve, reject) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    ws.onmessage = (m) => {
      const msg = JSON.parse(m.data);
      if (msg.type === 'reply') { ws.close(); resolve(msg); }
    };
    ws.onopen = () => ws.send(JSON.stringify(req));
    ws.onerror = () => reject(new Error('websocket'));
  }), request);
}

const snapshot = async (page) => (await ask(page, { command: 'snapshot' })).snapshot;

async function until(page, predicate, what, limitMs = 20000) {
  const end = Date.now() + limitMs;
  for (;;) {
    const s = await snapshot(page);
    if (predicate(s)) return s;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}: ${JSON.stringify(s).slice(0, 300)}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

async function drawnMatches(page, s, tolerance) {
  const drawn = await page.evaluate(() => window.canhilView.drawn());
  assert.equal(drawn.robots.length, s.robots.length);
  for (const [i, r] of s.robots.entries()) {
    assert.ok(Math.hypot(drawn.robots[i].x - r.x, drawn.robots[i].y - r.y) < tolerance, `robot ${i} drawn at ${JSON.stringify(drawn.robots[i])}, world ${JSON.stringify(r)}`);
  }
  assert.ok(Math.hypot(drawn.ball.x - s.ball.x, drawn.ball.y - s.ball.y) < tolerance, 'ball');
}

async function dragFromTo(page, from, to, { button = 'left', modifier = null } = {}) {
  const a = await page.evaluate((x, y) => window.canhilView.toScreen(x, y), from.x, from.y);
  const b = await page.evaluate((x, y) => window.canhilView.toScreen(x, y), to.x, to.y);
  if (modifier) await page.keyboard.down(modifier);
  await page.mouse.move(a.x, a.y);
  await page.mouse.down({ button });
  for (let k = 1; k <= 8; k++) await page.mouse.move(a.x + ((b.x - a.x) * k) / 8, a.y + ((b.y - a.y) * k) / 8);
  await page.mouse.up({ button });
  if (modifier) await page.keyboard.up(modifier);
}

test('the page draws the world where the run has it, and a drag moves a robot in the physics world', async () => {
  const run = await start(['run', '--virtual-time', '--config', join(SOURCE, 'emulator/scenarios/five_robots.toml'), '--paused',
    '--duration', '600', '--view-port', '0', '--no-control']);
  const page = await open(run.url);
  await page.waitForFunction(() => window.canhilView.state().robots.length === 5);
  await new Promise((r) => setTimeout(r, 300));
  await shot(page, '1-loaded');
  await drawnMatches(page, await snapshot(page), 0.05);
  // Robot 0 (at -2, 0) dragged to (1, -3): the physics world has it there, paused or not.
  const before0 = (await snapshot(page)).robots[0];
  await dragFromTo(page, before0, { x: 1, y: -3 });
  const s = await until(page, (x) => Math.hypot(x.robots[0].x - 1, x.robots[0].y + 3) < 0.15, 'the robot at (1, -3)');
  await new Promise((r) => setTimeout(r, 200));
  await drawnMatches(page, s, 0.05);
  await shot(page, '2-robot-dragged');
  // Right-button drag turns it: its front toward the point dragged to (+y of the field: heading 0).
  await dragFromTo(page, { x: 1, y: -3 }, { x: 1, y: 0 }, { button: 'right' });
  const turned = await until(page, (x) => Math.abs(x.robots[0].heading_deg) < 5, 'the robot turned to face +y');
  assert.ok(Math.hypot(turned.robots[0].x - 1, turned.robots[0].y + 3) < 0.15);
  assert.deepEqual(page.errors, []);
  run.child.kill('SIGINT');
});

test('a ctrl-drag from the ball gives it the velocity; pause and step advance exactly one EC', async () => {
  const run = await start(['run', '--virtual-time', '--paused', '--duration', '600', '--view-port', '0', '--no-control']);
  const page = await open(run.url);
  const ec = await page.evaluate(() => window.canhilView.hello().ec_s);
  const s0 = await snapshot(page);
  // Three single steps: each exactly one EC of virtual time.
  let t = s0.time_s;
  for (let k = 0; k < 3; k++) {
    await page.click('#step');
    const s = await until(page, (x) => x.time_s > t + ec / 2, 'one step');
    await new Promise((r) => setTimeout(r, 300));
    const settled = await snapshot(page);
    assert.ok(Math.abs(settled.time_s - (t + ec)) < 1e-9, `step ${k}: ${t} -> ${settled.time_s}, EC ${ec}`);
    assert.equal(settled.steps, s.steps);
    t = settled.time_s;
  }
  await shot(page, '3-stepped');
  // Drag 1.5 m along +x and 1 m along +y from the ball with ctrl: 2 m/s per metre -> (3, 2) m/s.
  const ball = s0.ball;
  await dragFromTo(page, ball, { x: ball.x + 1.5, y: ball.y + 1.0 }, { modifier: 'Control' });
  await shot(page, '4-ball-kicked-paused');
  await page.click('#step');
  const s = await until(page, (x) => Math.hypot(x.ball_velocity.x, x.ball_velocity.y) > 1, 'the ball moving');
  const speed = Math.hypot(s.ball_velocity.x, s.ball_velocity.y);
  const angle = (Math.atan2(s.ball_velocity.y, s.ball_velocity.x) * 180) / Math.PI;
  const wantAngle = (Math.atan2(2, 3) * 180) / Math.PI;
  assert.ok(Math.abs(angle - wantAngle) < 10, `direction ${angle} deg, sent ${wantAngle}`);
  assert.ok(Math.abs(speed - Math.hypot(3, 2)) / Math.hypot(3, 2) < 0.15, `speed ${speed}`);
  assert.deepEqual(page.errors, []);
  run.child.kill('SIGINT');
});

test('a scenario saved from the page loads back while running', async () => {
  const run = await start(['run', '--virtual-time', '--paused', '--duration', '600', '--view-port', '0', '--no-control',
    '--save-dir', join(WORK, 'saves')]);
  const page = await open(run.url);
  assert.equal((await ask(page, { command: 'move_robot', robot: 0, x: 2, y: 2, heading_deg: 0 })).ok, true);
  await until(page, (x) => Math.hypot(x.robots[0].x - 2, x.robots[0].y - 2) < 0.05, 'the robot at (2, 2)');
  await page.type('#save-name', 'round-trip');
  await page.select('#save-kind', 'scenario');
  await page.click('#save');
  await page.waitForFunction(() => [...document.querySelectorAll('#saves li')].some((li) => li.textContent.includes('round-trip')));
  const text = readFileSync(join(WORK, 'saves', 'round-trip.toml'), 'utf8');
  assert.match(text, /\[\[robots\]\]/);
  await ask(page, { command: 'move_robot', robot: 0, x: -5, y: -4, heading_deg: 0 });
  await until(page, (x) => Math.hypot(x.robots[0].x + 5, x.robots[0].y + 4) < 0.05, 'the robot moved away');
  await shot(page, '5-before-load');
  const load = await page.$$('#saves li button');
  await load[0].click();
  await until(page, (x) => Math.hypot(x.robots[0].x - 2, x.robots[0].y - 2) < 0.05, 'the robot back at the saved place');
  await new Promise((r) => setTimeout(r, 200));
  await shot(page, '6-loaded');
  assert.deepEqual(page.errors, []);
  run.child.kill('SIGINT');
});

test('the replay scrubber shows the recorded positions', async () => {
  const log = join(WORK, 'world.csv'), trace = join(WORK, 'trace.log');
  execFileSync(CANHIL, ['run', '--virtual-time', '--duration', '4', '--world-log', log, '--trace', trace, '--no-view', '--no-control', '--quiet'],
    { cwd: WORK, env: { ...process.env, RTDB_KEY: String(0x5f100000 + ((process.pid & 0xfff) << 8)) } });
  const rows = readFileSync(log, 'utf8').trim().split('\n').slice(1).map((l) => l.split(',').map(Number));
  const view = await start(['view', log, '--trace', trace, '--view-port', '0']);
  const page = await open(view.url);
  await page.waitForFunction(() => window.canhilView.replayTime() !== null);
  for (const want of [rows[10], rows[Math.floor(rows.length / 2)], rows[rows.length - 1]]) {
    const duration = rows[rows.length - 1][0];
    // The scrubber's own input: a value out of 1000.
    await page.$eval('#scrub', (el, v) => { el.value = v; el.dispatchEvent(new Event('input')); }, Math.round((want[0] / duration) * 1000));
    const t = await page.evaluate(() => window.canhilView.replayTime());
    const row = rows.reduce((best, r) => (Math.abs(r[0] - t) < Math.abs(best[0] - t) ? r : best));
    await new Promise((r) => setTimeout(r, 100));
    const drawn = await page.evaluate(() => window.canhilView.drawn());
    assert.ok(Math.abs(row[0] - t) < 0.03, `cursor at ${t}`);
    assert.ok(Math.hypot(drawn.ball.x - row[1], drawn.ball.y - row[2]) < 0.05, `ball at t=${t}: drawn ${JSON.stringify(drawn.ball)}, log ${row.slice(1, 3)}`);
    assert.ok(Math.hypot(drawn.robots[0].x - row[4], drawn.robots[0].y - row[5]) < 0.05, `robot at t=${t}`);
  }
  await page.waitForFunction(() => document.querySelectorAll('#frames tr').length > 0);
  await shot(page, '7-replay');
  assert.deepEqual(page.errors, []);
  view.child.kill('SIGINT');
});

test('ten robots are drawn at 30 frames per second or more', async () => {
  const log = join(WORK, 'ten.csv');
  let text = 'time_s,ball_x_m,ball_y_m,ball_z_m';
  for (let r = 0; r < 10; r++) text += `,robot${r}_x_m,robot${r}_y_m,robot${r}_heading_deg,robot${r}_reported_x_m,robot${r}_reported_y_m,robot${r}_reported_heading_deg`;
  text += '\n';
  for (let i = 0; i <= 400; i++) {
    const t = i * 0.05;
    const row = [t.toFixed(3), (6 * Math.sin(t / 3)).toFixed(4), (3 * Math.cos(t / 2)).toFixed(4), '0.11'];
    for (let r = 0; r < 10; r++) {
      const x = -7 + 1.5 * r + Math.sin(t + r), y = 4 * Math.cos(t / 2 + r), h = (t * 40 + r * 30) % 360 - 180;
      row.push(x.toFixed(4), y.toFixed(4), h.toFixed(2), (x + 0.05).toFixed(4), (y - 0.05).toFixed(4), h.toFixed(2));
    }
    text += row.join(',') + '\n';
  }
  writeFileSync(log, text);
  const view = await start(['view', log, '--view-port', '0']);
  const page = await open(view.url);
  await page.waitForFunction(() => window.canhilView.replayTime() !== null);
  await page.evaluate(() => window.canhilView.play(1));
  await new Promise((r) => setTimeout(r, 3000));
  const fps = await page.evaluate(() => window.canhilView.fps());
  const drawn = await page.evaluate(() => window.canhilView.drawn());
  await shot(page, '8-ten-robots');
  console.log(`ten robots: ${fps.toFixed(1)} frames per second drawn (target >= 30)`);
  assert.equal(drawn.robots.length, 10);
  assert.ok(fps >= 30, `${fps} frames per second`);
  view.child.kill('SIGINT');
});

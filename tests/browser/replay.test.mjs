// The viewer page against `canhil view` (replay), in headless chromium: the
// scrubber, moved with the mouse, shows the recorded positions; the bus panel
// lists the trace's frames around the cursor; ten robots play at 30 frames per
// second or more.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import {
  CANHIL, SOURCE, sharedBrowser, startCanhil, openPage, shot, sleep, workDir, rtdbEnv, dist, bodyColour, magenta,
} from './support.mjs';

const shared = sharedBrowser();

function readLog(path) {
  const lines = readFileSync(path, 'utf8').trim().split('\n').filter((l) => !l.startsWith('#'));  // rows, not comments
  const columns = lines[0].split(',');
  return { columns, rows: lines.slice(1).map((l) => l.split(',').map(Number)) };
}

// The world log at time t, interpolated between its rows as a replay should.
function logAt(log, t) {
  const { rows, columns } = log;
  const c = (name) => columns.indexOf(name);
  let i = 0;
  while (i + 1 < rows.length && rows[i + 1][0] <= t) i++;
  const a = rows[i], b = rows[Math.min(i + 1, rows.length - 1)];
  const k = b[0] > a[0] ? Math.min(1, Math.max(0, (t - a[0]) / (b[0] - a[0]))) : 0;
  const at = (j) => a[j] + (b[j] - a[j]) * k;
  const robots = [];
  for (let r = 0; c(`robot${r}_x_m`) >= 0; r++) robots.push({ x: at(c(`robot${r}_x_m`)), y: at(c(`robot${r}_y_m`)) });
  return { ball: { x: at(c('ball_x_m')), y: at(c('ball_y_m')) }, robots };
}

// Records the addresses the page opens (WebSocket and fetch), before its scripts run.
function recordUrls() {
  window.__urls = [];
  const Ws = window.WebSocket;
  window.WebSocket = function recorded(url, ...rest) {
    window.__urls.push(String(url));
    return new Ws(url, ...rest);
  };
  window.WebSocket.prototype = Ws.prototype;
  Object.assign(window.WebSocket, { CONNECTING: 0, OPEN: 1, CLOSING: 2, CLOSED: 3 });
  const f = window.fetch;
  window.fetch = (url, ...rest) => {
    window.__urls.push(String(url));
    return f(url, ...rest);
  };
}

async function view(args, { query = '' } = {}) {
  const v = await startCanhil(['view', ...args, '--view-port', '0'], workDir('view'));
  shared.cleanup(v.stop);
  const page = await openPage(shared.browser, v.url + query, { beforeLoad: recordUrls });
  shared.cleanup(() => page.close());
  await page.waitForFunction(() => window.canhilView.replayTime() !== null, { timeout: 20000 });
  return { v, page };
}

test('6. replay: scrubbing the timeline to t shows the recorded positions', async () => {
  const dir = workDir('record');
  const worldLog = join(dir, 'world.csv'), trace = join(dir, 'trace.log');
  execFileSync(CANHIL, ['run', '--virtual-time', '--duration', '3', '--world-log', worldLog, '--trace', trace,
    '--no-view', '--no-control'], { cwd: dir, env: rtdbEnv(), stdio: ['ignore', 'ignore', 'pipe'] });
  const log = readLog(worldLog);
  assert.ok(log.rows.length > 20, `${log.rows.length} rows in the world log`);
  // With ?token=: the page passes it on to /ws and /api (a loopback server needs none, takes any).
  const { page } = await view([worldLog, '--trace', trace], { query: '?token=t0k3n' });
  const hello = await page.evaluate(() => window.canhilView.hello());
  assert.equal(hello.mode, 'replay');
  // Live-only controls are hidden, the timeline shown.
  assert.equal(await page.$eval('#run-panel', (e) => e.hidden), true);
  assert.equal(await page.$eval('#timeline', (e) => e.hidden), false);
  const box = await (await page.$('#rp-scrub')).boundingBox();
  for (const fraction of [0.2, 0.55, 0.9]) {
    // A click on the scrubber's track: the thumb jumps there.
    await page.mouse.click(box.x + 8 + (box.width - 16) * fraction, box.y + box.height / 2);
    await sleep(150);
    const t = await page.evaluate(() => window.canhilView.replayTime());
    const end = log.rows[log.rows.length - 1][0];
    assert.ok(Math.abs(t - fraction * end) < 0.1 * end, `the cursor at ${t} s for ${fraction} of ${end} s`);
    const want = logAt(log, t);
    const d = await page.evaluate(() => window.canhilView.drawn());
    assert.ok(dist(d.ball, want.ball) <= 0.02, `t=${t}: ball drawn at ${JSON.stringify(d.ball)}, logged ${JSON.stringify(want.ball)}`);
    assert.equal(d.robots.length, want.robots.length);
    want.robots.forEach((r, i) => assert.ok(dist(d.robots[i], r) <= 0.02,
      `t=${t}: robot ${i} drawn at ${JSON.stringify(d.robots[i])}, logged ${JSON.stringify(r)}`));
  }
  // The bus panel: the trace's frames within 0.1 s of the cursor, decoded.
  await page.waitForFunction(() => document.querySelectorAll('#frames tr').length > 0 &&
    Number(document.getElementById('frames').dataset.at) === window.canhilView.replayTime(), { timeout: 10000 });
  const t = await page.evaluate(() => window.canhilView.replayTime());
  const times = await page.$$eval('#frames tr td:first-child', (tds) => tds.map((td) => Number(td.textContent)));
  assert.ok(times.every((x) => Math.abs(x - t) <= 0.1 + 1e-3), `frames around ${t}: ${times.slice(0, 5)}…`);
  await shot(page, '6-replay-scrubbed');
  const urls = await page.evaluate(() => window.__urls);
  assert.ok(urls.some((u) => /\/ws\?token=t0k3n$/.test(u)), `the WebSocket with the token: ${urls}`);
  assert.ok(urls.some((u) => /^\/api\/replay\?token=t0k3n$/.test(u)), `/api/replay with the token: ${urls}`);
  assert.ok(urls.some((u) => /^\/api\/frames\?from=.*&token=t0k3n$/.test(u)), `/api/frames with the token: ${urls}`);
  // Next kick (when the recording has one) puts the cursor on it.
  const events = await page.evaluate(async () => (await (await fetch('/api/replay')).json()).events);
  const kick = events.find((e) => e.kind === 'kick' && e.time_s > 0);
  if (kick) {
    await page.mouse.click(box.x + 8, box.y + box.height / 2);  // back to the start
    await sleep(100);
    const from = await page.evaluate(() => window.canhilView.replayTime());
    await page.click('#rp-next-kick');
    const after = await page.evaluate(() => window.canhilView.replayTime());
    const want = events.find((e) => e.kind === 'kick' && e.time_s > from + 1e-6);
    assert.ok(Math.abs(after - want.time_s) < 1e-6, `next kick: cursor ${after}, kick at ${want.time_s}`);
  } else {
    console.log('replay: the 3 s recording has no kick; next kick not checked');
  }
  assert.deepEqual(page.errors, []);
});

test('7. ten robots play back at 30 frames per second or more', async () => {
  const dir = workDir('ten');
  const worldLog = join(dir, 'ten.csv');
  const header = ['time_s', 'ball_x_m', 'ball_y_m', 'ball_z_m'];
  for (let k = 0; k < 10; k++) {
    header.push(`robot${k}_x_m`, `robot${k}_y_m`, `robot${k}_heading_deg`,
      `robot${k}_reported_x_m`, `robot${k}_reported_y_m`, `robot${k}_reported_heading_deg`);
  }
  const lines = [header.join(',')];
  for (let i = 0; i <= 400; i++) {
    const t = i * 0.05;
    const row = [t.toFixed(2), (6 * Math.sin(t / 3)).toFixed(4), (3 * Math.cos(t / 2)).toFixed(4), (0.11 + Math.max(0, Math.sin(t)) * 0.6).toFixed(4)];
    for (let k = 0; k < 10; k++) {
      const x = -7.5 + 1.6 * k + 0.8 * Math.sin(t + k), y = 4 * Math.cos(t / 2 + k);
      const h = ((t * 40 + k * 36) % 360) - 180;
      row.push(x.toFixed(4), y.toFixed(4), h.toFixed(2), (x + 0.06).toFixed(4), (y - 0.04).toFixed(4), h.toFixed(2));
    }
    lines.push(row.join(','));
  }
  writeFileSync(worldLog, `${lines.join('\n')}\n`);
  const { page } = await view([worldLog]);
  await page.select('#rp-speed', '1');
  await page.click('#rp-play');
  await sleep(1000);  // past the start
  const n0 = await page.evaluate(() => window.canhilView.framesDrawn());
  const t0 = await page.evaluate(() => window.canhilView.replayTime());
  const wall0 = Date.now();
  await sleep(3000);
  const n1 = await page.evaluate(() => window.canhilView.framesDrawn());
  const t1 = await page.evaluate(() => window.canhilView.replayTime());
  const wall = (Date.now() - wall0) / 1000;
  const fps = (n1 - n0) / wall;
  const fps2 = await page.evaluate(() => window.canhilView.fps());
  console.log(`ten robots at 1x: ${fps.toFixed(1)} frames drawn per second over ${wall.toFixed(2)} s (page's own figure over 2 s: ${fps2.toFixed(1)}); replay advanced ${(t1 - t0).toFixed(2)} s`);
  await shot(page, '7-ten-robots');
  // The ball in the air (the log lifts it to 0.71 m around t = 1.57 s): its height is shown.
  await page.click('#rp-play');
  const box = await (await page.$('#rp-scrub')).boundingBox();
  await page.mouse.click(box.x + 8 + (box.width - 16) * (1.57 / 20), box.y + box.height / 2);
  await sleep(150);
  const z = await page.evaluate(() => window.canhilView.state().ball.z);
  assert.ok(z > 0.6, `ball at ${z} m`);
  await shot(page, '7-ball-in-the-air');
  const d = await page.evaluate(() => window.canhilView.drawn());
  assert.equal(d.robots.length, 10);
  assert.ok(Math.abs((t1 - t0) - wall) < 0.5, `1x: ${t1 - t0} s of replay in ${wall} s`);
  assert.ok(fps >= 30, `${fps.toFixed(1)} frames per second`);
  assert.deepEqual(page.errors, []);
});

test('8. two teams: a replay draws the second team in magenta and keeps the score', async () => {
  const dir = workDir('two-teams');
  const worldLog = join(dir, 'two.csv');
  execFileSync(CANHIL, ['run', '--virtual-time', '--config', join(SOURCE, 'emulator/scenarios/two_teams.toml'),
    '--duration', '2', '--world-log', worldLog, '--no-view', '--no-control'],
  { cwd: dir, env: rtdbEnv(), stdio: ['ignore', 'ignore', 'pipe'] });
  // Then the ball rolls into the +x goal, the one the first team attacks.
  const log = readLog(worldLog);
  const last = log.rows[log.rows.length - 1];
  const extra = [];
  for (let i = 1; i <= 20; i++) {
    const row = last.slice();
    row[0] = last[0] + 0.05 * i;
    row[1] = 7.5 + 0.1 * i;  // ball_x_m: past the goal line (9 m) from i = 16
    row[2] = 0;
    row[3] = 0.11;
    extra.push(row.map((v) => v.toFixed(4)).join(','));
  }
  writeFileSync(worldLog, `${readFileSync(worldLog, 'utf8')}${extra.join('\n')}\n`);
  const { page } = await view([worldLog]);
  const hello = await page.evaluate(() => window.canhilView.hello());
  assert.deepEqual(hello.teams.map((t) => [t.name, t.attacks_positive_x]), [['new', true], ['old', false]]);
  const teamOf = hello.robots.map((r) => r.team);
  assert.deepEqual(teamOf, [0, 0, 0, 0, 0, 1, 1, 1, 1, 1]);
  assert.deepEqual(hello.robots.map((r) => r.interface), [...Array(10).keys()].map((k) => `vcan${k}`));
  const box = await (await page.$('#rp-scrub')).boundingBox();
  const scrubTo = async (fraction) => {
    await page.mouse.click(box.x + 8 + (box.width - 16) * fraction, box.y + box.height / 2);
    await sleep(200);
  };
  await scrubTo(0.3);
  const state = await page.evaluate(() => window.canhilView.state());
  for (let i = 0; i < state.robots.length; ++i) {
    const colour = await bodyColour(page, hello, state.robots[i]);
    assert.equal(magenta(colour), teamOf[i] === 1, `robot ${i} (team ${teamOf[i]}) drawn ${colour}`);
  }
  const bar = () => page.$eval('#st-goals', (e) => e.textContent);
  assert.equal(await bar(), 'new 0 : 0 old');
  await scrubTo(1);
  assert.equal(await bar(), 'new 1 : 0 old', "the goal in the +x goal is the first team's");
  await shot(page, '8-two-teams-replay');
  assert.deepEqual(page.errors, []);
});

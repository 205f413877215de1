// What the browser tests share: Debian's chromium launched headless with
// puppeteer-core, canhil started with its viewer on a free port (the address
// read from its output), a second WebSocket to the server for the test's own
// questions (snapshot, step, ...), screenshots into $CANHIL_BROWSER_OUT.
import { spawn } from 'node:child_process';
import { mkdtempSync, mkdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { before, after } from 'node:test';
import puppeteer from 'puppeteer-core';

export const CANHIL = process.env.CANHIL;
if (!CANHIL) throw new Error('set CANHIL to the canhil binary (e.g. build/dev/app/canhil)');
export const OUT = process.env.CANHIL_BROWSER_OUT || mkdtempSync(join(tmpdir(), 'canhil-browser-'));
mkdirSync(OUT, { recursive: true });
export const SOURCE = new URL('../../', import.meta.url).pathname;
export const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/** A fresh work folder for one test file. */
export function workDir(name) {
  return mkdtempSync(join(tmpdir(), `canhil-browser-${name}-`));
}

// Each canhil its own RTDB key range, so tests (and a run beside them) do not share memory.
let rtdbCount = 0;
export function rtdbEnv() {
  rtdbCount += 1;
  return { ...process.env, RTDB_KEY: String(0x5e000000 + ((process.pid & 0xfff) << 12) + (rtdbCount << 8)) };
}

export async function launchBrowser() {
  const profile = mkdtempSync(join(tmpdir(), 'canhil-chromium-'));
  const browser = await puppeteer.launch({
    executablePath: CHROMIUM,
    headless: true,  // puppeteer passes --headless
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', `--user-data-dir=${profile}`],
  });
  const close = browser.close.bind(browser);
  browser.close = async () => {
    await close();
    rmSync(profile, { recursive: true, force: true });
  };
  return browser;
}

/**
 * Starts `canhil ARGS` and resolves when it prints "canhil run|view: viewer at URL".
 * Returns {child, url, output(), stop()}.
 */
export function startCanhil(args, cwd) {
  return new Promise((resolve, reject) => {
    const child = spawn(CANHIL, args, { cwd, env: rtdbEnv(), stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let done = false;
    const exited = new Promise((r) => child.on('exit', r));
    const stop = async () => {
      if (child.exitCode === null && child.signalCode === null) {
        child.kill('SIGINT');
        const t = setTimeout(() => child.kill('SIGKILL'), 5000);
        await exited;
        clearTimeout(t);
      }
    };
    const timer = setTimeout(() => {
      if (done) return;
      done = true;
      child.kill('SIGKILL');
      reject(new Error(`no viewer address from canhil ${args.join(' ')} in 60 s:\n${out}`));
    }, 60000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/canhil (?:run|view): viewer at (http:\/\/\S+)/);
      if (m && !done) {
        done = true;
        clearTimeout(timer);
        resolve({ child, url: m[1], output: () => out, stop });
      }
    });
    child.stderr.on('data', (d) => { out += d; });
    child.on('exit', (code, signal) => {
      if (done) return;
      done = true;
      clearTimeout(timer);
      reject(new Error(`canhil ${args.join(' ')} ended (${code ?? signal}) before its viewer was up:\n${out}`));
    });
  });
}

/** Opens the page and waits for the server's hello and a first state. */
// One browser for a test file, launched before its tests and closed after
// them, with what its tests started (runs, pages, connections) stopped first,
// newest first: `const shared = sharedBrowser(); ... shared.cleanup(run.stop)`.
export function sharedBrowser() {
  const shared = { browser: null, cleanups: [], cleanup(fn) { this.cleanups.push(fn); } };
  before(async () => { shared.browser = await launchBrowser(); });
  after(async () => {
    for (const c of shared.cleanups.reverse()) await c();
    if (shared.browser) await shared.browser.close();
  });
  return shared;
}

export async function openPage(browser, url, { viewport = { width: 1400, height: 950 }, beforeLoad = null } = {}) {
  const page = await browser.newPage();
  await page.setViewport(viewport);
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  if (beforeLoad) await page.evaluateOnNewDocument(beforeLoad);
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.canhilView && window.canhilView.hello() && window.canhilView.state(), { timeout: 20000 });
  page.errors = errors;
  return page;
}

export async function shot(page, name) {
  const path = join(OUT, `${name}.png`);
  await page.screenshot({ path });
  console.log(`screenshot ${path}`);
  return path;
}

/**
 * The test's own connection to the server: node's WebSocket when it has one
 * (node 22, or 20 with --experimental-websocket), else one opened inside the page.
 */
export class Control {
  static async open(url, page) {
    const c = new Control();
    c.page = page;
    c.wsUrl = url.replace(/^http/, 'ws').replace(/\/?(\?.*)?$/, (m, q) => `/ws${q || ''}`);
    c.nextId = 1;
    if (typeof globalThis.WebSocket === 'function') {
      c.pending = new Map();
      c.ws = new globalThis.WebSocket(c.wsUrl);
      await new Promise((resolve, reject) => {
        c.ws.onopen = resolve;
        c.ws.onerror = () => reject(new Error(`cannot open ${c.wsUrl}`));
      });
      c.ws.onmessage = (m) => {
        const msg = JSON.parse(m.data);
        if (msg.type !== 'reply') return;
        const p = c.pending.get(msg.id);
        if (p) { c.pending.delete(msg.id); p(msg); }
      };
      c.via = 'node';
    } else {
      c.via = 'page';
    }
    return c;
  }

  async ask(command, args = {}) {
    const request = { command, id: `test-${this.nextId++}`, ...args };
    if (this.via === 'node') {
      return new Promise((resolve, reject) => {
        const t = setTimeout(() => reject(new Error(`no reply to ${command} in 15 s`)), 15000);
        this.pending.set(request.id, (msg) => { clearTimeout(t); resolve(msg); });
        this.ws.send(JSON.stringify(request));
      });
    }
    return this.page.evaluate((wsUrl, req) => new Promise((resolve, reject) => {
      const ws = new WebSocket(wsUrl);
      const t = setTimeout(() => reject(new Error('no reply in 15 s')), 15000);
      ws.onmessage = (m) => {
        const msg = JSON.parse(m.data);
        if (msg.type === 'reply' && msg.id === req.id) { clearTimeout(t); ws.close(); resolve(msg); }
      };
      ws.onopen = () => ws.send(JSON.stringify(req));
      ws.onerror = () => reject(new Error('websocket'));
    }), this.wsUrl, request);
  }

  /** ask(), and fail the test on an error reply. */
  async must(command, args = {}) {
    const r = await this.ask(command, args);
    if (!r.ok) throw new Error(`${command} ${JSON.stringify(args)} refused: ${r.error}`);
    return r;
  }

  async snapshot() {
    return (await this.must('snapshot')).snapshot;
  }

  /** Polls snapshots until `predicate` holds; returns that snapshot. */
  async until(predicate, what, limitMs = 20000) {
    const end = Date.now() + limitMs;
    for (;;) {
      const s = await this.snapshot();
      if (predicate(s)) return s;
      if (Date.now() > end) throw new Error(`timed out waiting for ${what}; last snapshot ${JSON.stringify(s).slice(0, 400)}`);
      await sleep(100);
    }
  }

  close() {
    if (this.ws) this.ws.close();
  }
}

/** A mouse drag between two world points, aimed with canhilView.toScreen. */
export async function dragWorld(page, from, to, { button = 'left', modifier = null, steps = 10 } = {}) {
  const a = await page.evaluate((x, y) => window.canhilView.toScreen(x, y), from.x, from.y);
  const b = await page.evaluate((x, y) => window.canhilView.toScreen(x, y), to.x, to.y);
  if (modifier) await page.keyboard.down(modifier);
  await page.mouse.move(a.x, a.y);
  await page.mouse.down({ button });
  for (let k = 1; k <= steps; k++) await page.mouse.move(a.x + ((b.x - a.x) * k) / steps, a.y + ((b.y - a.y) * k) / steps);
  return {
    screenFrom: a,
    screenTo: b,
    release: async () => {
      await page.mouse.up({ button });
      if (modifier) await page.keyboard.up(modifier);
    },
  };
}

export const dist = (a, b) => Math.hypot(a.x - b.x, a.y - b.y);

/** A robot body's colour, [r, g, b], read back from the field's canvas beside
 * its centre (robot frame +x, clear of the front wedge and the number). */
export function bodyColour(page, hello, pose) {
  const a = pose.heading_deg * Math.PI / 180;
  return page.evaluate((x, y) => {
    const c = document.getElementById('field');
    const p = window.canhilView.toScreen(x, y);
    const box = c.getBoundingClientRect();
    const k = c.width / box.width;
    const d = c.getContext('2d').getImageData(Math.round((p.x - box.left) * k), Math.round((p.y - box.top) * k), 1, 1).data;
    return [d[0], d[1], d[2]];
  }, pose.x + 0.7 * hello.robot_radius_m * Math.cos(a), pose.y + 0.7 * hello.robot_radius_m * Math.sin(a));
}

/** The second team's magenta body, as field.js draws it. */
export const magenta = ([r, g, b]) => r > 90 && r > g + 50 && b > g + 30;

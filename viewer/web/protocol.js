// The page's side of the viewer protocol (docs/viewer.md): one WebSocket to
// /ws, JSON objects both ways, a request's id echoed in its reply. The
// connection comes back by itself after a close, with a growing pause.

const params = new URLSearchParams(location.search);
const token = params.get('token');

/** `path` with the page's ?token=... passed on (for /ws and /api). */
export function withToken(path) {
  if (!token) return path;
  return `${path}${path.includes('?') ? '&' : '?'}token=${encodeURIComponent(token)}`;
}

/** GET an /api path as JSON; throws with the server's status on a refusal. */
export async function getJson(path) {
  const response = await fetch(withToken(path), { cache: 'no-store' });
  if (!response.ok) throw new Error(`${path}: ${response.status} ${response.statusText}`);
  return response.json();
}

const REPLY_WAIT_MS = 15000;

export class Connection {
  /**
   * handlers: {hello(msg), state(msg), log(text), refused(command, error),
   *            status(kind, text)} with kind 'connecting' | 'open' | 'closed'.
   */
  constructor(handlers) {
    this.handlers = handlers;
    this.socket = null;
    this.nextId = 1;
    this.pending = new Map();  // id -> {resolve, command, timer}
    this.retryMs = 500;
    this.retryTimer = null;
  }

  open() {
    const scheme = location.protocol === 'https:' ? 'wss' : 'ws';
    const socket = new WebSocket(`${scheme}://${location.host}${withToken('/ws')}`);
    this.socket = socket;
    this.handlers.status('connecting', 'connecting…');
    socket.onopen = () => {
      this.retryMs = 500;
      this.handlers.status('open', 'connected');
    };
    socket.onmessage = (event) => this.receive(event.data);
    socket.onclose = () => {
      if (this.socket !== socket) return;
      this.failPending('the connection closed');
      const wait = this.retryMs;
      this.retryMs = Math.min(5000, this.retryMs * 2);
      this.handlers.status('closed', `disconnected — retrying in ${(wait / 1000).toFixed(1)} s`);
      this.retryTimer = setTimeout(() => this.open(), wait);
    };
  }

  get connected() {
    return this.socket !== null && this.socket.readyState === WebSocket.OPEN;
  }

  receive(text) {
    let msg;
    try {
      msg = JSON.parse(text);
    } catch {
      this.handlers.log(`a message from the server that is not JSON: ${String(text).slice(0, 80)}`, true);
      return;
    }
    switch (msg.type) {
      case 'hello': this.handlers.hello(msg); break;
      case 'state': this.handlers.state(msg); break;
      case 'log': this.handlers.log(String(msg.text)); break;
      case 'reply': this.reply(msg); break;
      default: break;  // a newer server's message this page does not know
    }
  }

  reply(msg) {
    const waiting = this.pending.get(msg.id);
    const command = waiting ? waiting.command : '?';
    if (!msg.ok) this.handlers.refused(command, msg.error || 'refused, no reason given');
    if (!waiting) return;
    clearTimeout(waiting.timer);
    this.pending.delete(msg.id);
    waiting.resolve(msg);
  }

  failPending(why) {
    for (const [, waiting] of this.pending) {
      clearTimeout(waiting.timer);
      waiting.resolve({ ok: false, error: why });
    }
    this.pending.clear();
  }

  /** Sends {command, id, ...args}; resolves with the reply ({ok: false, error} when none came). */
  ask(command, args = {}) {
    return new Promise((resolve) => {
      if (!this.connected) {
        this.handlers.refused(command, 'not connected: nothing sent');
        resolve({ ok: false, error: 'not connected' });
        return;
      }
      const id = this.nextId++;
      const timer = setTimeout(() => {
        this.pending.delete(id);
        this.handlers.refused(command, `no reply in ${REPLY_WAIT_MS / 1000} s`);
        resolve({ ok: false, error: 'no reply' });
      }, REPLY_WAIT_MS);
      this.pending.set(id, { resolve, command, timer });
      this.socket.send(JSON.stringify({ command, id, ...args }));
    });
  }
}

/** The ball's velocity from a state, whichever way the server spells it. */
export function ballVelocity(s) {
  const b = s.ball || {};
  if (typeof b.vx === 'number') return { x: b.vx, y: b.vy || 0, z: b.vz || 0 };
  if (s.ball_velocity) return s.ball_velocity;
  return null;
}

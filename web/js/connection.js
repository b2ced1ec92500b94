// connection.js -- one WebSocket to iird's /ws: hello, seq numbering, input-to-frame latency and
// reconnection with backoff. It knows the transport and the session life of docs/protocol.md, not
// what the messages mean to the page (main.js decides that).
//
// Latency: every input message (light, camera, params, scene) gets a seq and its send time; a frame
// whose header seq is s answers every pending input with seq <= s, and is reported with the send
// time of the newest such input (main.js takes the latency when the frame is on screen).
//
// Reconnect: after a close (daemon stopped, network gone, `busy`), retry after 250 ms, doubling up to
// 4 s, with some jitter so that many pages do not reconnect in step; the backoff resets at the next
// welcome. The page re-sends its state after that welcome (main.js). Except after the server closed
// an idle session (an `idle_timeout` error, then close 4000): state 'closed', no retry until the user
// asks (retryNow), so a forgotten tab does not hold a session forever.

import { hello, parseFrame, INPUT_TYPES, NO_SEQ, MAX_RATE } from './protocol.js';

const RETRY_FIRST_MS = 250;
const RETRY_MAX_MS = 4000;
const PENDING_MAX_AGE_MS = 10000;
const CLOSE_IDLE = 4000;

export class Connection {
    // url: ws(s)://host:port/ws. handlers: {status(info), welcome(msg, fresh: the first welcome on
    // this socket, i.e. a new session; later ones answer a hello sent again), message(msg),
    // frame(header, sentAt: performance.now() of the newest input it answers, or null), badFrame(error)}. token: optional hello token.
    constructor(url, handlers, { client = 'iir-web', token = null } = {}) {
        this.url = url;
        this.h = handlers;
        this.client = client;
        this.token = token;
        this.ws = null;
        this.ready = false; // welcome received on the current socket
        this.seq = 0;
        this.pending = []; // [{seq, t}] inputs not yet answered by a frame, seq increasing
        this.attempt = 0;
        this.retryTimer = 0;
        this.retryAt = 0;
        this.lastError = '';
        // A token bucket below the server's limit so a stuck key or a fast wheel never trips it.
        this.tokens = MAX_RATE * 0.8;
        this.tokensAt = performance.now();
        this.droppedSends = 0;
        this.session = null;
    }

    start() {
        this.open();
    }

    // Sends a message with the next seq (returns it), or returns -1 when not connected or over the
    // client's own rate budget (the page re-sends its state after the next welcome anyway).
    send(msg) {
        if (!this.ready || !this.ws || this.ws.readyState !== WebSocket.OPEN) return -1;
        if (!this.takeToken()) {
            this.droppedSends++;
            return -1;
        }
        return this.sendRaw(msg);
    }

    sendRaw(msg) {
        const seq = ++this.seq;
        if (this.seq >= NO_SEQ - 1) this.seq = 0;
        const text = JSON.stringify({ ...msg, seq });
        this.ws.send(text);
        if (INPUT_TYPES.has(msg.type)) this.pending.push({ seq, t: performance.now() });
        return seq;
    }

    takeToken() {
        const now = performance.now();
        const rate = MAX_RATE * 0.8;
        this.tokens = Math.min(rate, this.tokens + ((now - this.tokensAt) / 1000) * rate);
        this.tokensAt = now;
        if (this.tokens < 1) return false;
        this.tokens -= 1;
        return true;
    }

    // ---- socket life ----

    open() {
        this.retryTimer = 0;
        this.status('connecting');
        let ws;
        try {
            ws = new WebSocket(this.url);
        } catch (e) {
            this.lastError = String(e.message || e);
            this.scheduleRetry();
            return;
        }
        ws.binaryType = 'arraybuffer';
        this.ws = ws;
        ws.onopen = () => {
            const msg = hello(this.client);
            if (this.token) msg.token = this.token;
            this.sendRaw(msg);
        };
        ws.onmessage = (ev) => this.receive(ev.data);
        ws.onclose = (ev) => {
            if (this.ws !== ws) return;
            this.ws = null;
            this.ready = false;
            this.pending = [];
            if (ev.code !== 1000 && ev.code !== 1005 && ev.reason) this.lastError = `closed ${ev.code}: ${ev.reason}`;
            if (ev.code === CLOSE_IDLE) {
                this.status('closed');
                return;
            }
            this.scheduleRetry();
        };
        // onerror is always followed by onclose, which handles it.
        ws.onerror = () => {};
    }

    scheduleRetry() {
        const base = Math.min(RETRY_MAX_MS, RETRY_FIRST_MS * 2 ** this.attempt);
        const delay = base * (0.8 + 0.4 * Math.random());
        this.attempt++;
        this.retryAt = performance.now() + delay;
        this.retryTimer = setTimeout(() => this.open(), delay);
        this.status('disconnected');
    }

    // Skips the wait of the current backoff, or reconnects after an idle close (the "reconnect now"
    // button).
    retryNow() {
        if (this.ws) return;
        clearTimeout(this.retryTimer);
        this.attempt = 0;
        this.open();
    }

    status(state) {
        this.h.status({
            state,
            attempt: this.attempt,
            retryInMs: state === 'disconnected' ? Math.max(0, this.retryAt - performance.now()) : 0,
            session: this.session,
            error: this.lastError,
        });
    }

    // ---- incoming ----

    receive(data) {
        if (typeof data === 'string') {
            let msg;
            try {
                msg = JSON.parse(data);
            } catch (e) {
                console.warn('iir: server sent text that is not JSON:', data.slice(0, 200));
                return;
            }
            if (msg.type === 'welcome') {
                const fresh = !this.ready; // the first on this socket: a new session
                this.ready = true;
                this.attempt = 0;
                this.lastError = '';
                this.session = msg.session;
                this.status('connected');
                this.h.welcome(msg, fresh);
                return;
            }
            if (msg.type === 'error' && ['busy', 'unauthorized', 'idle_timeout'].includes(msg.code)) {
                this.lastError = `${msg.code}: ${msg.message}`;
            }
            this.h.message(msg);
            return;
        }
        let header;
        try {
            header = parseFrame(data);
        } catch (e) {
            this.h.badFrame(e);
            return;
        }
        this.h.frame(header, header.kind === 1 ? this.answer(header.seq) : null);
    }

    // Send time of the newest pending input with seq <= frameSeq, or null when the frame answers
    // none; drops the answered inputs and any older than PENDING_MAX_AGE_MS.
    answer(frameSeq) {
        const now = performance.now();
        let sentAt = null;
        if (frameSeq !== NO_SEQ) {
            let i = 0;
            while (i < this.pending.length && this.pending[i].seq <= frameSeq) i++;
            if (i > 0) sentAt = this.pending[i - 1].t;
            this.pending.splice(0, i);
        }
        while (this.pending.length && now - this.pending[0].t > PENDING_MAX_AGE_MS) this.pending.shift();
        return sentAt;
    }
}

// ws://host:port/ws for the page's own origin.
export function defaultUrl(loc = window.location) {
    const scheme = loc.protocol === 'https:' ? 'wss:' : 'ws:';
    return `${scheme}//${loc.host}/ws`;
}

// requests.js -- which request a reply belongs to: every message the page sends is remembered by its
// seq with its kind (params, scene, light, camera, pick, snapshot, record, save, hello) until a reply
// settles it, so an `error` can be charged to the request that caused it and a later success of the
// same kind can clear it. Not what the page shows about it (errors.js, curtain.js).
//
// How a request succeeds (docs/protocol.md): params, scene and hello by a `state` with their seq (a
// light move the server kept inside the scene too); pick, snapshot, record and save by their reply;
// light and camera by the first frame whose seq is at least theirs (the server's error replies are
// queued before any later frame, so a request still waiting then was accepted).

const MAX_KEPT = 512; // requests waiting at most; older ones are forgotten (their replies were lost)
const FRAME_ANSWERED = new Set(['light', 'camera']);

export class Requests {
    constructor() {
        this.waiting = new Map(); // seq -> {kind, seq, ...details}, in send order
    }

    // A message sent with seq; details are kept with it (e.g. the scene asked for).
    sent(seq, kind, details = {}) {
        if (!(seq > 0)) return;
        this.waiting.set(seq, { kind, seq, ...details });
        if (this.waiting.size > MAX_KEPT) this.waiting.delete(this.waiting.keys().next().value);
    }

    // The request with this seq, settled (removed), or null.
    take(seq) {
        if (seq === undefined || seq === null) return null;
        const r = this.waiting.get(seq) || null;
        this.waiting.delete(seq);
        return r;
    }

    // The request with this seq, still waiting, or null.
    peek(seq) {
        return this.waiting.get(seq) || null;
    }

    // A frame answering inputs up to frameSeq: the light and camera requests it settles (accepted).
    answeredByFrame(frameSeq) {
        const done = [];
        for (const [seq, r] of this.waiting) {
            if (seq > frameSeq) break;
            if (FRAME_ANSWERED.has(r.kind)) done.push(r);
        }
        for (const r of done) this.waiting.delete(r.seq);
        return done;
    }

    // A new session (reconnect): nothing sent before it will be answered.
    reset() {
        this.waiting.clear();
    }
}

// The kind of an error reply: that of the request it answers, else read from the field it names
// (`params.kmax` -> params), else 'other'.
export function errorKind(msg, request) {
    if (request) return request.kind;
    const head = (msg.field || '').split(/[.[]/)[0];
    const known = ['params', 'scene', 'light', 'camera', 'pick', 'snapshot', 'record', 'save', 'hello'];
    if (known.includes(head)) return head;
    if (head === 'action' || head === 'fps') return 'record';
    return 'other';
}

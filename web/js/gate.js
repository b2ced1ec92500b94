// gate.js -- which frames the page may show, so that the image is always the scene and method the
// panel says: none whose `generation` is below the newest `state`'s (a frame of the previous scene,
// method or parameters), and none while a switch (a `scene` or `params` message) waits for its
// `state` reply. The stats and domain messages of a frame go with it (they name their frame id;
// frame ids increase, so the first frame of the current generation marks where they start to count).
// Not how a switch looks (main.js greys the image, curtain.js says why).

export class FrameGate {
    constructor() {
        this.generation = 0; // of the newest state (or welcome) received
        this.pending = new Map(); // seq -> request: switches sent, not yet answered
        this.firstId = Infinity; // id of the first frame seen of `generation` or later
        this.lastScene = 0; // seq of the newest scene switch asked for
    }

    // A welcome: a session whose state has this generation (a new session after a reconnect starts
    // its frame ids again at 1, and nothing sent to the old one will be answered).
    reset(generation) {
        this.generation = generation;
        this.pending.clear();
        this.firstId = Infinity;
        this.lastScene = 0;
    }

    // A switch sent: nothing is shown until its state (or error) reply. Scene switches are
    // latest-wins (docs/protocol.md): a newer one replaces those still waiting, so the page waits
    // only for the reply of the last scene asked for (a lost reply of a replaced one cannot hold the
    // image; their states, of lower generations, show nothing anyway).
    asked(request) {
        if (request.kind === 'scene') {
            for (const [seq, r] of this.pending) if (r.kind === 'scene') this.pending.delete(seq);
            this.lastScene = request.seq;
        }
        this.pending.set(request.seq, request);
    }

    // Whether scene switch `seq` was replaced by a newer one.
    replaced(seq) {
        return this.lastScene > seq;
    }

    // The state reply (seq may be undefined for a state the client did not ask for). sameRender:
    // only encoding settings changed (exposure, quality...): the daemon re-encodes the image it has,
    // so the stats and domains of the frames before still describe what is shown (the frames
    // themselves, encoded with the old settings, are still not shown).
    stated(seq, generation, sameRender = false) {
        if (seq !== undefined) this.pending.delete(seq);
        if (generation > this.generation) {
            this.generation = generation;
            if (!sameRender) this.firstId = Infinity;
        }
    }

    // The switch with this seq was refused: the session shows what it showed.
    refused(seq) {
        this.pending.delete(seq);
    }

    get switching() {
        return this.pending.size > 0;
    }

    // Every frame header as it arrives; returns whether it may be shown.
    seen(h) {
        if (h.generation >= this.generation && h.frameId < this.firstId) this.firstId = h.frameId;
        return this.mayShow(h);
    }

    mayShow(h) {
        return this.pending.size === 0 && h.generation >= this.generation;
    }

    // Whether the stats or domain of frame `frameId` belong to what may be shown.
    belongs(frameId) {
        return this.pending.size === 0 && frameId >= this.firstId;
    }
}

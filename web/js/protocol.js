// protocol.js -- the wire format of docs/protocol.md as plain values: client message builders and
// the parser of the 44-byte binary frame header. No sockets, no DOM: connection.js sends what these
// build, view.js draws what parseFrame returns.

export const PROTOCOL_VERSION = 1;
export const FRAME_HEADER_BYTES = 44;
export const NO_SEQ = 0xffffffff; // a frame that answers no input yet
export const KIND_FRAME = 1; // JPEG
export const KIND_SNAPSHOT = 2; // PNG or EXR file
export const FLAG_CONVERGED = 1;
export const FLAG_REFINEMENT = 2;
export const FLAG_REENCODED = 4;

// Per docs/protocol.md: 65536 bytes per text message, 250 messages/s (bucket of 250, burst 500).
export const MAX_MESSAGE_BYTES = 65536;
export const MAX_RATE = 250;

// Messages that change what the next frame shows: a frame's header seq answers these (latency).
export const INPUT_TYPES = new Set(['light', 'camera', 'params', 'scene']);

// The `params` fields and their types and ranges are not written here: the welcome message carries
// every method's parameter table and the session settings' (panel.js builds the form from them).

// ---- client -> server ----

export function hello(client) {
    return { type: 'hello', protocol: PROTOCOL_VERSION, client };
}

// fields: any of position, direction, target (vectors), cone_angle, intensity.
export function light(fields) {
    return { type: 'light', ...fields };
}

// fields: any of position, target, up (vectors), fov.
export function camera(fields) {
    return { type: 'camera', ...fields };
}

export function params(fields) {
    return { type: 'params', ...fields };
}

export function scene(name) {
    return { type: 'scene', name };
}

// x, y: pixel position in the current frame, (0,0) top-left; clamped into [0, size) here so a drag
// that leaves the canvas still aims at its edge instead of drawing an out_of_range error.
export function pick(x, y, width, height) {
    const cx = Math.min(Math.max(x, 0), width - 0.001);
    const cy = Math.min(Math.max(y, 0), height - 0.001);
    return { type: 'pick', x: cx, y: cy };
}

export function snapshot(format) {
    return { type: 'snapshot', format };
}

export function recordStart(fps = 30) {
    return { type: 'record', action: 'start', fps };
}

export function recordStop() {
    return { type: 'record', action: 'stop' };
}

// ---- server -> client ----

// Parses a binary message (ArrayBuffer). Returns {kind, version, frameId, seq, width, height,
// renderMs, encodeMs, pass, flags, converged, refinement, reencoded, generation, payload (Uint8Array view)} or throws an
// Error saying what is wrong (bad magic, short message, payload length mismatch).
export function parseFrame(buf) {
    if (buf.byteLength < FRAME_HEADER_BYTES) {
        throw new Error(`binary message of ${buf.byteLength} bytes is shorter than a frame header`);
    }
    const dv = new DataView(buf);
    const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1), dv.getUint8(2), dv.getUint8(3));
    if (magic !== 'IIRF') throw new Error(`binary message has magic "${magic}", expected "IIRF"`);
    const headerLen = dv.getUint16(6, true);
    const payloadLen = dv.getUint32(36, true);
    if (headerLen < FRAME_HEADER_BYTES || headerLen + payloadLen > buf.byteLength) {
        throw new Error(`frame header length ${headerLen} + payload ${payloadLen} exceeds message of ${buf.byteLength} bytes`);
    }
    const flags = dv.getUint32(32, true);
    return {
        kind: dv.getUint8(4),
        version: dv.getUint8(5),
        frameId: dv.getUint32(8, true),
        seq: dv.getUint32(12, true),
        width: dv.getUint16(16, true),
        height: dv.getUint16(18, true),
        renderMs: dv.getFloat32(20, true),
        encodeMs: dv.getFloat32(24, true),
        pass: dv.getUint32(28, true),
        flags,
        converged: (flags & FLAG_CONVERGED) !== 0,
        refinement: (flags & FLAG_REFINEMENT) !== 0,
        reencoded: (flags & FLAG_REENCODED) !== 0,
        generation: dv.getUint32(40, true),
        payload: new Uint8Array(buf, headerLen, payloadLen),
    };
}

// A frame's render time as the page shows it (the image's line, the stats panel): "re-encoded" for a
// frame that was not rendered (only quality or exposure changed: the last image encoded again, its
// time 0), else the milliseconds, with two decimals under one (a fast frame never reads "0.0 ms").
export function renderTime(ms, reencoded) {
    if (reencoded) return 're-encoded';
    if (!(ms >= 0.005)) return '< 0.01 ms';
    return `${ms.toFixed(ms < 1 ? 2 : 1)} ms`;
}

// One line for an error reply: "light.cone_angle must be in (0, 90] degrees, got 120 [out_of_range]"
// (the field is named in front unless the server's message already names it).
export function describeError(msg) {
    let text = msg.message || 'error';
    if (msg.field && !text.includes(msg.field)) text = `${msg.field}: ${text}`;
    return `${text} [${msg.code || 'error'}]`;
}

// main.js -- wiring: the page's model of the session (scene, light, camera, params), the connection,
// and the views that show it. Owns what happens on welcome (adopt the server's state the first
// time, re-send ours after a reconnect), on state, stats, domain, pick, snapshot, record and error.
//
// window.iir is a read-only view for tests and the console: framesReceived, framesDrawn, lastFrame
// (header of the newest drawn frame), lastDomain, lastStats, connected, state, inputSeq (newest
// input sent), latencyMs.

import * as P from './protocol.js';
import { Connection, defaultUrl } from './connection.js';
import { View } from './view.js';
import { Controls } from './controls.js';
import { Panel } from './panel.js';
import { Charts } from './charts.js';
import { DomainView } from './domain.js';

const $ = (sel) => document.querySelector(sel);

const app = {
    framesReceived: 0,
    framesDrawn: 0,
    lastFrame: null,
    lastDomain: null,
    lastStats: null,
    connected: false,
    state: null, // {scene, light, camera, params}: the page's model, what it re-sends after a reconnect
    welcomed: false, // a welcome was ever received (later welcomes are reconnects or re-syncs)
    resync: false, // adopt the next welcome's state instead of re-sending ours
    lastLightSeq: 0, // seq of the newest light message sent (a `state` older than it keeps our light)
    lastCameraSeq: 0,
    exposureAsked: null, // exposure sent by the keys and not yet confirmed by a `state`
    exposureSeq: 0, // its seq
    latencyMs: null, // of the newest frame that answered an input
    frameLatencyMs: null, // of the newest frame, null when it answered no new input
    inputSeq: 0, // seq of the newest input (light, camera, params, scene) sent
    snapshot: null, // the `snapshot` text reply waiting for its binary message
};

const clone = (x) => JSON.parse(JSON.stringify(x));

// ---- views ----

const view = new View($('#viewport'));
const domainView = new DomainView($('#domain'), $('#domain-caption'));
const charts = new Charts($('#chart-phases').parentElement);

const conn = new Connection(defaultUrl(), {
    status: onStatus,
    welcome: onWelcome,
    message: onMessage,
    frame: onFrame,
    badFrame: (e) => console.warn(`iir: ${e.message}`),
}, { token: new URLSearchParams(location.search).get('token') });

// ---- sending ----

function send(msg) {
    const seq = conn.send(msg);
    if (seq > 0 && P.INPUT_TYPES.has(msg.type)) app.inputSeq = seq;
    return seq;
}

function sendLight(fields) {
    const seq = send(P.light(fields));
    if (seq > 0) app.lastLightSeq = seq;
    panel.setLight(app.state.light);
    return seq;
}

function sendCamera(fields) {
    const seq = send(P.camera(fields));
    if (seq > 0) app.lastCameraSeq = seq;
    panel.setCamera(app.state.camera);
    return seq;
}

// The model's params change only with the server's `state` reply (a refused edit changes nothing).
function sendParams(fields) {
    return send(P.params(fields));
}

const actions = {
    cone(delta) {
        const L = app.state.light;
        L.cone_angle = Math.min(90, Math.max(1, Math.round(L.cone_angle + delta)));
        sendLight({ cone_angle: L.cone_angle });
        panel.setLight(L);
    },
    // Key repeats add up before the state replies: the newest exposure asked for is the base.
    exposure(delta) {
        const base = app.exposureAsked ?? app.state.params.exposure ?? 0;
        app.exposureAsked = Math.min(20, Math.max(-20, base + delta));
        app.exposureSeq = sendParams({ exposure: app.exposureAsked });
    },
    snapshot: (format = 'png') => send(P.snapshot(format)),
    record() {
        send(panel.recording ? P.recordStop() : P.recordStart(30));
    },
    toggleVpls(on = !view.showVpls) {
        view.showVpls = on;
        $('#show-vpls').checked = on;
        view.drawOverlay();
    },
    help(show = $('#help').hidden) {
        $('#help').hidden = !show;
    },
    resetView: () => send(P.scene(app.state.scene)),
};

const controls = new Controls($('#stage'), view, {
    get light() {
        return app.state.light;
    },
    get camera() {
        return app.state.camera;
    },
}, { light: sendLight, camera: sendCamera, pick: send }, actions);

const panel = new Panel($('#panel'), {
    scene: (name) => send(P.scene(name)),
    params: sendParams,
    light(fields) {
        const L = app.state.light;
        if ('cone_angle' in fields) L.cone_angle = fields.cone_angle;
        if ('intensity' in fields) {
            // A number scales the colour so its largest channel equals it (as the server does).
            const m = Math.max(...L.intensity);
            const x = fields.intensity;
            L.intensity = m > 0 ? L.intensity.map((c) => (c * x) / m) : [x, x, x];
        }
        sendLight(fields);
    },
    camera(fields) {
        Object.assign(app.state.camera, fields);
        sendCamera(fields);
    },
    snapshot: actions.snapshot,
    record: actions.record,
    resetView: actions.resetView,
    fitSize() {
        const box = $('#viewport').getBoundingClientRect();
        const lim = app.limits || { max_width: 1920, max_height: 1080 };
        const w = Math.max(16, Math.min(lim.max_width, Math.floor(box.width / 8) * 8));
        const h = Math.max(16, Math.min(lim.max_height, Math.floor(box.height / 8) * 8));
        sendParams({ width: w, height: h });
    },
});

// ---- connection events ----

function onStatus(s) {
    app.connected = s.state === 'connected';
    app.status = s;
    controls.enabled = app.connected && !!app.state;
    showStatus();
}

function showStatus() {
    const s = app.status;
    const conn = $('#conn');
    conn.dataset.state = s.state;
    let text = s.state === 'connecting' ? 'connecting…' : s.state;
    if (s.state === 'closed') text = 'closed by the server';
    if (s.state === 'disconnected') {
        const secs = Math.max(0, (conn_retryAt() - performance.now()) / 1000);
        text = `disconnected · retry in ${secs.toFixed(1)} s`;
    }
    $('#conn-text').textContent = text;
    const offline = $('#offline');
    offline.hidden = s.state === 'connected' || (s.state === 'connecting' && !app.welcomed);
    $('#offline-text').textContent = s.error ? `${text}\n${s.error}` : text;
}

const conn_retryAt = () => conn.retryAt;
setInterval(() => {
    if (app.status && app.status.state === 'disconnected') showStatus();
    panel.tickRecording();
}, 200);

function onWelcome(w) {
    app.limits = w.limits;
    app.methods = w.methods;
    if (!app.welcomed || app.resync) {
        app.state = clone(w.state);
    } else {
        resend(app.state, w.state);
    }
    app.welcomed = true;
    app.resync = false;
    controls.enabled = true;
    panel.setWelcome({ ...w, state: app.state });
    showStatus();
}

// After a reconnect: the new session starts from the server's defaults; make it show what the page
// showed (scene first: it resets the light and camera, which follow).
function resend(mine, theirs) {
    if (mine.scene !== theirs.scene) send(P.scene(mine.scene));
    const L = mine.light;
    sendLight({ position: L.position, direction: L.direction, cone_angle: L.cone_angle, intensity: L.intensity });
    const C = mine.camera;
    sendCamera({ position: C.position, target: C.target, up: C.up, fov: C.fov });
    const diff = {};
    for (const [k, val] of Object.entries(mine.params)) if (theirs.params[k] !== val) diff[k] = val;
    if (Object.keys(diff).length) send(P.params(diff));
}

function onMessage(msg) {
    switch (msg.type) {
    case 'state':
        return onState(msg);
    case 'stats':
        app.lastStats = msg;
        charts.push(msg, app.frameLatencyMs);
        panel.setStats(msg, app.latencyMs, app.lastFrame);
        return;
    case 'domain':
        app.lastDomain = msg;
        view.setVpls(msg.vpls || null);
        domainView.update(msg, app.state && app.state.params.method);
        return;
    case 'pick':
        return controls.onPick(msg);
    case 'snapshot':
        app.snapshot = msg;
        return;
    case 'record':
        return onRecord(msg);
    case 'error':
        return onError(msg);
    default:
        console.warn(`iir: unexpected message type "${msg.type}"`);
    }
}

// A state after params/scene/hello. Our light and camera stay when we sent newer ones since.
function onState(msg) {
    const s = app.state;
    const fresh = msg.seq === undefined;
    if (msg.params.method !== s.params.method || msg.scene !== s.scene) {
        app.lastDomain = null; // the old method's or scene's VPLs mean nothing now
        view.setVpls(null);
    }
    s.scene = msg.scene;
    s.params = msg.params;
    if (fresh || msg.seq >= app.exposureSeq) app.exposureAsked = null;
    if (fresh || msg.seq >= app.lastLightSeq) s.light = msg.light;
    if (fresh || msg.seq >= app.lastCameraSeq) s.camera = msg.camera;
    panel.setState(s);
    domainView.update(app.lastDomain, s.params.method);
}

// A `record` reply: start (recording), stop (the script), or a scene switch while recording (the
// script of the old scene, and recording goes on).
function onRecord(msg) {
    panel.setRecording(!!msg.recording);
    if (msg.script) {
        const name = `light-path-${msg.script.scene || app.state.scene}.json`;
        download(new Blob([JSON.stringify(msg.script, null, 2) + '\n'], { type: 'application/json' }), name);
        panel.setRecordInfo(`${msg.keyframes} keyframes, ${Number(msg.duration).toFixed(1)} s → ${name}`);
    }
}

function onError(msg) {
    const text = P.describeError(msg);
    console.warn(`iir: server error: ${text}`);
    panel.showError(text, msg.field);
    const field = msg.field || '';
    if (field === 'record.action' || field === 'action') panel.setRecording(false);
    // A refused light or camera leaves the server's state as it was: fetch it again.
    if (/^(light|camera)/.test(field) && msg.code !== 'rate_limited') {
        app.resync = true;
        send(P.hello('iir-web'));
    }
}

// sentAt: when the newest input this frame answers was sent (null: it answers no new input). The
// input-to-frame latency is taken when the frame is on screen, decoding included.
function onFrame(h, sentAt) {
    if (h.kind === P.KIND_SNAPSHOT) return onSnapshotFile(h);
    if (h.kind !== P.KIND_FRAME) return;
    app.framesReceived++;
    h.sentAt = sentAt;
    view.show(h);
}

view.onDrawn = (h) => {
    app.framesDrawn++;
    app.frameLatencyMs = h.sentAt !== null ? performance.now() - h.sentAt : null;
    if (app.frameLatencyMs !== null) app.latencyMs = app.frameLatencyMs;
    const { payload, ...header } = h;
    app.lastFrame = { ...header, bytes: payload.byteLength, drawnAt: performance.now() };
    const pass = h.pass ? ` · pass ${h.pass}${h.converged ? ' converged' : ''}` : '';
    const lat = app.latencyMs !== null ? ` · ${app.latencyMs.toFixed(0)} ms` : '';
    $('#hud-frame').textContent = `${h.width}×${h.height} · frame ${h.frameId}${pass} · ${h.renderMs.toFixed(1)} ms render${lat}`;
};

function onSnapshotFile(h) {
    const info = app.snapshot || { format: 'png', frame: h.frameId };
    app.snapshot = null;
    const type = info.format === 'exr' ? 'image/x-exr' : 'image/png';
    const name = `iir-${app.state ? app.state.scene : 'frame'}-f${info.frame}${info.pass ? `-p${info.pass}` : ''}.${info.format}`;
    download(new Blob([h.payload], { type }), name);
    panel.setRecordInfo(`saved ${name} (${(h.payload.byteLength / 1024).toFixed(0)} KiB)`);
}

function download(blob, name) {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

// ---- page bits ----

$('#help-button').addEventListener('click', () => actions.help());
$('#help').addEventListener('click', () => actions.help(false));
$('#show-vpls').addEventListener('change', (e) => actions.toggleVpls(e.target.checked));
$('#retry-now').addEventListener('click', () => conn.retryNow());

window.iir = Object.freeze({
    get methods() {
        return app.methods; // welcome.methods: names, summaries, parameter tables
    },
    get framesReceived() {
        return app.framesReceived;
    },
    get framesDrawn() {
        return app.framesDrawn;
    },
    get lastFrame() {
        return app.lastFrame;
    },
    get lastDomain() {
        return app.lastDomain;
    },
    get lastStats() {
        return app.lastStats;
    },
    get inputSeq() {
        return app.inputSeq;
    },
    get latencyMs() {
        return app.latencyMs;
    },
    get connected() {
        return app.connected;
    },
    get state() {
        return app.state && clone(app.state);
    },
});

conn.start();

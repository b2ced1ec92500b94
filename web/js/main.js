// main.js -- wiring: the page's model of the session (scene, lights, camera, params), the connection,
// and the views that show it. Owns what happens on welcome (adopt the server's state the first
// time, re-send ours after a reconnect), on state, stats, domain, pick, snapshot, record, save and
// error: each reply is matched to the request it answers (requests.js), switches go through
// switcher.js and the frame gate (gate.js), errors become banners of their request's kind
// (errors.js), saves go to saving.js, and the stats and domain shown are those of the frame on
// screen (one frame counter everywhere). Of the session's lights one is selected: the one the mouse
// and the light controls move (at first the one the session moves by default, state.light).
//
// window.iir (inspect.js) is a read-only view of all this for tests and the console.

import * as P from './protocol.js';
import { Connection, defaultUrl } from './connection.js';
import { View } from './view.js';
import { Controls } from './controls.js';
import { Panel } from './panel.js';
import { Charts } from './charts.js';
import { DomainView } from './domain.js';
import { Requests, errorKind } from './requests.js';
import { ErrorBanners } from './errors.js';
import { FrameGate } from './gate.js';
import { Curtain } from './curtain.js';
import { Switcher } from './switcher.js';
import { SaveControls } from './saving.js';
import { inspector } from './inspect.js';
import { kindOf } from './gizmo.js';
import { vplStep } from './vplstats.js';
import * as v from './vec.js';

const $ = (sel) => document.querySelector(sel);

const app = {
    framesReceived: 0,
    framesDrawn: 0,
    framesHeld: 0,
    lastFrame: null,
    drawn: [], // {frameId, generation, pass, t} of the last DRAWN_KEPT frames drawn
    lastInteractiveId: 0, // id of the newest interactive frame received (a pass refines it)
    shown: null, // {frameId, pass, base}: the frame on screen
    stats: new Map(), // frame id -> its stats (the last STATS_KEPT)
    noDisk: new Set(), // methods whose domain messages have no disk (ir)
    lastDomain: null,
    lastStats: null,
    connected: false,
    state: null, // {scene, lights, light, camera, params}: the page's model, what it re-sends after a
    // reconnect; light is the entry of lights that a message without a name moves (linkLights)
    selected: 0, // index into state.lights of the light the mouse moves
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
    afterScene: null, // after a reconnect: sends the page's light and camera once its scene is back
    notesText: '', // the notice of what the method leaves out, as shown (showNotes)
};

const clone = (x) => JSON.parse(JSON.stringify(x));
const DRAWN_KEPT = 400;
// Settings the daemon applies by encoding the image again, not rendering it (docs/architecture.md).
const ENCODING_ONLY = new Set(['exposure', 'quality', 'refine', 'domain']);
const STATS_KEPT = 32;

// ---- views ----

const view = new View($('#viewport'));
const domainView = new DomainView($('#domain'), $('#domain-caption'), $('#domain-map'));
const charts = new Charts($('#chart-phases').parentElement);
const requests = new Requests();
const errors = new ErrorBanners($('#errors'));
const gate = new FrameGate();
const curtain = new Curtain($('#curtain'));
view.mayShow = (h) => gate.mayShow(h);

const conn = new Connection(defaultUrl(), {
    status: onStatus,
    welcome: onWelcome,
    message: onMessage,
    frame: onFrame,
    badFrame: (e) => console.warn(`iir: ${e.message}`),
}, { token: new URLSearchParams(location.search).get('token') });

// ---- sending ----

// Every message goes out here and is remembered with its kind (details: kept with it).
function send(msg, details = {}) {
    if (msg.type === 'scene' || msg.type === 'params') controls.flushInput(); // after the moves before it
    const seq = conn.send(msg);
    if (seq > 0 && P.INPUT_TYPES.has(msg.type)) app.inputSeq = seq;
    if (seq > 0) requests.sent(seq, msg.type, details);
    return seq;
}

// ---- the lights ----

// state.light is the entry of state.lights it names (the same object), so that a move of either is
// a move of both; an older server's state without lights gets a list of that one light.
function linkLights(s) {
    if (!s) return;
    if (!Array.isArray(s.lights) || !s.lights.length) s.lights = s.light ? [s.light] : [];
    const name = s.light && s.light.name;
    s.light = s.lights.find((L) => L.name === name) || s.lights[0] || null;
}

function selectedLight() {
    const s = app.state;
    return s && s.lights ? s.lights[app.selected] || s.light : null;
}

// Selects light i (the mouse and the light controls move it from now on).
function selectLight(i) {
    const s = app.state;
    if (!s || !s.lights || i < 0 || i >= s.lights.length) return;
    app.selected = i;
    panel.setLights(s.lights, i);
    showGizmo();
    showDomain();
}

// The selected light after a state (a new scene: the light it moves by default).
function keepSelection(newScene) {
    const s = app.state;
    const moved = Math.max(0, s.lights.indexOf(s.light));
    if (newScene || !(app.selected < s.lights.length)) app.selected = moved;
}

// The position sent is kept with the request: a `state` reply to it says where the daemon put the
// light instead (kept inside the scene), and the model moves by the difference. fields name the
// light (name).
function sendLight(fields) {
    const details = { name: fields.name };
    if (fields.position) details.position = fields.position;
    const seq = send(P.light(fields), details);
    if (seq > 0) app.lastLightSeq = seq;
    panel.setLights(app.state.lights, app.selected);
    showGizmo();
    return seq;
}

function sendCamera(fields) {
    const seq = send(P.camera(fields));
    if (seq > 0) app.lastCameraSeq = seq;
    panel.setCamera(app.state.camera);
    showGizmo();
    return seq;
}

function showGizmo() {
    const s = app.state;
    view.setGizmo(s && s.lights && s.lights.length && s.camera
        ? { lights: s.lights, selected: app.selected, camera: s.camera, madeUp: !!s.default_light }
        : null);
}

// The model's params change only with the server's `state` reply (a refused edit changes nothing).
function sendParams(fields) {
    return switcher.params(fields);
}

// Fields of the selected light changed in the panel (or by the keys): the model first, then the
// message naming it.
function editLight(fields) {
    const L = selectedLight();
    if (!L) return;
    if ('cone_angle' in fields) {
        L.cone_angle = fields.cone_angle;
        if (L.inner_angle > L.cone_angle) L.inner_angle = L.cone_angle;
    }
    if ('inner_angle' in fields) L.inner_angle = fields.inner_angle;
    if ('size' in fields) L.size = fields.size;
    if ('on' in fields) L.on = fields.on;
    if ('intensity' in fields) {
        // A number scales the colour so its largest channel equals it (as the server does).
        const m = Math.max(...L.intensity);
        const x = fields.intensity;
        L.intensity = m > 0 ? L.intensity.map((c) => (c * x) / m) : [x, x, x];
    }
    sendLight({ name: L.name, ...fields });
}

const actions = {
    cone(delta) {
        const L = selectedLight();
        if (!L || !(kindOf(L) === 'spot' || kindOf(L) === 'gltf_spot')) return; // only spots have a cone
        editLight({ cone_angle: Math.min(90, Math.max(1, Math.round(L.cone_angle + delta))) });
    },
    selectLight,
    nextLight() {
        const n = app.state && app.state.lights ? app.state.lights.length : 0;
        if (n > 1) selectLight((app.selected + 1) % n);
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
    resetView: () => switcher.scene(app.state.scene),
};

const controls = new Controls($('#stage'), view, {
    get light() {
        return selectedLight();
    },
    get camera() {
        return app.state.camera;
    },
}, { light: sendLight, camera: sendCamera, pick: send }, actions);

const panel = new Panel($('#panel'), {
    scene: (name) => switcher.scene(name),
    params: sendParams,
    light: editLight,
    selectLight,
    lightOn(i, on) {
        const L = app.state.lights[i];
        if (!L) return;
        L.on = on;
        sendLight({ name: L.name, on });
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

const switcher = new Switcher({
    gate,
    view,
    curtain,
    panel,
    send,
    state: () => app.state,
    methods: () => app.methods || [],
    busy: () => updateEnabled(),
});

const saving = new SaveControls($('#panel'), {
    send,
    download: (blob, name) => download(blob, name),
    scenes: (list, more) => listScenes(list, more),
    scene: () => app.state.scene,
});

// The scene picker's names; `more` saved scenes left out (welcome and save list the newest
// saved ones only): the `scenes` request brings them all.
function listScenes(list, more) {
    panel.setScenes(list);
    if (more) send({ type: 'scenes' });
}

// Light and camera input needs a session, and no scene switch waiting for its reply, a reset view
// included (the switch resets both: a move sent meanwhile would move the old scene's light, and the
// page would show it moved while the image shows the scene's own).
function updateEnabled() {
    controls.enabled = app.connected && !!app.state && !switcher.sceneLoading && switcher.pendingScene() === null;
}

// ---- connection events ----

function onStatus(s) {
    app.connected = s.state === 'connected';
    app.status = s;
    updateEnabled();
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

// newSession: the first welcome on a new socket (session ids start again when the daemon restarts).
function onWelcome(w, newSession) {
    app.limits = w.limits;
    app.methods = w.methods;
    if (newSession) {
        requests.reset();
        app.stats.clear();
        app.lastInteractiveId = 0;
    }
    requests.take(w.seq); // the hello it answers
    switcher.welcome(w, newSession);
    const first = !app.welcomed || app.resync;
    if (first) {
        const scene = app.state && app.state.scene;
        app.state = clone(w.state);
        linkLights(app.state);
        keepSelection(scene !== app.state.scene);
        showNotes(w.state.notes);
    }
    app.welcomed = true;
    app.resync = false;
    panel.setWelcome({ ...w, state: app.state }, app.selected);
    if (w.scenes_more) send({ type: 'scenes' });
    saving.setLimits(w.limits);
    if (!first) resend(app.state, w.state);
    else if (!app.framesDrawn) curtain.loading(`waiting for the first frame…`, `${app.state.scene} with ${app.state.params.method}`);
    updateEnabled();
    showGizmo();
    showDomain();
    showStatus();
}

// After a reconnect: the new session starts from the server's defaults; make it show what the page
// showed. Parameters first (the method must be one that renders the scene), then the scene, and the
// light and camera only once the scene is there (a scene switch resets both).
function resend(mine, theirs) {
    const keep = clone(mine);
    const diff = {};
    for (const [k, val] of Object.entries(keep.params)) if (theirs.params[k] !== val) diff[k] = val;
    if (Object.keys(diff).length) sendParams(diff);
    const lightAndCamera = () => {
        const s = app.state;
        s.lights = keep.lights;
        s.light = keep.light;
        linkLights(s);
        s.camera = keep.camera;
        for (const L of keep.lights) sendLight(lightFields(L));
        const C = keep.camera;
        sendCamera({ position: C.position, target: C.target, up: C.up, fov: C.fov });
    };
    app.afterScene = null;
    if (keep.scene === theirs.scene) return lightAndCamera();
    app.afterScene = lightAndCamera;
    switcher.scene(keep.scene, theirs.scene);
}

// Every field of light L that a `light` message sets, for its kind (a sun: no position).
function lightFields(L) {
    const k = kindOf(L);
    const f = { name: L.name, on: L.on !== false };
    if (k !== 'sun') f.position = L.position;
    if (k !== 'point') f.direction = L.direction;
    if (k === 'spot' || k === 'gltf_spot') f.cone_angle = L.cone_angle;
    if (k === 'gltf_spot') f.inner_angle = L.inner_angle;
    if (k === 'area') f.size = L.size;
    f.intensity = L.intensity;
    return f;
}

function onMessage(msg) {
    switch (msg.type) {
    case 'state':
        return onState(msg);
    case 'stats':
        return onStats(msg);
    case 'domain':
        return onDomain(msg);
    case 'pick':
        settled(msg);
        return controls.onPick(msg);
    case 'snapshot':
        settled(msg);
        app.snapshot = msg;
        return;
    case 'record':
        settled(msg);
        return onRecord(msg);
    case 'save':
        return saving.saved(msg, settled(msg));
    case 'scenes':
        settled(msg);
        return panel.setScenes(msg.scenes);
    case 'error':
        return onError(msg);
    default:
        console.warn(`iir: unexpected message type "${msg.type}"`);
    }
}

// A reply that settles its request: an error of that kind from before it goes.
function settled(msg) {
    const req = requests.take(msg.seq);
    if (req && !req.restore) errors.succeeded(req.kind, req.seq); // a restore says nothing of the error
    return req;
}

// A state after params/scene/hello, or after a light move the daemon kept inside the scene. Our
// light and camera stay when we sent newer ones since (a kept-inside light moves by the difference
// between the position sent and the position used).
// What the method leaves out of the scene (state.notes: a sun iir ignores, a second light's indirect
// light...): one notice, shown again only when the list changes (a dismissed one stays away). Only
// warnings (what is not rendered) go in it; notes (what was made of the scene: a lamp material that
// became the movable area light) are rendered, and are not news.
// Notes with the same kind and text are one line naming them all (as the commands print them:
// server/scene_notes.c), the first eight by name.
function groupNotes(notes) {
    const groups = new Map();
    for (const n of notes) {
        const key = `${n.kind}\u0000${n.what}`;
        if (!groups.has(key)) groups.set(key, { kind: n.kind, what: n.what, names: [] });
        groups.get(key).names.push(`'${n.name}'`);
    }
    return [...groups.values()].map((g) => {
        const shown = g.names.slice(0, 8).join(', ');
        const more = g.names.length > 8 ? ` and ${g.names.length - 8} more` : '';
        return `${g.kind}${g.names.length > 1 ? 's' : ''} ${shown}${more}: ${g.what}`;
    });
}

function showNotes(notes) {
    const text = groupNotes((notes || []).filter((n) => n.severity !== 'note')).join(' · ');
    if (text === app.notesText) return;
    app.notesText = text;
    if (text) errors.show('notes', text, 0, true);
    else errors.dismiss('notes');
}

function onState(msg) {
    // A scene switch replaced by a newer one before it began: answered, nothing changed (the
    // newer switch's own reply brings the state).
    if (msg.superseded) return switcher.stated(msg, settled(msg));
    const req = settled(msg);
    showNotes(msg.notes);
    const s = app.state;
    const fresh = msg.seq === undefined;
    const changed = Object.keys(msg.params).filter((k) => msg.params[k] !== s.params[k]);
    const sameRender = msg.scene === s.scene && changed.every((k) => ENCODING_ONLY.has(k));
    if (msg.params.method !== s.params.method || msg.scene !== s.scene) {
        app.lastDomain = null; // the old method's or scene's VPLs mean nothing now
        view.setVpls(null);
    }
    s.params = msg.params;
    s.generation = msg.generation;
    s.default_light = !!msg.default_light;
    if (fresh || msg.seq >= app.exposureSeq) app.exposureAsked = null;
    const newScene = msg.scene !== s.scene;
    takeLights(s, msg, req, fresh || msg.seq >= app.lastLightSeq);
    keepSelection(newScene);
    if (fresh || msg.seq >= app.lastCameraSeq) s.camera = msg.camera;
    switcher.stated(msg, req, sameRender);
    panel.setState(s, app.selected);
    panel.showScene(switcher.pendingScene()); // the picker says the scene on its way, not one passed
    if (req && req.kind === 'params' && req.fields && !req.restore) panel.clearFieldErrors(req.fields);
    saving.sceneChanged();
    if (req && req.kind === 'scene' && app.afterScene) {
        const then = app.afterScene;
        app.afterScene = null;
        then();
    }
    showGizmo();
    showDomain();
}

// A state's lights into the model s: all of them when no newer light message was sent since (all),
// else ours stay and a light kept inside the scene moves by the difference between the position
// sent (req) and the position used: shown where the user's gesture asked for, moved by that
// difference (controls.kept), so that moves go on from where the user asked, not from the wall.
function takeLights(s, msg, req, all) {
    const lights = msg.lights || (msg.light ? [msg.light] : []);
    s.scene = msg.scene;
    const kept = req && req.kind === 'light' && req.position ? lights.find((L) => L.name === req.name) : null;
    const shown = kept ? controls.kept(req.name, req.position, kept.position, req.seq) : null;
    if (all) {
        s.lights = lights;
        s.light = msg.light;
    } else if (kept && shown !== null) {
        const mine = s.lights.find((L) => L.name === req.name);
        if (mine) mine.position = shown || v.add(mine.position, v.sub(kept.position, req.position));
    }
    linkLights(s);
}

// Light moves a frame answered: the daemon used the positions sent (it kept none inside the
// scene, or a state would have said so first); a gesture's light is shown where it asked for.
function lightsAnswered(done) {
    const s = app.state;
    let moved = false;
    for (const r of done) {
        if (r.kind !== 'light' || !r.position || !s || !s.lights) continue;
        const shown = controls.kept(r.name, r.position, r.position, r.seq);
        const mine = s.lights.find((L) => L.name === r.name);
        if (!shown || !mine || v.length(v.sub(shown, mine.position)) < 1e-9) continue;
        mine.position = shown;
        moved = true;
    }
    if (!moved) return;
    panel.setLights(s.lights, app.selected);
    showGizmo();
}

function onStats(msg) {
    if (!gate.belongs(msg.frame)) return; // a frame of a state no longer shown
    app.lastStats = msg;
    charts.push(msg, app.frameLatencyMs);
    app.stats.set(msg.frame, msg);
    if (app.stats.size > STATS_KEPT) app.stats.delete(app.stats.keys().next().value);
    if (app.shown && app.shown.frameId === msg.frame) {
        panel.setStats(msg, app.latencyMs, app.lastFrame);
        showDomain(); // whether the frame on screen has VPLs to draw
    }
}

function onDomain(msg) {
    if (!gate.belongs(msg.frame)) return;
    app.lastDomain = msg;
    if (!msg.sites && app.state) app.noDisk.add(app.state.params.method);
    showDomain();
}

// The domain drawing of the frame on screen, or one line on why there is none; and the VPLs on the
// image, marked new only on the frame that inserted them (a refinement pass changes nothing): none
// when every light is off or the frame on screen has no VPLs (its stats say so; the last domain
// message is an older frame's). The daemon leaves out the VPLs the camera does not see.
function showDomain() {
    const d = app.lastDomain;
    const refined = !!(d && app.shown && app.shown.pass > 0 && app.shown.base === d.frame);
    const shownStats = app.shown ? app.stats.get(app.shown.frameId) : null;
    const dark = !!(app.state && app.state.lights && app.state.lights.length && app.state.lights.every((L) => L.on === false));
    const empty = dark || (shownStats && vplStep(shownStats).kind === 'none');
    view.setVpls(d && !empty ? d.vpls || null : null, !refined);
    const s = app.state;
    const m = s ? s.params.method : '';
    const row = s && app.methods ? app.methods.find((x) => x.name === m) : null;
    const hasVpls = !!(row && row.params.some((p) => p.name === 'vpls'));
    let note = `waiting for the first frame of ${m || 'the session'}`;
    if (row && !hasVpls) note = `${m} has no VPL domain`;
    else if (s && s.params.domain === false) note = 'the domain drawing is off (Frame & stream: domain)';
    else if (app.noDisk.has(m)) note = `${m} has no disk domain: it makes a new VPL set every frame (its VPLs are the dots on the image)`;
    // the domain drawn is the light the session moves by default (state.light), as iir draws it
    const of = s && s.lights && s.lights.length > 1 && s.light ? `light '${s.light.name}'` : '';
    domainView.update(hasVpls ? app.lastDomain : null, app.shown, note, of);
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

// An error belongs to the request that caused it: a banner of that kind, until a later request of
// the same kind succeeds or the user dismisses it. A refused switch puts the panel back.
function onError(msg) {
    const text = P.describeError(msg);
    console.warn(`iir: server error: ${text}`);
    let req = requests.take(msg.seq);
    // an error after the state of a switch: the session took it but cannot render it
    const late = !req && switcher.answeredSwitch(msg.seq);
    if (late) req = late;
    const kind = errorKind(msg, req);
    errors.show(kind, text, msg.seq || 0);
    panel.flagField(msg.field, text);
    if (late) {
        switcher.lateRefusal(msg, req);
        showDomain();
    } else if (req && (req.kind === 'scene' || req.kind === 'params')) {
        if (req.kind === 'scene') app.afterScene = null; // the light and camera of a scene not shown
        switcher.refused(msg, req);
        showDomain(); // the VPLs over the image shown again
    }
    if (kind === 'record') panel.setRecording(false);
    if (kind === 'save') saving.refused(msg);
    // A refused light or camera leaves the server's state as it was: fetch it again.
    if ((kind === 'light' || kind === 'camera') && msg.code !== 'rate_limited') {
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
    if (h.seq !== P.NO_SEQ) {
        const done = requests.answeredByFrame(h.seq);
        for (const r of done) errors.succeeded(r.kind, r.seq);
        lightsAnswered(done);
    }
    if (!h.pass) app.lastInteractiveId = h.frameId;
    h.base = h.pass ? app.lastInteractiveId : h.frameId;
    h.sentAt = sentAt;
    if (gate.seen(h)) view.show(h);
    else app.framesHeld++;
}

view.onDrawn = (h) => {
    app.framesDrawn++;
    app.frameLatencyMs = h.sentAt !== null ? performance.now() - h.sentAt : null;
    if (app.frameLatencyMs !== null) app.latencyMs = app.frameLatencyMs;
    const { payload, ...header } = h;
    app.lastFrame = { ...header, bytes: payload.byteLength, drawnAt: performance.now() };
    app.drawn.push({ frameId: h.frameId, generation: h.generation, pass: h.pass, t: performance.now() });
    if (app.drawn.length > DRAWN_KEPT) app.drawn.shift();
    app.shown = { frameId: h.frameId, pass: h.pass, base: h.base };
    const pass = h.pass ? ` · pass ${h.pass}${h.converged ? ' converged' : ''}` : '';
    const lat = app.latencyMs !== null ? ` · ${app.latencyMs.toFixed(0)} ms` : '';
    const render = h.reencoded ? 're-encoded, not rendered' : `${P.renderTime(h.renderMs)} render`;
    $('#hud-frame').textContent = `${h.width}×${h.height} · frame ${h.frameId}${pass} · ${render}${lat}`;
    const st = app.stats.get(h.frameId);
    if (st) panel.setStats(st, app.latencyMs, app.lastFrame);
    switcher.drawn();
    showDomain();
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

window.iir = inspector({ app, gate, controls, errors, curtain, view, charts, domainView, panel });

conn.start();

// controls.js -- mouse, wheel and keyboard on the image turned into light, camera and pick messages.
// They move the selected light (main.js keeps which one; a click on another light's gizmo selects
// it, N the next one). Moves change the page's model of the light and camera at once and mark the
// changed fields; one light message (naming its light) and one camera message with the newest
// values go out per animation frame (the server is latest-wins anyway), and at most one pick is in
// flight at a time.
//
//   drag             aim the spot at the point under the cursor (pick, then light.target)
//   shift-drag       move the light in the view plane        wheel        light along its axis
//   right-drag       orbit the camera around its target      shift-wheel  camera dolly
//   keys             see KEYS below (and the help overlay, index.html)
//
// A sun has no position: any left drag turns it (its arrow follows the cursor's motion) and the
// moves that would carry it (shift-drag, wheel, WASD, QE) do nothing.
// The arrows move the spot's light pool across the screen (left/right/up/down as the user sees it)
// by equal angles, also from straight down, where a yaw about the up axis would change nothing (see
// aimBy); on a point light (no axis) they move the light in the view plane instead.
// The daemon keeps a moved light inside the scene: main.js puts its position back into the model.
// Within one gesture (a shift-drag until the button goes up; wheel and key moves less than
// INTENT_MS apart) moves add up on the position the user asked for (intent), not on the kept one:
// the messages send it, the model shows it moved by the daemon's last difference (kept), so a move
// into a wall and back brings the light back to where it started.

import * as v from './vec.js';
import { pick as pickMsg } from './protocol.js';
import { isPoint, isSun } from './gizmo.js';

const AIM_STEP_DEG = 2; // arrows; shift: x5
const MOVE_STEP = 0.02; // WASD/QE, in units of the camera's distance to its target; shift: x5
const ORBIT_DEG_PER_PX = 0.3;
const ORBIT_STEP_DEG = 5; // IJKL
const WHEEL_STEP = 0.04; // light along its axis per wheel notch (100 deltaY), camera distances
const TURN_DEG_PER_PX = 0.25; // a sun turned by dragging
const DOLLY = 1.1;
const PICK_TIMEOUT_MS = 300; // a lost pick reply does not stall aiming
const INTENT_MS = 1000; // wheel and key moves closer together than this are one gesture

export class Controls {
    // stage: the element under the pointer; view: View; model: {light (the selected one), camera}
    // kept current by main.js; send: {light(fields), camera(fields), pick(msg) -> seq}; actions:
    // keyboard actions and selectLight(index).
    constructor(stage, view, model, send, actions) {
        this.stage = stage;
        this.view = view;
        this.model = model;
        this.send = send;
        this.actions = actions;
        this.enabled = false;
        this.drag = null; // {mode: 'aim'|'move'|'turn'|'orbit', x, y, id}
        this.pendingLight = null; // {name, ...fields} of the newest moves of one light
        this.pendingCamera = null;
        this.pendingPick = null; // {x, y} in frame pixels
        this.pickInFlight = null; // {seq, t}
        this.lastAim = null; // {name, position, distance}: the selected spot's last aim by the mouse
        // {name, position (asked for), diff (the daemon's last kept - asked), shown (the model's
        // position then), seq (of the newest light message whose outcome diff is), until (ms; a
        // drag holds it until the button goes up)}: see moveLight
        this.intent = null;
        this.lightSeq = 0; // of the newest light message sent
        this.orbitIntent = null; // {position, target}: the eye an orbit drag asked for last
        this.raf = 0;
        this.bind();
    }

    bind() {
        const s = this.stage;
        s.addEventListener('pointerdown', (e) => this.down(e));
        s.addEventListener('pointermove', (e) => this.move(e));
        s.addEventListener('pointerup', (e) => this.up(e));
        s.addEventListener('pointercancel', (e) => this.up(e));
        s.addEventListener('contextmenu', (e) => e.preventDefault());
        s.addEventListener('wheel', (e) => this.wheel(e), { passive: false });
        window.addEventListener('keydown', (e) => this.key(e));
    }

    // ---- pointer ----

    down(e) {
        if (!this.enabled || this.drag) return;
        let mode = null;
        if (e.button === 0) mode = e.shiftKey ? 'move' : 'aim';
        else if (e.button === 2) mode = 'orbit';
        if (!mode) return;
        e.preventDefault();
        if (e.button === 0 && this.selectAt(e)) return;
        if (mode !== 'orbit' && isSun(this.model.light)) mode = 'turn';
        this.stage.setPointerCapture(e.pointerId);
        this.drag = { mode, x: e.clientX, y: e.clientY, id: e.pointerId };
        this.stage.dataset.drag = mode;
        if (mode === 'aim') this.aimAt(e);
    }

    move(e) {
        const d = this.drag;
        if (!d || e.pointerId !== d.id) return;
        const dx = e.clientX - d.x;
        const dy = e.clientY - d.y;
        d.x = e.clientX;
        d.y = e.clientY;
        if (d.mode === 'aim') this.aimAt(e);
        else if (d.mode === 'move') this.moveLightInView(dx, dy);
        else if (d.mode === 'turn') this.turnBy(dx * TURN_DEG_PER_PX, -dy * TURN_DEG_PER_PX);
        else this.orbit(-dx * ORBIT_DEG_PER_PX, dy * ORBIT_DEG_PER_PX); // grab the scene
    }

    up(e) {
        if (!this.drag || e.pointerId !== this.drag.id) return;
        if (this.stage.hasPointerCapture(e.pointerId)) this.stage.releasePointerCapture(e.pointerId);
        if (this.drag.mode === 'move' && this.intent) this.intent.until = 0; // the next starts anew
        this.orbitIntent = null;
        this.drag = null;
        delete this.stage.dataset.drag;
        this.view.setMarker(null);
    }

    // A click on another light's gizmo selects that light (and starts no drag).
    selectAt(e) {
        const p = this.view.toFrame(e.clientX, e.clientY);
        const i = this.view.gizmoNear(p.x, p.y);
        if (i < 0 || this.view.gizmo && i === this.view.gizmo.selected) return false;
        this.actions.selectLight(i);
        return true;
    }

    aimAt(e) {
        const p = this.view.toFrame(e.clientX, e.clientY);
        this.pendingPick = { x: p.x, y: p.y };
        this.view.setMarker({ x: p.x, y: p.y, kind: 'aim' });
        this.schedule();
    }

    // The reply to a pick: aim the light at the hit point.
    onPick(msg) {
        if (this.pickInFlight && msg.seq >= this.pickInFlight.seq) this.pickInFlight = null;
        if (!msg.hit) {
            if (this.drag && this.view.marker) this.view.setMarker({ ...this.view.marker, kind: 'miss' });
            this.schedule();
            return;
        }
        const L = this.model.light;
        if (isSun(L)) return; // the drag turned into a turn (selection changed meanwhile)
        L.direction = v.normalize(v.sub(msg.position, L.position), L.direction);
        this.lastAim = { name: L.name, position: L.position.slice(), distance: v.length(v.sub(msg.position, L.position)) };
        this.queueLight({ target: msg.position });
    }

    wheel(e) {
        if (!this.enabled) return;
        e.preventDefault();
        const notches = -(e.deltaY || e.deltaX) / (e.deltaMode === 1 ? 3 : 100);
        if (e.shiftKey) this.dolly(Math.pow(DOLLY, -notches));
        else this.moveLightAlongAxis(notches * WHEEL_STEP * this.sceneScale());
    }

    // ---- light and camera moves (model first, message at the next animation frame) ----

    sceneScale() {
        const c = this.model.camera;
        return Math.max(1e-3, v.length(v.sub(c.target, c.position)));
    }

    // dx, dy in CSS pixels of the image: the light follows the cursor at its own depth.
    moveLightInView(dx, dy) {
        const c = this.model.camera;
        const L = this.model.light;
        const { f, r, u } = v.cameraBasis(c);
        let depth = v.dot(v.sub(L.position, c.position), f);
        if (!(depth > 1e-3)) depth = this.sceneScale();
        const worldPerPx = (2 * depth * Math.tan((c.fov * v.DEG) / 2)) / Math.max(1, this.view.cssH);
        this.moveLight(v.add(v.scale(r, dx * worldPerPx), v.scale(u, -dy * worldPerPx)));
    }

    moveLightAlongAxis(dist) {
        this.moveLight(v.scale(this.model.light.direction, dist));
    }

    // Moves the selected light by delta from the position asked for in this gesture (intent), or
    // from where it is when a new gesture starts (or the light was moved otherwise meanwhile: a
    // reset, another light selected). The model shows it moved by the daemon's last difference.
    moveLight(delta) {
        const L = this.model.light;
        if (isSun(L)) return; // its disk stays over the scene
        const now = performance.now();
        let i = this.intent;
        const held = i && i.name === L.name && (now < i.until || (this.drag && this.drag.mode === 'move')) &&
            v.length(v.sub(i.shown, L.position)) < 1e-4; // not moved otherwise (sent values are rounded)
        if (!held) i = { name: L.name, position: L.position, diff: [0, 0, 0], seq: this.lightSeq };
        const position = v.add(i.position, delta);
        L.position = v.add(position, i.diff);
        this.intent = { ...i, position, shown: L.position, until: now + INTENT_MS };
        this.queueLight({ position });
    }

    // The daemon used `used` where light message `seq` asked for `sent` (main.js: from the state
    // that answers it when it kept the light inside the scene, else from the frame that does, used =
    // sent): the position the model shows for light `name`, the one asked for in the last gesture
    // moved by that difference. null for an answer older than one already taken or than the
    // gesture (the model stays); undefined when no gesture moved that light.
    kept(name, sent, used, seq) {
        const i = this.intent;
        if (!i || i.name !== name) return undefined;
        if (!(seq > i.seq)) return null;
        i.seq = seq;
        i.diff = v.sub(used, sent);
        i.shown = v.add(i.position, i.diff);
        return i.shown;
    }

    // Tilts the spot's axis so its light pool moves right (rightDeg > 0) and up (upDeg > 0) on the
    // screen, by that angle whatever the aim (straight down too): the pool is taken as the point at
    // aimDistance() along the axis on a floor (a ceiling, or a wall facing the light, by where the
    // axis points), and the axis turns toward the
    // direction w (perpendicular to it) that moves that point's image the way asked (the 2x2 system
    // of the projection's derivative on the plane across the axis). Where that is undefined (the
    // point behind the camera, or its plane seen edge-on) the axis turns toward the screen direction
    // itself. A sun turns (turnBy); a point light moves instead.
    aimBy(rightDeg, upDeg) {
        const L = this.model.light;
        if (isSun(L)) return this.turnBy(rightDeg, upDeg);
        const c = this.model.camera;
        const { f, r, u } = v.cameraBasis(c);
        if (isPoint(L)) {
            const step = (MOVE_STEP * this.sceneScale()) / AIM_STEP_DEG;
            this.moveLight(v.add(v.scale(r, rightDeg * step), v.scale(u, upDeg * step)));
            return;
        }
        const angle = Math.hypot(rightDeg, upDeg) * v.DEG;
        if (!(angle > 0)) return;
        const d = v.normalize(L.direction);
        const sx = rightDeg / Math.hypot(rightDeg, upDeg);
        const sy = upDeg / Math.hypot(rightDeg, upDeg);
        // an orthonormal pair across the axis
        const e1 = v.sideOf(d, Math.abs(d[1]) < 0.9 ? [0, 1, 0] : [0, 0, 1]);
        const e2 = v.cross(d, e1);
        // the lit surface: a floor under a spot pointing down, a ceiling over one pointing up, else
        // a wall facing it; the pool slides on it by t(e) as the axis turns toward e
        const up = v.normalize(c.up || [0, 1, 0]);
        const du = v.dot(d, up);
        const n = du < -0.5 ? up : du > 0.5 ? v.scale(up, -1) : v.scale(d, -1);
        const slide = (e) => v.sub(e, v.scale(d, v.dot(e, n) / v.dot(d, n)));
        const q = v.sub(v.add(L.position, v.scale(d, this.aimDistance(L, Math.abs(du) > 0.5 ? Math.abs(du) : 1))), c.position);
        const z = v.dot(q, f);
        let w = null;
        if (z > 1e-6) {
            const x = v.dot(q, r) / z;
            const y = v.dot(q, u) / z;
            // screen motion (right, up) of the pool as the axis turns toward e: d(q.r / q.f), d(q.u / q.f)
            const J = (e0) => {
                const e = slide(e0);
                return [(v.dot(e, r) - x * v.dot(e, f)) / z, (v.dot(e, u) - y * v.dot(e, f)) / z];
            };
            const [a11, a21] = J(e1);
            const [a12, a22] = J(e2);
            const det = a11 * a22 - a12 * a21;
            const norm = Math.hypot(a11, a21) * Math.hypot(a12, a22);
            if (Math.abs(det) > 1e-3 * norm) {
                const a = (sx * a22 - sy * a12) / det;
                const b = (a11 * sy - a21 * sx) / det;
                const ab = v.add(v.scale(e1, a), v.scale(e2, b));
                if (v.length(ab) > 1e-9) w = v.normalize(ab);
            }
        }
        if (!w) {
            const s = v.add(v.scale(r, sx), v.scale(u, sy));
            w = v.normalize(v.sub(s, v.scale(d, v.dot(s, d))), e1);
        }
        L.direction = v.normalize(v.add(v.scale(d, Math.cos(angle)), v.scale(w, Math.sin(angle))), L.direction);
        this.queueLight({ direction: L.direction });
    }

    // How far along the axis the selected spot's pool is: the hit of its last aim by the mouse while
    // the light has not moved since, else the surface half the camera's distance to its target (the
    // scene's scale) away (cos: of the axis against the surface's normal).
    aimDistance(L, cos = 1) {
        const a = this.lastAim;
        if (a && a.name === L.name && v.length(v.sub(a.position, L.position)) < 1e-6 && a.distance > 1e-6) return a.distance;
        return (0.5 * this.sceneScale()) / cos;
    }

    // A sun turned by a drag: rotations about d x r and d x u, the axes that move d towards the
    // camera's right r and up u (its arrow follows the cursor's motion).
    turnBy(rightDeg, upDeg) {
        const L = this.model.light;
        const { r, u } = v.cameraBasis(this.model.camera);
        const about = (k, fallback) => (v.length(k) > 1e-3 ? v.normalize(k) : fallback);
        let d = v.normalize(L.direction);
        d = v.rotate(d, about(v.cross(d, r), u), rightDeg * v.DEG);
        d = v.rotate(d, about(v.cross(d, u), r), upDeg * v.DEG);
        L.direction = v.normalize(d, L.direction);
        this.queueLight({ direction: L.direction });
    }

    // Orbits the eye around the target; the elevation stays 2 degrees away from the poles. The
    // daemon keeps the eye in the room (in front of a wall it would pass): within one orbit drag the
    // orbit goes on from the eye asked for, so swinging back past the opening comes back out.
    orbit(yawDeg, pitchDeg) {
        const c = this.model.camera;
        const up = v.normalize(c.up || [0, 1, 0]);
        const i = this.orbitIntent;
        const held = i && this.drag && this.drag.mode === 'orbit' && v.length(v.sub(i.target, c.target)) < 1e-6;
        let off = v.sub(held ? i.position : c.position, c.target);
        off = v.rotate(off, up, yawDeg * v.DEG);
        const dist = v.length(off);
        const elev = Math.asin(Math.max(-1, Math.min(1, v.dot(off, up) / dist))) / v.DEG;
        const pitch = Math.max(-88 - elev, Math.min(88 - elev, pitchDeg));
        off = v.rotate(off, v.sideOf(v.scale(off, -1), up), -pitch * v.DEG);
        c.position = v.add(c.target, off);
        this.orbitIntent = { position: c.position, target: c.target.slice() };
        this.queueCamera({ position: c.position });
    }

    dolly(factor) {
        const c = this.model.camera;
        const off = v.scale(v.sub(c.position, c.target), factor);
        if (v.length(off) < 1e-3) return;
        c.position = v.add(c.target, off);
        this.queueCamera({ position: c.position });
    }

    // fields for the selected light; moves of another light still waiting go out first.
    queueLight(fields) {
        const name = this.model.light.name;
        if (this.pendingLight && this.pendingLight.name !== name) this.flushLight();
        const p = (this.pendingLight = { ...this.pendingLight, ...fields, name });
        if ('target' in fields) delete p.direction; // direction and target exclude each other
        if ('direction' in fields) delete p.target;
        this.schedule();
    }

    queueCamera(fields) {
        this.pendingCamera = { ...this.pendingCamera, ...fields };
        this.schedule();
    }

    schedule() {
        if (!this.raf) this.raf = requestAnimationFrame(() => this.flush());
    }

    // Once per animation frame: one pick (if none is in flight), one light, one camera message.
    flush() {
        this.raf = 0;
        const now = performance.now();
        if (this.pickInFlight && now - this.pickInFlight.t > PICK_TIMEOUT_MS) this.pickInFlight = null;
        if (this.pendingPick && !this.pickInFlight) {
            const { width, height } = this.view.frameSize();
            const seq = this.send.pick(pickMsg(this.pendingPick.x, this.pendingPick.y, width, height));
            if (seq >= 0) this.pickInFlight = { seq, t: now };
            this.pendingPick = null;
        }
        this.flushInput();
        if (this.pendingPick) this.schedule();
    }

    // The light and camera moves waiting for the next animation frame go now: a scene or params
    // message sent after them must not overtake them (the wire keeps the order the user acted in).
    flushInput() {
        this.flushLight();
        if (this.pendingCamera) {
            this.send.camera(roundFields(this.pendingCamera));
            this.pendingCamera = null;
        }
    }

    // Whether a light or camera move waits for the next animation frame (window.iir.inputPending).
    get inputPending() {
        return !!(this.pendingLight || this.pendingCamera);
    }

    flushLight() {
        if (!this.pendingLight) return;
        const seq = this.send.light(roundFields(this.pendingLight));
        if (seq > 0) this.lightSeq = seq;
        this.pendingLight = null;
    }

    // ---- keyboard ----

    key(e) {
        const t = e.target;
        if (t && (t.tagName === 'INPUT' || t.tagName === 'SELECT' || t.tagName === 'TEXTAREA')) return;
        if (e.ctrlKey || e.metaKey || e.altKey) return;
        const name = e.key.length === 1 ? e.key.toLowerCase() : e.key;
        const fn = KEYS[name];
        if (!fn) return;
        if (!this.enabled && !OFFLINE_KEYS.has(name)) return;
        e.preventDefault();
        fn(this, e.shiftKey ? 5 : 1);
    }
}

// key -> action(controls, multiplier). Documented in the help overlay and README.
const KEYS = {
    ArrowLeft: (c, m) => c.aimBy(-AIM_STEP_DEG * m, 0),
    ArrowRight: (c, m) => c.aimBy(AIM_STEP_DEG * m, 0),
    ArrowUp: (c, m) => c.aimBy(0, AIM_STEP_DEG * m),
    ArrowDown: (c, m) => c.aimBy(0, -AIM_STEP_DEG * m),
    w: (c, m) => c.moveLight(v.scale(v.cameraBasis(c.model.camera).u, MOVE_STEP * m * c.sceneScale())),
    s: (c, m) => c.moveLight(v.scale(v.cameraBasis(c.model.camera).u, -MOVE_STEP * m * c.sceneScale())),
    a: (c, m) => c.moveLight(v.scale(v.cameraBasis(c.model.camera).r, -MOVE_STEP * m * c.sceneScale())),
    d: (c, m) => c.moveLight(v.scale(v.cameraBasis(c.model.camera).r, MOVE_STEP * m * c.sceneScale())),
    e: (c, m) => c.moveLightAlongAxis(MOVE_STEP * m * c.sceneScale()),
    q: (c, m) => c.moveLightAlongAxis(-MOVE_STEP * m * c.sceneScale()),
    j: (c, m) => c.orbit(ORBIT_STEP_DEG * m, 0),
    l: (c, m) => c.orbit(-ORBIT_STEP_DEG * m, 0),
    i: (c, m) => c.orbit(0, ORBIT_STEP_DEG * m),
    k: (c, m) => c.orbit(0, -ORBIT_STEP_DEG * m),
    u: (c) => c.dolly(1 / DOLLY),
    o: (c) => c.dolly(DOLLY),
    '[': (c, m) => c.actions.cone(-5 * m),
    ']': (c, m) => c.actions.cone(5 * m),
    '{': (c) => c.actions.cone(-25),
    '}': (c) => c.actions.cone(25),
    '-': (c) => c.actions.exposure(-0.5),
    '=': (c) => c.actions.exposure(0.5),
    '+': (c) => c.actions.exposure(0.5),
    p: (c) => c.actions.snapshot(),
    r: (c) => c.actions.record(),
    v: (c) => c.actions.toggleVpls(),
    '0': (c) => c.actions.resetView(),
    n: (c) => c.actions.nextLight(),
    '?': (c) => c.actions.help(),
    h: (c) => c.actions.help(),
    Escape: (c) => c.actions.help(false),
};
const OFFLINE_KEYS = new Set(['?', 'h', 'Escape', 'v']); // work while disconnected

// Six decimals are plenty for a light or camera and keep the messages short.
function roundFields(fields) {
    const out = {};
    for (const [k, val] of Object.entries(fields)) out[k] = Array.isArray(val) ? v.round(val, 6) : val;
    return out;
}

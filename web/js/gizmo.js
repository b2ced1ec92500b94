// gizmo.js -- the lights drawn over the image so the user sees where they are, one gizmo per light,
// projected into the frame with the session's camera: a point light's star, a spot's cone (axis and
// rim; a glTF spot's inner cone dashed inside it), an area light's rectangle and the way it faces, a
// sun's arrow along the way its light travels through the middle of the scene (a sun has no position:
// the arrow's tail, a small sun, is its handle). The projection is core/src/camera.c's pinhole (f
// towards the target, r = f x up image right, u = r x f image up, vertical fov, aspect = width /
// height; pixel (0,0) top-left). The selected light (the one the mouse moves) is drawn in the scene
// light's colour, the others dimmer, a light switched off grey; a light made up by iird (the scene has
// none) dashed, in its own colour and labelled so. A light out of view gets an arrow at the frame's
// edge pointing at it. Drawing only; view.js calls it.

import * as v from './vec.js';

const NEAR = 1e-3; // points closer to the camera plane than this (or behind it) are not drawn
const CONE_LENGTH = 0.12; // slant length of the drawn cone, in camera-to-target distances
const SUN_LENGTH = 0.3; // length of a sun's arrow, in camera-to-target distances
export const COLORS = { scene: '#ffd23c', other: '#a0a8b8', off: '#6c6c6c', madeUp: '#5fd3ff' };

// World point p to frame pixels {x, y, z} (z: depth along the view direction), or null when p is
// behind the camera.
export function project(cam, width, height, p) {
    const { f, r, u } = v.cameraBasis(cam);
    const d = v.sub(p, cam.position);
    const z = v.dot(d, f);
    if (!(z > NEAR)) return null;
    const t = Math.tan(((cam.fov || 45) * v.DEG) / 2);
    const sx = v.dot(d, r) / (z * t * (width / height));
    const sy = v.dot(d, u) / (z * t);
    return { x: ((sx + 1) / 2) * width, y: ((1 - sy) / 2) * height, z };
}

// The light's kind as state.lights names it (point, spot, gltf_spot, sun, area); a light without
// one (an older server) is a spot unless it has no cone.
export function kindOf(L) {
    if (L.kind) return L.kind;
    return !(L.cone_angle > 0) || v.length(L.direction || [0, 0, 0]) < 1e-9 ? 'point' : 'spot';
}

export const isPoint = (L) => kindOf(L) === 'point';
export const isSpot = (L) => kindOf(L) === 'spot' || kindOf(L) === 'gltf_spot';
export const isSun = (L) => kindOf(L) === 'sun';
export const isArea = (L) => kindOf(L) === 'area';

const sceneScale = (cam) => Math.max(1e-3, v.length(v.sub(cam.target, cam.position)));

// Where a light is handled in the image (the point a click selects, the point an off-screen arrow
// points at): its position; a sun's, the tail of its arrow.
export function anchorOf(L, cam) {
    if (!isSun(L)) return L.position;
    return v.sub(L.position, v.scale(v.normalize(L.direction), SUN_LENGTH * sceneScale(cam)));
}

// The rim of a cone of half-angle alphaDeg: n points at slant length h from the apex.
function rim(L, alphaDeg, h, n) {
    const d = v.normalize(L.direction);
    const a = v.sideOf(d, Math.abs(d[1]) < 0.99 ? [0, 1, 0] : [0, 0, 1]);
    const b = v.cross(d, a);
    const alpha = Math.min(90, alphaDeg) * v.DEG;
    const c = v.add(L.position, v.scale(d, h * Math.cos(alpha)));
    const rho = h * Math.sin(alpha);
    const pts = [];
    for (let i = 0; i < n; i++) {
        const t = (2 * Math.PI * i) / n;
        pts.push(v.add(c, v.add(v.scale(a, rho * Math.cos(t)), v.scale(b, rho * Math.sin(t)))));
    }
    return { c, pts };
}

// The world point of an area light's light-local q = (x, y) in [-1/2, 1/2]^2: its frame is core's
// (f = direction, r = up x f, u = f x r).
function areaPoint(L) {
    const f = v.normalize(L.direction);
    let r = v.cross(L.up || [0, 1, 0], f);
    if (v.length(r) < 1e-5) r = v.cross(Math.abs(f[0]) < 0.9 ? [1, 0, 0] : [0, 0, 1], f);
    r = v.normalize(r);
    const u = v.cross(f, r);
    const [w, h] = L.size || [1, 1];
    return (x, y) => v.add(L.position, v.add(v.scale(r, x * w), v.scale(u, y * h)));
}

// An area light's (bounding) rectangle's corners.
export function areaCorners(L) {
    const at = areaPoint(L);
    return [at(-0.5, -0.5), at(0.5, -0.5), at(0.5, 0.5), at(-0.5, 0.5)];
}

// An area light's outline as world segments [[a, b], ...]: its rectangle's four sides, or for a
// shaped light (a disc lamp, an L-shaped panel: `shape`, light-local triangles) the edges that only
// one of its triangles has (inner edges shared by two are not drawn).
export function areaOutline(L) {
    const at = areaPoint(L);
    if (!Array.isArray(L.shape) || L.shape.length === 0) {
        const c = areaCorners(L);
        return c.map((p, i) => [p, c[(i + 1) % 4]]);
    }
    const key = (p) => `${p[0].toFixed(5)},${p[1].toFixed(5)}`;
    const count = new Map();
    const edges = [];
    for (const t of L.shape) {
        for (let k = 0; k < 3; k++) {
            const a = t[k];
            const b = t[(k + 1) % 3];
            const id = [key(a), key(b)].sort().join('|');
            count.set(id, (count.get(id) || 0) + 1);
            edges.push([id, a, b]);
        }
    }
    return edges.filter(([id]) => count.get(id) === 1).map(([, a, b]) => [at(a[0], a[1]), at(b[0], b[1])]);
}

// Where a light out of view is marked: the point of the frame's edge (inset by `inset` frame pixels)
// in the light's direction on screen from the centre, {x, y, dx, dy (unit, outwards), behind}.
export function edgeMark(cam, width, height, p, inset) {
    const { f, r, u } = v.cameraBasis(cam);
    const d = v.sub(p, cam.position);
    let dx = v.dot(d, r) / (width / height);
    let dy = -v.dot(d, u);
    const len = Math.hypot(dx, dy) || 1;
    dx /= len;
    dy /= len;
    const hw = width / 2 - inset;
    const hh = height / 2 - inset;
    const t = Math.min(Math.abs(dx) > 1e-9 ? hw / Math.abs(dx) : Infinity, Math.abs(dy) > 1e-9 ? hh / Math.abs(dy) : Infinity);
    return { x: width / 2 + dx * t, y: height / 2 + dy * t, dx, dy, behind: !(v.dot(d, f) > NEAR) };
}

// Text with a dark edge, readable on light and dark walls.
function label(o, text, x, y, colour, dpr, align = 'left') {
    o.font = `${11 * dpr}px system-ui, sans-serif`;
    o.textAlign = align;
    o.lineWidth = 3 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.75)';
    o.strokeText(text, x, y);
    o.fillStyle = colour;
    o.fillText(text, x, y);
}

// The name a gizmo is labelled with.
function title(g) {
    if (g.madeUp) return "iird's spot (the scene has no light)";
    const name = g.light.name || 'light';
    return g.light.on === false ? `${name} (off)` : name;
}

function colourOf(g) {
    if (g.light.on === false) return COLORS.off;
    if (g.madeUp) return COLORS.madeUp;
    return g.selected ? COLORS.scene : COLORS.other;
}

// A light outside the frame or behind the camera: an arrow at the frame's edge pointing towards it,
// labelled. Returns {x, y, visible: false, offscreen: true, behind} in frame pixels.
function drawEdgeMark(o, g, anchor, sx, sy, dpr, colour) {
    const m = edgeMark(g.camera, g.width, g.height, anchor, 16 * dpr / Math.min(sx, sy));
    const x = m.x * sx;
    const y = m.y * sy;
    const s = 9 * dpr;
    o.save();
    o.beginPath();
    o.moveTo(x + m.dx * s, y + m.dy * s);
    o.lineTo(x - m.dx * s - m.dy * s * 0.7, y - m.dy * s + m.dx * s * 0.7);
    o.lineTo(x - m.dx * s + m.dy * s * 0.7, y - m.dy * s - m.dx * s * 0.7);
    o.closePath();
    o.fillStyle = colour;
    o.fill();
    o.lineWidth = 1.5 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.8)';
    o.stroke();
    const where = m.behind ? 'behind the camera' : 'out of view';
    const align = m.dx > 0.3 ? 'right' : m.dx < -0.3 ? 'left' : 'center';
    label(o, `${g.madeUp ? 'light' : title(g)} (${where})`, x - m.dx * 16 * dpr, y - m.dy * 16 * dpr + (m.dy < 0 ? 10 * dpr : 0), colour, dpr, align);
    o.restore();
    return { x: m.x, y: m.y, visible: false, offscreen: true, behind: m.behind };
}

// The lines of the light's shape (not its handle) into the current path; P projects to overlay
// pixels (null behind the camera).
function shape(o, g, P, apex, dpr) {
    const L = g.light;
    const line = (a, b) => {
        if (!a || !b) return;
        o.moveTo(a[0], a[1]);
        o.lineTo(b[0], b[1]);
    };
    const ring = (pts) => pts.forEach((p, i) => line(p, pts[(i + 1) % pts.length]));
    const scale = sceneScale(g.camera);
    if (isPoint(L)) {
        const r = 11 * dpr;
        for (let i = 0; i < 8; i++) {
            const t = (Math.PI * i) / 4;
            line([apex[0] + 0.55 * r * Math.cos(t), apex[1] + 0.55 * r * Math.sin(t)], [apex[0] + r * Math.cos(t), apex[1] + r * Math.sin(t)]);
        }
    } else if (isArea(L)) {
        for (const [a, b] of areaOutline(L)) line(P(a), P(b));
        if (!Array.isArray(L.shape) || L.shape.length === 0) {
            const c = areaCorners(L).map(P);
            line(c[0], c[2]);
            line(c[1], c[3]);
        }
        line(apex, P(v.add(L.position, v.scale(v.normalize(L.direction), CONE_LENGTH * scale))));
    } else if (isSun(L)) {
        const head = P(L.position);
        line(apex, head);
        if (head) arrowHead(o, apex, head, 9 * dpr);
        for (let i = 0; i < 8; i++) {
            const t = (Math.PI * i) / 4;
            line([apex[0] + 7 * dpr * Math.cos(t), apex[1] + 7 * dpr * Math.sin(t)], [apex[0] + 11 * dpr * Math.cos(t), apex[1] + 11 * dpr * Math.sin(t)]);
        }
    } else {
        const { c, pts } = rim(L, L.cone_angle, CONE_LENGTH * scale, 48);
        const r = pts.map(P);
        ring(r);
        for (let i = 0; i < r.length; i += r.length / 4) line(apex, r[i]);
        line(apex, P(c));
    }
}

function arrowHead(o, from, to, s) {
    const dx = to[0] - from[0];
    const dy = to[1] - from[1];
    const len = Math.hypot(dx, dy) || 1;
    const [ux, uy] = [dx / len, dy / len];
    o.moveTo(to[0] - ux * s - uy * s * 0.5, to[1] - uy * s + ux * s * 0.5);
    o.lineTo(to[0], to[1]);
    o.lineTo(to[0] - ux * s + uy * s * 0.5, to[1] - uy * s - ux * s * 0.5);
}

// A glTF spot's inner cone, dashed inside the outer one.
function innerCone(o, g, P, dpr) {
    const L = g.light;
    if (kindOf(L) !== 'gltf_spot' || !(L.inner_angle > 0)) return;
    const r = rim(L, L.inner_angle, CONE_LENGTH * sceneScale(g.camera), 48).pts.map(P);
    o.beginPath();
    o.setLineDash([3 * dpr, 3 * dpr]);
    r.forEach((p, i) => {
        const q = r[(i + 1) % r.length];
        if (!p || !q) return;
        o.moveTo(p[0], p[1]);
        o.lineTo(q[0], q[1]);
    });
    o.stroke();
}

// g: {light, camera, madeUp, selected, width, height} (frame size in pixels); sx, sy: overlay
// pixels per frame pixel. Returns where the light's handle is drawn, in frame pixels: {x, y,
// visible}; a light out of view gets an arrow at the frame's edge instead ({x, y} the arrow's,
// visible false, offscreen).
export function drawGizmo(o, g, sx, sy, dpr) {
    const { light: L, camera: cam, width, height } = g;
    const P = (p) => {
        const q = project(cam, width, height, p);
        return q && [q.x * sx, q.y * sy];
    };
    const anchor = anchorOf(L, cam);
    const apex = P(anchor);
    const colour = colourOf(g);
    const inside = apex && apex[0] >= 0 && apex[1] >= 0 && apex[0] <= width * sx && apex[1] <= height * sy;
    if (!inside) return drawEdgeMark(o, g, anchor, sx, sy, dpr, colour);
    o.save();
    o.lineWidth = (g.selected ? 1.5 : 1.2) * dpr;
    o.strokeStyle = colour;
    o.setLineDash(g.madeUp || L.on === false ? [5 * dpr, 4 * dpr] : []);
    o.beginPath();
    shape(o, g, P, apex, dpr);
    o.stroke();
    innerCone(o, g, P, dpr);
    // The handle: a filled dot with a dark edge, readable on light and dark walls.
    o.setLineDash([]);
    o.beginPath();
    o.arc(apex[0], apex[1], (g.selected ? 5 : 4) * dpr, 0, 2 * Math.PI);
    o.fillStyle = colour;
    o.fill();
    o.lineWidth = 1.5 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.8)';
    o.stroke();
    label(o, title(g), apex[0] + 9 * dpr, apex[1] - 8 * dpr, colour, dpr);
    o.restore();
    return { x: apex[0] / sx, y: apex[1] / sy, visible: true };
}

// gizmo.js -- the light drawn over the image so the user sees where it is: its position and, for a
// spot, its cone (axis and rim), projected into the frame with the session's camera. The projection
// is core/src/camera.c's pinhole (f towards the target, r = f x up image right, u = r x f image up,
// vertical fov, aspect = width / height; pixel (0,0) top-left). A light made up by iird (the scene
// has none) is drawn dashed, in its own colour and labelled so. Drawing only; view.js calls it.

import * as v from './vec.js';

const NEAR = 1e-3; // points closer to the camera plane than this (or behind it) are not drawn
const CONE_LENGTH = 0.12; // slant length of the drawn cone, in camera-to-target distances
export const COLORS = { scene: '#ffd23c', madeUp: '#5fd3ff' };

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

export const isPoint = (L) => !(L.cone_angle > 0) || v.length(L.direction || [0, 0, 0]) < 1e-9;

// The cone's rim: n points at slant length h from the apex, in world space.
function rim(L, h, n) {
    const d = v.normalize(L.direction);
    const a = v.sideOf(d, Math.abs(d[1]) < 0.99 ? [0, 1, 0] : [0, 0, 1]);
    const b = v.cross(d, a);
    const alpha = Math.min(90, L.cone_angle) * v.DEG;
    const c = v.add(L.position, v.scale(d, h * Math.cos(alpha)));
    const rho = h * Math.sin(alpha);
    const pts = [];
    for (let i = 0; i < n; i++) {
        const t = (2 * Math.PI * i) / n;
        pts.push(v.add(c, v.add(v.scale(a, rho * Math.cos(t)), v.scale(b, rho * Math.sin(t)))));
    }
    return { c, pts };
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

// A light outside the frame or behind the camera: an arrow at the frame's edge pointing towards it,
// labelled. Returns {x, y, visible: false, offscreen: true, behind} in frame pixels.
function drawEdgeMark(o, g, sx, sy, dpr, colour) {
    const m = edgeMark(g.camera, g.width, g.height, g.light.position, 16 * dpr / Math.min(sx, sy));
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
    const label = m.behind ? 'light (behind the camera)' : 'light (out of view)';
    o.font = `${11 * dpr}px system-ui, sans-serif`;
    o.textAlign = m.dx > 0.3 ? 'right' : m.dx < -0.3 ? 'left' : 'center';
    const ty = y - m.dy * 16 * dpr + (m.dy < 0 ? 10 * dpr : 0);
    const tx = x - m.dx * 16 * dpr;
    o.lineWidth = 3 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.75)';
    o.strokeText(label, tx, ty);
    o.fillStyle = colour;
    o.fillText(label, tx, ty);
    o.restore();
    return { x: m.x, y: m.y, visible: false, offscreen: true, behind: m.behind };
}

// g: {light, camera, madeUp, width, height} (frame size in pixels); sx, sy: overlay pixels per frame
// pixel. Returns where the light's position is drawn, in frame pixels: {x, y, visible}; a light out
// of view gets an arrow at the frame's edge instead ({x, y} the arrow's, visible false, offscreen).
export function drawGizmo(o, g, sx, sy, dpr) {
    const { light: L, camera: cam, width, height } = g;
    const P = (p) => {
        const q = project(cam, width, height, p);
        return q && [q.x * sx, q.y * sy];
    };
    const apex = P(L.position);
    const colour = g.madeUp ? COLORS.madeUp : COLORS.scene;
    const inside = apex && apex[0] >= 0 && apex[1] >= 0 && apex[0] <= width * sx && apex[1] <= height * sy;
    if (!inside) return drawEdgeMark(o, g, sx, sy, dpr, colour);
    o.save();
    o.lineWidth = 1.5 * dpr;
    o.strokeStyle = colour;
    o.setLineDash(g.madeUp ? [5 * dpr, 4 * dpr] : []);
    const line = (a, b) => {
        if (!a || !b) return;
        o.moveTo(a[0], a[1]);
        o.lineTo(b[0], b[1]);
    };
    o.beginPath();
    if (isPoint(L)) {
        const r = 11 * dpr;
        for (let i = 0; i < 8; i++) {
            const t = (Math.PI * i) / 4;
            line([apex[0] + 0.55 * r * Math.cos(t), apex[1] + 0.55 * r * Math.sin(t)], [apex[0] + r * Math.cos(t), apex[1] + r * Math.sin(t)]);
        }
    } else {
        const scale = Math.max(1e-3, v.length(v.sub(cam.target, cam.position)));
        const { c, pts } = rim(L, CONE_LENGTH * scale, 48);
        const ring = pts.map(P);
        for (let i = 0; i < ring.length; i++) line(ring[i], ring[(i + 1) % ring.length]);
        for (let i = 0; i < ring.length; i += ring.length / 4) line(apex, ring[i]);
        line(apex, P(c));
    }
    o.stroke();
    // The position: a filled dot with a dark edge, readable on light and dark walls.
    o.setLineDash([]);
    o.beginPath();
    o.arc(apex[0], apex[1], 5 * dpr, 0, 2 * Math.PI);
    o.fillStyle = colour;
    o.fill();
    o.lineWidth = 1.5 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.8)';
    o.stroke();
    const label = g.madeUp ? "iird's spot (the scene has no light)" : 'light';
    o.font = `${11 * dpr}px system-ui, sans-serif`;
    o.lineWidth = 3 * dpr;
    o.strokeStyle = 'rgba(0,0,0,0.75)';
    o.strokeText(label, apex[0] + 9 * dpr, apex[1] - 8 * dpr);
    o.fillStyle = colour;
    o.fillText(label, apex[0] + 9 * dpr, apex[1] - 8 * dpr);
    o.restore();
    return { x: apex[0] / sx, y: apex[1] / sy, visible: true };
}

// vec.js -- 3-vectors as plain arrays [x, y, z] and the few operations the controls need (camera
// basis, rotations about an axis). No state.

export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [
    a[1] * b[2] - a[2] * b[1],
    a[2] * b[0] - a[0] * b[2],
    a[0] * b[1] - a[1] * b[0],
];
export const length = (a) => Math.sqrt(dot(a, a));
export const DEG = Math.PI / 180;

// a / |a|, or fallback when a is (nearly) zero.
export function normalize(a, fallback = [0, 0, -1]) {
    const l = length(a);
    return l > 1e-12 ? scale(a, 1 / l) : fallback.slice();
}

// Rodrigues: v rotated by angle (radians) about the unit axis k.
export function rotate(v, k, angle) {
    const c = Math.cos(angle);
    const s = Math.sin(angle);
    const kv = cross(k, v);
    const kdv = dot(k, v) * (1 - c);
    return [
        v[0] * c + kv[0] * s + k[0] * kdv,
        v[1] * c + kv[1] * s + k[1] * kdv,
        v[2] * c + kv[2] * s + k[2] * kdv,
    ];
}

// The camera's orthonormal frame: forward f, right r, up u (u is the true up, not the hint).
export function cameraBasis(cam) {
    const f = normalize(sub(cam.target, cam.position));
    let r = cross(f, cam.up || [0, 1, 0]);
    if (length(r) < 1e-6) r = cross(f, [1, 0, 0]);
    r = normalize(r);
    return { f, r, u: cross(r, f) };
}

// A unit vector perpendicular to d that lies as horizontal as the up hint allows (a light's right).
export function sideOf(d, up) {
    let r = cross(d, up);
    if (length(r) < 1e-6) r = cross(d, [1, 0, 0]);
    return normalize(r);
}

export const round = (a, digits = 4) => a.map((x) => Number(x.toFixed(digits)));
export const fmt = (a, digits = 2) => a.map((x) => x.toFixed(digits)).join(', ');

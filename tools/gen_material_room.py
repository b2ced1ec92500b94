#!/usr/bin/env python3
"""gen_material_room.py -- writes scenes/material_room/: a glTF 2.0 test room of glTF's material and
light features (material_room.gltf, material_room.bin, PNG textures in textures/), its sidecar
material_room.scene.json (light paths only), paths/*.json and SOURCE.md.

A closed room 6 x 3 x 5 m (metres, +y up; x in [-3, 3], y in [0, 3], z in [-2.5, 2.5]) with a window
in the right (+x) wall:
  - floor: procedural wood planks (sRGB base colour, no baseColorFactor, as Blender writes a linked
    texture), roughness 0.6, KHR_texture_transform scale [3, 3], REPEAT sampler;
  - back (-z) wall: procedural bricks (sRGB) with a tangent-space normal map made from the brick
    height field (mortar grooves), TANGENT attributes (w = +1);
  - two rows of UV spheres (32 x 16 segments) as Khronos' MetalRoughSpheres: copper metal and red
    dielectric at roughness 0.05, 0.25, 0.5, 0.75, 1.0, on a low plinth;
  - a box with a metallic-roughness texture (data PNG: G = roughness in 8 columns, B = metallic in
    4 rows);
  - an alpha-masked leaf card (two crossed quads, RGBA leaves, MASK at 0.5, double-sided) on a
    Lambertian box, in the sun that comes through the window;
  - an emissive sign (emissive texture, emissiveFactor 1, KHR_materials_emissive_strength 5);
  - a glossy white plastic box (roughness 0.2) and the Lambertian box (roughness 1);
  - KHR_lights_punctual spot (400 W), point (200 W) and sun (3 W/m^2), photometric as Blender's
    exporter writes them (P W -> P*683/(4 pi) cd, S W/m^2 -> S*683 lux); a perspective camera.

Standard library only (json, struct, zlib, math, random with fixed seeds). Deterministic: running it
twice gives byte-identical files (with the same zlib). The output is CC0 1.0.

Usage: tools/gen_material_room.py [REPO_ROOT]
"""
import json
import math
import os
import random
import struct
import sys
import zlib

ROOM_X, ROOM_Y, ROOM_Z = 3.0, 3.0, 2.5  # half width, height, half depth (m)
WINDOW = (0.3, 1.5, 0.9, 2.3)  # in the x = +3 wall: z0, z1, y0, y1 (m)
SPHERE_R, SPHERE_STACKS, SPHERE_SLICES = 0.2, 16, 32
ROUGHNESS = (0.05, 0.25, 0.5, 0.75, 1.0)
SPHERE_X = (-1.0, -0.5, 0.0, 0.5, 1.0)
PLINTH = ((-1.35, 1.35), 0.15, (-1.95, -0.75))  # x range, height, z range
METAL_Z, DIELECTRIC_Z = -1.6, -1.1  # sphere rows
COPPER, RED = (0.95, 0.64, 0.54), (0.8, 0.1, 0.1)
LM_PER_W = 683.0
SPOT_W, POINT_W, SUN_W_M2 = 400.0, 200.0, 3.0
SPOT_POS, SPOT_TARGET = (-1.2, 2.7, 0.9), (0.0, 0.35, -1.35)
POINT_POS = (1.8, 2.4, 1.5)
SUN_DIR = (-1.0, -0.8, -0.2)  # the way its light travels
CAMERA_POS, CAMERA_TARGET = (-2.5, 1.9, 2.3), (0.5, 0.85, -0.7)
CAMERA_YFOV, CAMERA_ASPECT = 0.9, 4.0 / 3.0
POT = (2.1, 0.75, 0.35)  # Lambertian box under the leaves: x, z, edge (m)
LEAF_SIZE, LEAF_TURN = 1.0, 20.0  # card width = height (m), turn about y (degrees)
MR_BOX = ((2.2, 0.0, -1.6), -20.0, 0.6)  # base centre, turn about y (degrees), edge (m)
PLASTIC_BOX = ((-1.95, 0.0, -0.2), 25.0, 0.5)
SIGN = (0.0, 2.3, 1.6, 0.4)  # centre x, centre y, width, height (m), 1 cm before the back wall
TEX_FLOOR_M, FLOOR_UV_SCALE = 2.0, 3  # metres of floor per copy of the plank texture; its
#   KHR_texture_transform scale (the floor's uvs run 0..1 over 6 m = TEX_FLOOR_M * FLOOR_UV_SCALE)
TEX_BRICK_M = 1.2  # metres of wall one copy of the brick texture covers

LINEAR, LINEAR_MIPMAP_LINEAR, REPEAT = 9729, 9987, 10497
FLOAT, USHORT = 5126, 5123
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


# ------------------------------------------------------------------ small vector helpers

def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


def r6(x):
    """A number for the JSON: 6 decimals, -0 as 0, whole numbers as ints."""
    v = round(x, 6) + 0.0
    return int(v) if v == int(v) else v


def rot(q):
    """A unit quaternion for the JSON: 9 decimals, so its length is 1 within float precision."""
    return [int(v) if v == int(v) else v for v in (round(c, 9) + 0.0 for c in q)]


def quat_from_basis(x, y, z):
    """Unit quaternion [x, y, z, w] of the rotation whose matrix has columns x, y, z."""
    m00, m10, m20 = x
    m01, m11, m21 = y
    m02, m12, m22 = z
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    if q[3] < 0:
        q = tuple(-c for c in q)
    return norm(q)


def look_rotation(forward, up=(0.0, 1.0, 0.0)):
    """Rotation taking the node's -z to forward, its +y as near up as possible (glTF's rule for
    cameras and lights)."""
    f = norm(forward)
    r = norm(cross(f, up))
    u = cross(r, f)
    return quat_from_basis(r, u, scale(f, -1.0))


def quat_y(degrees):
    a = math.radians(degrees) / 2
    return (0.0, math.sin(a), 0.0, math.cos(a))


# ------------------------------------------------------------------ PNG

def png(width, height, channels, pixels):
    """PNG bytes of 8-bit RGB (channels 3) or RGBA (4) rows: pixels is a bytearray, row by row.
    Each row gets the filter (None, Sub, Up, Average, Paeth) with the smallest sum of absolute
    values, the usual heuristic."""
    stride = width * channels
    raw = bytearray()
    prev = bytearray(stride)
    for y in range(height):
        row = pixels[y * stride:(y + 1) * stride]
        left = bytes(channels) + bytes(row[:-channels])
        ul = bytes(channels) + bytes(prev[:-channels])
        cands = [row,
                 bytearray((a - b) & 255 for a, b in zip(row, left)),
                 bytearray((a - b) & 255 for a, b in zip(row, prev)),
                 bytearray((a - ((b + c) >> 1)) & 255 for a, b, c in zip(row, left, prev))]
        paeth = bytearray(stride)
        for i in range(stride):
            a, b, c = left[i], prev[i], ul[i]
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            paeth[i] = (row[i] - pred) & 255
        cands.append(paeth)
        costs = [sum(v if v < 128 else 256 - v for v in c) for c in cands]
        best = costs.index(min(costs))
        raw.append(best)
        raw += cands[best]
        prev = row

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    colour_type = {3: 2, 4: 6}[channels]
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


# ------------------------------------------------------------------ procedural textures

def clamp8(v):
    return 0 if v < 0 else (255 if v > 255 else int(v + 0.5))


def smoothstep(e0, e1, x):
    t = min(1.0, max(0.0, (x - e0) / (e1 - e0)))
    return t * t * (3 - 2 * t)


class Noise:
    """Periodic value noise: a lattice of period cells x cells (so it tiles), smooth-interpolated."""

    def __init__(self, seed, cells_x, cells_y=None):
        rng = random.Random(seed)
        self.cx, self.cy = cells_x, cells_y or cells_x
        self.v = [[rng.random() for _ in range(self.cx)] for _ in range(self.cy)]

    def at(self, u, v):
        """u, v in lattice cells (any real; wraps)."""
        x0, y0 = math.floor(u), math.floor(v)
        fx, fy = u - x0, v - y0
        fx, fy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
        x0, y0 = x0 % self.cx, y0 % self.cy
        x1, y1 = (x0 + 1) % self.cx, (y0 + 1) % self.cy
        a = self.v[y0][x0] + (self.v[y0][x1] - self.v[y0][x0]) * fx
        b = self.v[y1][x0] + (self.v[y1][x1] - self.v[y1][x0]) * fx
        return a + (b - a) * fy


def floor_texture(n=512):
    """Wood planks running along u: 8 rows of 64 px (0.25 m), planks of random length with a
    random per-plank tint, grain lines along the plank, dark gaps between planks. Tiles."""
    rng = random.Random(11)
    rows, rh = 8, n // 8
    grain = Noise(12, 4, 32)
    fine = Noise(13, 64, 128)
    planks = []  # per row: sorted start columns and a tint per plank
    for r in range(rows):
        cuts, x = [], rng.randrange(0, n // 2)
        while True:
            cuts.append(x % n)
            x += rng.choice((160, 192, 224, 256, 288))
            if x >= cuts[0] + n - 96:
                break
        cuts.sort()
        tints = [(rng.uniform(0.78, 1.18), rng.uniform(-0.06, 0.06), rng.random() * 100) for _ in cuts]
        planks.append((cuts, tints))
    px = bytearray(n * n * 3)
    for y in range(n):
        r = y // rh
        yin = y - r * rh
        cuts, tints = planks[r]
        for x in range(n):
            k = len(cuts) - 1
            for i, c in enumerate(cuts):
                if x >= c:
                    k = i
            if x < cuts[0]:
                k = len(cuts) - 1
            start = cuts[k]
            dx = (x - start) % n
            bright, hue, off = tints[k]
            gap = yin < 2 or dx < 2
            # grain: stretched noise along u, as rings, plus fine fibres
            g = grain.at((x + off * 7) / n * 4, (y + off) / n * 32 + 0.5 * math.sin(x / 37.0 + off))
            ring = 0.5 + 0.5 * math.sin(g * 28.0 + yin * 0.35)
            f = fine.at(x / n * 64, y / n * 128)
            s = bright * (0.78 + 0.16 * ring + 0.10 * f)
            cr, cg, cb = 168 * s * (1 + hue), 112 * s, 64 * s * (1 - hue)
            if gap:
                cr, cg, cb = cr * 0.35, cg * 0.33, cb * 0.3
            i = (y * n + x) * 3
            px[i], px[i + 1], px[i + 2] = clamp8(cr), clamp8(cg), clamp8(cb)
    return png(n, n, 3, px)


def brick_height(n=512):
    """Height field of running-bond bricks: 16 courses of 32 px (7.5 cm at 1.2 m per texture),
    bricks of 128 px (30 cm), 4 px mortar; 1 on a brick face, bevelled over 3 px to the mortar
    (0.15 with a little noise). Also each pixel's brick id (-1 in mortar). Tiles."""
    course, blen, mortar = 32, 128, 4
    nz = Noise(21, 64)
    h = [0.0] * (n * n)
    ids = [-1] * (n * n)
    for y in range(n):
        c = y // course
        yin = y - c * course
        shift = 0 if c % 2 == 0 else blen // 2
        for x in range(n):
            xs = (x + shift) % n
            b = xs // blen
            xin = xs - b * blen
            # distance to the brick's edge (the mortar is the 4 px at the low end of each cell)
            d = min(xin - mortar, blen - 1 - xin, yin - mortar, course - 1 - yin)
            noise = nz.at(x / n * 64, y / n * 64)
            if d < 0:
                v = 0.12 + 0.06 * noise
            else:
                v = 0.15 + 0.85 * smoothstep(-0.5, 3.0, d) + 0.04 * (noise - 0.5)
                ids[y * n + x] = c * 16 + b
            h[y * n + x] = v
    return h, ids


def brick_textures(n=512):
    h, ids = brick_height(n)
    rng = random.Random(22)
    tint = [(rng.uniform(0.8, 1.15), rng.uniform(-0.08, 0.08)) for _ in range(16 * 16)]
    speck = Noise(23, 128)
    col = bytearray(n * n * 3)
    nrm = bytearray(n * n * 3)
    strength = 2.5  # tangent-space slope per unit of height per pixel
    for y in range(n):
        for x in range(n):
            i = y * n + x
            s = speck.at(x / n * 128, y / n * 128)
            if ids[i] < 0:
                cr, cg, cb = (178 + 30 * s, 172 + 30 * s, 160 + 30 * s)
            else:
                t, hue = tint[ids[i]]
                t *= 0.85 + 0.3 * s
                cr, cg, cb = 150 * t * (1 + hue), 62 * t, 44 * t * (1 - hue)
                if h[i] < 0.9:  # the bevel is a little darker
                    f = 0.8 + 0.2 * h[i]
                    cr, cg, cb = cr * f, cg * f, cb * f
            j = i * 3
            col[j], col[j + 1], col[j + 2] = clamp8(cr), clamp8(cg), clamp8(cb)
            # normal: X right (+u), Y up (towards row 0, i.e. -v), Z out of the surface
            dhdx = (h[y * n + (x + 1) % n] - h[y * n + (x - 1) % n]) * 0.5
            dhdy = (h[((y + 1) % n) * n + x] - h[((y - 1) % n) * n + x]) * 0.5  # down the image
            nx, ny, nz = -strength * dhdx, strength * dhdy, 1.0
            m = math.sqrt(nx * nx + ny * ny + nz * nz)
            nrm[j] = clamp8((nx / m * 0.5 + 0.5) * 255)
            nrm[j + 1] = clamp8((ny / m * 0.5 + 0.5) * 255)
            nrm[j + 2] = clamp8((nz / m * 0.5 + 0.5) * 255)
    return png(n, n, 3, col), png(n, n, 3, nrm)


def mr_texture(n=256):
    """glTF metallic-roughness data: R unused (255), G = roughness in 8 columns from 1/16 to
    15/16, B = metallic alternating 0 and 1 in 4 rows."""
    px = bytearray(n * n * 3)
    for y in range(n):
        metal = 255 if (y * 4 // n) % 2 == 0 else 0
        for x in range(n):
            rough = clamp8(((x * 8 // n) + 0.5) / 8 * 255)
            i = (y * n + x) * 3
            px[i], px[i + 1], px[i + 2] = 255, rough, metal
    return png(n, n, 3, px)


def leaf_texture(n=256):
    """RGBA leaves on a stem: alpha 255 on the stem and the leaves, 0 elsewhere (the colour there
    is the leaves' mean green, so filtering at the cut-out's edge shows no dark fringe)."""
    rng = random.Random(31)
    rgba = bytearray(n * n * 4)
    bg = (64, 112, 40)
    for i in range(n * n):
        rgba[i * 4:i * 4 + 4] = bytes((bg[0], bg[1], bg[2], 0))

    def stem_x(y):
        return n / 2 + 8 * math.sin((n - y) / n * 3.0)

    # (stem point y, angle from straight up in degrees: + to the right, length, width)
    leaves = [(72, 0, 62, 26)]
    y = 214
    side = 1
    while y > 96:
        leaves.append((y, side * rng.uniform(48, 68), rng.uniform(64, 84), rng.uniform(26, 34)))
        side = -side
        y -= rng.uniform(17, 23)
    for (ly, ang, length, width) in leaves:
        sx, sy = stem_x(ly), ly
        a = math.radians(ang)
        ux, uy = math.sin(a), -math.cos(a)  # along the leaf (image y grows downwards)
        vx, vy = -uy, ux
        shade = rng.uniform(0.85, 1.15)
        ex, ey = sx + ux * length, sy + uy * length  # the leaf's tip
        x0, x1 = int(max(0, min(sx, ex) - width)), int(min(n, max(sx, ex) + width))
        y0, y1 = int(max(0, min(sy, ey) - width)), int(min(n, max(sy, ey) + width))
        for py in range(max(4, y0), min(n - 4, y1 + 1)):
            for qx in range(max(4, x0), min(n - 4, x1 + 1)):
                dx, dy = qx + 0.5 - sx, py + 0.5 - sy
                s, t = dx * ux + dy * uy, dx * vx + dy * vy
                if not 0 < s < length:
                    continue
                half = 0.5 * width * math.sin(math.pi * s / length) ** 0.8
                if abs(t) > half:
                    continue
                g = s / length
                vein = abs(t) < 1.2 or abs((s - abs(t) * 1.4) % 14 - 7) < 0.8
                f = shade * (0.75 if vein else 1.0) * (0.85 + 0.25 * g)
                k = (py * n + qx) * 4
                rgba[k:k + 4] = bytes((clamp8(55 * f), clamp8(128 * f), clamp8(38 * f), 255))
    for py in range(72, n - 4):
        cx = stem_x(py)
        for qx in range(int(cx - 3), int(cx + 4)):
            if abs(qx + 0.5 - cx) <= 2.2:
                k = (py * n + qx) * 4
                rgba[k:k + 4] = bytes((84, 96, 40, 255))
    return png(n, n, 4, rgba)


def sign_texture(w=256, h=64):
    """Emission of a sign: a thin cyan frame and two lines of warm "words" (rounded bars) on black."""
    rng = random.Random(41)
    px = bytearray(w * h * 3)

    def put(x, y, c):
        i = (y * w + x) * 3
        px[i], px[i + 1], px[i + 2] = c

    for x in range(w):
        for y in range(h):
            if x in (3, 4, w - 5, w - 4) and 3 <= y <= h - 4 or y in (3, 4, h - 5, h - 4) and 3 <= x <= w - 4:
                put(x, y, (40, 210, 230))
    for (top, bh, scale_) in ((14, 14, 1.0), (38, 10, 0.8)):
        x = 14
        while True:
            ln = rng.randrange(14, 44)
            if x + ln > w - 14:
                break
            r = bh / 2
            for yy in range(top, top + bh):
                for xx in range(x, x + ln):
                    cx = min(max(xx + 0.5, x + r), x + ln - r)
                    if (xx + 0.5 - cx) ** 2 + (yy + 0.5 - (top + r)) ** 2 <= r * r:
                        put(xx, yy, (clamp8(255 * scale_), clamp8(186 * scale_), clamp8(92 * scale_)))
            x += ln + rng.randrange(7, 12)
    return png(w, h, 3, px)


# ------------------------------------------------------------------ geometry

class Mesh:
    """Triangles with per-vertex position, normal, uv (glTF: (0, 0) is the image's top-left) and,
    if asked, tangents."""

    def __init__(self, tangents=False, uvs=True):
        self.pos, self.nrm, self.uv, self.tan, self.idx = [], [], [], [], []
        self.tangents, self.uvs = tangents, uvs

    def quad(self, o, U, V, uv0, uv_scale, tangent_w=1.0):
        """Quad from corner o spanning U (direction of +u) and V (direction of +v: down the image);
        its front (normal) is V x U, i.e. u to the right and v down when seen from the front."""
        n = norm(cross(V, U))
        base = len(self.pos)
        for (a, b) in ((0, 0), (1, 0), (1, 1), (0, 1)):
            self.pos.append(add(o, add(scale(U, a), scale(V, b))))
            self.nrm.append(n)
            lu, lv = math.sqrt(dot(U, U)), math.sqrt(dot(V, V))
            self.uv.append((uv0[0] + a * lu / uv_scale, uv0[1] + b * lv / uv_scale))
            if self.tangents:
                self.tan.append(norm(U) + (tangent_w,))
        # (o, o+U+V, o+U) and (o, o+V, o+U+V) are counter-clockwise seen from n's side
        self.idx += [base, base + 2, base + 1, base, base + 3, base + 2]

    def tri_count(self):
        return len(self.idx) // 3


def room_meshes():
    X, Y, Z = ROOM_X, ROOM_Y, ROOM_Z
    floor = Mesh()
    # u along +x, v along +z: seen from above with -z up the view, the planks read the right way
    floor.quad((-X, 0, -Z), (2 * X, 0, 0), (0, 0, 2 * Z), (0, 0), TEX_FLOOR_M * FLOOR_UV_SCALE)
    ceiling = Mesh(uvs=False)  # the painted surfaces have no texture, so no uvs
    ceiling.quad((-X, Y, Z), (2 * X, 0, 0), (0, 0, -2 * Z), (0, 0), 2 * X)
    back = Mesh(tangents=True)
    back.quad((-X, Y, -Z), (2 * X, 0, 0), (0, -Y, 0), (0, 0), TEX_BRICK_M)
    front = Mesh(uvs=False)
    front.quad((X, Y, Z), (-2 * X, 0, 0), (0, -Y, 0), (0, 0), 2.0)
    left = Mesh(uvs=False)
    left.quad((-X, Y, Z), (0, 0, -2 * Z), (0, -Y, 0), (0, 0), 2.0)
    # right wall (x = +X, facing -x): u along +z, v down; four quads around the window's hole
    right = Mesh(uvs=False)
    z0, z1, y0, y1 = WINDOW
    tile = 2.0

    def rq(za, zb, ya, yb):  # the part z in [za, zb], y in [ya, yb]; uv continuous over the wall
        right.quad((X, yb, za), (0, 0, zb - za), (0, ya - yb, 0), ((za + Z) / tile, (Y - yb) / tile), tile)

    rq(-Z, Z, y1, Y)    # above the window
    rq(-Z, Z, 0, y0)    # below it
    rq(-Z, z0, y0, y1)  # beside it (towards -z)
    rq(z1, Z, y0, y1)   # beside it (towards +z)
    return [("floor", floor), ("ceiling", ceiling), ("wall_back", back), ("wall_front", front),
            ("wall_left", left), ("wall_right", right)]


def box_mesh():
    """Unit box x, z in [-0.5, 0.5], y in [0, 1], outward faces, each face uv 0..1 (image up =
    world up on the sides); no bottom face (the boxes stand on something)."""
    m = Mesh()
    h = 0.5
    m.quad((-h, 1, h), (1, 0, 0), (0, -1, 0), (0, 0), 1.0)    # +z
    m.quad((h, 1, -h), (-1, 0, 0), (0, -1, 0), (0, 0), 1.0)   # -z
    m.quad((h, 1, h), (0, 0, -1), (0, -1, 0), (0, 0), 1.0)    # +x
    m.quad((-h, 1, -h), (0, 0, 1), (0, -1, 0), (0, 0), 1.0)   # -x
    m.quad((-h, 1, -h), (1, 0, 0), (0, 0, 1), (0, 0), 1.0)    # +y
    return m


def sphere_mesh(r=SPHERE_R, stacks=SPHERE_STACKS, slices=SPHERE_SLICES):
    """UV sphere about the origin: (slices + 1) x (stacks + 1) vertices (the seam and the poles
    repeated for the uvs), smooth normals, u around (increasing to the right seen from outside),
    v from the top pole (0) to the bottom one (1); outward-wound triangles, none degenerate."""
    m = Mesh()
    for i in range(stacks + 1):
        th = math.pi * i / stacks
        for j in range(slices + 1):
            ph = 2 * math.pi * j / slices
            n = (math.sin(th) * math.sin(ph), math.cos(th), math.sin(th) * math.cos(ph))
            if i in (0, stacks):
                n = (0.0, 1.0 if i == 0 else -1.0, 0.0)
            m.pos.append(scale(n, r))
            m.nrm.append(n)
            m.uv.append((j / slices, i / stacks))
    row = slices + 1
    for i in range(stacks):
        for j in range(slices):
            a, b, c, d = i * row + j, (i + 1) * row + j, (i + 1) * row + j + 1, i * row + j + 1
            if i != 0:
                m.idx += [a, b, d]
            if i != stacks - 1:
                m.idx += [b, c, d]
    return m


def leaf_card_mesh():
    """Two crossed vertical quads LEAF_SIZE wide and tall, base centre at the origin; double-sided
    in the material, so each is one quad."""
    m = Mesh()
    s = LEAF_SIZE
    m.quad((-s / 2, s, 0), (s, 0, 0), (0, -s, 0), (0, 0), s)
    m.quad((0, s, s / 2), (0, 0, -s), (0, -s, 0), (0, 0), s)
    return m


def sign_mesh():
    x, y, w, h = SIGN
    m = Mesh()
    m.quad((x - w / 2, y + h / 2, -ROOM_Z + 0.01), (w, 0, 0), (0, -h, 0), (0, 0), w)
    m.uv = [(u, v * w / h) for (u, v) in m.uv]  # the image fills the quad
    return m


# ------------------------------------------------------------------ glTF assembly

class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data),
                           "target": target})
        self.bin += data
        return len(self.views) - 1

    def floats(self, rows, kind, minmax=False):
        data = b"".join(struct.pack("<%df" % len(r), *r) for r in rows)
        acc = {"bufferView": self._view(data, ARRAY_BUFFER), "componentType": FLOAT,
               "count": len(rows), "type": kind}
        if minmax:  # exactly the stored float32 values
            stored = [struct.unpack("<%df" % len(r), struct.pack("<%df" % len(r), *r)) for r in rows]
            acc["min"] = [min(s[k] for s in stored) for k in range(len(rows[0]))]
            acc["max"] = [max(s[k] for s in stored) for k in range(len(rows[0]))]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        assert max(idx) < 65536
        data = struct.pack("<%dH" % len(idx), *idx)
        self.accessors.append({"bufferView": self._view(data, ELEMENT_ARRAY_BUFFER),
                               "componentType": USHORT, "count": len(idx), "type": "SCALAR"})
        return len(self.accessors) - 1

    def primitive(self, m):
        attrs = {"POSITION": self.floats(m.pos, "VEC3", minmax=True),
                 "NORMAL": self.floats(m.nrm, "VEC3")}
        if m.uvs:
            attrs["TEXCOORD_0"] = self.floats(m.uv, "VEC2")
        if m.tangents:
            attrs["TANGENT"] = self.floats(m.tan, "VEC4")
        return {"attributes": attrs, "indices": self.indices(m.idx)}


def pbr(base=None, metallic=0.0, roughness=1.0, **extra):
    p = {}
    if base is not None:
        p["baseColorFactor"] = [r6(c) for c in base] + [1]
    p["metallicFactor"] = r6(metallic)
    p["roughnessFactor"] = r6(roughness)
    p.update(extra)
    return p


def build_gltf():
    b = Builder()
    images = ["floor_basecolor", "brick_basecolor", "brick_normal", "metal_rough_stripes",
              "leaf_basecolor", "sign_emissive"]
    tex = {name: i for i, name in enumerate(images)}
    materials = []
    mat_index = {}

    def material(name, **m):
        mat_index[name] = len(materials)
        materials.append(dict({"name": name}, **m))

    paint = lambda c, r=0.9: {"pbrMetallicRoughness": pbr(c, 0.0, r)}
    material("floor_wood", pbrMetallicRoughness=pbr(None, 0.0, 0.6, baseColorTexture={
        "index": tex["floor_basecolor"],
        "extensions": {"KHR_texture_transform": {"scale": [FLOOR_UV_SCALE, FLOOR_UV_SCALE]}}}))
    material("ceiling_paint", **paint((0.85, 0.85, 0.84)))
    material("brick_wall", pbrMetallicRoughness=pbr(None, 0.0, 0.85, baseColorTexture={
        "index": tex["brick_basecolor"]}), normalTexture={"index": tex["brick_normal"], "scale": 1})
    material("wall_front_paint", **paint((0.72, 0.70, 0.66)))
    material("wall_left_paint", **paint((0.55, 0.64, 0.70)))
    material("wall_right_paint", **paint((0.78, 0.76, 0.70)))
    material("plinth", **paint((0.30, 0.30, 0.32), 0.8))
    for r in ROUGHNESS:
        material("metal_r%.2f" % r, pbrMetallicRoughness=pbr(COPPER, 1.0, r))
    for r in ROUGHNESS:
        material("dielectric_r%.2f" % r, pbrMetallicRoughness=pbr(RED, 0.0, r))
    material("metal_rough_stripes", pbrMetallicRoughness=pbr(
        (0.8, 0.8, 0.8), 1.0, 1.0, metallicRoughnessTexture={"index": tex["metal_rough_stripes"]}))
    material("plastic_glossy", pbrMetallicRoughness=pbr((0.9, 0.9, 0.88), 0.0, 0.2))
    material("lambert", pbrMetallicRoughness=pbr((0.7, 0.7, 0.7), 0.0, 1.0))
    material("leaves", pbrMetallicRoughness=pbr(None, 0.0, 0.7, baseColorTexture={
        "index": tex["leaf_basecolor"]}), alphaMode="MASK", alphaCutoff=0.5, doubleSided=True)
    material("sign", pbrMetallicRoughness=pbr((0.02, 0.02, 0.02), 0.0, 0.5),
             emissiveTexture={"index": tex["sign_emissive"]}, emissiveFactor=[1, 1, 1],
             extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 5}})

    meshes, nodes = [], []

    def mesh(name, prim, mat):
        meshes.append({"name": name, "primitives": [dict(prim, material=mat_index[mat])]})
        return len(meshes) - 1

    def node(name, **n):
        nodes.append(dict({"name": name}, **n))

    room_mats = {"floor": "floor_wood", "ceiling": "ceiling_paint", "wall_back": "brick_wall",
                 "wall_front": "wall_front_paint", "wall_left": "wall_left_paint",
                 "wall_right": "wall_right_paint"}
    tris = 0
    for name, m in room_meshes():
        node(name, mesh=mesh(name, b.primitive(m), room_mats[name]))
        tris += m.tri_count()

    box = box_mesh()
    box_prim = b.primitive(box)
    (px0, px1), ph, (pz0, pz1) = PLINTH
    node("plinth", mesh=mesh("plinth", box_prim, "plinth"),
         translation=[r6((px0 + px1) / 2), 0, r6((pz0 + pz1) / 2)],
         scale=[r6(px1 - px0), r6(ph), r6(pz1 - pz0)])
    node("box_metal_rough_stripes", mesh=mesh("box_metal_rough_stripes", box_prim, "metal_rough_stripes"),
         translation=[r6(c) for c in MR_BOX[0]], rotation=rot(quat_y(MR_BOX[1])),
         scale=[MR_BOX[2]] * 3)
    node("box_plastic_glossy", mesh=mesh("box_plastic_glossy", box_prim, "plastic_glossy"),
         translation=[r6(c) for c in PLASTIC_BOX[0]], rotation=rot(quat_y(PLASTIC_BOX[1])),
         scale=[PLASTIC_BOX[2]] * 3)
    node("box_lambert", mesh=mesh("box_lambert", box_prim, "lambert"),
         translation=[POT[0], 0, POT[1]], scale=[POT[2]] * 3)
    tris += 4 * box.tri_count()

    sph = sphere_mesh()
    sph_prim = b.primitive(sph)
    for z, kind in ((METAL_Z, "metal"), (DIELECTRIC_Z, "dielectric")):
        for x, r in zip(SPHERE_X, ROUGHNESS):
            name = "sphere_%s_r%.2f" % (kind, r)
            node(name, mesh=mesh(name, sph_prim, "%s_r%.2f" % (kind, r)),
                 translation=[r6(x), r6(ph + SPHERE_R), r6(z)])
            tris += sph.tri_count()

    leaf = leaf_card_mesh()
    node("leaf_card", mesh=mesh("leaf_card", b.primitive(leaf), "leaves"),
         translation=[POT[0], POT[2], POT[1]], rotation=rot(quat_y(LEAF_TURN)))
    tris += leaf.tri_count()
    sign = sign_mesh()
    node("sign", mesh=mesh("sign", b.primitive(sign), "sign"))
    tris += sign.tri_count()

    spot_cd = SPOT_W * LM_PER_W / (4 * math.pi)
    point_cd = POINT_W * LM_PER_W / (4 * math.pi)
    sun_lux = SUN_W_M2 * LM_PER_W
    lights = [
        {"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": r6(spot_cd),
         "spot": {"innerConeAngle": 0.4, "outerConeAngle": 0.6}},
        {"name": "point", "type": "point", "color": [1, 1, 1], "intensity": r6(point_cd)},
        {"name": "sun", "type": "directional", "color": [1, 1, 1], "intensity": r6(sun_lux)},
    ]
    q = lambda f: rot(look_rotation(f))
    node("spot", translation=[r6(c) for c in SPOT_POS], rotation=q(sub(SPOT_TARGET, SPOT_POS)),
         extensions={"KHR_lights_punctual": {"light": 0}})
    node("point", translation=[r6(c) for c in POINT_POS], extensions={"KHR_lights_punctual": {"light": 1}})
    sun_pos = add((0.0, 1.6, 0.3), scale(norm(SUN_DIR), -4.0))  # outside the window, for viewers
    node("sun", translation=[r6(c) for c in sun_pos], rotation=q(SUN_DIR),
         extensions={"KHR_lights_punctual": {"light": 2}})
    node("camera", camera=0, translation=[r6(c) for c in CAMERA_POS],
         rotation=q(sub(CAMERA_TARGET, CAMERA_POS)))

    gltf = {
        "asset": {"version": "2.0", "generator": "iir tools/gen_material_room.py",
                  "copyright": "CC0 1.0 (public domain dedication), made for iir"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform",
                           "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": "material_room", "nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": CAMERA_YFOV, "aspectRatio": r6(CAMERA_ASPECT),
                                     "znear": 0.05, "zfar": 50}}],
        "meshes": meshes,
        "materials": materials,
        "textures": [{"name": n, "sampler": 0, "source": i} for i, n in enumerate(images)],
        "images": [{"name": n, "uri": "textures/%s.png" % n, "mimeType": "image/png"} for n in images],
        "samplers": [{"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT,
                      "wrapT": REPEAT}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"uri": "material_room.bin", "byteLength": len(b.bin)}],
    }
    info = {"triangles": tris, "spot_cd": spot_cd, "point_cd": point_cd, "sun_lux": sun_lux}
    return gltf, bytes(b.bin), info


# ------------------------------------------------------------------ sidecar, paths, SOURCE.md

def paths():
    sx, _, sz = SPOT_POS
    phase = math.degrees(math.atan2(sz, sx))
    radius = math.hypot(sx, sz)
    return {
        "orbit": {
            "description": "The spot (glTF spot, inner cone 0.4 rad, outer 0.6) circles once under the "
                           "ceiling (radius %.2f about the room's vertical axis, 2.7 high), starting where "
                           "the scene has it and always aiming at the middle of the spheres: a smooth orbit "
                           "that sweeps the beam over the spheres, the boxes, the floor and the brick "
                           "wall." % radius,
            "fps": 30,
            "duration": 8,
            "lights": [{"name": "spot", "orbit": {
                "center": [0, SPOT_POS[1], 0], "radius": r6(radius), "turns": 1, "phase": r6(phase),
                "target": [r6(c) for c in SPOT_TARGET]}}],
        },
        "sweep": {
            "description": "The point light crosses the room at constant speed 0.9 high, 0.6 in front of "
                           "the dielectric spheres, from x = -1.6 to x = 1.6: its highlight runs along both "
                           "rows of spheres.",
            "fps": 30,
            "duration": 4,
            "lights": [{"name": "point", "sweep": {"from": [-1.6, 0.9, -0.5], "to": [1.6, 0.9, -0.5]}}],
        },
        "day": {
            "description": "The sun moves across the sky in front of the window (Catmull-Rom on its "
                           "direction): its patch of light and the leaf card's shadow slide over the floor "
                           "from the front of the room to the spheres and the back wall.",
            "fps": 30,
            "duration": 8,
            "lights": [{"name": "sun", "interpolation": "catmull-rom", "keys": [
                {"t": 0, "direction": [r6(c) for c in norm((-1.0, -0.55, 0.35))]},
                {"t": 4, "direction": [r6(c) for c in norm(SUN_DIR)]},
                {"t": 8, "direction": [r6(c) for c in norm((-1.0, -0.6, -0.75))]}]}],
        },
    }


def source_md(info):
    z0, z1, y0, y1 = WINDOW
    f = lambda v: "(%s)" % ", ".join("%g" % c for c in v)
    return """# material_room (generated here, CC0)

A glTF 2.0 test room of glTF's material and light features, written by
`tools/gen_material_room.py` (Python 3, standard library only). Regenerate it from the repository
root with

    python3 tools/gen_material_room.py

which rewrites every file of this folder (none is written by hand): `material_room.gltf`,
`material_room.bin`, `textures/*.png`, `material_room.scene.json`, `paths/*.json` and this
`SOURCE.md`. The output is deterministic (fixed seeds): a re-run gives byte-identical files (the
PNGs' compressed streams with the same zlib). Licence: CC0 1.0
(https://creativecommons.org/publicdomain/zero/1.0/), made for iir; the textures are procedural.

- Room: 6 x 3 x 5 m (x -3..3, y 0..3, z -2.5..2.5, metres, +y up), {tris} triangles, every node
  and light named. Floor `floor_wood` (planks, sRGB base colour texture, no `baseColorFactor`,
  roughness 0.6, `KHR_texture_transform` scale [{uvs}, {uvs}], REPEAT sampler); back wall
  `brick_wall` (bricks, sRGB, and a tangent-space normal map made from the bricks' height field:
  mortar grooves, bevelled edges; TANGENT attributes with w = +1); painted ceiling and front, left
  and right walls, a window (a hole, z {z0:g}..{z1:g}, y {y0:g}..{y1:g}) in the right (+x) wall.
- Spheres (r {r:g}, {sl} x {st} segments, smooth normals, uvs) on a plinth as Khronos'
  MetalRoughSpheres: back row copper metal (`metal_r0.05` ... `metal_r1.00`, base {cu}), front row
  red dielectric (`dielectric_r0.05` ...), roughness 0.05, 0.25, 0.5, 0.75, 1.0 from -x to +x.
- `box_metal_rough_stripes` at {mr} (metallic-roughness data texture: G roughness in 8 columns,
  B metallic in 4 rows), `box_plastic_glossy` at {pl} (roughness 0.2), `box_lambert` at
  ({px:g}, 0, {pz:g}) (roughness 1) with the alpha-masked `leaf_card` on it (two crossed
  double-sided quads, RGBA leaves, MASK at 0.5), lit by the sun through the window so that its
  shadow falls on the floor; the emissive `sign` on the back wall (emissive texture,
  `emissiveFactor` 1, `KHR_materials_emissive_strength` 5).
- Lights (KHR_lights_punctual, photometric as Blender's exporter writes them; iir divides by
  683 lm/W): `spot` at {sp} aiming at {st_} (glTF spot, cones 0.4 / 0.6 rad), {spot_cd:.1f} cd =
  400 W (31.83 W/sr); `point` at {pp}, {point_cd:.1f} cd = 200 W (15.92 W/sr); `sun` travelling
  along {sd}, {sun_lux:g} lux = 3 W/m^2. The emissive `sign` stays static emissive triangles in
  iir (it has an emission texture; noted when the scene loads). Camera `camera` at {cp} looking at {ct}, yfov
  0.9 rad, aspect 4:3: the spheres, the brick wall with the sign, the sun's patch with the leaves'
  shadow and the window in one view.
- Sidecar `material_room.scene.json`: `file` and `paths` only. `paths/orbit.json`: the spot
  circles under the ceiling aiming at the spheres; `paths/sweep.json`: the point light crosses in
  front of the spheres; `paths/day.json`: the sun's direction moves and the leaves' shadow slides
  over the floor. Tracks name their light (`"lights": [{{"name": "spot", ...}}]`).
- iir reads the materials as glTF 2.0 writes them (docs/scene-format.md, section 3): textures,
  the normal map, the alpha mask, metallic and roughness; a textured material without
  `baseColorFactor` has factor 1. The VPL methods shade the glossy materials by their diffuse
  albedo only, and say so.
""".format(tris=info["triangles"], uvs=FLOOR_UV_SCALE, z0=z0, z1=z1, y0=y0, y1=y1, r=SPHERE_R,
           sl=SPHERE_SLICES, st=SPHERE_STACKS, cu=f(COPPER), mr=f(MR_BOX[0]), pl=f(PLASTIC_BOX[0]),
           px=POT[0], pz=POT[1], sp=f(SPOT_POS), st_=f(SPOT_TARGET), spot_cd=info["spot_cd"],
           pp=f(POINT_POS), point_cd=info["point_cd"], sd=f(SUN_DIR), sun_lux=info["sun_lux"],
           cp=f(CAMERA_POS), ct=f(CAMERA_TARGET))


def dump(obj, indent=0):
    """JSON text indented by 2 with arrays of numbers (vectors, quaternions) on one line."""
    pad, inner = "  " * indent, "  " * (indent + 1)
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = ["%s%s: %s" % (inner, json.dumps(k), dump(v, indent + 1)) for k, v in obj.items()]
        text = "{\n" + ",\n".join(items) + "\n" + pad + "}"
    elif isinstance(obj, list) and obj and not all(isinstance(v, (int, float)) for v in obj):
        text = "[\n" + ",\n".join(inner + dump(v, indent + 1) for v in obj) + "\n" + pad + "]"
    else:
        text = json.dumps(obj, ensure_ascii=True, separators=(", ", ": "))
    return text + "\n" if indent == 0 else text


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    dst = os.path.join(root, "scenes", "material_room")
    os.makedirs(os.path.join(dst, "textures"), exist_ok=True)
    os.makedirs(os.path.join(dst, "paths"), exist_ok=True)
    files = {}
    files["textures/floor_basecolor.png"] = floor_texture()
    files["textures/brick_basecolor.png"], files["textures/brick_normal.png"] = brick_textures()
    files["textures/metal_rough_stripes.png"] = mr_texture()
    files["textures/leaf_basecolor.png"] = leaf_texture()
    files["textures/sign_emissive.png"] = sign_texture()
    gltf, binary, info = build_gltf()
    files["material_room.gltf"] = dump(gltf).encode()
    files["material_room.bin"] = binary
    scripts = paths()
    files["material_room.scene.json"] = dump(
        {"file": "material_room.gltf",
         "paths": {name: "paths/%s.json" % name for name in scripts}}).encode()
    for name, script in scripts.items():
        files["paths/%s.json" % name] = dump(script).encode()
    files["SOURCE.md"] = source_md(info).encode()
    total = sum(len(v) for v in files.values())
    for rel, data in sorted(files.items()):
        with open(os.path.join(dst, rel), "wb") as f:
            f.write(data)
    print("%s: %d files, %d triangles, %d bytes" % (dst, len(files), info["triangles"], total))


if __name__ == "__main__":
    main()

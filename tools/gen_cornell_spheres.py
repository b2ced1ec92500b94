#!/usr/bin/env python3
"""gen_cornell_spheres.py -- writes scenes/cornell_spheres/cornell_spheres.{obj,mtl}: the Cornell box
(scenes/cornell_box's McGuire OBJ, its two blocks left out) with a tessellated mirror sphere and a
glass sphere. Not the sidecar or paths (written by hand). Deterministic: the output is committed.

Usage: tools/gen_cornell_spheres.py [REPO_ROOT]
"""
import math
import os
import sys

# (name, material, centre, radius): the classic arrangement, mirror at the back left, glass front
# right, both resting on the floor (y = 0).
SPHERES = [
    ("mirrorSphere", "mirror", (-0.42, 0.33, -0.38), 0.33),
    ("glassSphere", "glass", (0.42, 0.33, 0.30), 0.33),
]
STACKS, SLICES = 24, 48  # latitude bands, longitude segments

MATERIALS = """
newmtl mirror
  illum 3
  Kd 0 0 0
  Ks 0.95 0.95 0.95
  Ke 0 0 0

newmtl glass
  illum 7
  Ni 1.5
  Kd 0 0 0
  Ks 1 1 1
  Tf 1 1 1
  Ke 0 0 0
"""


def box_objects(obj_text, drop):
    """The OBJ's lines without the objects named in drop ('## Object NAME' to the next object)."""
    out, skipping = [], False
    for line in obj_text.splitlines():
        if line.startswith("## Object"):
            skipping = line.split()[2] in drop
        if not skipping:
            out.append(line.rstrip())
    return out


def box_materials(mtl_text, drop):
    out, skipping = [], False
    for line in mtl_text.splitlines():
        if line.startswith("newmtl"):
            skipping = line.split()[1] in drop
        if not skipping:
            out.append(line.rstrip())
    return out


def sphere(centre, r):
    """Vertices (poles once) and outward-wound triangles (0-based) of a UV sphere."""
    cx, cy, cz = centre
    verts = [(cx, cy + r, cz)]
    for i in range(1, STACKS):
        theta = math.pi * i / STACKS
        for j in range(SLICES):
            phi = 2.0 * math.pi * j / SLICES
            verts.append((cx + r * math.sin(theta) * math.cos(phi), cy + r * math.cos(theta),
                          cz + r * math.sin(theta) * math.sin(phi)))
    verts.append((cx, cy - r, cz))
    ring = lambda i, j: 1 + (i - 1) * SLICES + (j % SLICES)
    tris = []
    for j in range(SLICES):
        tris.append((0, ring(1, j), ring(1, j + 1)))
        tris.append((len(verts) - 1, ring(STACKS - 1, j + 1), ring(STACKS - 1, j)))
    for i in range(1, STACKS - 1):
        for j in range(SLICES):
            a, b, c, d = ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    return verts, [outward(verts, t, centre) for t in tris]


def outward(verts, t, centre):
    """t wound so that its normal (counter-clockwise) points away from the centre."""
    p = [verts[k] for k in t]
    e1 = [p[1][k] - p[0][k] for k in range(3)]
    e2 = [p[2][k] - p[0][k] for k in range(3)]
    n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    m = [sum(q[k] for q in p) / 3.0 - centre[k] for k in range(3)]
    return t if sum(n[k] * m[k] for k in range(3)) > 0 else (t[0], t[2], t[1])


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    src = os.path.join(root, "scenes", "cornell_box")
    dst = os.path.join(root, "scenes", "cornell_spheres")
    drop = {"shortBox", "tallBox"}
    with open(os.path.join(src, "CornellBox-Original.obj")) as f:
        obj = box_objects(f.read(), drop)
    with open(os.path.join(src, "CornellBox-Original.mtl")) as f:
        mtl = box_materials(f.read(), drop)
    obj = [l.replace("CornellBox-Original.mtl", "cornell_spheres.mtl") for l in obj]
    head = ["# cornell_spheres.obj -- written by tools/gen_cornell_spheres.py: McGuire's Cornell box",
            "# (scenes/cornell_box, CC BY 3.0; its header follows) without its two blocks, plus a",
            "# mirror sphere and a glass sphere (CC0).", "#"]
    out = head + obj
    for name, mat, centre, r in SPHERES:
        verts, tris = sphere(centre, r)
        out += ["", "## Object %s" % name]
        out += ["v %.6f %.6f %.6f" % v for v in verts]
        out += ["", "g %s" % name, "usemtl %s" % mat]
        out += ["f %d %d %d" % tuple(k - len(verts) for k in t) for t in tris]
    os.makedirs(dst, exist_ok=True)
    with open(os.path.join(dst, "cornell_spheres.obj"), "w") as f:
        f.write("\n".join(out) + "\n")
    mhead = ["# cornell_spheres.mtl -- written by tools/gen_cornell_spheres.py: the Cornell box's",
             "# materials (CC BY 3.0; header follows) and the spheres' mirror and glass (CC0).", "#"]
    with open(os.path.join(dst, "cornell_spheres.mtl"), "w") as f:
        f.write("\n".join(mhead + mtl).rstrip() + "\n" + MATERIALS)


if __name__ == "__main__":
    main()

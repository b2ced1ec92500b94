#!/usr/bin/env bash
# test_scenes.sh -- scenes users bring (issue 16): an OBJ room without a sidecar is framed from
# inside and renders lit (a room with a wall missing from outside), and each command says which
# camera it chose; an entirely black image gets a warning saying why (no lights, the lights shut
# in a room the camera is outside of, a camera looking away or inside geometry); a glTF sun, a
# textured and a metal material are warned about by name, and so is what a method leaves out
# (iir: a point light's indirect light; ir: an emissive material's); render --anim's default size
# follows the scene camera's aspect. Usage: test_scenes.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" scenes

# ---- the scenes: OBJ rooms (closed, open, dark, with a cabinet) and a glTF room ----
python3 - "$tmp" <<'PY' || fail "could not write the test scenes"
import base64, json, struct, sys
d = sys.argv[1]
def obj(name, parts, mtl="room.mtl"):
    V, F = [], []
    def quad(c, a, b, m):
        F.append((m, len(V) + 1))
        for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            V.append([c[k] + s * a[k] + t * b[k] for k in range(3)])
    W, H, D = 2.0, 2.5, 1.5  # walls face inwards
    quad((0, 0, 0), (0, 0, D), (W, 0, 0), "white"); quad((0, H, 0), (W, 0, 0), (0, 0, D), "white")
    quad((-W, H / 2, 0), (0, H / 2, 0), (0, 0, D), "red"); quad((W, H / 2, 0), (0, 0, D), (0, H / 2, 0), "white")
    quad((0, H / 2, -D), (W, 0, 0), (0, H / 2, 0), "white")
    if "front" in parts: quad((0, H / 2, D), (0, H / 2, 0), (W, 0, 0), "white")
    if "lamp" in parts: quad((0, H - 0.01, 0), (0.4, 0, 0), (0, 0, 0.3), "lamp")
    c, h = (0.5, 0.4, 0.0), 0.4  # a box on the floor, faces outwards
    for a, b, n in (((0, 0, h), (h, 0, 0), (0, h, 0)), ((h, 0, 0), (0, 0, h), (0, -h, 0)),
                    ((0, h, 0), (0, 0, h), (h, 0, 0)), ((0, 0, h), (0, h, 0), (-h, 0, 0)),
                    ((h, 0, 0), (0, h, 0), (0, 0, h)), ((0, h, 0), (h, 0, 0), (0, 0, -h))):
        quad([c[k] + n[k] for k in range(3)], a, b, "white")
    with open(f"{d}/{name}.obj", "w") as f:
        f.write(f"mtllib {mtl}\n")
        f.writelines("v %g %g %g\n" % tuple(v) for v in V)
        f.writelines(f"usemtl {m}\nf {i} {i + 1} {i + 2} {i + 3}\n" for m, i in F)
open(f"{d}/room.mtl", "w").write("newmtl white\nKd 0.75 0.75 0.75\nnewmtl red\nKd 0.7 0.1 0.1\n"
                                 "newmtl lamp\nKd 0.8 0.8 0.8\nKe 20 18 15\n")
obj("room", ("front", "lamp")); obj("open", ("lamp",)); obj("dark", ("front",))
open(f"{d}/tex.mtl", "w").write("newmtl white\nKd 0.75 0.75 0.75\nmap_Kd plaster.png\n"
                                "newmtl red\nKd 0.7 0.1 0.1\nmap_Kd brick.png\nd 0.5\n"
                                "newmtl lamp\nKd 0.8 0.8 0.8\nKe 20 18 15\n")
obj("textured", ("front", "lamp"), "tex.mtl")
# a glTF room 2 x 2 x 2 (walls facing in): spot "key", point "fill", directional "sun"; material
# "paint" has a colour texture, "steel" is metal; no camera
V, I = [], []
def quad(c, a, b):
    base = len(V)
    for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        V.append([c[k] + s * a[k] + t * b[k] for k in range(3)])
    I.extend([base, base + 1, base + 2, base, base + 2, base + 3])
quad((0, 0, 0), (0, 0, 1), (1, 0, 0)); quad((0, 2, 0), (1, 0, 0), (0, 0, 1))
quad((-1, 1, 0), (0, 1, 0), (0, 0, 1)); quad((1, 1, 0), (0, 0, 1), (0, 1, 0))
quad((0, 1, -1), (1, 0, 0), (0, 1, 0)); quad((0, 1, 1), (0, 1, 0), (1, 0, 0))
walls = len(I)
quad((0, 0.3, 0), (0, 0, 0.3), (0.3, 0, 0))
vb = b"".join(struct.pack("<3f", *v) for v in V)
ib = b"".join(struct.pack("<H", i) for i in I)
light = lambda i: {"KHR_lights_punctual": {"light": i}}
g = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
     "extensions": {"KHR_lights_punctual": {"lights": [
         {"type": "spot", "name": "key", "color": [1, 1, 1], "intensity": 3,
          "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.7}},
         {"type": "point", "name": "fill", "color": [1, 1, 1], "intensity": 0.5},
         {"type": "directional", "name": "sun", "color": [1, 1, 1], "intensity": 2}]}},
     "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
     "nodes": [{"mesh": 0, "name": "walls"}, {"mesh": 1, "name": "plate"},
               {"name": "keynode", "translation": [0, 1.9, 0],
                "rotation": [-0.70710678, 0, 0, 0.70710678], "extensions": light(0)},
               {"name": "fillnode", "translation": [0.5, 1.5, 0.5], "extensions": light(1)},
               {"name": "sunnode", "translation": [0, 1.5, 0], "extensions": light(2)}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
                {"primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "material": 1}]}],
     "materials": [{"name": "paint", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1],
                    "metallicFactor": 0, "baseColorTexture": {"index": 0}}},
                   {"name": "steel", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                    "metallicFactor": 1}}],
     "textures": [{"source": 0}], "images": [{"uri": "paint.png"}],
     "buffers": [{"byteLength": len(vb + ib),
                  "uri": "data:application/octet-stream;base64," + base64.b64encode(vb + ib).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(vb)},
                     {"buffer": 0, "byteOffset": len(vb), "byteLength": walls * 2},
                     {"buffer": 0, "byteOffset": len(vb) + walls * 2, "byteLength": (len(I) - walls) * 2}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(V), "type": "VEC3",
                    "min": [min(v[k] for v in V) for k in range(3)],
                    "max": [max(v[k] for v in V) for k in range(3)]},
                   {"bufferView": 1, "componentType": 5123, "count": walls, "type": "SCALAR"},
                   {"bufferView": 2, "componentType": 5123, "count": len(I) - walls, "type": "SCALAR"}]}
json.dump(g, open(f"{d}/sunroom.gltf", "w"))
PY

# mean_of FILE.pfm: the mean of every channel of a PFM image.
mean_of() {
    python3 - "$1" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
parts = data.split(b"\n", 3)
w, h = map(int, parts[1].split())
n = w * h * 3
vals = struct.unpack(("<" if float(parts[2]) < 0 else ">") + "%df" % n, parts[3][:4 * n])
print(sum(vals) / n)
PY
}
# png_size FILE.png: "WxH" from the PNG header.
png_size() { python3 -c 'import struct,sys; d=open(sys.argv[1],"rb").read(24); print("%dx%d" % struct.unpack(">II", d[16:24]))' "$1"; }
lit() { python3 -c 'import sys; sys.exit(0 if float(sys.argv[1]) > float(sys.argv[2]) else 1)' "$1" "$2"; }

pt=(--method pt --size 48x36 --refine-passes 16)

# ---- 5. a scene without a camera: framed from inside a closed room, else from outside ----
out=$("$iird" render "$tmp/room.obj" "${pt[@]}" --out "$tmp/room.pfm" 2>&1) || fail "render room: $out"
echo "$out" | grep -q "^iird render: camera: no camera in the scene: framed from inside (it is a closed room), at (" ||
    fail "no note of the camera framed inside the room: $out"
echo "$out" | grep -q "entirely black" && fail "the closed room renders black: $out"
m=$(mean_of "$tmp/room.pfm")
lit "$m" 0.05 || fail "the closed room, framed from inside, is not lit: mean $m"
out=$("$iird" render "$tmp/open.obj" "${pt[@]}" --out "$tmp/open.pfm" 2>&1) || fail "render open: $out"
echo "$out" | grep -q "camera: no camera in the scene: framed from outside" ||
    fail "the open room is not framed from outside: $out"
lit "$(mean_of "$tmp/open.pfm")" 0.01 || fail "the open room, framed from outside, is not lit"
# a scene with its own camera says nothing about it
out=$("$iird" render --method pt --size 8x8 --refine-passes 1 --out "$tmp/box.png" 2>&1)
echo "$out" | grep -q "camera:" && fail "the built-in box's own camera was reported: $out"

# render --anim and bench say it too (a glTF room with a spot, no camera)
cat > "$tmp/sway.json" <<'JS'
{ "fps": 10, "duration": 0.1, "light": { "sweep": { "from": [-0.2, 1.9, 0], "to": [0.2, 1.9, 0], "target": [0, 0, 0] } } }
JS
out=$("$iird" render "$tmp/sunroom.gltf" --anim "$tmp/sway.json" --method pt --size 16x12 \
    --out "$tmp/anim" 2>&1) || fail "render --anim sunroom: $out"
echo "$out" | grep -q "^iird render: camera: no camera in the scene: framed from inside" ||
    fail "render --anim does not say which camera: $out"
out=$("$iird" bench "$tmp/sunroom.gltf" --anim "$tmp/sway.json" --methods iir,pt --ref-spp 0 \
    --size 16x12 --vpls 8 --sm-res 8 --no-charts 2>&1) || fail "bench sunroom: $out"
echo "$out" | grep -q "^iird bench: camera: no camera in the scene: framed from inside" ||
    fail "bench does not say which camera: $out"

# ---- 5. an entirely black image: a warning that says why; the exit code stays 0 ----
printf '{"file": "room.obj", "camera": {"position": [0, 1.2, 8], "target": [0, 1.2, 0]}}' \
    > "$tmp/outside.scene.json"
expect 0 "warning: the image is entirely black: no light reaches the camera: the lights are inside a closed room and the camera is outside it" \
    -- "$iird" render "$tmp/outside.scene.json" "${pt[@]}" --out "$tmp/x.png"
expect 0 "warning: the image is entirely black: the scene has no lights" \
    -- "$iird" render "$tmp/dark.obj" "${pt[@]}" --out "$tmp/x.png"
printf '{"file": "room.obj", "camera": {"position": [0, 1.2, 8], "target": [0, 1.2, 20]}}' \
    > "$tmp/away.scene.json"
expect 0 "warning: the image is entirely black: the camera sees no geometry" \
    -- "$iird" render "$tmp/away.scene.json" "${pt[@]}" --out "$tmp/x.png"
printf '{"file": "room.obj", "camera": {"position": [0.5, 0.4, 0.1], "target": [0, 0.4, 0]}}' \
    > "$tmp/inbox.scene.json"
expect 0 "warning: the image is entirely black: the camera may be inside geometry" \
    -- "$iird" render "$tmp/inbox.scene.json" "${pt[@]}" --out "$tmp/x.png"
out=$("$iird" render "$tmp/room.obj" "${pt[@]}" --out "$tmp/x.png" 2>&1)
echo "$out" | grep -q "black" && fail "a lit image was called black: $out"
# render --anim: one warning for its black frames
printf '{ "fps": 10, "duration": 0.2, "camera": { "keys": [ {"t": 0, "position": [0, 1.2, 8], "target": [0, 1.2, 0]} ] } }' \
    > "$tmp/outside.json"
out=$("$iird" render "$tmp/room.obj" --anim "$tmp/outside.json" --method pt --size 16x12 \
    --out "$tmp/anim_black" 2>&1) || fail "render --anim of black frames: $out"
echo "$out" | grep -q "warning: all 3 frames are entirely black: no light reaches the camera" ||
    fail "render --anim's black frames: $out"
printf '{"file": "sunroom.gltf", "camera": {"position": [0, 1, 6], "target": [0, 1, 0]}, "lights": [{"type": "spot", "name": "key", "position": [0, 1.9, 0], "direction": [0, -1, 0], "cone_angle": 45, "intensity": 3}]}' \
    > "$tmp/sunout.scene.json"
out=$("$iird" bench "$tmp/sunout.scene.json" --anim "$tmp/sway.json" --methods iir --ref-spp 0 \
    --size 16x12 --vpls 8 --sm-res 8 --no-charts 2>&1) || fail "bench of black frames: $out"
echo "$out" | grep -q "warning: iir default: 2 of 2 frames (first: frame 0) are entirely black: no light reaches the camera: the lights are inside a closed room" ||
    fail "bench's black frames: $out"

# ---- 6. what no method renders, and what a method leaves out, is named ----
out=$("$iird" render "$tmp/sunroom.gltf" "${pt[@]}" --out "$tmp/sun.png" 2>&1) || fail "render sunroom: $out"
echo "$out" | grep -q "light 'sunnode'" && fail "the sun is rendered, yet it was warned about: $out"
echo "$out" | grep -q "warning: material 'paint': a texture cannot be read (.*paint.png" ||
    fail "no warning on the texture that is not there: $out"
echo "$out" | grep -q "material 'steel'" && fail "pt renders the metal, yet it was warned about: $out"
echo "$out" | grep -q "fillnode" && fail "pt renders the point light, yet it was warned about: $out"
out=$("$iird" render "$tmp/sunroom.gltf" --method iir --size 16x12 --vpls 8 --sm-res 8 \
    --refine-passes 1 --out "$tmp/sun_iir.png" 2>&1) || fail "render sunroom iir: $out"
echo "$out" | grep -q "light '" && fail "iir keeps VPLs for every light, yet one was warned about: $out"
echo "$out" | grep -q "warning: iir: material 'steel': is glossy (a metal, or roughness below 0.6): iir renders it by the full BSDF, VPLs on it and the light paths leaving them too, but clamps its lobes as the geometry term; pt does not clamp" ||
    fail "iir shades the metal diffuse, silently: $out"
# the room's lamp kept as static emissive triangles (a sidecar with a "lights" array)
printf '{"file": "room.obj", "lights": []}' > "$tmp/static.scene.json"
out=$("$iird" render "$tmp/static.scene.json" --method ir --size 16x12 --vpls 8 --sm-res 8 \
    --refine-passes 1 --out "$tmp/room_ir.png" 2>&1) || fail "render static room ir: $out"
echo "$out" | grep -q "warning: ir: material 'lamp': emits light: its indirect light is left out" ||
    fail "ir leaves out the lamp's indirect light silently: $out"
# without a sidecar the lamp (an emissive quad) is a movable area light: iir renders it, and says so
out=$("$iird" render "$tmp/room.obj" --method iir --size 16x12 --vpls 8 --sm-res 8 \
    --refine-passes 1 --out "$tmp/room_iir.pfm" 2>&1) || fail "render room iir: $out"
echo "$out" | grep -q "material 'lamp': emits light: became the movable area light 'lamp'" ||
    fail "the lamp's conversion to an area light is not noted: $out"
lit "$(mean_of "$tmp/room_iir.pfm")" 0.05 || fail "iir's room lit by its lamp is dark"
# an OBJ's map_Kd that is not there: a warning naming the material and the file, once each
out=$("$iird" render "$tmp/textured.obj" "${pt[@]}" --out "$tmp/tex.png" 2>&1) || fail "render textured: $out"
[ "$(echo "$out" | grep -c "a texture cannot be read")" = 2 ] &&
    echo "$out" | grep -q "warning: material 'white': a texture cannot be read (.*plaster.png.*): its flat colour is used" &&
    echo "$out" | grep -q "warning: material 'red': a texture cannot be read (.*brick.png" ||
    fail "textured materials: $out"
echo "$out" | grep -q "warning: material 'red': transparency (opacity 0.5): rendered opaque" ||
    fail "a transparent material: $out"
out=$("$iird" bench "$tmp/sunroom.gltf" --anim "$tmp/sway.json" --methods iir,pt,ir --ref-spp 0 \
    --size 16x12 --vpls 8 --sm-res 8 --no-charts 2>&1) || fail "bench sunroom: $out"
echo "$out" | grep -q "warning: material 'paint'" || fail "bench: no texture warning: $out"
[ "$(echo "$out" | grep -c "warning: material 'paint'")" = 1 ] || fail "bench: a note warned about other than once: $out"

# ---- 3. render --anim's default size follows the scene camera's aspect ----
orbit=$src/scenes/cornell_box/paths/orbit.json
out=$("$iird" render --anim "$orbit" --frames 0:1 --method pt --bounces 1 --out "$tmp/box" 2>&1) ||
    fail "render --anim of the box: $out"
[ "$(png_size "$tmp/box/frame_00000.png")" = 512x512 ] ||
    fail "the Cornell box's frames are not square: $(png_size "$tmp/box/frame_00000.png"): $out"
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["settings"]["size"] == [512, 512]' \
    "$tmp/box/render.json" || fail "render.json's size is not 512x512"
out=$("$iird" render "$tmp/sunroom.gltf" --anim "$tmp/sway.json" --frames 0:1 --method pt --bounces 1 \
    --out "$tmp/wide" 2>&1) || fail "render --anim of a scene without an aspect: $out"
[ "$(png_size "$tmp/wide/frame_00000.png")" = 910x512 ] ||
    fail "a scene without an aspect: $(png_size "$tmp/wide/frame_00000.png"), expected 910x512"
printf '{"file": "sunroom.gltf", "camera": {"position": [0, 1, 0.9], "target": [0, 1, 0], "aspect": 2}}' \
    > "$tmp/wide2.scene.json"
out=$("$iird" render "$tmp/wide2.scene.json" --anim "$tmp/sway.json" --frames 0:1 --method pt \
    --bounces 1 --out "$tmp/wide2" --video "$tmp/wide2.mp4" 2>&1) || fail "render --anim aspect 2: $out"
[ "$(png_size "$tmp/wide2/frame_00000.png")" = 1024x512 ] ||
    fail "camera.aspect 2: $(png_size "$tmp/wide2/frame_00000.png"), expected 1024x512"
expect 0 "wrote 1 frames .*, 48x20 png" -- "$iird" render "$tmp/wide2.scene.json" --anim "$tmp/sway.json" \
    --frames 0:1 --method pt --size 48x20 --out "$tmp/given"

[ "$failures" = 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "scenes users bring: cameras, black images, dropped lights and materials, sizes"

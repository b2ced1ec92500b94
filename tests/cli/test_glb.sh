#!/usr/bin/env bash
# test_glb.sh -- a binary glTF (.glb) as Blender exports it by default, its images inside the file
# (bufferViews of the BIN chunk), loads with its textures (issue 28): the material room packed into
# one .glb renders like the .gltf (every texture read, no warning), and a .glb whose image view
# points past its chunk is refused with a message naming the file (assimp checks every view).
# Usage: test_glb.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" glb

# pack scenes/material_room into room.glb (images into the BIN chunk), and a copy with a bad view
/usr/bin/python3 - "$src/scenes/material_room" "$tmp" <<'PY' || fail "could not pack the .glb"
import json, struct, sys
src, out = sys.argv[1], sys.argv[2]
def pack(g, binary, path):
    js = json.dumps(g).encode()
    js += b" " * (-len(js) % 4)
    blob = (b"glTF" + struct.pack("<II", 2, 28 + len(js) + len(binary)) + struct.pack("<I", len(js))
            + b"JSON" + js + struct.pack("<I", len(binary)) + b"BIN\0" + binary)
    open(path, "wb").write(blob)
g = json.load(open(f"{src}/material_room.gltf"))
binary = bytearray(open(f"{src}/material_room.bin", "rb").read())
binary += b"\0" * (-len(binary) % 4)
for im in g["images"]:
    data = open(f"{src}/{im.pop('uri')}", "rb").read()
    g["bufferViews"].append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data)})
    im["bufferView"], im["mimeType"] = len(g["bufferViews"]) - 1, "image/png"
    binary += data + b"\0" * (-len(data) % 4)
g["buffers"] = [{"byteLength": len(binary)}]
pack(g, bytes(binary), f"{out}/room.glb")
view = g["images"][0]["bufferView"]
g["bufferViews"][view]["byteOffset"] = len(binary) + 64  # past the chunk
pack(g, bytes(binary), f"{out}/badview.glb")
PY

out=$("$iird" render "$tmp/room.glb" --method pt --spp 1 --size 32x24 --out "$tmp/room.png" 2>&1) ||
    fail "render room.glb: $out"
echo "$out" | grep -q "texture cannot be read" && fail "room.glb: a texture was not read: $out"
[ -s "$tmp/room.png" ] || fail "room.glb rendered nothing"
expect 2 "badview.glb.*(out of range|outside)" -- "$iird" render "$tmp/badview.glb" --method pt --spp 1 \
    --size 32x24 --out "$tmp/bad.png"
[ "$failures" = 0 ] && echo "ok"
exit "$((failures > 0))"

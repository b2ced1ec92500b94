#!/usr/bin/env bash
# test_anim_lights.sh -- scripts that animate several lights by name ("lights" tracks), as
# `iird render --anim` and `iird bench --anim` run them on a small two-light scene (the Cornell box
# lit by two point lights, "left" and "right"): moving only the second light changes the frames
# far more than the frame-to-frame change of a still scene, switching it off darkens the frame,
# and a name the scene lacks, or the moved light named in both tracks, is refused before any work
# with the scene's light names. Usage: test_anim_lights.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" anim-lights

scenes=$tmp/scenes
mkdir -p "$scenes/two"
ln -s "$src/scenes/cornell_box" "$scenes/cornell_box"
cat >"$scenes/two/two.scene.json" <<'EOF'
{ "base": "cornell_box",
  "lights": [ {"type": "point", "name": "left", "position": [-0.5, 1.5, 0], "intensity": 0.6},
              {"type": "point", "name": "right", "position": [0.5, 1.5, 0], "intensity": 0.6} ] }
EOF
# script NAME TRACKS: a 1 s script at 1 fps (frames 0 and 1) with the given "lights" tracks.
script() {
    printf '{"fps": 1, "duration": 1, "lights": [%s]}\n' "$2" >"$tmp/$1.json"
}
script moved '{"name": "right", "keys": [{"t": 0, "position": [0.5, 1.5, 0]},
                                         {"t": 1, "position": [0.6, 0.3, 0.8]}]}'
script still '{"name": "right", "keys": [{"t": 0, "position": [0.5, 1.5, 0]}]}'
script off '{"name": "right", "keys": [{"t": 0}, {"t": 1, "on": false}]}'
script typo '{"name": "rigth", "keys": [{"t": 0}]}'
printf '%s\n' '{"duration": 1, "light": {"keys": [{"t": 0}]},
  "lights": [{"name": "left", "keys": [{"t": 0}]}]}' >"$tmp/both.json"
small=(--scenes "$scenes" --method iir --size 48x48 --vpls 64 --sm-res 32 --format pfm)

# pfm_stats A B: mean of A, mean of B and the mean absolute difference (PFM frames).
pfm_stats() {
    python3 - "$1" "$2" <<'PY'
import struct, sys
def read(p):
    b = open(p, "rb").read()
    head, dims, scale, data = b.split(b"\n", 3)
    w, h = map(int, dims.split())
    n = w * h * 3
    return struct.unpack(("<" if float(scale) < 0 else ">") + "%df" % n, data[:4 * n])
a, b = read(sys.argv[1]), read(sys.argv[2])
print(sum(a) / len(a), sum(b) / len(b), sum(abs(x - y) for x, y in zip(a, b)) / len(a))
PY
}

for s in moved still off; do
    out=$("$iird" render two --anim "$tmp/$s.json" --out "$tmp/$s" "${small[@]}" 2>&1) ||
        fail "render --anim $s.json: $out"
done
read -r _ _ d_moved < <(pfm_stats "$tmp/moved/frame_00000.pfm" "$tmp/moved/frame_00001.pfm")
read -r _ _ d_still < <(pfm_stats "$tmp/still/frame_00000.pfm" "$tmp/still/frame_00001.pfm")
python3 -c "import sys; sys.exit(not (float('$d_moved') > 5 * float('$d_still') + 1e-4))" ||
    fail "moving the second light changed the frame by $d_moved, a still scene by $d_still"
read -r m0 m1 _ < <(pfm_stats "$tmp/off/frame_00000.pfm" "$tmp/off/frame_00001.pfm")
python3 -c "import sys; sys.exit(not (0.3 < float('$m1') / float('$m0') < 0.7))" ||
    fail "switching one of two equal lights off: mean $m0 -> $m1, expected about half"

# Refusals, before any work: the unknown name with the scene's names; a light in both tracks.
quick 3000 2 "rigth.*its lights: left, right" -- \
    "$iird" render two --anim "$tmp/typo.json" --out "$tmp/x" "${small[@]}"
[ -e "$tmp/x" ] && fail "a refused script left $tmp/x"
quick 3000 2 "'left' is the light the \"light\" track moves" -- \
    "$iird" render two --anim "$tmp/both.json" --out "$tmp/x" "${small[@]}"
quick 3000 2 "rigth.*its lights: left, right" -- \
    "$iird" bench two --scenes "$scenes" --anim "$tmp/typo.json" --methods iir --out "$tmp/b"

# bench runs a "lights" script (the moved light's track is not needed).
out=$("$iird" bench two --scenes "$scenes" --anim "$tmp/moved.json" --methods iir --size 32x24 \
    --vpls 32 --sm-res 32 --ref-spp 4 --no-ref-cache --no-charts --out "$tmp/bench" 2>&1) ||
    fail "bench --anim moved.json: $out"
[ -s "$tmp/bench/frames.csv" ] || fail "bench wrote no frames.csv: $out"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all anim lights checks passed"

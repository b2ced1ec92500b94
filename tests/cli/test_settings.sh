#!/usr/bin/env bash
# test_settings.sh -- the settings a command prints are the ones its method reads, and each
# parameter has one default (issue 16): `render --method iir` names iir's parameters and not pt's
# spp or bounces; render --anim and bench print each method's; pt's spp is 1 everywhere and a still
# is the converged frame (refine_passes samples), byte for byte the frame of --spp 64
# --refine-passes 1; iird params shows one default. Usage: test_settings.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" settings

# settings LINE_PREFIX OUTPUT: the "<method> settings: ..." line of OUTPUT.
settings() { echo "$2" | grep "^$1 settings: "; }

# ---- a still prints the parameters of its method, with the values it used ----
out=$("$iird" render --method iir --size 32x24 --vpls 16 --sm-res 32 --refine-passes 2 \
    --out "$tmp/iir.png" 2>&1) || fail "render --method iir: $out"
line=$(settings iir "$out")
[ "$line" = "iir settings: bounces 2, vpls 16, kmin 4, kmax 8, insert-ms 0, weights surface, regen-threshold 0.5, refill true, visibility shadowmap, sm-res 32, sm-bias 0.005, interleave 4, area-samples 8, receiver-bsdf glossy, vpl-kind point, ism-points 16384, ism-res 32, ism-points-per-vpl 1024, clamp 100, shading full, clamp-compensation off, mr-levels 4, mr-depth 0.01, mr-normal 0.95, mr-window 16, mr-direct full, light-split 0.02, target-fps 0, ctl-vpls-max 1024, ctl-vpls-min 64, ctl-sm-res-min 64, seed 1, refine-passes 2, jitter true" ] ||
    fail "iir's settings line: $out"
echo "$out" | grep -qE "spp" && fail "render --method iir prints settings iir does not read: $out"
echo "$out" | grep -q "method iir, 2 refinement passes over 16 VPLs," || fail "iir's work: $out"
out=$("$iird" render --method iir --bounces 4 --size 32x24 --vpls 16 --sm-res 32 --refine-passes 2 \
    --out "$tmp/iir4.png" 2>&1) || fail "render --method iir --bounces 4: $out"
echo "$out" | grep -qE "method iir, 2 refinement passes over 16 VPLs \(\+[1-9][0-9]* of later bounces\)" ||
    fail "iir's work with later bounces: $out"

out=$("$iird" render --method ir --size 32x24 --vpls 16 --sm-res 32 --refine-passes 1 \
    --bounces 3 --out "$tmp/ir.png" 2>&1) || fail "render --method ir: $out"
settings ir "$out" | grep -q "^ir settings: bounces 3, vpls 16, same-random false, " ||
    fail "ir's settings line: $out"
echo "$out" | grep -q "spp" && fail "render --method ir prints pt's spp: $out"

out=$("$iird" render --method pt --size 16x12 --bounces 3 --seed 5 --out "$tmp/pt.png" 2>&1) ||
    fail "render --method pt: $out"
[ "$(settings pt "$out")" = "pt settings: spp 1, bounces 3, seed 5, refine-passes 64, jitter true" ] ||
    fail "pt's settings line: $out"
echo "$out" | grep -qE "vpls|kmin" && fail "render --method pt prints VPL settings: $out"

# ---- one default per parameter: pt's spp is 1; a still is the converged frame ----
echo "$out" | grep -q "method pt, 64 samples per pixel" ||
    fail "a default pt still is not refine_passes (64) samples: $out"
"$iird" render --method pt --size 16x12 --out "$tmp/default.pfm" >/dev/null 2>&1
"$iird" render --method pt --size 16x12 --spp 64 --refine-passes 1 --out "$tmp/one.pfm" >/dev/null 2>&1
cmp -s "$tmp/default.pfm" "$tmp/one.pfm" ||
    fail "the default still (64 passes of spp 1) differs from one frame of 64 samples"
expect 0 "method pt, 1024 samples per pixel" -- \
    "$iird" render --method pt --size 4x4 --spp 1024 --out "$tmp/many.png"
expect 0 "method pt, 4 samples per pixel" -- \
    "$iird" render --method pt --size 4x4 --spp 4 --refine-passes 4 --out "$tmp/few.png"
expect 0 "method pt, 66 samples per pixel" -- \
    "$iird" render --method pt --size 4x4 --spp 3 --out "$tmp/three.png"
expect 0 "method iir, 64 refinement passes" -- \
    "$iird" render --method iir --size 8x8 --vpls 8 --sm-res 8 --out "$tmp/iir64.png"
help=$("$iird" params --method pt)
echo "$help" | grep -A1 -- "--spp N" | grep -q "default 1 samples" || fail "params: spp's default: $help"
md=$("$iird" params --markdown)
echo "$md" | grep -q '^| `--spp` | int 1..1048576 samples | 1 | at most 64 |' ||
    fail "params --markdown: spp's row: $(echo "$md" | grep -- --spp)"
echo "$md" | grep -q "default [0-9]" && fail "params --markdown shows a second (live) default"

# ---- render --anim and bench print their methods' settings too ----
orbit=$src/scenes/cornell_box/paths/orbit.json
out=$("$iird" render --anim "$orbit" --frames 0:2 --size 16x12 --vpls 8 --sm-res 8 \
    --out "$tmp/anim" 2>&1) || fail "render --anim: $out"
settings iir "$out" | grep -q "^iir settings: bounces 2, vpls 8, kmin 4, kmax 8, .*sm-res 8, " ||
    fail "render --anim's settings line: $out"
out=$("$iird" bench --anim orbit --methods iir,pt --frames 0:2 --ref-spp 0 --size 16x12 --vpls 8 \
    --sm-res 8 --no-charts 2>&1) || fail "bench: $out"
settings iir "$out" | grep -q "^iir settings: bounces 2, vpls 8, " || fail "bench's iir settings: $out"
[ "$(settings iir "$out" | grep -c spp)" = 0 ] || fail "bench's iir settings name spp: $out"
settings pt "$out" | grep -q "^pt settings: spp 1, bounces 2, seed 1, refine-passes 64, jitter false" ||
    fail "bench's pt settings: $out"

[ "$failures" = 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "settings: each command prints what its method reads; one default per parameter"

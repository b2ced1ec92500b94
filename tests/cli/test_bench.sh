#!/usr/bin/env bash
# test_bench.sh -- `iird bench` and the VPL methods from the command line: the CSV has the
# documented columns and finite numbers, references score the frames they exist for, images are
# saved on request, and bad options are refused. Usage: test_bench.sh IIRD SOURCE_DIR
set -u
iird=$1
tmp=${IIR_TEST_TMP:-/tmp}/cli-bench-$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# Stills with the VPL methods.
for m in ir iir; do
    out=$("$iird" render --method $m --size 32x24 --vpls 64 --out "$tmp/$m.png" 2>&1) ||
        fail "render --method $m: $out"
    echo "$out" | grep -q "method $m, .* VPLs" || fail "render --method $m summary: $out"
done
out=$("$iird" render --method iir --kmin 9 --kmax 8 --size 8x8 --out "$tmp/x.png" 2>&1)
[ $? = 2 ] && echo "$out" | grep -q kmin || fail "kmin > kmax not refused: $out"
out=$("$iird" render --method iir --visibility maybe --out "$tmp/x.png" 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "shadowmap or rays" || fail "bad --visibility: $out"

# A short bench with references at frames 0, 1, 2, 3.
"$iird" bench --methods iir,ir --frames 4 --ref-every 2 --ref-spp 4 --size 32x24 --vpls 64 \
    --out "$tmp" --save-images > "$tmp/summary.txt" 2>&1 || fail "bench failed: $(cat "$tmp/summary.txt")"
grep -q "iir/ir: frame rate x" "$tmp/summary.txt" || fail "no ratio line: $(cat "$tmp/summary.txt")"
python3 - "$tmp/frames.csv" <<'PY' || fail "frames.csv is not as documented"
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
need = ["method", "setting", "frame", "total_ms", "trace_ms", "vpls_ms", "shadowmaps_ms",
        "gbuffer_ms", "direct_ms", "indirect_ms", "filter_ms", "rays_camera", "rays_shadow",
        "rays_vpl", "rays_shadowmap", "vpls", "vpls_valid", "vpls_invalidated", "vpls_deleted",
        "vpls_inserted", "vpls_null", "regenerated", "shadowmaps", "rmse", "relmse", "flicker"]
missing = [c for c in need if c not in rows[0]]
assert not missing, missing
assert len(rows) == 8 and {r["method"] for r in rows} == {"iir", "ir"}, len(rows)
for r in rows:
    for c in need[3:-3]:
        assert math.isfinite(float(r[c])) and float(r[c]) >= 0, (c, r[c])
    assert float(r["total_ms"]) > 0
    for c in ["rmse", "relmse"]:
        assert math.isfinite(float(r[c])) and float(r[c]) >= 0, (c, r[c])
    assert (r["flicker"] == "") == (r["frame"] == "0"), r["frame"]
iir = [r for r in rows if r["method"] == "iir"]
assert int(iir[0]["shadowmaps"]) > int(iir[1]["shadowmaps"]), "iir rebuilt every map"
PY
for f in ref_00000 ref_00003 iir_00001 ir_00002; do
    [ -s "$tmp/$f.pfm" ] || fail "missing $f.pfm"
done

# A script drives the light: its frame count, cut by --frames; the summary names the path.
src=$2
out=$("$iird" bench --anim "$src/scenes/cornell_box/paths/teleport.json" --frames 3 --ref-spp 0 \
    --size 16x12 --vpls 32 2>&1) || fail "bench --anim: $out"
echo "$out" | grep -q "path .*teleport.json, 16x12, 3 frames" || fail "bench --anim summary: $out"
printf '{"fps": 30, "duration": 1, "light": {"keys": [{"t": 0, "postion": [0, 1, 0]}]}}' > "$tmp/bad.json"
out=$("$iird" bench --anim "$tmp/bad.json" --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "postion" || fail "bad script not refused by field: $out"

out=$("$iird" bench --methods iir,nope --frames 2 --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "unknown method 'nope'" || fail "unknown method: $out"
out=$("$iird" bench --frames 1 2>&1)
[ $? = 2 ] || fail "--frames 1 accepted: $out"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all bench checks passed"

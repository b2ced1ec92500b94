#!/usr/bin/env bash
# test_bench.sh -- `iird bench` and the VPL methods from the command line: the CSV has the
# documented columns and finite numbers, a --sweep gives one run per method and value it uses,
# summary.json has its keys, charts are drawn when matplotlib is there, references come from their
# cache on a second run with identical scores, paths are found by name, and bad options are refused
# naming the option. Usage: test_bench.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" bench

# A Python with matplotlib (iird bench looks for the same two).
py=""
for p in python3 /usr/bin/python3; do
    if "$p" -c 'import matplotlib' 2>/dev/null; then py=$p; break; fi
done
pyany=$(command -v python3 || echo /usr/bin/python3)

# Stills with the VPL methods.
for m in ir iir; do
    out=$("$iird" render --method $m --size 32x24 --vpls 64 --refine-passes 1 --out "$tmp/$m.png" 2>&1) ||
        fail "render --method $m: $out"
    echo "$out" | grep -q "method $m, " || fail "render --method $m summary: $out"
done
out=$("$iird" render --method iir --kmin 9 --kmax 8 --size 8x8 --out "$tmp/x.png" 2>&1)
[ $? = 2 ] && echo "$out" | grep -q kmin || fail "kmin > kmax not refused: $out"

# A short bench: three methods, a sweep over vpls (pt does not read it: one default run), a
# frame range of a named path, references at range frames 0, 1, 2, 3.
mkdir -p "$tmp/a" "$tmp/b"
args=(--anim orbit --methods iir,ir,pt --sweep vpls=16,48 --frames 10:14 --ref-every 2
      --ref-spp 24 --spp 2 --size 64x48 --sm-res 32 --ref-cache "$tmp/cache")
"$iird" bench "${args[@]}" --out "$tmp/a" --save-images > "$tmp/a/stdout.txt" 2>&1 ||
    fail "bench failed: $(cat "$tmp/a/stdout.txt")"
grep -q "iir/ir \[vpls=16 vs vpls=16\]: frame rate x" "$tmp/a/stdout.txt" ||
    fail "no ratio line: $(cat "$tmp/a/stdout.txt")"
grep -q "references: 4 at 24 spp, 0 from the cache" "$tmp/a/stdout.txt" ||
    fail "first run used a cache: $(cat "$tmp/a/stdout.txt")"
"$pyany" - "$tmp/a" <<'PY' || fail "frames.csv / summary.json are not as documented"
import csv, json, math, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(d + "/frames.csv")))
need = ["method", "setting", "frame", "total_ms", "trace_ms", "vpls_ms", "shadowmaps_ms",
        "gbuffer_ms", "direct_ms", "indirect_ms", "filter_ms", "rays_camera", "rays_shadow",
        "rays_bounce", "rays_vpl", "rays_shadowmap", "rays_visibility", "vpls", "vpls_valid",
        "vpls_invalidated", "vpls_deleted", "vpls_inserted", "vpls_null", "regenerated",
        "shadowmaps", "vpl_evals", "vpl_reused", "rss_mb", "method_mb", "mean_lum", "rmse",
        "relmse", "flicker"]
missing = [c for c in need if c not in rows[0]]
assert not missing, missing
runs = sorted({(r["method"], r["setting"]) for r in rows})
assert runs == [("iir", "vpls=16"), ("iir", "vpls=48"), ("ir", "vpls=16"), ("ir", "vpls=48"),
                ("pt", "default")], runs
assert len(rows) == 5 * 4, len(rows)
# a row fills the phase columns its method declares and leaves the others empty
PHASES = {"pt": ["trace"], "ir": ["vpls", "shadowmaps", "gbuffer", "direct", "indirect", "filter"]}
PHASES["iir"] = PHASES["ir"]
for r in rows:
    assert r["frame"] in ("10", "11", "12", "13"), r["frame"]
    for c in need[3:-3]:
        if c.endswith("_ms") and c != "total_ms" and c[:-3] not in PHASES[r["method"]]:
            assert r[c] == "", (r["method"], c, r[c])
            continue
        assert math.isfinite(float(r[c])) and float(r[c]) >= 0, (c, r[c])
    assert float(r["total_ms"]) > 0 and float(r["rss_mb"]) > 0 and float(r["mean_lum"]) > 0
    for c in ["rmse", "relmse"]:
        assert math.isfinite(float(r[c])) and float(r[c]) >= 0, (c, r[c])
    assert (r["flicker"] == "") == (r["frame"] == "10"), r["frame"]
    if r["method"] == "pt":
        assert float(r["method_mb"]) == 0 and int(r["vpls"]) == 0
    else:
        assert float(r["method_mb"]) > 0, r
iir = [r for r in rows if r["method"] == "iir" and r["setting"] == "vpls=48"]
assert int(iir[0]["shadowmaps"]) > int(iir[1]["shadowmaps"]), "iir rebuilt every map"
# the kept VPLs' columns: written at a VPL's second frame while the set is new (its first after),
# read from the next; ir keeps none
for r in rows:
    assert int(r["vpl_reused"]) <= int(r["vpl_evals"]), r
    if r["method"] != "iir" or r["frame"] in ("10", "11"):
        assert int(r["vpl_reused"]) == 0, r
assert all(int(r["vpl_reused"]) > 0.5 * int(r["vpl_evals"]) for r in iir[2:]), iir
assert int(iir[0]["vpls"]) == 48, iir[0]["vpls"]

s = json.load(open(d + "/summary.json"))
for k in ["version", "date", "command", "machine", "scene", "scene_hash", "path", "frames",
          "first_frame", "width", "height", "references", "runs", "ratios"]:
    assert k in s, k
assert s["machine"]["nproc"] >= 1 and s["machine"]["cpu_model"], s["machine"]
assert s["command"].startswith("iird bench") and "--sweep vpls=16,48" in s["command"]
assert s["first_frame"] == 10 and s["frames"] == 4 and s["path"].endswith("orbit.json")
assert s["references"]["needed"] == 4 and s["references"]["from_cache"] == 0
assert len(s["runs"]) == 5
for run in s["runs"]:
    for k in ["mean_ms", "median_ms", "p95_ms", "fps", "rmse", "relmse", "flicker"]:
        assert isinstance(run[k], float) and math.isfinite(run[k]) and run[k] > 0, (k, run)
    assert run["p95_ms"] >= run["median_ms"] > 0
    want = ["trace"] if run["method"] == "pt" else ["vpls", "shadowmaps", "gbuffer", "direct",
                                                    "indirect", "filter"]
    assert list(run["phase_ms"]) == want, (run["method"], run["phase_ms"])
    assert run["counters_per_frame"] == {}, run["counters_per_frame"]
    assert run["rays_per_frame"]["total"] > 0
    assert set(run["vpl_churn_per_frame"]) >= {"inserted", "deleted", "invalidated"}
    assert isinstance(run["regenerations"], int) and run["rss_peak_mb"] > 0
assert [(r["iir"], r["ir"]) for r in s["ratios"]] == [("vpls=16", "vpls=16"),
                                                      ("vpls=48", "vpls=48")], s["ratios"]
PY
for f in ref_00010 ref_00013 iir_vpls=16_00011 ir_vpls=48_00012 pt_00010; do
    [ -s "$tmp/a/$f.pfm" ] || fail "missing $f.pfm"
done

# Charts, when matplotlib is there: PNG magic, SVG that parses as XML.
if [ -n "$py" ]; then
    for c in time_vs_error error_over_time flicker_over_time phases vpl_churn; do
        [ "$(head -c 8 "$tmp/a/$c.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] ||
            fail "$c.png is not a PNG"
        "$py" -c 'import sys, xml.etree.ElementTree as E; assert E.parse(sys.argv[1]).getroot().tag.endswith("svg")' \
            "$tmp/a/$c.svg" || fail "$c.svg is not SVG"
    done
else
    echo "note: no python3 with matplotlib; chart checks skipped"
    grep -q "apt-get install python3-matplotlib" "$tmp/a/stdout.txt" || fail "no hint on charts"
fi

# The same bench again: every reference from the cache, faster, the same scores.
"$iird" bench "${args[@]}" --out "$tmp/b" --no-charts > "$tmp/b/stdout.txt" 2>&1 ||
    fail "second bench failed: $(cat "$tmp/b/stdout.txt")"
grep -q "references: 4 at 24 spp, 4 from the cache in $tmp/cache" "$tmp/b/stdout.txt" ||
    fail "second run missed the cache: $(cat "$tmp/b/stdout.txt")"
[ -e "$tmp/b/time_vs_error.png" ] && fail "--no-charts drew charts"
"$pyany" - "$tmp/a" "$tmp/b" <<'PY' || fail "cached references changed the scores"
import csv, json, sys
a, b = (list(csv.DictReader(open(d + "/frames.csv"))) for d in sys.argv[1:3])
cols = ["method", "setting", "frame", "rmse", "relmse", "flicker"]
assert [[r[c] for c in cols] for r in a] == [[r[c] for c in cols] for r in b]
ta, tb = (json.load(open(d + "/summary.json"))["references"]["seconds"] for d in sys.argv[1:3])
assert tb < ta, (ta, tb)
PY

# Without a script, --frames N is the orbit's length.
out=$("$iird" bench --methods iir --frames 3 --ref-spp 0 --size 16x12 --vpls 16 2>&1) ||
    fail "bench --frames 3: $out"
echo "$out" | grep -q "built-in orbit, 16x12, 3 frames (0:3" || fail "orbit summary: $out"
# A script file by path, cut by --frames N.
out=$("$iird" bench --anim "$src/scenes/cornell_box/paths/teleport.json" --frames 3 --ref-spp 0 \
    --methods iir --size 16x12 --vpls 32 2>&1) || fail "bench --anim FILE: $out"
echo "$out" | grep -q "path .*teleport.json, 16x12, 3 frames" || fail "bench --anim summary: $out"

# Bad input: exit 2 and the option named.
printf '{"fps": 30, "duration": 1, "light": {"keys": [{"t": 0, "postion": [0, 1, 0]}]}}' > "$tmp/bad.json"
out=$("$iird" bench --anim "$tmp/bad.json" --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "postion" || fail "bad script not refused by field: $out"
out=$("$iird" bench --anim nosuchpath --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "names no path 'nosuchpath' (its paths: orbit" ||
    fail "unknown path name: $out"
out=$("$iird" bench --methods iir,nope --frames 2 --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "unknown method 'nope'" || fail "unknown method: $out"
for bad in "1" "5:3" "4:5" "x" "2:" "-1:4"; do
    out=$("$iird" bench --frames "$bad" --ref-spp 0 --size 8x8 2>&1)
    [ $? = 2 ] && echo "$out" | grep -q -- "--frames" || fail "--frames $bad: $out"
done
out=$("$iird" bench --anim teleport --frames 0:100000 --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q -- "--frames 0:100000: the path has 151 frames" ||
    fail "--frames past the script: $out"
for bad in "vpls" "=1" "nope=1" "vpls=0" "vpls=" "threads=1" "ir-same-random=1" "weights=odd"; do
    out=$("$iird" bench --sweep "$bad" --ref-spp 0 --size 8x8 2>&1)
    [ $? = 2 ] && echo "$out" | grep -q -- "--sweep" || fail "--sweep $bad: $out"
done
out=$("$iird" bench --sweep vpls=8 --sweep vpls=16 --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q "given twice" || fail "--sweep twice: $out"
out=$("$iird" bench --methods iir --sweep kmax=2 --frames 2 --ref-spp 0 --size 8x8 2>&1)
[ $? = 2 ] && echo "$out" | grep -q -- "--sweep: iir with kmax=2" || fail "kmax < kmin: $out"

# Output folders: --out and --ref-cache are made with their parents before any work; an --out
# that cannot be written is refused at once (exit 3, --out named) before references are rendered
# (none reach the cache) however long the bench would have taken; a --ref-cache that cannot be
# made is a warning and the bench goes on without it.
quickargs=(--methods iir --frames 2 --ref-spp 2 --size 16x12 --vpls 16 --sm-res 32 --no-charts)
out=$("$iird" bench "${quickargs[@]}" --out "$tmp/new/deep/out" --ref-cache "$tmp/new/cache/refs" 2>&1) ||
    fail "bench into new nested folders: $out"
[ -s "$tmp/new/deep/out/frames.csv" ] || fail "no frames.csv in a new nested --out"
[ "$(ls "$tmp/new/cache/refs" | grep -c '\.pfm$')" = 2 ] || fail "no references in a new nested --ref-cache"
touch "$tmp/file"
quick 2000 3 "--out .*file/out.*not a directory" -- "$iird" bench --methods iir,ir,pt --frames 400 \
    --ref-spp 4096 --size 512x384 --ref-cache "$tmp/unused" --out "$tmp/file/out"
[ -e "$tmp/unused" ] && fail "a refused --out still prepared the reference cache"
out=$("$iird" bench "${quickargs[@]}" --ref-cache "$tmp/file/cache" 2>&1) ||
    fail "bench with an unusable --ref-cache failed: $out"
echo "$out" | grep -qi "warning: no reference cache: --ref-cache .*file/cache.*not a directory" ||
    fail "no warning for an unusable --ref-cache: $out"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all bench checks passed"

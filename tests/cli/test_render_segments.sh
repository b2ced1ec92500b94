#!/usr/bin/env bash
# test_render_segments.sh -- `iird render --anim --segment I/N` and `iird render --merge DIR` (issue
# 17, docs/cli.md and docs/deploy.md): the orbit rendered by one process and as 4 segments into one
# directory (out of order, as a farm's tasks finish) gives byte-identical frames; the merge writes
# one render.json holding every frame and every part's run, and the video; a segment run again after
# a failed task goes on from the first frame its part file lacks; the merge refuses, naming what to
# re-run, a missing part, a missing frame image, parts of different settings, and bad arguments.
# And `iird bench --refs-only --segment I/N`: two shares fill one reference cache, and a bench then
# renders no reference.
# Usage: test_render_segments.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" segments
orbit=$src/scenes/cornell_box/paths/orbit.json
common=(--size 48x36 --sm-res 16)

"$iird" render --anim "$orbit" "${common[@]}" --out "$tmp/one" >/dev/null 2>&1 || fail "one process"
for i in 2 0 3 1; do
    out=$("$iird" render --anim "$orbit" "${common[@]}" --out "$tmp/parts" --segment $i/4 2>&1) ||
        fail "segment $i/4: $out"
    echo "$out" | grep -q "render.part-$i-of-4.json: " || fail "segment $i/4's summary: $out"
done
[ -e "$tmp/parts/render.json" ] && fail "a segment wrote render.json (its log is its part file)"
out=$("$iird" render --merge "$tmp/parts" --video "$tmp/video/orbit.mp4" 2>&1) || fail "merge: $out"
echo "$out" | grep -q "merged 4 segments of 201 frames" || fail "merge's summary: $out"
[ -s "$tmp/video/orbit.mp4" ] || fail "the merge wrote no video"
n=0
for f in "$tmp"/one/frame_*.png; do cmp -s "$f" "$tmp/parts/${f##*/}" || n=$((n + 1)); done
[ "$n" = 0 ] || fail "$n frames of the segments differ from one process's"
python3 - "$tmp/parts/render.json" <<'PY' || fail "the merged render.json"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["totals"]["frames"] == 201 and d["totals"]["missing"] == 0, d["totals"]
assert [f["frame"] for f in d["frames"]] == list(range(201))
assert len(d["runs"]) == 4 and "segment" not in d
PY

# a failed task run again resumes: drop two frames of segment 1 from its part file
python3 - "$tmp/parts/render.part-1-of-4.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["frames"] = [f for f in d["frames"] if f["frame"] < 70]
json.dump(d, open(sys.argv[1], "w"))
PY
expect 2 "segment 1 of 4 has no frame 70.*--segment 1/4" -- "$iird" render --merge "$tmp/parts"
out=$("$iird" render --anim "$orbit" "${common[@]}" --out "$tmp/parts" --segment 1/4 2>&1) ||
    fail "segment 1/4 again: $out"
echo "$out" | grep -q "going on from frame 70" || fail "the segment did not resume: $out"
expect 0 "merged 4 segments" -- "$iird" render --merge "$tmp/parts"
cmp -s "$tmp/one/frame_00080.png" "$tmp/parts/frame_00080.png" || fail "a resumed frame differs"

# what the merge refuses
mv "$tmp/parts/render.part-3-of-4.json" "$tmp/part3"
expect 2 "segment 3 of 4 is missing .*--segment 3/4" -- "$iird" render --merge "$tmp/parts"
mv "$tmp/part3" "$tmp/parts/render.part-3-of-4.json"
rm "$tmp/parts/frame_00180.png"
expect 3 "frame_00180.png \(frame 180, segment 3 of 4\) is missing" -- "$iird" render --merge "$tmp/parts"
"$iird" render --anim "$orbit" "${common[@]}" --vpls 64 --out "$tmp/mixed" --segment 0/2 >/dev/null 2>&1
"$iird" render --anim "$orbit" "${common[@]}" --vpls 32 --out "$tmp/mixed" --segment 1/2 >/dev/null 2>&1
expect 2 "--vpls differs" -- "$iird" render --merge "$tmp/mixed"
expect 2 "no render.part-I-of-N.json" -- "$iird" render --merge "$tmp/one"
expect 64 "--merge DIR takes no --out" -- "$iird" render --merge "$tmp/parts" --out "$tmp/x"
expect 64 "--merge DIR takes no --size" -- "$iird" render --merge "$tmp/parts" --size 64x48
expect 64 "give --frames or --segment" -- "$iird" render --anim "$orbit" --out "$tmp/x" --segment 0/2 --frames 0:4
expect 64 "the video comes from the merge" -- "$iird" render --anim "$orbit" --out "$tmp/x" --segment 0/2 --video "$tmp/x.mp4"
expect 2 "--segment '2/2' must be I/N" -- "$iird" render --anim "$orbit" --out "$tmp/x" --segment 2/2
expect 64 "--segment needs --anim" -- "$iird" render --out "$tmp/x.png" --segment 0/2

# bench's references as shares (--refs-only --segment I/N) into one cache: a later bench renders none
bench=(--frames 0:12 --size 32x24 --ref-spp 4 --ref-every 4 --methods iir,ir --sweep bounces=2,3)
for i in 1 0; do
    out=$("$iird" bench --refs-only --segment $i/2 --ref-cache "$tmp/refs" "${bench[@]}" 2>&1) ||
        fail "references share $i/2: $out"
    echo "$out" | grep -q "share $i/2: 6 of the 12 needed; 6 rendered" || fail "share $i/2: $out"
done
out=$("$iird" bench --ref-cache "$tmp/refs" "${bench[@]}" --out "$tmp/bench" --no-charts 2>&1) ||
    fail "bench after the shares: $out"
echo "$out" | grep -q "references: 12 at 4 spp, 12 from the cache" || fail "a reference was rendered again: $out"
expect 64 "--segment needs --refs-only" -- "$iird" bench --segment 0/2 "${bench[@]}"
expect 64 "no --out" -- "$iird" bench --refs-only --out "$tmp/x" "${bench[@]}"
expect 2 "the reference cache, which is off" -- "$iird" bench --refs-only --no-ref-cache "${bench[@]}"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "ok: 4 segments byte-identical to one process, merged, resumed, refusals; reference shares"

#!/usr/bin/env bash
# test_render_anim.sh -- `iird render --anim` as an animator runs it: the frame files and
# render.json, a resumed run that continues (and matches an uninterrupted one byte for byte),
# refusing to resume with other settings, Ctrl-C keeping whole frames and printing a resume
# command that completes the set, bad options naming themselves, the MP4 through ffmpeg, and
# determinism. Usage: test_render_anim.sh IIRD SOURCE_DIR
set -u
iird=$(realpath "$1") # some checks run from other folders
src=$2
. "$(dirname "$0")/lib.sh" render-anim

orbit=$src/scenes/cornell_box/paths/orbit.json
small=(--size 64x48 --vpls 32 --sm-res 32)

# has_frames DIR EXT A B: frame_A..frame_{B-1} exist and start with the format's magic bytes.
has_frames() {
    local dir=$1 ext=$2 a=$3 b=$4 magic f
    case $ext in png) magic="89 50 4e 47" ;; exr) magic="76 2f 31 01" ;; pfm) magic="50 46 0a" ;; esac
    for ((f = a; f < b; f++)); do
        printf -v name 'frame_%05d.%s' "$f" "$ext"
        [ -s "$dir/$name" ] || { fail "$dir/$name missing"; return; }
        head -c ${#magic} "$dir/$name" | od -An -tx1 | grep -q "${magic:0:8}" ||
            fail "$dir/$name is not a $ext file"
    done
}

# check_log DIR N: render.json parses, has N frame entries 0..N-1 with finite stats, and totals.
check_log() {
    python3 - "$1/render.json" "$2" <<'PY' || fail "$1/render.json is not as documented"
import json, math, sys
d = json.load(open(sys.argv[1]))
n = int(sys.argv[2])
s = d["settings"]
assert s["method"] == "iir" and s["size"] == [64, 48] and s["format"] in ("png", "exr", "pfm"), s
assert s["params"]["vpls"] == 32 and s["params"]["seed"] == 1 and s["script"]["frames"] == 201, s
assert d["script"].endswith("orbit.json"), d["script"]
fr = d["frames"]
assert [e["frame"] for e in fr] == list(range(n)), [e["frame"] for e in fr]
for e in fr:
    assert math.isfinite(e["total_ms"]) and e["total_ms"] > 0, e
    assert abs(e["time_s"] - e["frame"] / 30) < 1e-9, e
    assert list(e["phase_ms"]) == ["vpls", "shadowmaps", "gbuffer", "direct", "indirect", "filter"], e
    assert e["counters"] == {}, e
    assert e["vpls"]["count"] == 32 and e["rays"]["shadow"] > 0, e
    assert e["file"] == "frame_%05d.%s" % (e["frame"], s["format"]), e
assert fr[0]["rays"]["camera"] == 64 * 48, fr[0]
assert fr[0]["vpls"]["inserted"] == 32 and all(e["vpls"]["inserted"] <= 8 for e in fr[1:])
t = d["totals"]
assert t["frames"] == n and t["missing"] == 201 - n, t
assert abs(t["total_ms"] - sum(e["total_ms"] for e in fr)) < 1e-2, t
assert all(r["status"] == "complete" for r in d["runs"]), d["runs"]
PY
}

# ---- a short run: files, render.json, summary ----
out=$("$iird" render --anim "$orbit" --out "$tmp/a" --frames 0:6 "${small[@]}" 2>&1) ||
    fail "render --anim: $out"
echo "$out" | grep -qE "wrote 6 frames \(0\.\.5 of 201\) to .*ms/frame rendering \([0-9.]+ fps\)" ||
    fail "summary line: $out"
has_frames "$tmp/a" png 0 6
[ -e "$tmp/a/frame_00006.png" ] && fail "frame 6 was rendered outside --frames 0:6"
check_log "$tmp/a" 6
ls "$tmp/a" | grep -q '\.part$' && fail "temporary files left in $tmp/a"

# Determinism: the same command again gives the same bytes.
"$iird" render --anim "$orbit" --out "$tmp/b" --frames 0:6 "${small[@]}" >/dev/null 2>&1
for f in "$tmp"/a/frame_*.png; do
    cmp -s "$f" "$tmp/b/${f##*/}" || fail "${f##*/} differs between two identical runs"
done

# ---- resume: 0:3 then 3: fills the set; frames 3..5 equal the uninterrupted run's ----
"$iird" render --anim "$orbit" --out "$tmp/r" --frames 0:3 "${small[@]}" >/dev/null 2>&1 ||
    fail "render --frames 0:3"
out=$("$iird" render --anim "$orbit" --out "$tmp/r" --frames 3:6 "${small[@]}" 2>&1) ||
    fail "render --frames 3:6: $out"
echo "$out" | grep -q "warm-up of frames 0..2" || fail "no warm-up reported: $out"
has_frames "$tmp/r" png 0 6
check_log "$tmp/r" 6
for f in "$tmp"/a/frame_*.png; do
    cmp -s "$f" "$tmp/r/${f##*/}" || fail "${f##*/} of the resumed run differs from one run's"
done
python3 - "$tmp/r/render.json" <<'PY' || fail "resumed render.json lacks its runs or warm-up"
import json, sys
runs = json.load(open(sys.argv[1]))["runs"]
assert [r["frames"] for r in runs] == [[0, 3], [3, 6]], runs
assert runs[0]["warmup"]["frames"] == 0 and runs[1]["warmup"]["frames"] == 3, runs
PY

# Other settings are refused, naming the option; the directory is left as it was.
expect 2 "--vpls differs .*render.json \(32 there, 16 now\)" -- \
    "$iird" render --anim "$orbit" --out "$tmp/r" --frames 6:7 --size 64x48 --vpls 16 --sm-res 32
expect 2 "--size differs" -- \
    "$iird" render --anim "$orbit" --out "$tmp/r" --frames 6:7 --size 32x24 --vpls 32 --sm-res 32
expect 2 "--method differs" -- \
    "$iird" render --anim "$orbit" --out "$tmp/r" --frames 6:7 "${small[@]}" --method ir
expect 2 "--anim .*differs" -- \
    "$iird" render --anim "$src/scenes/cornell_box/paths/sweep-fast.json" --out "$tmp/r" \
    --frames 6:7 "${small[@]}"
[ -e "$tmp/r/frame_00006.png" ] && fail "a refused resume rendered a frame"
check_log "$tmp/r" 6

# ---- other formats ----
for ext in exr pfm; do
    "$iird" render --anim "$orbit" --out "$tmp/$ext" --frames 0:2 --format $ext "${small[@]}" \
        >/dev/null 2>&1 || fail "--format $ext"
    has_frames "$tmp/$ext" $ext 0 2
done

# ---- bad input: exit 2 naming the option, before any work ----
expect 2 "--frames 5:2" -- "$iird" render --anim "$orbit" --out "$tmp/x" --frames 5:2
expect 2 "--frames 'x:y'" -- "$iird" render --anim "$orbit" --out "$tmp/x" --frames x:y
expect 2 "--frames '7'" -- "$iird" render --anim "$orbit" --out "$tmp/x" --frames 7
expect 2 "--frames 190:300.*201 frames" -- "$iird" render --anim "$orbit" --out "$tmp/x" --frames 190:300
expect 2 "--frames 201:.*201 frames" -- "$iird" render --anim "$orbit" --out "$tmp/x" --frames 201:
expect 2 "--format 'bmp'" -- "$iird" render --anim "$orbit" --out "$tmp/x" --format bmp
expect 64 "--frames needs --anim" -- "$iird" render --out "$tmp/x.png" --frames 0:2
expect 64 "--out DIR is required" -- "$iird" render --anim "$orbit"
touch "$tmp/plain"
expect 3 "--out .*plain/such.*not a directory" -- \
    "$iird" render --anim "$orbit" --out "$tmp/plain/such" --frames 0:1 "${small[@]}"
[ -e "$tmp/x" ] && fail "a refused run created its --out directory"
expect 2 "--size 65x48: --video needs an even" -- \
    "$iird" render --anim "$orbit" --out "$tmp/x" --size 65x48 --video "$tmp/x.mp4"
expect 4 "ffmpeg" -- env PATH=/nonexistent "$iird" render --anim "$orbit" --out "$tmp/x" \
    "${small[@]}" --video "$tmp/x.mp4"

# ---- Ctrl-C: whole frames only, exit 130, a resume command that completes the set ----
"$iird" render --anim "$orbit" --out "$tmp/i" --frames 0:40 "${small[@]}" --threads 1 \
    >/dev/null 2>"$tmp/int.log" &
pid=$!
for _ in $(seq 200); do
    [ -e "$tmp/i/frame_00000.png" ] && break
    sleep 0.02
done
kill -INT $pid
wait $pid
rc=$?
[ "$rc" = 130 ] || fail "interrupted run exited $rc, expected 130: $(cat "$tmp/int.log")"
cmd=$(sed -n 's/^iird render: interrupted after \([0-9]*\) of 40 frames; resume with: //p' "$tmp/int.log")
done_n=$(sed -n 's/^iird render: interrupted after \([0-9]*\) of 40 frames.*/\1/p' "$tmp/int.log")
[ -n "$cmd" ] || fail "no resume command: $(cat "$tmp/int.log")"
if [ -n "$cmd" ]; then
    [ "$(ls "$tmp/i" | grep -c '^frame_.*\.png$')" = "$done_n" ] ||
        fail "$done_n frames reported, $(ls "$tmp/i" | grep -c '^frame_') on disk"
    ls "$tmp/i" | grep -q '\.part$' && fail "a partial frame was left behind"
    for f in "$tmp"/i/frame_*.png; do
        tail -c 12 "$f" | grep -q IEND || fail "${f##*/} is cut short"
    done
    echo "$cmd" | grep -q -- "--frames $done_n:40" || fail "resume command: $cmd"
    eval "$cmd" >/dev/null 2>&1 || fail "the resume command failed: $cmd"
    has_frames "$tmp/i" png 0 40
    [ "$(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["frames"]))' \
        "$tmp/i/render.json")" = 40 ] || fail "render.json after the resume lacks frames"
fi

# ---- --video: an MP4 with one frame per rendered frame ----
if command -v ffmpeg >/dev/null && command -v ffprobe >/dev/null; then
    out=$("$iird" render --anim "$orbit" --out "$tmp/v" --frames 0:7 "${small[@]}" \
        --video "$tmp/v/anim.mp4" 2>&1) || fail "--video: $out"
    echo "$out" | grep -q "video .*anim.mp4: 7 frames at 30 fps" || fail "--video summary: $out"
    n=$(ffprobe -v error -select_streams v:0 -count_frames -show_entries \
        stream=nb_read_frames,codec_name,width,height -of csv=p=0 "$tmp/v/anim.mp4")
    [ "$n" = "h264,64,48,7" ] || fail "ffprobe says '$n', expected h264,64,48,7"
else
    fail "--video checks need ffmpeg and ffprobe: run make deps (it installs ffmpeg)"
fi

# ---- a script that names its scene (a browser recording): rendered there without SCENE; another
# SCENE gets a warning naming both ----
python3 - "$orbit" "$tmp/rec.json" conference <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["scene"] = sys.argv[3]
json.dump(d, open(sys.argv[2], "w"))
PY
sed 's/"conference"/"cornell_box"/' "$tmp/rec.json" >"$tmp/rec_box.json"
out=$("$iird" render --anim "$tmp/rec_box.json" --scenes "$src/scenes" --out "$tmp/s1" --frames 0:1 \
    "${small[@]}" 2>&1) || fail "a script naming cornell_box: $out"
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["scene_source"].endswith("cornell_box.scene.json"), d["scene_source"]' \
    "$tmp/s1/render.json" || fail "without SCENE the script's scene (cornell_box) is not the one rendered"
echo "$out" | grep -q warning && fail "a warning for the script's own scene: $out"
out=$("$iird" render builtin --anim "$tmp/rec.json" --out "$tmp/s2" --frames 0:1 "${small[@]}" 2>&1) ||
    fail "a script naming another scene: $out"
echo "$out" | grep -q "warning: the script was made on scene 'conference'; rendering it on 'builtin'" ||
    fail "no warning for a script made on another scene: $out"
out=$("$iird" bench builtin --anim "$tmp/rec.json" --methods iir --frames 0:2 --size 64x48 --out "$tmp/s3" 2>&1) ||
    fail "bench with a script naming another scene: $out"
echo "$out" | grep -q "iird bench: warning: the script was made on scene 'conference'" ||
    fail "bench: no warning for a script made on another scene: $out"

# ---- the script's scenes folder and size (a browser recording names both): used without --scenes
# and --size, from another folder; a folder missing here is passed over with a warning ----
python3 - "$tmp/rec_box.json" "$tmp/rec_where.json" "$src/scenes" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d.update(scenes=sys.argv[3], size=[40, 30])
json.dump(d, open(sys.argv[2], "w"))
PY
sed "s|\"scenes\": \"[^\"]*\"|\"scenes\": \"$tmp/gone\"|" "$tmp/rec_where.json" >"$tmp/rec_gone.json"
mkdir -p "$tmp/elsewhere"
out=$(cd "$tmp/elsewhere" && IIR_SCENES= "$iird" render --anim "$tmp/rec_where.json" --out "$tmp/w1" \
    --frames 0:1 --vpls 32 --sm-res 32 2>&1) || fail "a script naming its scenes folder: $out"
python3 -c 'import json,sys; s=json.load(open(sys.argv[1]))["settings"]; assert s["size"] == [40, 30], s' \
    "$tmp/w1/render.json" || fail "without --size the script's size (40x30) is not the frames'"
out=$("$iird" render --anim "$tmp/rec_gone.json" --scenes "$src/scenes" --out "$tmp/w2" --frames 0:1 \
    "${small[@]}" 2>&1) || fail "--scenes over a script's missing folder: $out"
echo "$out" | grep -q warning && fail "a warning for a folder --scenes replaces: $out"
out=$(cd "$src" && "$iird" render --anim "$tmp/rec_gone.json" --out "$tmp/w3" --frames 0:1 "${small[@]}" 2>&1) ||
    fail "a script whose scenes folder is missing here: $out"
echo "$out" | grep -q "warning: the script's scenes folder $tmp/gone is not a folder here; looking 'cornell_box' up in scenes" ||
    fail "no warning for a script's missing scenes folder: $out"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all render --anim checks passed"

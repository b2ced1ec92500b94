#!/usr/bin/env bash
# test_render.sh -- `iird render` and `iird raybench` as a user runs them: outputs that exist and
# decode, deterministic images across thread counts, and every bad input giving its exit code and
# a message that names the problem. Usage: test_render.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" render

expect 0 "iird [0-9]+\.[0-9]+\.[0-9]+ \(CGAL" -- "$iird" --version
expect 0 "usage: iird render" -- "$iird" render --help
expect 0 "usage: iird raybench" -- "$iird" raybench --help
expect 64 "unknown command" -- "$iird" frobnicate
expect 64 "out FILE is required" -- "$iird" render --spp 1
expect 64 "unexpected argument" -- "$iird" render a b --out "$tmp/x.png"
expect 64 "usage" -- "$iird" render --no-such-flag --out "$tmp/x.png"

# Bad values are refused before any work.
expect 2 "size" -- "$iird" render --size 0x5 --out "$tmp/x.png"
expect 2 "size" -- "$iird" render --size 12by4 --out "$tmp/x.png"
expect 2 "spp" -- "$iird" render --spp -3 --out "$tmp/x.png"
expect 2 "bounces" -- "$iird" render --bounces 0 --out "$tmp/x.png"
expect 2 "seed" -- "$iird" render --seed abc --out "$tmp/x.png"
expect 2 "exposure" -- "$iird" render --exposure nan --out "$tmp/x.png"
expect 2 "method 'nope'.*pt" -- "$iird" render --method nope --size 8x8 --out "$tmp/x.png"
expect 2 "\.png, \.exr or \.pfm" -- "$iird" render --out "$tmp/x.txt"
[ -e "$tmp/x.txt" ] && fail "an image with a bad extension was written"

# Scenes: unknown names, paths outside the scenes directory, broken files.
expect 3 "no scene named 'nosuch'" -- "$iird" render nosuch --scenes "$src/scenes" --size 8x8 --out "$tmp/x.png"
# a path that does not exist cannot be read: 3, as docs/cli.md says (a bad bare name is 2)
expect 3 "\.\./etc" -- "$iird" render ../etc --scenes "$src/scenes" --size 8x8 --out "$tmp/x.png"
printf 'v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n' > "$tmp/broken.obj"
expect 2 "broken.obj" -- "$iird" render "$tmp/broken.obj" --size 8x8 --out "$tmp/x.png"
printf '{"camera": {"position": [0,0,0], "target": [0,0,0]}}' > "$tmp/broken.scene.json"
expect 2 "broken.scene.json" -- "$iird" render "$tmp/broken.scene.json" --size 8x8 --out "$tmp/x.png"

# A render writes the file and says so; PNG, EXR and PFM all work.
for ext in png exr pfm; do
    expect 0 "wrote .*cornell_box, 24x16, method pt, 4 samples per pixel" -- \
        "$iird" render --spp 4 --refine-passes 4 --size 24x16 --out "$tmp/c.$ext"
    [ -s "$tmp/c.$ext" ] || fail "no $ext written"
done
head -c 8 "$tmp/c.png" | od -An -tx1 | grep -q "89 50 4e 47" || fail "c.png is not a PNG"
head -c 4 "$tmp/c.exr" | od -An -tx1 | grep -q "76 2f 31 01" || fail "c.exr is not an EXR"
head -c 3 "$tmp/c.pfm" | grep -q "PF" || fail "c.pfm is not a PFM"

# Same seed: the same bytes whatever the thread count; another seed: other bytes.
"$iird" render --spp 3 --size 32x24 --seed 7 --threads 1 --out "$tmp/a.pfm" >/dev/null
"$iird" render --spp 3 --size 32x24 --seed 7 --threads 2 --out "$tmp/b.pfm" >/dev/null
"$iird" render --spp 3 --size 32x24 --seed 8 --threads 2 --out "$tmp/c.pfm" >/dev/null
cmp -s "$tmp/a.pfm" "$tmp/b.pfm" || fail "seed 7 differs between 1 and 2 threads"
cmp -s "$tmp/a.pfm" "$tmp/c.pfm" && fail "seeds 7 and 8 gave the same image"

# A shipped scene by name, and the raw-rate benchmark.
expect 0 "wrote .*cornell_box" -- "$iird" render cornell_box --scenes "$src/scenes" --spp 1 --size 16x16 --out "$tmp/s.png"
expect 0 "raw closest-hit.*Mrays/s" -- "$iird" raybench --rays 20000 --size 16x16 --spp 1

# Output folders are made with their parents and checked for writing before any work: a folder
# under a regular file is refused at once (exit 3, the option named), however long the work would
# have taken, and nothing is written.
expect 0 "wrote .*new/deep/x.png" -- "$iird" render --spp 1 --size 8x8 --out "$tmp/new/deep/x.png"
[ -s "$tmp/new/deep/x.png" ] || fail "no image in a new nested folder"
touch "$tmp/file"
quick 2000 3 "--out .*file/sub/x.png.*not a directory" -- \
    "$iird" render --spp 100000 --size 512x512 --out "$tmp/file/sub/x.png"
quick 2000 3 "--out .*file.*not a folder" -- "$iird" render --spp 100000 --out "$tmp/file/x.png"
orbit=$src/scenes/cornell_box/paths/orbit.json
small=(--size 16x12 --vpls 16 --sm-res 32)
expect 0 "wrote 2 frames \(0\.\.1 " -- "$iird" render --anim "$orbit" --frames 0:2 "${small[@]}" \
    --out "$tmp/new/anim" --video "$tmp/new/video/v.mp4"
[ -s "$tmp/new/anim/frame_00001.png" ] || fail "no frames in a new nested --anim folder"
[ -s "$tmp/new/video/v.mp4" ] || fail "no video in a new nested folder"
quick 2000 3 "--out .*file/anim.*not a directory" -- \
    "$iird" render --anim "$orbit" --size 1280x720 --out "$tmp/file/anim"
quick 2000 3 "--video .*file/v.mp4.*not a folder" -- \
    "$iird" render --anim "$orbit" --size 1280x720 --out "$tmp/anim2" --video "$tmp/file/v.mp4"
[ -e "$tmp/anim2/render.json" ] && fail "a refused --video still started the render"

# Ctrl-C keeps what is done: the partial image is written and the exit code is 130.
"$iird" render --spp 100000 --size 64x64 --out "$tmp/partial.png" >/dev/null 2>"$tmp/int.log" &
pid=$!
sleep 2
kill -INT $pid
wait $pid
rc=$?
[ "$rc" = 130 ] || fail "interrupted render exited $rc, expected 130: $(cat "$tmp/int.log")"
grep -q "interrupted after" "$tmp/int.log" || fail "no interruption message: $(cat "$tmp/int.log")"
[ -s "$tmp/partial.png" ] || fail "the partial image was not written"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s)"
    exit 1
fi
echo "all CLI checks passed"

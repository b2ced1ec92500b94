#!/usr/bin/env bash
# test_messages.sh -- issue 26 item 11, the CLI side: a parameter's range error names the unit of the
# asked method's own row (iir's vpls are VPLs, ir's paths), whatever order the options come in; a
# missing startup scene exits 3 (docs/cli.md, iir_status_exit_code: a file that cannot be read)
# for a bare name and for a path alike, with the path in the message once; a method that does not
# refine (hier, rsm) says so instead of "0 refinement passes". Usage: test_messages.sh IIRD SOURCE_DIR
set -u
iird=$(readlink -f "$1")
src=$2
. "$(dirname "$0")/lib.sh" messages

# ---- the method's own unit ----
expect 2 "^iird render: --vpls must be in \[1, 16384\] VPLs, got 99999$" -- \
    "$iird" render --method iir --vpls 99999 --out "$tmp/a.png"
expect 2 "--vpls must be in \[1, 16384\] VPLs, got 99999" -- \
    "$iird" render --vpls 99999 --method iir --out "$tmp/a.png"
expect 2 "--vpls must be in \[1, 16384\] paths, got 99999" -- \
    "$iird" render --method ir --vpls 99999 --out "$tmp/a.png"
out=$("$iird" render --method iir --vpls 99999 --out "$tmp/a.png" 2>&1)
echo "$out" | grep -q "paths" && fail "iir's vpls worded in paths: $out"
# the first bad option is still the one reported
expect 2 "--vpls must be" -- "$iird" render --method iir --vpls 0 --size 0x0 --out "$tmp/a.png"

# ---- a missing startup scene: 3, as docs/cli.md says ----
cd "$tmp" || exit 1
for s in nosuch nosuch.gltf ./nosuch.obj "$tmp/nowhere/x.gltf"; do
    expect 3 "scene" -- "$iird" serve --scene "$s" --port 0 --scenes "$src/scenes"
    expect 3 "scene" -- "$iird" render "$s" --size 16x16 --out "$tmp/b.png"
done
out=$("$iird" serve --scene "$tmp/nowhere/x.gltf" --port 0 2>&1)
[ "$(echo "$out" | grep -c "$tmp/nowhere/x.gltf")" = 1 ] || fail "the path once in: $out"
echo "$out" | grep -q "no 'x.gltf' or" && fail "the operator's message had its paths hidden: $out"
cd - >/dev/null || exit 1

# ---- methods without refinement ----
for m in hier rsm; do
    out=$("$iird" render --method $m --size 32x24 --out "$tmp/$m.png" 2>&1) || fail "render $m: $out"
    echo "$out" | grep -q "0 refinement passes" && fail "$m: $out"
    echo "$out" | grep -qE "method $m, one frame \($m does not refine\) over [1-9][0-9]* VPLs," ||
        fail "$m's work: $out"
done

[ "$failures" = 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "messages: units of the method asked, exit 3 for a missing scene, no refinement said"

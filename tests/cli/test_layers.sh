#!/usr/bin/env bash
# test_layers.sh -- the core's layers point one way: every `#include "..."` of a file under core/
# names a header of the file's own layer or of one below it, in the order docs/architecture.md
# lists between its "layers: begin" and "layers: end" marks (issue 27). Every core source file and
# public header must belong to a layer, so a new one cannot land unplaced.
# Usage: test_layers.sh IIRD SOURCE_DIR (IIRD unused: the ctest script tests' calling form)
set -u
exec /usr/bin/python3 - "$2" <<'EOF'
import os, re, sys

src = sys.argv[1]
core = os.path.join(src, "core", "src")
doc = open(os.path.join(src, "docs", "architecture.md")).read()
block = re.search(r"<!-- layers: begin -->\n(.*?)<!-- layers: end -->", doc, re.S)
if not block:
    sys.exit("FAIL: docs/architecture.md has no layers block")

place, header_layer, names = [], {}, []  # place: (core/src path or folder/, layer)
for line in block.group(1).splitlines():
    m = re.match(r"(\d+)\. ([^:]+): (.*) \| (.*)$", line)
    if not m:
        sys.exit(f"FAIL: unreadable layer line: {line!r}")
    n = int(m.group(1))
    names.append(m.group(2))
    for p in m.group(3).split():
        if p != "-":
            place.append((p, n))
    for h in m.group(4).split():
        header_layer[h] = n


def layer_of_path(rel):
    """The layer of a path under core/src: the longest folder prefix or the exact file."""
    best = None
    for p, n in place:
        if p == rel or (p.endswith("/") and rel.startswith(p)):
            if best is None or len(p) > len(best[0]):
                best = (p, n)
    return best[1] if best else None


bad = 0
files = []
for d, _, fs in os.walk(core):
    for f in fs:
        if f.endswith((".c", ".cpp", ".h", ".hpp")):
            files.append(os.path.relpath(os.path.join(d, f), core))
for h in sorted(os.listdir(os.path.join(src, "core", "include", "iir"))):
    if h not in header_layer:
        print(f"FAIL: core/include/iir/{h} belongs to no layer in docs/architecture.md")
        bad += 1

for rel in sorted(files):
    own = layer_of_path(rel)
    if own is None:
        print(f"FAIL: core/src/{rel} belongs to no layer in docs/architecture.md")
        bad += 1
        continue
    text = open(os.path.join(core, rel)).read()
    for m in re.finditer(r'^\s*#\s*include\s+"([^"]+)"', text, re.M):
        inc = m.group(1)
        if inc.startswith("iir/"):
            h = inc[4:]
            to = header_layer.get(h)
            if to is None:
                print(f"FAIL: core/src/{rel} includes {inc}, which belongs to no layer")
                bad += 1
                continue
        else:
            here = os.path.normpath(os.path.join(os.path.dirname(rel), inc))
            cand = [here, os.path.normpath(inc)]
            hit = [c for c in cand if os.path.exists(os.path.join(core, c))]
            if not hit:
                continue  # a test or system header reached through the include path
            to = layer_of_path(hit[0])
        if to is not None and to > own:
            print(f"FAIL: core/src/{rel} ({names[own - 1]}) includes {inc} ({names[to - 1]}), "
                  "a layer above it")
            bad += 1

if bad:
    print(f"{bad} layer violation(s)")
    sys.exit(1)
print(f"ok: {len(files)} core files include only their own layer or those below "
      f"({' < '.join(names)})")
EOF

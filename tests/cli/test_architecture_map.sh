#!/usr/bin/env bash
# test_architecture_map.sh -- docs/architecture.md is the code's map: every C source file of core/
# and server/ and every public header (core/include/iir/) is named in it, so a new file cannot land
# unmapped (issue 27). A file is named when its base name appears in the map.
# Usage: test_architecture_map.sh IIRD SOURCE_DIR (IIRD unused: the ctest script tests' calling form)
set -u
src=$2
map="$src/docs/architecture.md"
[ -f "$map" ] || { echo "FAIL: no $map"; exit 1; }
missing=0
while IFS= read -r f; do
    name=$(basename "$f")
    if ! grep -qF -- "$name" "$map"; then
        echo "FAIL: ${f#"$src"/} is not in docs/architecture.md's map"
        missing=$((missing + 1))
    fi
done < <(find "$src/core/src" "$src/server" -name '*.c' -o -name '*.cpp' | sort;
         find "$src/core/include/iir" -name '*.h' | sort)
if [ "$missing" -gt 0 ]; then
    echo "$missing file(s) missing from the map"
    exit 1
fi
echo "ok: every source file and public header is in docs/architecture.md"

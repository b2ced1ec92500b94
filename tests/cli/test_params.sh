#!/usr/bin/env bash
# test_params.sh -- the parameter tables as the command line shows them: docs/cli.md's generated
# section equals `iird params --markdown`; `--method M --help` lists M's parameters and no other
# method's; options a method does not declare are refused; a value outside a row's range names the
# option. Usage: test_params.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$src/tests/cli/lib.sh" params

# 1. docs/cli.md between the markers is exactly what the tables print.
doc=$(sed -n '/<!-- params:begin -->/,/<!-- params:end -->/p' "$src/docs/cli.md" | sed '1d;$d')
gen=$("$iird" params --markdown | sed '1{/^$/d}')
if [ "$doc" != "$gen" ]; then
    fail "docs/cli.md's parameter tables differ from 'iird params --markdown' (regenerate them):
$(diff <(echo "$doc") <(echo "$gen") | head -20)"
fi

# 2. Per-method help comes from the tables.
help_iir=$("$iird" render --method iir --help) || fail "render --method iir --help failed"
help_pt=$("$iird" render --method pt --help) || fail "render --method pt --help failed"
for opt in --kmin --kmax --weights --regen-threshold --sm-res --interleave --seed; do
    echo "$help_iir" | grep -q -- "$opt" || fail "iir's help lacks $opt"
done
echo "$help_iir" | grep -q -- "--spp " && fail "iir's help lists pt's --spp"
echo "$help_pt" | grep -q -- "--spp " || fail "pt's help lacks --spp"
echo "$help_pt" | grep -q -- "--kmin" && fail "pt's help lists iir's --kmin"
"$iird" params --method ir | grep -q -- "--same-random" || fail "iird params --method ir lacks --same-random"

# 3. Refusals name the option.
expect_exit() { # CODE PATTERN ARGS...
    local code=$1 pat=$2
    shift 2
    out=$("$iird" "$@" 2>&1)
    rc=$?
    [ $rc = "$code" ] || fail "iird $*: exit $rc, expected $code: $out"
    echo "$out" | grep -q -- "$pat" || fail "iird $*: message lacks '$pat': $out"
}
expect_exit 2 "--vpls is not a parameter of pt" render --method pt --vpls 8 --out "$IIR_TEST_TMP/x.png"
expect_exit 2 "--sm-res must be in \[8, 2048\]" render --method iir --sm-res 4 --out "$IIR_TEST_TMP/x.png"
expect_exit 2 "--weights must be one of uniform, voronoi" render --method iir --weights area --out "$IIR_TEST_TMP/x.png"
expect_exit 2 "--jitter must be true or false" render --method pt --jitter=maybe --out "$IIR_TEST_TMP/x.png"
expect_exit 2 "--sweep spp is not a parameter of iir" bench --methods iir --sweep spp=1,2 --frames 2 --ref-spp 0
expect_exit 2 "not a parameter of any method" bench --methods iir --sweep nope=1 --frames 2 --ref-spp 0

[ "$failures" = 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "parameter tables: doc, help and refusals agree"

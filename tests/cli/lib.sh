# lib.sh -- what the CLI test scripts share: a scratch directory removed on exit, failure
# counting, and `expect` for exit codes and messages. Source it after setting iird and src:
#   . "$(dirname "$0")/lib.sh" NAME
# (not a test itself: ctest runs only tests/cli/test_*.sh).
tmp=${IIR_TEST_TMP:-/tmp}/cli-$1-$$
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT
failures=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect CODE PATTERN -- CMD...: runs CMD, checks exit code and that stderr+stdout match PATTERN.
expect() {
    local code=$1 pattern=$2
    shift 3
    local out rc
    out=$("$@" 2>&1)
    rc=$?
    [ "$rc" = "$code" ] || fail "'$*' exited $rc, expected $code: $out"
    echo "$out" | grep -qiE -- "$pattern" || fail "'$*' output lacks /$pattern/: $out"
}

# quick LIMIT_MS CODE PATTERN -- CMD...: expect, and CMD must also end within LIMIT_MS (for refusals
# that must come before any work: give CMD work that would take far longer).
quick() {
    local limit=$1 t0=${EPOCHREALTIME/./}
    shift
    expect "$@"
    local ms=$(((${EPOCHREALTIME/./} - t0) / 1000))
    [ "$ms" -lt "$limit" ] || fail "'${*:4}' took $ms ms, expected under $limit ms: work before the check?"
}

#!/usr/bin/env bash
# test_progress.sh -- the progress bars' ETAs agree with the time the work then takes (issue 16:
# the bench showed 1:17 and took 2:25). A bench runs on a pseudo-terminal (the bars are drawn only
# there): references, a fast iir run, then a slow pt run. While iir runs, the bar's whole-bench ETA
# ("bench MM:SS") must cover the pt run still to come (estimated from the references' time per
# frame), and while pt runs its own ETA must match what is left; both within a factor of 2.5 of
# the time that really followed. Usage: test_progress.sh IIRD SOURCE_DIR
set -u
iird=$1
src=$2
. "$(dirname "$0")/lib.sh" progress

python3 - "$iird" "$tmp" <<'PY' || fail "the bench's ETAs do not match the time it took (see above)"
import os, pty, re, statistics, subprocess, sys, time
iird, tmp = sys.argv[1], sys.argv[2]
args = [iird, "bench", "--anim", "orbit", "--methods", "iir,pt", "--frames", "0:60", "--spp", "16",
        "--ref-spp", "16", "--ref-every", "10", "--size", "192x144", "--vpls", "32", "--sm-res", "32",
        "--no-ref-cache", "--no-charts"]
master, slave = pty.openpty()
t0 = time.monotonic()
p = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave)
os.close(slave)
buf, draws = b"", []
while True:
    try:
        chunk = os.read(master, 4096)
    except OSError:
        break
    if not chunk:
        break
    now = time.monotonic() - t0
    buf += chunk
    *lines, buf = re.split(rb"[\r\n]", buf)
    draws += [(now, x.decode(errors="replace")) for x in lines if x.strip()]
rc = p.wait()
end = time.monotonic() - t0
if rc != 0:
    sys.exit(f"bench exited {rc}")
def secs(t):
    m, s = t.split(":")[-2:]
    return int(m) * 60 + int(s)
phase = {}  # label -> [(time, percent, eta, bench eta)]
for t, line in draws:
    m = re.match(r"^(\S+).*?(\d+)%\s+elapsed \S+\s+eta ([-\d:]+)(?:, bench ([-\d:]+))?", line)
    if m and "-" not in m.group(3):
        phase.setdefault(m.group(1), []).append(
            (t, int(m.group(2)), secs(m.group(3)), secs(m.group(4)) if m.group(4) else None))
print("phases:", {k: len(v) for k, v in phase.items()}, "total %.1f s" % end)
if set(phase) != {"references", "iir", "pt"}:
    sys.exit(f"bars drawn: {sorted(phase)}")
def ratio(label, column, lo_pct, hi_pct):
    """median of (ETA shown) / (time that really followed) over the draws between the percents"""
    r = [(d[column] + 0.5) / (end - d[0]) for d in phase[label]
         if lo_pct <= d[1] <= hi_pct and d[column] is not None and end - d[0] > 1.0]
    if not r:
        sys.exit(f"{label}: no draws between {lo_pct}% and {hi_pct}% with an ETA")
    return statistics.median(r)
bench_eta = ratio("iir", 3, 20, 90)
pt_eta = ratio("pt", 2, 20, 80)
print(f"iir phase: bench ETA / time left = {bench_eta:.2f}; pt phase: its ETA / time left = {pt_eta:.2f}")
ok = True
for name, r in (("the whole-bench ETA during iir", bench_eta), ("pt's ETA", pt_eta)):
    if not 0.4 <= r <= 2.5:
        print(f"FAIL: {name} is {r:.2f} x the time that followed")
        ok = False
sys.exit(0 if ok else 1)
PY

[ "$failures" = 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "progress: the bench's ETAs match the time it took"

#!/usr/bin/env python3
"""live_bench.py -- measures `iird serve` as a user meets it, over a real WebSocket on loopback:
input-to-frame latency while dragging the light at a steady rate and one move at a time, what a burst
of 100 moves renders, memory per session, and the daemon's CPU once the frame has converged; and the
VPL set's size during a fast drag (the light swept across the scene and back three times in 3 s, as
a user drags the Cornell box's spot across its ceiling). Prints a table and writes JSON. Not a test:
run it against a Release build (`make bench` does; `--params` gives the session method parameters,
e.g. an insertion budget).

    tools/live_bench.py --iird build/iird [--scene builtin] [--size 512x384] [--method iir]
                        [--rate 60] [--seconds 10] [--params '{"insert_ms": 4, "kmax": 0}']
                        [--out out/bench/live.json]

Latency of an input = arrival of the first frame whose header seq is >= the input's seq, minus the
moment the input was sent; a frame time is the server's render time of the frames in the same run
(header field), so latency / frame time says how many frames of delay the pipeline adds; "srv ms" is the
server's own part (stats.latency_ms: input received to frame handed to libwebsockets)."""

import argparse
import asyncio
import json
import math
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "integration"))
import iirserve  # noqa: E402  (the integration tests' daemon and client harness)
from iirserve import NO_SEQ, Client, Daemon, Frame, metric, metrics, pct, rss_bytes  # noqa: E402

CLK_TCK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime (fields 14, 15)


def path_point(base, u):
    """A light position on a small circle around the scene's own light (u in turns)."""
    a = 2 * math.pi * u
    return [base[0] + 0.4 * math.cos(a), base[1], base[2] + 0.4 * math.sin(a)]


def latencies(c, sent, since):
    """For every sent (seq, t): arrival of the first frame from log index `since` answering it, minus t."""
    frames = [m for m in c.log[since:] if isinstance(m, Frame) and m.kind == 1 and m.seq != NO_SEQ]
    out, j = [], 0
    for seq, t in sent:
        while j < len(frames) and frames[j].seq < seq:
            j += 1
        if j < len(frames):
            out.append((frames[j].t - t) * 1000.0)
    return out, frames


def summary(lat_ms, frames, stats=()):
    interactive = [f for f in frames if f.pass_ == 0]
    ids = {f.id for f in interactive}
    server = [m["latency_ms"] for m in stats if m.get("frame") in ids and "latency_ms" in m]
    ft = statistics.median([f.render_ms for f in interactive]) if interactive else float("nan")
    enc = statistics.median([f.encode_ms for f in interactive]) if interactive else float("nan")
    med, p95 = pct(lat_ms, 50), pct(lat_ms, 95)
    return {
        "inputs_answered": len(lat_ms),
        "frames": len(frames),
        "latency_median_ms": round(med, 2),
        "latency_p95_ms": round(p95, 2),
        "frame_ms_median": round(ft, 2),
        "encode_ms_median": round(enc, 2),
        "latency_median_frames": round(med / ft, 2) if ft > 0 else None,
        "latency_p95_frames": round(p95 / ft, 2) if ft > 0 else None,
        "server_latency_median_ms": round(pct(server, 50), 2),
    }


async def drag(c, base, rate, seconds):
    """Sends light moves at `rate` Hz for `seconds`, like a user dragging; returns the summary."""
    sent = []
    at = c.mark()
    period = 1.0 / rate
    t0 = time.monotonic()
    n = int(rate * seconds)
    for i in range(n):
        target_t = t0 + i * period
        delay = target_t - time.monotonic()
        if delay > 0:
            await asyncio.sleep(delay)
        seq = c.next_seq()
        t = time.monotonic()
        await c.send({"type": "light", "seq": seq, "position": path_point(base, i / n)})
        sent.append((seq, t))
    await c.wait_frame(since=at, min_seq=sent[-1][0], timeout=30)
    lat, frames = latencies(c, sent, at)
    s = summary(lat, frames, c.texts("stats", at))
    s["inputs_sent"] = n
    s["fps"] = round(len([f for f in frames if f.pass_ == 0]) / max(1e-9, frames[-1].t - t0), 2)
    return s


def sweep_point(base, u, half_width):
    """A light position swept along x across base and back, three times as u goes 0..1."""
    return [base[0] + half_width * math.sin(2 * math.pi * 3 * u), base[1], base[2]]


async def fast_drag(c, base, rate, seconds, half_width):
    """Sweeps the light across the scene at `rate` Hz from where it rested 2 s (the set full again);
    the VPL counts the frames' stats report."""
    seq = c.next_seq()
    await c.send({"type": "light", "seq": seq, "position": sweep_point(base, 0.0, half_width)})
    await c.wait_frame(min_seq=seq, timeout=30)
    await asyncio.sleep(2.0)
    at = c.mark()
    t0 = time.monotonic()
    n = int(rate * seconds)
    seq = None
    for i in range(n):
        delay = t0 + i / rate - time.monotonic()
        if delay > 0:
            await asyncio.sleep(delay)
        seq = c.next_seq()
        await c.send({"type": "light", "seq": seq, "position": sweep_point(base, i / n, half_width)})
    await c.wait_frame(since=at, min_seq=seq, timeout=30)
    stats = [m for m in c.texts("stats", at) if m.get("pass") == 0]
    counts = [m["vpl"]["count"] for m in stats]
    total = [m["total_ms"] for m in stats]
    return {"moves": n, "frames": len(stats), "half_width": half_width,
            "vpls_min": min(counts) if counts else None,
            "vpls_median": statistics.median(counts) if counts else None,
            "frame_ms_median": round(statistics.median(total), 2) if total else None,
            "counts": counts}


async def one_at_a_time(c, base, count, gap):
    """One move, wait for its frame, pause `gap` s (below the 250 ms refinement delay), repeat."""
    sent = []
    at = c.mark()
    for i in range(count):
        seq = c.next_seq()
        t = time.monotonic()
        await c.send({"type": "light", "seq": seq, "position": path_point(base, 0.5 + i / (4 * count))})
        sent.append((seq, t))
        await c.wait_frame(since=at, min_seq=seq, timeout=30)
        await asyncio.sleep(gap)
    lat, frames = latencies(c, sent, at)
    return summary(lat, frames, c.texts("stats", at))


async def burst(c, base, count=100):
    at = c.mark()
    first = c.seq + 1
    t0 = time.monotonic()
    for i in range(count):
        await c.send({"type": "light", "seq": c.next_seq(), "position": path_point(base, 0.25 + i / (8 * count))})
    last = c.seq
    f = await c.wait_frame(since=at, min_seq=last, timeout=30)
    answering = [m for m in c.frames(at) if m.seq != NO_SEQ and first <= m.seq <= last and m.pass_ == 0]
    return {"moves": count, "frames_answering": len(answering), "last_frame_seq_is_last": f.seq == last,
            "ms_to_last_frame": round((f.t - t0) * 1000, 1)}


async def idle_cpu(c, pid, seconds=5.0, converge_timeout=120.0):
    """Waits for a converged frame (or the stream to go quiet), then the daemon's CPU over `seconds`."""
    t0 = time.monotonic()
    converged = False
    try:
        await c.wait_for(lambda m: isinstance(m, Frame) and m.kind == 1 and m.flags & 1, timeout=converge_timeout,
                         since=c.mark(), what="a converged frame")
        converged = True
    except AssertionError:
        pass
    waited = time.monotonic() - t0
    await asyncio.sleep(0.5)
    n0, c0, w0 = len(c.frames()), cpu_seconds(pid), time.monotonic()
    await asyncio.sleep(seconds)
    c1, w1 = cpu_seconds(pid), time.monotonic()
    return {"converged": converged, "seconds_to_converge": round(waited, 2),
            "cpu_percent_of_one_core": round(100.0 * (c1 - c0) / (w1 - w0), 2),
            "frames_while_idle": len(c.frames()) - n0}


async def run(args):
    w, h = (int(x) for x in args.size.split("x"))
    d = Daemon("--scenes", args.scenes, scenes=False) if args.scenes else Daemon()
    result = {"scene": args.scene, "size": args.size, "method": args.method, "params": json.loads(args.params),
              "rate_hz": args.rate,
              "seconds": args.seconds, "cpus": os.cpu_count(), "iird": args.iird,
              "loadavg_before": os.getloadavg()}
    try:
        rss0 = rss_bytes(d.proc.pid)
        c = await Client.connect(d)
        if args.scene != "builtin":
            await c.request({"type": "scene", "name": args.scene}, "state", timeout=120)
        seq, st = await c.request({"type": "params", "width": w, "height": h, "method": args.method,
                                   **json.loads(args.params)}, "state")
        await c.wait_frame(min_seq=seq, timeout=60)
        base = st["light"]["position"]
        vpls = st["params"].get("vpls")
        await drag(c, base, args.rate, 1.0)  # warm-up: shadow maps, caches
        result["drag"] = await drag(c, base, args.rate, args.seconds)
        result["single"] = await one_at_a_time(c, base, args.single, 0.1)
        await c.request({"type": "params", "refine": False}, "state")
        result["single_no_refine"] = await one_at_a_time(c, base, args.single, 0.1)
        await c.request({"type": "params", "refine": True}, "state")
        result["burst"] = await burst(c, base)
        result["fast_drag"] = await fast_drag(c, base, args.rate, 3.0, args.sweep)
        result["fast_drag"]["vpls_target"] = vpls
        m = await asyncio.to_thread(metrics, d.port)
        sid = c.welcome["session"]
        result["memory"] = {
            "session_memory_bytes": metric(m, "iird_session_memory_bytes", f'session="{sid}"'),
            "process_rss_bytes": rss_bytes(d.proc.pid),
            "process_rss_before_session_bytes": rss0,
            "frames_dropped_total": metric(m, "iird_frames_dropped_total"),
        }
        result["idle"] = await idle_cpu(c, d.proc.pid)
        await c.close()
        result["loadavg_after"] = os.getloadavg()
        rc, secs = d.stop()
        result["shutdown"] = {"exit_code": rc, "seconds": round(secs, 2)}
    finally:
        d.close()
    return result


def table(r):
    rows = [("steady drag %g Hz, %g s" % (r["rate_hz"], r["seconds"]), r["drag"]),
            ("one move at a time", r["single"]), ("one at a time, refine off", r["single_no_refine"])]
    out = [f"iird serve live bench: {r['scene']} {r['size']} {r['method']}, loopback, {r['cpus']} CPUs "
           f"(load before {r['loadavg_before'][0]:.2f})",
           f"{'input':<26}{'answered':>9}{'frames':>8}{'med ms':>9}{'p95 ms':>9}{'frame ms':>10}"
           f"{'med fr':>8}{'p95 fr':>8}{'srv ms':>8}"]
    for name, s in rows:
        out.append(f"{name:<26}{s['inputs_answered']:>9}{s['frames']:>8}{s['latency_median_ms']:>9.1f}"
                   f"{s['latency_p95_ms']:>9.1f}{s['frame_ms_median']:>10.1f}"
                   f"{s['latency_median_frames'] or float('nan'):>8.2f}{s['latency_p95_frames'] or float('nan'):>8.2f}"
                   f"{s['server_latency_median_ms']:>8.1f}")
    b, m, i = r["burst"], r["memory"], r["idle"]
    out.append(f"drag frame rate {r['drag']['fps']} fps")
    fd = r["fast_drag"]
    out.append(f"fast drag (x +-{fd['half_width']}, 3 sweeps in 3 s at {r['rate_hz']:g} Hz): {fd['frames']} "
               f"frames of median {fd['frame_ms_median']} ms, VPLs min {fd['vpls_min']} median "
               f"{fd['vpls_median']} of {fd['vpls_target']}")
    out.append(f"burst of {b['moves']} moves: {b['frames_answering']} frames, last answers last seq: "
               f"{b['last_frame_seq_is_last']}, {b['ms_to_last_frame']} ms to it")
    mem = m["session_memory_bytes"]
    out.append(f"memory: session {mem / 2**20 if mem else float('nan'):.1f} MiB (/metrics), process RSS "
               f"{m['process_rss_bytes'] / 2**20:.1f} MiB ({m['process_rss_before_session_bytes'] / 2**20:.1f} "
               f"before the session)")
    out.append(f"idle after convergence ({'converged' if i['converged'] else 'NOT converged'} in "
               f"{i['seconds_to_converge']} s): {i['cpu_percent_of_one_core']}% of one core, "
               f"{i['frames_while_idle']} frames in 5 s")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iird", default="build/iird")
    ap.add_argument("--scenes", default=None, help="scenes directory (default: the daemon's)")
    ap.add_argument("--scene", default="builtin")
    ap.add_argument("--size", default="512x384")
    ap.add_argument("--method", default="iir")
    ap.add_argument("--rate", type=float, default=60.0)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--single", type=int, default=40, help="moves in the one-at-a-time run")
    ap.add_argument("--params", default="{}", help="method parameters for the session, as JSON")
    ap.add_argument("--sweep", type=float, default=0.45, help="fast drag: half the sweep's width (x)")
    ap.add_argument("--out", default="out/bench/live.json")
    args = ap.parse_args()
    iirserve.IIRD = os.path.abspath(args.iird)
    iirserve.SRC = os.path.abspath(os.path.join(HERE, ".."))
    r = asyncio.run(run(args))
    print(table(r))
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        with open(args.out, "w") as f:
            json.dump(r, f, indent=1)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

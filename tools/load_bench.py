#!/usr/bin/env python3
"""load_bench.py -- how many live sessions one `iird serve` holds at a frame rate that still feels
live (docs/deploy.md's capacity rule). For each session count K, one daemon and K WebSocket clients
on loopback, each dragging its own light at `--rate` Hz for `--seconds`; a session's frame rate is
its interactive frames over that window. Prints a table (per-session fps: median and worst; the
daemon's CPU) and writes JSON. Not a test: run it against a Release build on a quiet machine.

    tools/load_bench.py --iird build/iird [--size 512x384] [--sessions 1,2,3,4,6] [--rate 30]
                        [--seconds 8] [--method iir] [--out out/bench/load-512x384.json]"""

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
from iirserve import Client, Daemon  # noqa: E402

from live_bench import cpu_seconds  # noqa: E402  (the daemon's CPU time, from /proc)


async def drag(c, k, rate, seconds):
    """Session k's drag: its light circles at `rate` Hz; returns its interactive frames per second."""
    period, t0 = 1.0 / rate, time.monotonic()
    at = c.mark()
    for i in range(int(rate * seconds)):
        delay = t0 + i * period - time.monotonic()
        if delay > 0:
            await asyncio.sleep(delay)
        a = 2 * math.pi * (i / (rate * 2.0) + k / 7.0)
        await c.send({"type": "light", "seq": c.next_seq(),
                      "position": [0.5 * math.cos(a), 1.8, 0.5 * math.sin(a)]})
    window = time.monotonic() - t0
    frames = [f for f in c.frames(since=at) if f.pass_ == 0]
    return len(frames) / window


async def one_count(args, w, h, k):
    d = Daemon("--max-sessions", str(max(8, k)), "--size", f"{w}x{h}")
    try:
        clients = [await Client.connect(d) for _ in range(k)]
        for c in clients:
            await c.request({"type": "params", "width": w, "height": h, "method": args.method,
                             **json.loads(args.params)}, "state")
            await c.wait_frame()
        await asyncio.gather(*(drag(c, i, args.rate, 1.0) for i, c in enumerate(clients)))  # warm-up
        cpu0, t0 = cpu_seconds(d.proc.pid), time.monotonic()
        fps = await asyncio.gather(*(drag(c, i, args.rate, args.seconds) for i, c in enumerate(clients)))
        cpu = (cpu_seconds(d.proc.pid) - cpu0) / (time.monotonic() - t0)
        for c in clients:
            await c.close()
        return {"sessions": k, "fps_median": round(statistics.median(fps), 2),
                "fps_min": round(min(fps), 2), "fps_total": round(sum(fps), 2),
                "cpu_cores": round(cpu, 2)}
    finally:
        d.stop()
        d.close()


async def run(args):
    w, h = (int(x) for x in args.size.split("x"))
    rows = []
    for k in (int(x) for x in args.sessions.split(",")):
        rows.append(await one_count(args, w, h, k))
        r = rows[-1]
        print(f"{args.size} {k} session(s): {r['fps_median']} fps median, {r['fps_min']} worst, "
              f"{r['fps_total']} in all, {r['cpu_cores']} cores busy", flush=True)
    return {"size": args.size, "method": args.method, "rate_hz": args.rate, "seconds": args.seconds,
            "cpus": os.cpu_count(), "loadavg": os.getloadavg(), "rows": rows}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iird", default="build/iird")
    ap.add_argument("--size", default="512x384")
    ap.add_argument("--sessions", default="1,2,3,4,6")
    ap.add_argument("--rate", type=float, default=30.0)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--method", default="iir")
    ap.add_argument("--params", default="{}", help="method parameters for every session, as JSON")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    iirserve.IIRD = os.path.abspath(args.iird)
    iirserve.SRC = os.path.abspath(os.path.join(HERE, ".."))
    r = asyncio.run(run(args))
    out = args.out or f"out/bench/load-{args.size}.json"
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        json.dump(r, f, indent=1)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

"""test_serve_stop.py -- renders that stop when asked (issue 15, finding 4): a frame or a refinement
pass under way ends within about a tile of work when newer input arrives (after the frame has run
IIRD_FRAME_PATIENCE_MS, so a steady drag still shows frames), when the client leaves, and on SIGTERM.
Heavy work here is pt at the daemon's largest frame with its live-maximum samples, seconds to
minutes per frame under ASan. Usage: test_serve_stop.py IIRD SOURCE_DIR"""

import asyncio
import time

import iirserve
from iirserve import (Client, Daemon, DaemonTest, FAST_ARGS, metrics, session_render_seconds, wait_metric,
                      wait_metrics)

HEAVY = {"method": "pt", "width": 1920, "height": 1080, "spp": 64, "bounces": 8, "refine": False,
         "domain": False}
LIGHT = {"method": "iir", "width": 128, "height": 96, "refine": False}
# A light frame after heavy input must come within this: the heavy frame stops within a tile of
# 16x16 pixels x 64 samples (~0.1 s under ASan), then the light frame renders (~0.3 s).
ANSWER_S = 3.0
# Render time a heavy frame has run before the test acts: past its patience (newer input stops a
# frame only after IIRD_FRAME_PATIENCE_MS, or 3x the last frame's time, at most
# IIRD_FRAME_PATIENCE_MAX_MS = 1 s of the session's render time).
HEAVY_RUN_S = 1.0


async def start_heavy(port, clients):
    """After each client's first frame, asks for the heavy pt frame; returns once every one of them
    has rendered it for HEAVY_RUN_S of render time (/metrics' per-session render seconds, counted
    from its `state` reply: the worker was idle or refining, which new input stops at once)."""
    since = {}
    for c in clients:
        await c.wait_frame()
        await c.request({"type": "params", **HEAVY}, "state")
        since[c.welcome["session"]] = session_render_seconds(await asyncio.to_thread(metrics, port),
                                                            c.welcome["session"])

    def ran(samples, sid):
        return (session_render_seconds(samples, sid) or 0.0) - since[sid]

    await wait_metrics(port, lambda s: all(ran(s, sid) >= HEAVY_RUN_S for sid in since),
                       f"{HEAVY_RUN_S} s of render time of the heavy frame(s)",
                       show=lambda s: "rendered " + ", ".join(f"session {sid}: {ran(s, sid):.2f} s"
                                                              for sid in since))


class StopTest(DaemonTest):
    DAEMON_ARGS = ("--max-size", "1920x1080")

    async def heavy_then(self, c, msg):
        """Starts a heavy pt frame, lets it run past its patience, then sends msg; seconds to the
        frame answering msg (whose render must have cut the heavy one short)."""
        await start_heavy(self.daemon.port, [c])
        t0 = time.monotonic()
        seq = c.next_seq()
        await c.send({**msg, "seq": seq})
        f = await c.wait_frame(min_seq=seq)
        return time.monotonic() - t0, f

    async def test_new_input_stops_a_heavy_frame(self):
        c = await Client.connect(self.daemon)
        try:
            secs, f = await self.heavy_then(c, {"type": "params", **LIGHT})
            self.assertEqual((f.width, f.height), (128, 96), "the frame answering the light params")
            self.assertLess(secs, ANSWER_S, f"input waited {secs:.2f} s for a heavy pt frame")
            print(f"[input after a heavy frame answered in {secs:.2f} s] ", end="")
        finally:
            await c.close()

    async def test_a_leaving_client_frees_its_worker(self):
        c = await Client.connect(self.daemon)
        await start_heavy(self.daemon.port, [c])
        t0 = time.monotonic()
        await c.close()
        await wait_metric(self.daemon.port, "iird_sessions", 0,
                          f"end of the closed session's worker ({ANSWER_S} s after the close)",
                          timeout=max(0.0, t0 + ANSWER_S - time.monotonic()))
        print(f"[worker gone {time.monotonic() - t0:.2f} s after close] ", end="")

    async def test_sigterm_with_heavy_sessions(self):
        d = Daemon(*FAST_ARGS, "--max-size", "1920x1080")
        try:
            clients = [await Client.connect(d) for _ in range(2)]
            await start_heavy(d.port, clients)
            secs = d.stop_and_check(self, timeout=15.0)
            self.assertLess(secs, 2.0, f"SIGINT with two heavy sessions took {secs:.2f} s")
            print(f"[exit {secs:.2f} s after SIGINT] ", end="")
        finally:
            d.close()


if __name__ == "__main__":
    iirserve.main()

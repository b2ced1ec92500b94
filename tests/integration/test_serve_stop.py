"""test_serve_stop.py -- renders that stop when asked (issue 15, finding 4): a frame or a refinement
pass under way ends within about a tile of work when newer input arrives (after the frame has run
IIRD_FRAME_PATIENCE_MS, so a steady drag still shows frames), when the client leaves, and on SIGTERM.
Heavy work here is pt at the daemon's largest frame with its live-maximum samples, seconds to
minutes per frame under ASan. Usage: test_serve_stop.py IIRD SOURCE_DIR"""

import asyncio
import time

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, metric, metrics

HEAVY = {"method": "pt", "width": 1920, "height": 1080, "spp": 64, "bounces": 8, "refine": False,
         "domain": False}
LIGHT = {"method": "iir", "width": 128, "height": 96, "refine": False}
# A light frame after heavy input must come within this: the heavy frame stops within a tile of
# 16x16 pixels x 64 samples (~0.1 s under ASan), then the light frame renders (~0.3 s).
ANSWER_S = 3.0


class StopTest(DaemonTest):
    DAEMON_ARGS = ("--max-size", "1920x1080")

    async def heavy_then(self, c, msg):
        """Starts a heavy pt frame, lets it run a second, then sends msg; seconds to the frame
        answering msg (whose render must have cut the heavy one short)."""
        await c.request({"type": "params", **HEAVY}, "state")
        await asyncio.sleep(1.0)
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
        await c.request({"type": "params", **HEAVY}, "state")
        await asyncio.sleep(1.0)
        t0 = time.monotonic()
        await c.close()
        while metric(metrics(self.daemon.port), "iird_sessions") not in (0, 0.0):
            self.assertLess(time.monotonic() - t0, ANSWER_S, "the closed session's worker still renders")
            await asyncio.sleep(0.05)
        print(f"[worker gone {time.monotonic() - t0:.2f} s after close] ", end="")

    async def test_sigterm_with_heavy_sessions(self):
        d = Daemon(*FAST_ARGS, "--max-size", "1920x1080")
        try:
            clients = [await Client.connect(d) for _ in range(2)]
            for c in clients:
                await c.request({"type": "params", **HEAVY}, "state")
            await asyncio.sleep(1.0)
            secs = d.stop_and_check(self, timeout=15.0)
            self.assertLess(secs, 2.0, f"SIGINT with two heavy sessions took {secs:.2f} s")
            print(f"[exit {secs:.2f} s after SIGINT] ", end="")
        finally:
            d.close()


if __name__ == "__main__":
    iirserve.main()

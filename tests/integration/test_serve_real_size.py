"""test_serve_real_size.py -- the memory budget counts a method's real size on its scene (issue 25,
finding 2): radiosity's patches come from the scene's mesh (every triangle is one patch at least)
and its form factors' non-zeros from a few sampled hemicube rows, counted by the session's worker
before anything is built. On the shipped living_room_screen (142,973 triangles, 143,548 patches at
the default patch_area) the default radiosity needs about 1.9 GiB; the parameters alone said 21 MiB,
so under --max-session-memory 512M it was accepted and grew to 956 MB without end. Now it is refused
with the figure, the session goes back to its method (a `state` reply says so) and keeps streaming.
Usage: test_serve_real_size.py IIRD SOURCE_DIR"""

import time

import iirserve
from iirserve import Client, DaemonTest, rss_bytes


class RealSizeTest(DaemonTest):
    DAEMON_ARGS = ("--max-session-memory", "512M")

    async def test_radiosity_on_a_large_scene_is_refused_with_its_real_size(self):
        c = await Client.connect(self.daemon)
        try:
            await c.request({"type": "scene", "name": "living_room_screen"}, "state", timeout=120.0)
            await c.wait_frame(since=c.mark(), timeout=60.0)
            rss0 = rss_bytes(self.daemon.proc.pid)
            t0 = time.monotonic()
            seq, _ = await c.request({"type": "params", "method": "radiosity"}, "state")
            err = await c.wait_text("error", seq=seq, timeout=30.0)
            secs = time.monotonic() - t0
            self.assertEqual(err["code"], "out_of_range", err)
            self.assertIn("counted on the scene", err["message"])
            back = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "state"
                                    and m.get("seq") == seq and m.get("params", {}).get("method") == "iir",
                                    timeout=5.0, what="the state going back to iir")
            self.assertEqual(back["params"]["method"], "iir")
            f = await self.still_streaming(c, "a refused radiosity")
            self.assertIsNotNone(f)
            grown = rss_bytes(self.daemon.proc.pid) - rss0
            self.assertLess(grown, 256 << 20, f"the daemon grew {grown >> 20} MiB for a refused method")
            print(f"[refused in {secs:.2f} s: {err['message'][:90]}...; grew {grown >> 20} MiB] ", end="")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

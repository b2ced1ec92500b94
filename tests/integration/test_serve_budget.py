"""test_serve_budget.py -- the daemon's memory budget (issue 15, finding 1): a session reserves what its
settings will allocate (iird_session_estimate: frame buffers plus the method's own estimate from its
parameter tables) before anything is allocated, within --max-session-memory and, with every other
session, --max-memory. The attack message {"vpls":4096,"sm_res":2048} (64 GiB of shadow maps) is
refused naming the budget and the estimate, and leaves the session as it was; the estimate is checked
against the daemon's measured RSS. Usage: test_serve_budget.py IIRD SOURCE_DIR"""

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, metric, metrics, rss_bytes, wait_metric

ATTACK = {"type": "params", "vpls": 4096, "sm_res": 2048}
# 1024 VPLs with 256^2 shadow maps: 128 MiB of maps (half floats), far above everything else the
# session holds.
BIG = {"type": "params", "method": "iir", "vpls": 1024, "kmax": 8, "sm_res": 256}


def session_bytes(port):
    return sum(v for n, _, v in metrics(port) if n == "iird_session_memory_bytes")


async def refined(c, frame, timeout):
    """Waits for the first refinement pass of `frame` (the next frame, with pass > 0): the session has
    refined it, so what refinement allocates (iir's fresh VPL sets, counted in the estimate) is
    allocated. Refinement starts once input has been idle IIRD_REFINE_IDLE_MS; RSS grows by ~4 MiB
    (default session) and ~12 MiB (BIG) in its first pass."""
    return await c.wait_for(lambda m: isinstance(m, iirserve.Frame) and m.kind == 1 and m.pass_ > 0,
                            timeout, c.log.index(frame) + 1, what=f"refinement pass of frame {frame.id}")


class BudgetTest(DaemonTest):
    async def test_attack_refused_before_allocation(self):
        c = await Client.connect(self.daemon)
        try:
            rss0 = rss_bytes(self.daemon.proc.pid)
            seq, e = await c.request(ATTACK, "error")
            self.assertEqual(e.get("code"), "out_of_range", e)
            self.assertEqual(e.get("field"), "params", e)
            self.assertIn("--max-session-memory", e.get("message", ""))
            self.assertRegex(e.get("message", ""), r"about \d+ MiB")
            await self.still_streaming(c, "the refused attack")
            _, st = await c.request({"type": "params", "quality": 70}, "state")
            self.assertEqual(st["params"]["vpls"], 256, "the session kept its settings")
            grew = rss_bytes(self.daemon.proc.pid) - rss0
            self.assertLess(grew, 64 << 20, f"RSS grew {grew >> 20} MiB after a refused attack")
            print(f"[attack refused; RSS +{grew >> 20} MiB] ", end="")
        finally:
            await c.close()

    async def test_estimate_matches_rss(self):
        d = Daemon(*FAST_ARGS, "--max-session-memory", "2G")
        try:
            c = await Client.connect(d)
            await refined(c, await c.wait_frame(), iirserve.FRAME_TIMEOUT)
            rss0, est0 = rss_bytes(d.proc.pid), session_bytes(d.port)
            seq, _ = await c.request(BIG, "state")
            await refined(c, await c.wait_frame(min_seq=seq, timeout=120), 120)
            rss1, est1 = rss_bytes(d.proc.pid), session_bytes(d.port)
            grew, est = rss1 - rss0, est1 - est0
            print(f"[RSS +{grew / 2**20:.0f} MiB, estimate +{est / 2**20:.0f} MiB] ", end="")
            self.assertGreater(est, 100 << 20, "the estimate counts the shadow maps")
            self.assertLess(abs(grew - est), 0.25 * est, f"RSS grew {grew / 2**20:.0f} MiB, estimated {est / 2**20:.0f} MiB")
            await c.close()
            d.stop_and_check(self)
        finally:
            d.close()

    async def test_daemon_budget_across_sessions(self):
        d = Daemon(*FAST_ARGS, "--max-memory", "225M", "--max-session-memory", "200M")
        try:
            a, b = await Client.connect(d), await Client.connect(d)
            big = BIG  # ~140 MiB each: one fits in 225M, two do not
            await a.request(big, "state")
            seq, e = await b.request(big, "error")
            self.assertEqual(e.get("code"), "busy", e)
            self.assertIn("--max-memory", e.get("message", ""))
            await a.close()
            # a's reservation returns when its session ends: iird_session_destroy releases it before
            # the iird_sessions gauge counts the session out (server.c release_session)
            await wait_metric(d.port, "iird_sessions", 1, "end of a's session after its client left")
            await b.request(big, "state")
            await b.close()
            d.stop_and_check(self)
        finally:
            d.close()


class SceneBudgetTest(DaemonTest):
    """Issue 28: a scene in memory counts in --max-memory by its geometry and decoded textures
    (iird_scene_bytes): a scene that would pass the budget is refused naming it, one that fits loads."""

    async def test_scenes_count_in_the_budget(self):
        # what BIG reserves and what the two scenes hold, measured on a daemon without a tight budget
        d = Daemon(*FAST_ARGS, "--scene", "material_room")
        try:
            c = await Client.connect(d)
            await c.wait_frame()
            base = int(session_bytes(d.port))
            seq, _ = await c.request(BIG, "state")
            await c.wait_frame(min_seq=seq, timeout=120)
            big = int(session_bytes(d.port))
            room = int(metric(metrics(d.port), "iird_scene_bytes"))
            await c.close()
            d.stop_and_check(self)
        finally:
            d.close()
        self.assertGreater(room, 1 << 20, "the material room's textures are counted")
        # room for BIG and the material room (with 2 MiB to spare), not for the conference room too
        cap = big + room + (2 << 20)
        d = Daemon(*FAST_ARGS, "--scene", "material_room", "--max-memory", str(cap),
                   "--max-session-memory", str(cap))
        try:
            c = await Client.connect(d)
            await c.request(BIG, "state")
            seq, e = await c.request({"type": "scene", "name": "conference"}, "error")
            self.assertIn("--max-memory", e.get("message", ""), e)
            self.assertIn("conference", e.get("message", ""), e)
            print(f"[BIG {big >> 20} MiB (base {base >> 20}), material room {room / 2**20:.1f} MiB; "
                  f"conference refused: {e.get('code')}] ", end="")
            await self.still_streaming(c, "the refused scene")
            await c.close()
            d.stop_and_check(self)
        finally:
            d.close()


class SnapshotTest(DaemonTest):
    """Finding 7: every snapshot request gets its snapshot or an error; at most one is pending per
    session (requests close together are no longer merged into one answer)."""

    async def test_one_pending_snapshot(self):
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            at = c.mark()
            first, second = c.next_seq(), c.next_seq()
            await c.send({"type": "snapshot", "format": "exr", "seq": first})
            await c.send({"type": "snapshot", "format": "png", "seq": second})
            e = await c.wait_text("error", since=at, seq=second)
            self.assertEqual(e.get("code"), "busy", e)
            self.assertEqual(e.get("field"), "snapshot", e)
            s = await c.wait_text("snapshot", since=at, seq=first)
            self.assertEqual(s.get("format"), "exr")
            b = await c.wait_frame(since=c.log.index(s, at) + 1, kind=2)
            self.assertEqual(b.seq, first)
            self.assertEqual(len(c.frames(since=at, kind=2)), 1, "exactly one snapshot for two requests")
            seq, s = await c.request({"type": "snapshot", "format": "png"}, "snapshot")
            self.assertEqual(s.get("format"), "png", "once it arrived, the next is made")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

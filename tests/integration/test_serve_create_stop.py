"""test_serve_create_stop.py -- a method's creation stops when asked (issue 25, finding 1): one
`params` message asking radiosity (or hybrid) for form factors of ~11k patches through 512^2-cell
hemicubes -- minutes of work inside the method's creation -- must not wedge the session, its slot or
the daemon. A cheaper `params` afterwards gets its frame within seconds, closed sessions give back
their slots at once, and SIGTERM with --drain-seconds 0 ends the daemon within a second. Before the
fix: no frame for 30 s, both slots held 3 s after closing, and neither SIGTERM, a second SIGTERM nor
SIGINT ended the daemon in 60 s. Usage: test_serve_create_stop.py IIRD SOURCE_DIR"""

import asyncio
import signal
import time

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, metric, metrics

# The message: accepted within the default memory budget (10,950 patches).
RADIOSITY = {"method": "radiosity", "patch_area": 1e-4, "hemicube_res": 512}
HYBRID = {**RADIOSITY, "method": "hybrid"}
CHEAP = {"method": "iir", "width": 128, "height": 96, "refine": False}
# The cheap frame follows within this: the creation stops within milliseconds of the new params,
# then a first iir frame at 128x96 renders (~0.3 s under ASan on a loaded machine).
ANSWER_S = 3.0


class CreateStopTest(DaemonTest):
    async def heavy(self, c, msg):
        await c.request({"type": "params", **msg}, "state")
        await asyncio.sleep(1.0)  # well inside the form factors

    async def test_cheap_params_after_a_heavy_creation(self):
        for heavy in (RADIOSITY, HYBRID):
            c = await Client.connect(self.daemon)
            try:
                await self.heavy(c, heavy)
                t0 = time.monotonic()
                seq = c.next_seq()
                await c.send({"type": "params", **CHEAP, "seq": seq})
                f = await c.wait_frame(min_seq=seq, timeout=30.0)
                secs = time.monotonic() - t0
                self.assertEqual((f.width, f.height), (128, 96), "the frame answering the cheap params")
                self.assertLess(secs, ANSWER_S, f"{heavy['method']}: the cheap params waited {secs:.2f} s")
                print(f"[{heavy['method']}: cheap frame {secs:.2f} s after its params] ", end="")
            finally:
                await c.close()

    async def test_light_moves_do_not_restart_a_creation(self):
        """Input that only moves the light lets the creation go on: its frame comes once the form
        factors are done (~1,100 patches through 128^2-cell hemicubes, uncached: seconds), however
        often the light moves."""
        d = Daemon(*FAST_ARGS, env_extra={"IIR_CACHE_DIR": ""})
        c = await Client.connect(d)
        try:
            pseq, _ = await c.request({"type": "params", "method": "radiosity", "patch_area": 0.001,
                                       "hemicube_res": 128}, "state")
            base = c.welcome["state"]["light"]["position"]
            t0 = time.monotonic()
            got = None
            k = 0
            while got is None and time.monotonic() - t0 < 60.0:
                m = c.mark()
                k += 1
                await c.send({"type": "light", "seq": c.next_seq(),
                              "position": [base[0] + 0.01 * (k % 5), base[1], base[2]]})
                try:  # a frame of the radiosity settings: answering the params or a later move
                    got = await c.wait_frame(since=m, min_seq=pseq, timeout=0.1)
                except (asyncio.TimeoutError, AssertionError):
                    pass
            self.assertIsNotNone(got, f"no radiosity frame in 60 s while the light moved {k} times")
            print(f"[first frame {time.monotonic() - t0:.2f} s and {k} moves into dragging] ", end="")
        finally:
            await c.close()
            d.stop_and_check(self)
            d.close()

    async def test_closed_sessions_free_their_slots(self):
        clients = [await Client.connect(self.daemon) for _ in range(2)]
        for c in clients:
            await self.heavy(c, RADIOSITY)
        t0 = time.monotonic()
        for c in clients:
            await c.close()
        while metric(metrics(self.daemon.port), "iird_sessions") not in (0, 0.0):
            self.assertLess(time.monotonic() - t0, 2.0, "closed sessions still hold their slots")
            await asyncio.sleep(0.05)
        print(f"[slots free {time.monotonic() - t0:.2f} s after close] ", end="")

    async def test_sigterm_ends_a_creating_daemon(self):
        for sig2 in (None, signal.SIGINT):
            d = Daemon(*FAST_ARGS, "--drain-seconds", "0")
            try:
                clients = [await Client.connect(d) for _ in range(2)]
                await self.heavy(clients[0], RADIOSITY)
                await self.heavy(clients[1], HYBRID)
                t0 = time.monotonic()
                d.proc.send_signal(signal.SIGTERM)
                if sig2:
                    d.proc.send_signal(sig2)
                rc = d.proc.wait(timeout=20.0)
                secs = time.monotonic() - t0
                d.stopped = True
                self.assertEqual(rc, 0, f"exit code after SIGTERM: {rc}")
                self.assertLess(secs, 1.0, f"SIGTERM with two creating sessions took {secs:.2f} s")
                self.assertIsNone(d.sanitizer_report(), d.stderr()[-4000:])
                print(f"[exit {secs:.2f} s after SIGTERM] ", end="")
            finally:
                d.close()


if __name__ == "__main__":
    iirserve.main()

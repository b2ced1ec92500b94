"""test_serve_robust.py -- `iird serve` stays healthy through what clients do to it: disconnecting in
the middle of a render, many connect/disconnect cycles, connections dropped without a close handshake,
a refused Origin; and it stops cleanly on SIGINT/SIGTERM with sessions rendering (exit 0, no sanitizer
or leak report). Usage: test_serve_robust.py IIRD SOURCE_DIR"""

import asyncio
import signal
import unittest
import time

import websockets

import iirserve
from iirserve import Client, Daemon, DaemonTest, healthz, metric, metrics


class RobustTest(DaemonTest):
    async def wait_sessions_zero(self, timeout=15.0):
        """Polls /healthz until it reports no session; returns (healthz, /metrics samples)."""
        deadline = time.monotonic() + timeout
        while True:
            h = await asyncio.to_thread(healthz, self.daemon.port)
            self.assertEqual(h.get("status"), "ok", str(h))
            if h.get("sessions") == 0:
                break
            self.assertLess(time.monotonic(), deadline, f"sessions never went back to 0: {h}")
            await asyncio.sleep(0.2)
        m = await asyncio.to_thread(metrics, self.daemon.port)
        self.assertEqual(metric(m, "iird_sessions"), 0, "iird_sessions gauge back to 0")
        self.assertIsNone(metric(m, "iird_session_memory_bytes"), "no per-session memory left for closed sessions")
        return h, m

    async def test_disconnect_mid_render(self):
        for i in range(3):
            c = await Client.connect(self.daemon)
            lim = c.welcome["limits"]
            # A big frame, then gone before it is done.
            await c.send({"type": "params", "seq": 5, "width": min(lim["max_width"], 1920),
                          "height": min(lim["max_height"], 1080), "method": ("iir", "ir", "pt")[i]})
            await c.send({"type": "light", "seq": 6, "cone_angle": 40 + i})
            if i == 2:
                c.ws.transport.abort()  # no close handshake at all
            await c.close()
        # A scene load interrupted by the client leaving.
        c = await Client.connect(self.daemon)
        await c.send({"type": "params", "seq": 1, "width": 64, "height": 48})
        await c.send({"type": "scene", "seq": 2, "name": "living_room"})
        await asyncio.sleep(0.05)
        await c.close()
        self.assertTrue(self.daemon.alive(), self.daemon.stderr()[-3000:])
        await self.wait_sessions_zero(timeout=60)
        # And it still serves a new client.
        c = await Client.connect(self.daemon)
        try:
            await self.still_streaming(c, "disconnects mid-render")
        finally:
            await c.close()

    async def test_connect_cycles(self):
        m0 = await asyncio.to_thread(metrics, self.daemon.port)
        for i in range(20):
            c = await Client.connect(self.daemon, hello=(i % 4 != 3))
            if i % 4 == 0:
                await c.wait_frame()
            if i % 5 == 4:
                c.ws.transport.abort()
            await c.close()
        self.assertTrue(self.daemon.alive(), self.daemon.stderr()[-3000:])
        h, m = await self.wait_sessions_zero()
        opened = metric(m, "iird_sessions_total") - metric(m0, "iird_sessions_total")
        self.assertGreaterEqual(opened, 15, "iird_sessions_total counts the sessions (15 said hello)")
        self.assertLessEqual(opened, 20)


    async def test_silent_client_is_closed(self):
        """A connection that never says hello is closed after 10 s, freeing its session slot;
        one that said hello is not."""
        silent = await Client.connect(self.daemon, hello=False)
        talker = await Client.connect(self.daemon)
        t0 = time.monotonic()
        while not silent.closed and time.monotonic() - t0 < 20:
            await asyncio.sleep(0.2)
        waited = time.monotonic() - t0
        self.assertTrue(silent.closed, "a client without hello is still connected after 20 s")
        self.assertGreater(waited, 8.0, f"closed after {waited:.1f} s, before the 10 s allowed")
        self.assertFalse(talker.closed, "a client that said hello was closed too")
        await self.still_streaming(talker, "after the silent client was dropped")
        await talker.close()
        await self.wait_sessions_zero()


    async def test_port_in_use(self):
        """A second daemon on a port in use (or an address this machine lacks) stops at once with
        exit 1 and the system's reason, and no sanitizer report; the first keeps serving."""
        import subprocess
        for host, port, reason in (("127.0.0.1", self.daemon.port, "in use"),
                                   ("192.0.2.1", 8080, "assign requested address")):
            r = await asyncio.to_thread(subprocess.run, [iirserve.IIRD, "serve", "--host", host, "--port", str(port)],
                                        stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60)
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertIn(f"cannot listen on {host} port {port}", r.stderr)
            self.assertIn(reason, r.stderr)
            self.assertNotIn("Sanitizer", r.stderr)
            self.assertNotIn("iird: serving", r.stdout)
        h = await asyncio.to_thread(healthz, self.daemon.port)
        self.assertEqual(h.get("status"), "ok")


class OriginTest(DaemonTest):
    DAEMON_ARGS = ("--origin", "http://good.example", "--origin", "http://also.example:8080")

    async def test_origin_allowed_list(self):
        with self.assertRaises(websockets.InvalidStatusCode) as cm:
            await Client.connect(self.daemon, origin="http://evil.example")
        self.assertEqual(cm.exception.status_code, 403, "a foreign Origin is refused with 403")
        with self.assertRaises(websockets.InvalidStatusCode):
            await Client.connect(self.daemon, origin="http://good.example.evil.example")
        for ok in ("http://good.example", "http://also.example:8080"):
            c = await Client.connect(self.daemon, origin=ok)
            try:
                f = await c.wait_frame()
                f.check_header(self)
            finally:
                await c.close()
        self.assertEqual((await asyncio.to_thread(healthz, self.daemon.port))["status"], "ok")


class OwnOriginOnLoopbackTest(DaemonTest):
    async def test_own_origin_only_on_loopback(self):
        with self.assertRaises(websockets.InvalidStatusCode) as cm:
            await Client.connect(self.daemon, origin="http://evil.example")
        self.assertEqual(cm.exception.status_code, 403, "without --origin a foreign origin is refused, loopback too")
        c = await Client.connect(self.daemon, origin=f"http://127.0.0.1:{self.daemon.port}")
        try:
            self.assertIn("session", c.welcome, "the page the daemon serves may open a session")
        finally:
            await c.close()


class ShutdownTest(unittest.IsolatedAsyncioTestCase):
    async def stop_while_rendering(self, sig):
        d = Daemon("--drain-seconds", "1")  # SIGTERM drains 1 s (the clients stay), then stops
        try:
            clients = []
            for method in ("iir", "pt"):
                c = await Client.connect(d)
                await c.request({"type": "params", "width": 640, "height": 480, "method": method, "spp": 4}, "state")
                clients.append(c)
            c = clients[0]
            for i in range(5):
                await c.send({"type": "light", "seq": c.next_seq(), "cone_angle": 40 + i})
            await asyncio.sleep(0.3)
            t0 = time.monotonic()
            d.proc.send_signal(sig)
            rc = await asyncio.to_thread(d.proc.wait, 30)
            secs = time.monotonic() - t0
            d.stopped = True
            print(f"signal {sig.name}: exit {rc} after {secs:.2f} s")
            self.assertEqual(rc, 0, f"exit code after {sig.name}; stderr:\n{d.stderr()[-3000:]}")
            self.assertLess(secs, 10.0, f"{sig.name} took {secs:.1f} s")
            self.assertIsNone(d.sanitizer_report(), d.stderr()[-6000:])
            for c in clients:
                await asyncio.wait_for(c.reader, 5)
                self.assertTrue(c.closed, "clients are disconnected at shutdown")
        finally:
            d.close()

    async def test_sigint(self):
        await self.stop_while_rendering(signal.SIGINT)

    async def test_sigterm(self):
        await self.stop_while_rendering(signal.SIGTERM)


if __name__ == "__main__":
    iirserve.main()

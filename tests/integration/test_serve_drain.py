"""test_serve_drain.py -- `iird serve` as a load balancer's backend (issue 17, docs/deploy.md):
/healthz says ok, full (503 at --max-sessions) or draining (503 after SIGTERM); /livez is always 200;
after SIGTERM the open sessions keep their frames while new ones are refused busy, and the daemon
exits once they leave, or when --drain-seconds pass, or at a second SIGTERM; behind a trusted
balancer (--trust-proxy) per-address limits count the X-Forwarded-For client, not the balancer.

Usage (as ctest runs it): python3 test_serve_drain.py IIRD SOURCE_DIR"""

import asyncio
import json
import signal
import time
import unittest

import websockets

import iirserve
from iirserve import FAST_ARGS, Client, Daemon, http_get


def health(port, path="/healthz"):
    status, _, body = http_get(port, path)
    return status, json.loads(body)["status"]


async def wait_health(port, want, timeout=5.0):
    deadline = time.monotonic() + timeout
    while True:
        got = await asyncio.to_thread(health, port)
        if got == want or time.monotonic() > deadline:
            return got
        await asyncio.sleep(0.05)


async def refused(d):
    """Connects; returns (code, message, close code) of the error a refused session gets at once."""
    c = await Client.connect(d, hello=False)
    err = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "error", what="a busy error")
    await asyncio.wait_for(c.reader, 5)
    return err.get("code"), err.get("message", ""), c.ws.close_code


class DrainTest(unittest.IsolatedAsyncioTestCase):
    def daemon(self, *args):
        d = Daemon(*FAST_ARGS, *args)
        self.addCleanup(d.close)
        return d

    async def exit_code(self, d, limit):
        t0 = time.monotonic()
        rc = await asyncio.to_thread(d.proc.wait, 30)
        secs = time.monotonic() - t0
        d.stopped = True
        self.assertEqual(rc, 0, d.stderr()[-3000:])
        self.assertLess(secs, limit, f"exit took {secs:.2f} s")
        self.assertIsNone(d.sanitizer_report(), d.stderr()[-6000:])
        return secs

    async def test_health_ok_full_live(self):
        d = self.daemon("--max-sessions", "2")
        self.assertEqual(await asyncio.to_thread(health, d.port), (200, "ok"))
        self.assertEqual(await asyncio.to_thread(health, d.port, "/livez"), (200, "alive"))
        clients = [await Client.connect(d) for _ in range(2)]
        for c in clients:
            await c.wait_frame()
        self.assertEqual(await wait_health(d.port, (503, "full")), (503, "full"))
        self.assertEqual(await asyncio.to_thread(health, d.port, "/livez"), (200, "alive"))
        await clients[0].close()
        self.assertEqual(await wait_health(d.port, (200, "ok")), (200, "ok"))
        await clients[1].close()
        d.stop_and_check(self)

    async def test_sigterm_drains_until_the_last_session_leaves(self):
        d = self.daemon("--drain-seconds", "30")
        c = await Client.connect(d)
        await c.wait_frame()
        d.proc.send_signal(signal.SIGTERM)
        self.assertEqual(await wait_health(d.port, (503, "draining")), (503, "draining"))
        self.assertEqual(await asyncio.to_thread(health, d.port, "/livez"), (200, "alive"))
        code, msg, close = await refused(d)
        self.assertEqual((code, close), ("busy", 1013), msg)
        self.assertIn("draining", msg)
        seq = c.mark()
        await c.move_light(cone_angle=41)  # the open session still renders
        self.assertTrue(c.frames(since=seq), "no frame for the open session while draining")
        self.assertIn("draining 1 session", d.stderr())
        t0 = time.monotonic()
        await c.close()
        secs = await self.exit_code(d, 5.0)
        print(f"[exit {time.monotonic() - t0:.2f} s after the last session left] ", end="")
        self.assertLess(secs, 5.0)

    async def test_drain_ends_after_drain_seconds(self):
        d = self.daemon("--drain-seconds", "1")
        c = await Client.connect(d)
        await c.wait_frame()
        t0 = time.monotonic()
        d.proc.send_signal(signal.SIGTERM)
        await self.exit_code(d, 6.0)
        secs = time.monotonic() - t0
        self.assertGreater(secs, 0.9, "the drain did not wait for the open session")
        await asyncio.wait_for(c.reader, 5)
        self.assertEqual(c.ws.close_code, 1001, "the session is closed with 1001 (going away)")

    async def test_second_sigterm_stops_at_once(self):
        d = self.daemon("--drain-seconds", "60")
        c = await Client.connect(d)
        await c.wait_frame()
        d.proc.send_signal(signal.SIGTERM)
        await wait_health(d.port, (503, "draining"))
        d.proc.send_signal(signal.SIGTERM)
        await self.exit_code(d, 3.0)
        await asyncio.wait_for(c.reader, 5)

    async def test_trust_proxy_counts_the_forwarded_client(self):
        d = self.daemon("--trust-proxy", "127.0.0.1", "--max-sessions-per-address", "1")
        url = d.url

        async def via_proxy(client):
            ws = await websockets.connect(url, max_size=iirserve.MAX_MSG, open_timeout=15,
                                          extra_headers={"X-Forwarded-For": client})
            c = Client(ws)
            await c.hello()
            return c

        a = await via_proxy("203.0.113.7")
        b = await via_proxy("10.1.1.1, 198.51.100.9")  # the balancer's entry is the last one
        for c in (a, b):
            await c.wait_frame()
        ws = await websockets.connect(url, max_size=iirserve.MAX_MSG, open_timeout=15,
                                      extra_headers={"X-Forwarded-For": "6.6.6.6, 203.0.113.7"})
        c = Client(ws)  # a forged first entry changes nothing: 203.0.113.7 holds its one session
        err = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "error")
        self.assertEqual(err.get("code"), "busy")
        self.assertIn("this address", err.get("message", ""))
        for x in (a, b):
            await x.close()
        d.stop_and_check(self)

    async def test_untrusted_peer_is_its_own_address(self):
        d = self.daemon("--max-sessions-per-address", "1")  # no --trust-proxy: the header is ignored
        a = await websockets.connect(d.url, max_size=iirserve.MAX_MSG, open_timeout=15,
                                     extra_headers={"X-Forwarded-For": "203.0.113.7"})
        ca = Client(a)
        await ca.hello()
        await ca.wait_frame()
        code, msg, _ = await refused(d)
        self.assertEqual(code, "busy", msg)
        await ca.close()
        d.stop_and_check(self)


if __name__ == "__main__":
    iirserve.main()

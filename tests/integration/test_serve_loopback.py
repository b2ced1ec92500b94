"""test_serve_loopback.py -- issue 26 item 9: under the default --max-sessions-per-address
(max(1, --max-sessions / 4)), a user's own tabs on this machine (loopback) are held only by
--max-sessions, while a client behind --trust-proxy (never loopback, whatever its header says) and
any client under an explicit --max-sessions-per-address still meet the per-address limit.

Usage: python3 test_serve_loopback.py IIRD SOURCE_DIR"""

import asyncio
import unittest

import websockets

import iirserve
from iirserve import FAST_ARGS, Client, Daemon


async def outcome(url, headers=None):
    """Connects and says hello: ("welcome", client) or ("busy", message)."""
    ws = await websockets.connect(url, max_size=iirserve.MAX_MSG, open_timeout=15, close_timeout=5,
                                  extra_headers=headers or {})
    c = Client(ws)
    at = c.mark()
    try:
        await c.send({"type": "hello", "seq": 1, "client": "loopback-test"})
    except websockets.ConnectionClosed:
        pass  # refused before the hello went out: its error is logged all the same
    m = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") in ("welcome", "error"), since=at)
    if m["type"] == "welcome":
        return "welcome", c
    await asyncio.wait_for(c.reader, 10)
    return m.get("code"), m.get("message", "")


class LoopbackTest(unittest.IsolatedAsyncioTestCase):
    def daemon(self, *args):
        d = Daemon(*FAST_ARGS, *args, per_address=False)  # the product's per-address default
        self.addCleanup(d.close)
        return d

    async def close_all(self, clients):
        for c in clients:
            await c.close()

    async def test_own_tabs_are_not_limited_per_address(self):
        d = self.daemon("--max-sessions", "8")  # per-address default: 2
        tabs = []
        try:
            for i in range(4):
                got, c = await outcome(d.url)
                self.assertEqual(got, "welcome", f"tab {i + 1} from 127.0.0.1 was refused: {c}")
                tabs.append(c)
            for c in tabs:
                await c.wait_frame()
        finally:
            await self.close_all(tabs)
        d.stop_and_check(self)

    async def test_max_sessions_still_holds_loopback(self):
        d = self.daemon("--max-sessions", "3")
        tabs = []
        try:
            for _ in range(3):
                got, c = await outcome(d.url)
                self.assertEqual(got, "welcome")
                tabs.append(c)
            got, msg = await outcome(d.url)
            self.assertEqual(got, "busy")
            self.assertIn("the server has its maximum of 3", msg)
        finally:
            await self.close_all(tabs)
        d.stop_and_check(self)

    async def test_proxied_client_is_not_loopback(self):
        # the balancer is on 127.0.0.1, but the clients it forwards are strangers: default limit 2
        d = self.daemon("--max-sessions", "8", "--trust-proxy", "127.0.0.1")
        xff = {"X-Forwarded-For": "203.0.113.7"}
        tabs = []
        try:
            for _ in range(2):
                got, c = await outcome(d.url, xff)
                self.assertEqual(got, "welcome")
                tabs.append(c)
            got, msg = await outcome(d.url, xff)
            self.assertEqual(got, "busy")
            self.assertIn("this address has its maximum of 2", msg)
            # a forwarded header claiming loopback is still a stranger's
            for _ in range(2):
                got, c = await outcome(d.url, {"X-Forwarded-For": "127.0.0.1"})
                self.assertEqual(got, "welcome")
                tabs.append(c)
            got, msg = await outcome(d.url, {"X-Forwarded-For": "127.0.0.1"})
            self.assertEqual(got, "busy", "a client claiming 127.0.0.1 through the balancer")
        finally:
            await self.close_all(tabs)
        d.stop_and_check(self)

    async def test_explicit_limit_applies_to_loopback(self):
        d = self.daemon("--max-sessions", "8", "--max-sessions-per-address", "2")
        tabs = []
        try:
            for _ in range(2):
                got, c = await outcome(d.url)
                self.assertEqual(got, "welcome")
                tabs.append(c)
            got, msg = await outcome(d.url)
            self.assertEqual(got, "busy")
            self.assertIn("this address has its maximum of 2", msg)
        finally:
            await self.close_all(tabs)
        d.stop_and_check(self)


if __name__ == "__main__":
    iirserve.main()

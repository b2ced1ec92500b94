"""test_deploy.py -- several `iird serve` behind a real HAProxy, from the shipped configuration
(deploy/haproxy.cfg, issue 17, docs/deploy.md), all on loopback in a temporary directory.

Three daemons (as deploy/iird@.service runs them: --trust-proxy 127.0.0.1, --max-sessions 8, here
--drain-seconds 2) and Debian's haproxy started from deploy/haproxy.cfg with only what a test must
change rewritten: the listening ports (TLS kept, with a certificate made here), the daemons' ports,
and the lines a process without root cannot have (chroot, user, group, daemon, syslog). Twelve
WebSocket clients connect through HAProxy over TLS: leastconn gives each daemon 3 to 5. One daemon
is SIGTERMed: HAProxy's /healthz check sees "draining" and sends it no new session, its clients keep
their frames through the drain, then it closes them; they reconnect through HAProxy, as the web
client does (its state sent again after the welcome), and each has a frame again within 2 s with its
own state; no reconnect sees an HTTP error; the survivors' /metrics count all twelve sessions.
Nothing global is touched: every process is started and stopped here.

Usage (as ctest runs it): python3 test_deploy.py IIRD SOURCE_DIR"""

import asyncio
import json
import os
import re
import shutil
import signal
import socket
import ssl
import subprocess
import tempfile
import time
import unittest

import websockets

import iirserve
from iirserve import FAST_ARGS, Daemon, Frame, metric, metrics

HAPROXY = shutil.which("haproxy") or "/usr/sbin/haproxy"
CLIENTS = 12
RECONNECT_S = 2.0


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def balancer_config(text, tls_port, http_port, pem, backends):
    """The shipped configuration with the test's ports and certificate; global lines that need root
    or a syslog socket dropped. Fails when a line it must rewrite is missing."""
    out, servers = [], iter(backends)
    seen = {"tls": 0, "http": 0, "server": 0}
    for line in text.splitlines():
        word = line.split()[0] if line.split() else ""
        if word in ("chroot", "user", "group", "daemon", "log") and line.startswith("    "):
            continue
        if re.match(r"\s+bind :443 ssl crt ", line):
            line = f"    bind 127.0.0.1:{tls_port} ssl crt {pem} alpn http/1.1"
            seen["tls"] += 1
        elif re.match(r"\s+bind :80\s*$", line):
            line = f"    bind 127.0.0.1:{http_port}"
            seen["http"] += 1
        elif re.match(r"\s+server iird\d+ 127\.0\.0\.1:\d+ check", line):
            line = re.sub(r"127\.0\.0\.1:\d+", f"127.0.0.1:{next(servers)}", line)
            seen["server"] += 1
        out.append(line)
    assert seen == {"tls": 1, "http": 1, "server": len(backends)}, seen
    return "\n".join(out) + "\n"


class Session:
    """One client: its own state (size, method, VPLs, the spot's cone), sent after every welcome,
    and the web client's reconnect (connection.js: 250 ms after a close, through the balancer)."""

    def __init__(self, i, url, ctx):
        self.i, self.url, self.ctx = i, url, ctx
        self.state = {"width": 64 + 8 * i, "height": 48, "method": "iir", "vpls": 32 + i}
        self.cone = 30.0 + i
        self.frames = 0
        self.connects = 0
        self.closes = []          # when each connection closed
        self.frames_at_close = []
        self.back = []            # seconds from a close to the next connection's first frame
        self.http_errors = []     # reconnects answered with an HTTP error instead of 101
        self.errors = []
        self.restored = None
        self.done = False
        self.seq = 1

    def next_seq(self):
        self.seq += 1
        return self.seq

    def want(self):
        s = self.state
        return (s["width"], s["height"], s["method"], s["vpls"], round(self.cone))

    async def connect(self):
        self.ws = await websockets.connect(self.url, ssl=self.ctx, max_size=iirserve.MAX_MSG,
                                           open_timeout=10, close_timeout=2)
        self.connects += 1
        for msg in ({"type": "hello"}, {"type": "light", "cone_angle": self.cone},
                    {"type": "params", **self.state}):
            await self.ws.send(json.dumps({**msg, "seq": self.next_seq()}))

    def on_message(self, m):
        if isinstance(m, (bytes, bytearray)):
            if Frame(m).kind == 1:
                if self.frames_here == 0 and self.closes:
                    self.back.append(time.monotonic() - self.closes[-1])
                self.frames += 1
                self.frames_here += 1
            return
        msg = json.loads(m)
        if msg.get("type") == "state":
            p, light = msg.get("params", {}), msg.get("light", {})
            self.restored = (p.get("width"), p.get("height"), p.get("method"), p.get("vpls"),
                             round(light.get("cone_angle", -1)))
        elif msg.get("type") == "error":
            self.errors.append(msg)

    async def life(self):
        while not self.done:
            try:
                await self.connect()
            except websockets.exceptions.InvalidStatusCode as e:
                self.http_errors.append(str(e))
                await asyncio.sleep(0.25)
                continue
            self.frames_here = 0
            try:
                async for m in self.ws:
                    self.on_message(m)
            except websockets.exceptions.ConnectionClosed:
                pass
            if not self.done:
                self.closes.append(time.monotonic())
                self.frames_at_close.append(self.frames)
                await asyncio.sleep(0.25)


class DeployTest(unittest.IsolatedAsyncioTestCase):
    async def asyncSetUp(self):
        if not os.path.exists(HAPROXY):
            self.fail(f"{HAPROXY} not found: `make deps` installs Debian's haproxy")
        self.tmp = tempfile.TemporaryDirectory(prefix="iird-deploy-", dir=os.environ.get("IIR_TEST_TMP"))
        self.addCleanup(self.tmp.cleanup)
        self.daemons = []
        for _ in range(3):
            d = Daemon(*FAST_ARGS, "--trust-proxy", "127.0.0.1", "--max-sessions", "8",
                       "--drain-seconds", "2", "--max-sessions-per-address", "8")
            self.addCleanup(d.close)
            self.daemons.append(d)
        key, crt, pem = (os.path.join(self.tmp.name, n) for n in ("key.pem", "crt.pem", "iird.pem"))
        subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", key,
                        "-out", crt, "-days", "1", "-subj", "/CN=localhost"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(pem, "w") as f:
            f.write(open(crt).read() + open(key).read())
        self.tls_port, http_port = free_port(), free_port()
        shipped = open(os.path.join(iirserve.SRC, "deploy", "haproxy.cfg")).read()
        cfg = os.path.join(self.tmp.name, "haproxy.cfg")
        with open(cfg, "w") as f:
            f.write(balancer_config(shipped, self.tls_port, http_port, pem, [d.port for d in self.daemons]))
        check = subprocess.run([HAPROXY, "-c", "-f", cfg], capture_output=True, text=True)
        self.assertEqual(check.returncode, 0, check.stdout + check.stderr)
        self.log = open(os.path.join(self.tmp.name, "haproxy.log"), "w")
        self.haproxy = subprocess.Popen([HAPROXY, "-db", "-f", cfg], stdout=self.log, stderr=subprocess.STDOUT)
        self.addCleanup(self.stop_haproxy)
        await self.wait_balancer()

    def stop_haproxy(self):
        if self.haproxy.poll() is None:
            self.haproxy.terminate()
            try:
                self.haproxy.wait(5)
            except subprocess.TimeoutExpired:
                self.haproxy.kill()
        self.log.close()

    async def wait_balancer(self):
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                with socket.create_connection(("127.0.0.1", self.tls_port), 0.5):
                    await asyncio.sleep(2.5)  # rise 2 at inter 1s: the servers are up
                    return
            except OSError:
                await asyncio.sleep(0.1)
        self.fail("haproxy did not listen:\n" + open(self.log.name).read())

    def sessions(self, d):
        return metric(metrics(d.port), "iird_sessions") or 0

    async def test_balance_and_drain(self):
        ctx = ssl.create_default_context()
        ctx.check_hostname, ctx.verify_mode = False, ssl.CERT_NONE
        url = f"wss://127.0.0.1:{self.tls_port}/ws"
        clients = []
        for i in range(CLIENTS):  # one at a time: leastconn sees each new session
            c = Session(i, url, ctx)
            c.task = asyncio.create_task(c.life())
            clients.append(c)
            await asyncio.sleep(0.2)
        self.addAsyncCleanup(self.close_all, clients)
        deadline = time.monotonic() + 30
        while any(c.frames == 0 or c.restored != c.want() for c in clients) and time.monotonic() < deadline:
            await asyncio.sleep(0.1)
        for c in clients:
            self.assertTrue(c.frames, f"client {c.i} has a frame through HAProxy")
            self.assertEqual(c.restored, c.want(), f"client {c.i}'s state")
        counts = [await asyncio.to_thread(self.sessions, d) for d in self.daemons]
        print(f"[sessions per daemon {counts}] ", end="")
        self.assertEqual(sum(counts), CLIENTS)
        self.assertTrue(all(3 <= n <= 5 for n in counts), f"leastconn spread {counts}")

        # SIGTERM the busiest daemon: its clients keep their frames through the 2 s drain, then
        # it closes them and they come back through HAProxy to the others
        k = counts.index(max(counts))
        victim = self.daemons[k]
        frames_before = [c.frames for c in clients]
        t_term = time.monotonic()
        victim.proc.send_signal(signal.SIGTERM)
        await asyncio.sleep(0.3)
        for c in clients:  # every session still answers input during the drain
            await c.ws.send(json.dumps({"type": "light", "seq": c.next_seq(), "cone_angle": c.cone}))
        self.assertEqual(await asyncio.to_thread(victim.proc.wait, 15), 0, victim.stderr()[-3000:])
        victim.stopped = True
        stopped = time.monotonic() - t_term
        self.assertIsNone(victim.sanitizer_report(), victim.stderr()[-6000:])
        deadline = time.monotonic() + 10
        moved = lambda: [c for c in clients if c.closes]
        while time.monotonic() < deadline and (len(moved()) < counts[k] or any(not c.back for c in moved())):
            await asyncio.sleep(0.05)
        print(f"[daemon {k + 1} drained and stopped {stopped:.1f} s after SIGTERM] ", end="")
        self.assertEqual(len(moved()), counts[k], "the victim's clients, and only they, were closed")
        for c in moved():
            self.assertEqual(len(c.closes), 1)
            self.assertEqual(c.back and len(c.back), 1, f"client {c.i} has a frame again")
            self.assertEqual(c.restored, c.want(), f"client {c.i}'s state after reconnecting")
            self.assertGreater(c.frames_at_close[0], frames_before[c.i], f"client {c.i}: a frame during the drain")
        for c in clients:
            self.assertEqual(c.http_errors, [], f"client {c.i} saw an HTTP error reconnecting")
            self.assertEqual([e for e in c.errors if e.get("code") == "busy"], [], f"client {c.i}")
        worst = max(b for c in moved() for b in c.back)
        print(f"[{len(moved())} clients back with a frame, worst {worst:.2f} s after their close] ", end="")
        self.assertLess(worst, RECONNECT_S)
        survivors = [d for d in self.daemons if d is not victim]
        counts = [await asyncio.to_thread(self.sessions, d) for d in survivors]
        self.assertEqual(sum(counts), CLIENTS, f"the survivors' /metrics: {counts}")
        await self.close_all(clients)
        for d in survivors:
            d.stop_and_check(self)

    async def close_all(self, clients):
        for c in clients:
            c.done = True
            ws = getattr(c, "ws", None)
            if ws:
                await ws.close()
        await asyncio.gather(*(c.task for c in clients), return_exceptions=True)


if __name__ == "__main__":
    iirserve.main()

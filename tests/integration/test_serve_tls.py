"""test_serve_tls.py -- `iird serve --tls-cert C --tls-key K`: with a throwaway self-signed certificate
made by the `openssl` command, the daemon announces an https:// URL, a `wss://` client that trusts only
that certificate gets welcome and frames that decode, /healthz and /metrics answer over https, a plain
`ws://` or HTTP client on the TLS port is refused without harming the daemon, and bad TLS options stop
`iird serve` before it listens with the exit codes of docs/cli.md. Usage: test_serve_tls.py IIRD SRC"""

import asyncio
import http.client
import json
import os
import re
import shutil
import socket
import ssl
import subprocess
import tempfile
import time
import unittest

import websockets

import iirserve
from iirserve import FAST_ARGS, MAX_MSG, Client, Daemon, parse_metrics, metric

# docs/cli.md, "serve" and "Exit codes".
EXIT_BAD_INPUT = 2
EXIT_FILE = 3
EXIT_USAGE = 64


def openssl(*args, cwd):
    """Runs the openssl command; fails the test with what to install when it is missing."""
    if shutil.which("openssl") is None:
        raise AssertionError("the `openssl` command is missing: install Debian's `openssl` package "
                             "(it is in the Makefile's PACKAGES; `make deps` installs it)")
    r = subprocess.run(["openssl", *args], cwd=cwd, capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        raise AssertionError(f"openssl {' '.join(args)} failed ({r.returncode}):\n{r.stderr}")


def make_cert(dirname, name):
    """A self-signed certificate for 127.0.0.1 valid one day, and its key: (cert path, key path)."""
    cert, key = os.path.join(dirname, f"{name}.crt"), os.path.join(dirname, f"{name}.key")
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=127.0.0.1",
            "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", key, "-out", cert, cwd=dirname)
    return cert, key


class TlsDaemon(Daemon):
    """A Daemon whose announced URL must be https://127.0.0.1:PORT/; its WebSocket URL is wss://."""

    def _wait_port(self, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            m = re.search(r"iird: serving (\w+)://127\.0\.0\.1:(\d+)/", self.stdout())
            if m:
                self.scheme = m.group(1)
                return int(m.group(2))
            if self.proc.poll() is not None:
                raise AssertionError(f"{' '.join(self.cmd)} exited {self.proc.returncode} before serving:\n"
                                     f"{self.stdout()}\n{self.stderr()}")
            time.sleep(0.05)
        self.proc.kill()
        raise AssertionError(f"no 'iird: serving' line within {timeout} s:\n{self.stdout()}\n{self.stderr()}")

    @property
    def url(self):
        return f"wss://127.0.0.1:{self.port}/ws"


class TlsTest(unittest.IsolatedAsyncioTestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="iird-tls-", dir=os.environ.get("IIR_TEST_TMP"))
        cls.cert, cls.key = make_cert(cls.tmp.name, "server")
        with open(cls.cert) as f:
            cls.cert_der = ssl.PEM_cert_to_DER_cert(f.read())
        cls.ctx = ssl.create_default_context()  # verifies the chain and the IP in subjectAltName
        cls.ctx.load_verify_locations(cls.cert)
        cls.daemon = TlsDaemon(*FAST_ARGS, "--tls-cert", cls.cert, "--tls-key", cls.key)

    @classmethod
    def tearDownClass(cls):
        try:
            iirserve.stop_class_daemon(cls.daemon)
        finally:
            cls.tmp.cleanup()

    async def connect_wss(self):
        ws = await websockets.connect(self.daemon.url, ssl=self.ctx, max_size=MAX_MSG, open_timeout=15,
                                      close_timeout=5)
        c = Client(ws)
        await c.hello()
        return c

    def https_get(self, path):
        c = http.client.HTTPSConnection("127.0.0.1", self.daemon.port, timeout=10, context=self.ctx)
        try:
            c.request("GET", path)
            r = c.getresponse()
            return r.status, r.getheader("Content-Type", ""), r.read()
        finally:
            c.close()

    async def check_wss_streams(self):
        c = await self.connect_wss()
        try:
            peer = c.ws.transport.get_extra_info("ssl_object").getpeercert(binary_form=True)
            self.assertEqual(peer, self.cert_der, "the server presents the --tls-cert certificate")
            self.assertIn("session", c.welcome)
            f = await c.wait_frame()
            f.check_header(self)
            im = f.image()
            self.assertEqual(im.format, "JPEG")
            self.assertEqual(im.size, (f.width, f.height))
            seq, f = await c.move_light(cone_angle=33)
            self.assertEqual(f.seq, seq, "a frame over wss answers the light move")
            f.check_header(self)
            f.image()
        finally:
            await c.close()

    # ---- tests ----

    async def test_https_url_and_wss_frames(self):
        self.assertEqual(self.daemon.scheme, "https", f"announced URL: {self.daemon.stdout()!r}")
        await self.check_wss_streams()

    async def test_https_healthz_and_metrics(self):
        status, ctype, body = await asyncio.to_thread(self.https_get, "/healthz")
        self.assertEqual(status, 200, body[:200])
        self.assertIn("application/json", ctype)
        self.assertEqual(json.loads(body).get("status"), "ok")
        status, ctype, body = await asyncio.to_thread(self.https_get, "/metrics")
        self.assertEqual(status, 200)
        self.assertIsNotNone(metric(parse_metrics(body.decode()), "iird_sessions"), "/metrics over https")
        status, ctype, body = await asyncio.to_thread(self.https_get, "/")
        self.assertEqual(status, 200, "the web client over https")
        self.assertIn(b"<html", body.lower())

    async def test_plain_clients_refused(self):
        port = self.daemon.port
        with self.assertRaises((websockets.InvalidHandshake, websockets.ConnectionClosed, OSError,
                                asyncio.TimeoutError, EOFError), msg="ws:// on the TLS port must fail"):
            ws = await websockets.connect(f"ws://127.0.0.1:{port}/ws", open_timeout=5, close_timeout=2)
            await ws.close()

        def plain_http():
            """What a plain-text HTTP GET gets back from the TLS port (bytes until close or 5 s)."""
            with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                s.sendall(b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
                got = b""
                try:
                    while len(got) < 65536:
                        chunk = s.recv(4096)
                        if not chunk:
                            break
                        got += chunk
                except (socket.timeout, ConnectionResetError):
                    pass
                return got

        got = await asyncio.to_thread(plain_http)
        self.assertNotIn(b'"status"', got, "plain HTTP on the TLS port must not reach /healthz")
        self.assertFalse(got.startswith(b"HTTP/1.1 200"), got[:200])
        # The daemon is unharmed: alive, https answers, wss streams.
        self.assertTrue(self.daemon.alive(), self.daemon.stderr()[-3000:])
        status, _, body = await asyncio.to_thread(self.https_get, "/healthz")
        self.assertEqual(status, 200)
        await self.check_wss_streams()


class BadTlsOptionsTest(unittest.TestCase):
    """Refused before listening: the exit code of docs/cli.md, a message naming the option, no
    'serving' line, no sanitizer report."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="iird-tls-bad-", dir=os.environ.get("IIR_TEST_TMP"))
        cls.cert, cls.key = make_cert(cls.tmp.name, "a")
        cls.other_cert, cls.other_key = make_cert(cls.tmp.name, "b")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def serve(self, *args):
        env = dict(os.environ)
        env.setdefault("ASAN_OPTIONS", "detect_leaks=1")
        r = subprocess.run([iirserve.IIRD, "serve", "--port", "0", *FAST_ARGS, *args], stdin=subprocess.DEVNULL,
                           capture_output=True, text=True, timeout=60, env=env)
        self.assertNotIn("serving", r.stdout, f"iird serve {' '.join(args)} listened")
        for p in iirserve.SANITIZER_PATTERNS:
            self.assertNotIn(p, r.stderr, f"sanitizer report:\n{r.stderr[-4000:]}")
        return r

    def check(self, args, code, *words):
        r = self.serve(*args)
        self.assertEqual(r.returncode, code, f"iird serve {' '.join(args)}: stderr {r.stderr!r}")
        first = r.stderr.strip().splitlines()[0] if r.stderr.strip() else ""
        self.assertTrue(first.startswith("iird serve: "), f"one clear message first: {r.stderr!r}")
        for w in words:
            self.assertIn(w, first, f"the message names {w!r}")
        return first

    def test_mismatched_key(self):
        print(self.check(("--tls-cert", self.cert, "--tls-key", self.other_key), EXIT_BAD_INPUT,
                         "--tls-key", self.other_key, self.cert))

    def test_not_pem(self):
        self.check(("--tls-cert", self.key, "--tls-key", self.key), EXIT_BAD_INPUT, "--tls-cert", self.key)
        self.check(("--tls-cert", self.cert, "--tls-key", self.cert), EXIT_BAD_INPUT, "--tls-key", self.cert)

    def test_missing_files(self):
        missing = os.path.join(self.tmp.name, "missing.key")
        self.check(("--tls-cert", self.cert, "--tls-key", missing), EXIT_FILE, "--tls-key", missing)
        missing = os.path.join(self.tmp.name, "missing.crt")
        self.check(("--tls-cert", missing, "--tls-key", self.key), EXIT_FILE, "--tls-cert", missing)

    def test_one_without_the_other(self):
        self.check(("--tls-cert", self.cert), EXIT_USAGE, "--tls-key")
        self.check(("--tls-key", self.key), EXIT_USAGE, "--tls-cert")


if __name__ == "__main__":
    iirserve.main()

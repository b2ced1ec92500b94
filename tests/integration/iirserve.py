"""iirserve.py -- shared harness of the `iird serve` integration tests: starts and stops a daemon on a
free loopback port (checking its exit code and its stderr for sanitizer reports), a WebSocket client
that logs every message (frames decoded from the 44-byte header of docs/protocol.md, text as JSON)
and waits on them, plain HTTP GETs, and the unittest entry point. Not a test file itself.

Usage of a test file: `python3 test_X.py IIRD SOURCE_DIR` (as ctest runs it)."""

import asyncio
import http.client
import io
import json
import logging
import math
import os
import re
import signal
import struct
import subprocess
import sys
import tempfile
import time
import unittest

import websockets
from PIL import Image

IIRD = None  # path of the iird binary, from argv
SRC = None  # source tree, from argv

HEADER = struct.Struct("<4sBBHIIHHffIIII")
assert HEADER.size == 44
NO_SEQ = 0xFFFFFFFF
MAX_MSG = 64 << 20  # frames and EXR snapshots are larger than websockets' 1 MiB default

# Under ASan a 512x384 iir frame takes ~0.2 s on this 2-core machine shared with other builds.
FRAME_TIMEOUT = float(os.environ.get("IIR_TEST_FRAME_TIMEOUT", "20"))

# New sessions' defaults for the test daemons: smaller frames and shadow maps than the product's
# (512x384, 128^2), so a session's first frame (every VPL's shadow map) costs ~0.3 s under ASan, not 2 s.
FAST_ARGS = ("--size", "256x192", "--sm-res", "64")

SANITIZER_PATTERNS = ("ERROR: AddressSanitizer", "LeakSanitizer", "runtime error:", "ERROR: ThreadSanitizer")


# ---------------------------------------------------------------- daemon ----


# Every test client connects from 127.0.0.1, several at once: unless a test gives its own
# --max-sessions-per-address, the daemons let one address hold every slot (the product's default is a
# quarter of --max-sessions).
PER_ADDRESS_ARGS = ("--max-sessions-per-address", "1024")


class Daemon:
    """One `iird serve --port 0` process. stdout and stderr go to files (never a pipe that could
    fill); the port is read from the `iird: serving http://127.0.0.1:PORT/` line. per_address=False
    keeps the product's --max-sessions-per-address default; cwd and env_extra set the process's
    working directory and extra environment variables."""

    def __init__(self, *args, scenes=True, per_address=True, cwd=None, env_extra=None):
        self.tmp = tempfile.TemporaryDirectory(prefix="iird-integ-", dir=os.environ.get("IIR_TEST_TMP"))
        os.makedirs(self.tmp.name, exist_ok=True)
        self.out_path = os.path.join(self.tmp.name, "stdout")
        self.err_path = os.path.join(self.tmp.name, "stderr")
        cmd = [IIRD, "serve", "--port", "0"]
        if scenes:
            cmd += ["--scenes", os.path.join(SRC, "scenes")]
        if per_address and "--max-sessions-per-address" not in args:
            cmd += PER_ADDRESS_ARGS
        cmd += list(args)
        env = dict(os.environ)
        env.setdefault("ASAN_OPTIONS", "detect_leaks=1")
        env.setdefault("UBSAN_OPTIONS", "print_stacktrace=1")
        env.setdefault("OMP_NUM_THREADS", "2")
        env.update(env_extra or {})
        self.cmd = cmd
        with open(self.out_path, "wb") as out, open(self.err_path, "wb") as err:
            self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=out, stderr=err, env=env, cwd=cwd)
        self.port = self._wait_port(30.0)
        self.stopped = False

    def _wait_port(self, timeout):
        deadline = time.monotonic() + timeout
        pat = re.compile(r"iird: serving http://127\.0\.0\.1:(\d+)/")
        while time.monotonic() < deadline:
            m = pat.search(self.stdout())
            if m:
                return int(m.group(1))
            if self.proc.poll() is not None:
                raise AssertionError(
                    f"{' '.join(self.cmd)} exited {self.proc.returncode} before serving:\n"
                    f"{self.stdout()}\n{self.stderr()}"
                )
            time.sleep(0.05)
        self.proc.kill()
        raise AssertionError(f"no 'iird: serving' line within {timeout} s:\n{self.stdout()}\n{self.stderr()}")

    def stdout(self):
        with open(self.out_path, "r", errors="replace") as f:
            return f.read()

    def stderr(self):
        with open(self.err_path, "r", errors="replace") as f:
            return f.read()

    @property
    def url(self):
        return f"ws://127.0.0.1:{self.port}/ws"

    def alive(self):
        return self.proc.poll() is None

    def sanitizer_report(self):
        """The first sanitizer report line in stderr, or None."""
        for line in self.stderr().splitlines():
            if any(p in line for p in SANITIZER_PATTERNS):
                return line
        return None

    def stop(self, timeout=15.0):
        """SIGINT, then wait. Returns (exit code, seconds taken); kills after timeout (code None)."""
        if self.stopped:
            return self.proc.returncode, 0.0
        self.stopped = True
        t0 = time.monotonic()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            rc = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            rc = None
        return rc, time.monotonic() - t0

    def stop_and_check(self, test, timeout=15.0):
        """Stops the daemon and fails `test` unless it exited 0 in time with a clean stderr."""
        rc, secs = self.stop(timeout)
        err = self.stderr()
        test.assertEqual(rc, 0, f"iird serve exited {rc} after SIGINT ({secs:.1f} s); stderr tail:\n{err[-3000:]}")
        rep = self.sanitizer_report()
        test.assertIsNone(rep, f"sanitizer report in iird's stderr: {rep}\n{err[-6000:]}")
        return secs

    def close(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.tmp.cleanup()


# ------------------------------------------------------------- figures ----


def pct(xs, p):
    """The p-th percentile of xs, linearly interpolated; NaN for no values."""
    xs = sorted(xs)
    if not xs:
        return float("nan")
    k = (len(xs) - 1) * p / 100.0
    lo, hi = math.floor(k), math.ceil(k)
    return xs[lo] + (xs[hi] - xs[lo]) * (k - lo)


def rss_bytes(pid):
    """Resident memory of process pid (VmRSS)."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise AssertionError(f"no VmRSS in /proc/{pid}/status")


# ------------------------------------------------------------------ HTTP ----


def http_get(port, path, headers=None, timeout=10.0):
    """GET path; returns (status, content-type, body bytes)."""
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        c.request("GET", path, headers=headers or {})
        r = c.getresponse()
        return r.status, r.getheader("Content-Type", ""), r.read()
    finally:
        c.close()


METRIC_LINE = re.compile(
    r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{(?:[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\]|\\.)*"'
    r'(?:,[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\]|\\.)*")*,?)?\})? '
    r"([-+]?(?:[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?|NaN|\+Inf|-Inf))( -?[0-9]+)?$"
)


def parse_metrics(text):
    """Prometheus text format -> list of (name, labels text, value). Raises AssertionError naming the
    first line that is neither a comment, blank, nor `name{labels} value`."""
    samples = []
    for i, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        m = METRIC_LINE.match(line)
        if not m:
            raise AssertionError(f"/metrics line {i} is not Prometheus text: {line!r}")
        samples.append((m.group(1), m.group(2) or "", float(m.group(3))))
    return samples


def metric(samples, name, labels=None):
    """Value of the sample `name` (with labels containing `labels` if given); None when absent."""
    for n, lab, v in samples:
        if n == name and (labels is None or labels in lab):
            return v
    return None


def metrics(port):
    status, ctype, body = http_get(port, "/metrics")
    assert status == 200, f"/metrics answered {status}"
    return parse_metrics(body.decode())


def session_render_seconds(samples, session):
    """Render time session `session` has used (iird_session_render_seconds_total: its turns on the
    cores, counted while they last); None when the daemon lists no such session."""
    return metric(samples, "iird_session_render_seconds_total", f'session="{session}"')


async def wait_metrics(port, holds, what, timeout=FRAME_TIMEOUT, show=None):
    """Polls /metrics (from a thread: the clients' readers go on meanwhile) until holds(samples) is
    true; returns those samples. AssertionError "no `what` within timeout s" on timeout, with
    show(samples) of the last poll when given."""
    deadline = time.monotonic() + timeout
    while True:
        samples = await asyncio.to_thread(metrics, port)
        if holds(samples):
            return samples
        if time.monotonic() >= deadline:
            raise AssertionError(f"no {what} within {timeout:.1f} s" + (f"; {show(samples)}" if show else ""))
        await asyncio.sleep(0.05)


async def wait_metric(port, name, want, what, timeout=FRAME_TIMEOUT, labels=None):
    """wait_metrics until metric `name` (with `labels`) equals want; its last value on timeout."""
    return await wait_metrics(port, lambda s: metric(s, name, labels) == want, what, timeout,
                              show=lambda s: f"{name}{labels or ''} is {metric(s, name, labels)}, not {want}")


def healthz(port):
    status, ctype, body = http_get(port, "/healthz")
    assert status == 200, f"/healthz answered {status}: {body[:200]!r}"
    return json.loads(body)


# ------------------------------------------------------------- messages ----


class Frame:
    """A binary message: the header fields of docs/protocol.md and the payload."""

    def __init__(self, data):
        if len(data) < HEADER.size:
            raise AssertionError(f"binary message of {len(data)} bytes is shorter than the 44-byte header")
        (
            self.magic,
            self.kind,
            self.version,
            self.header_len,
            self.id,
            self.seq,
            self.width,
            self.height,
            self.render_ms,
            self.encode_ms,
            self.pass_,
            self.flags,
            self.payload_len,
            self.generation,
        ) = HEADER.unpack_from(data)
        self.size = len(data)
        self.payload = bytes(data[self.header_len :]) if self.header_len <= len(data) else b""
        self.t = time.monotonic()

    def check_header(self, test, kind=1):
        test.assertEqual(self.magic, b"IIRF", "frame magic")
        test.assertEqual(self.kind, kind, "frame kind")
        test.assertEqual(self.version, 2, "frame header version")
        test.assertEqual(self.header_len, 44, "frame header length")
        test.assertEqual(self.payload_len, self.size - 44, "payload length field vs message size")
        test.assertEqual(self.flags & ~7, 0, f"unknown flag bits {self.flags:#x}")
        if kind == 1:
            test.assertGreaterEqual(self.width, 16)
            test.assertGreaterEqual(self.height, 16)
            test.assertTrue(math.isfinite(self.render_ms) and self.render_ms >= 0, f"render ms {self.render_ms}")
            test.assertTrue(math.isfinite(self.encode_ms) and self.encode_ms >= 0, f"encode ms {self.encode_ms}")

    def image(self):
        im = Image.open(io.BytesIO(self.payload))
        im.load()
        return im

    def __repr__(self):
        return f"Frame(id={self.id}, seq={self.seq}, {self.width}x{self.height}, pass={self.pass_}, kind={self.kind})"


def mean_abs_diff(a, b):
    """Mean absolute difference of two same-size images over RGB, in 8-bit levels."""
    a = a.convert("RGB")
    b = b.convert("RGB")
    if a.size != b.size:
        raise AssertionError(f"image sizes differ: {a.size} vs {b.size}")
    from PIL import ImageChops, ImageStat

    d = ImageChops.difference(a, b)
    return sum(ImageStat.Stat(d).mean) / 3.0


def mean_level(im):
    from PIL import ImageStat

    return sum(ImageStat.Stat(im.convert("RGB")).mean) / 3.0


def finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


# ---------------------------------------------------------------- client ----


def stop_class_daemon(d):
    """Stops a test class's daemon with SIGINT and closes it; raises AssertionError on a non-zero exit
    or a sanitizer report (unittest has no failing hook in tearDownClass: raising makes the run fail)."""
    try:
        rc, secs = d.stop()
        rep = d.sanitizer_report()
        if rc != 0 or rep:
            raise AssertionError(f"iird serve {' '.join(d.cmd[2:])}: exit {rc} after SIGINT ({secs:.1f} s), "
                                 f"sanitizer: {rep}\nstderr tail:\n{d.stderr()[-6000:]}")
    finally:
        d.close()


class Client:
    """A WebSocket client that logs every message it receives (Frame or dict) in `log`, in order.
    Waits scan the log from a given index, so a test can mark a point and wait for what follows."""

    def __init__(self, ws):
        self.ws = ws
        self.log = []
        self.closed = False
        self.cond = asyncio.Condition()
        self.seq = 1000
        self.reader = asyncio.get_running_loop().create_task(self._read())

    @classmethod
    async def connect(cls, daemon_or_url, hello=True, origin=None, path="/ws", **hello_fields):
        url = daemon_or_url if isinstance(daemon_or_url, str) else daemon_or_url.url
        if path != "/ws":
            url = url.rsplit("/", 1)[0] + path
        ws = await websockets.connect(url, max_size=MAX_MSG, origin=origin, open_timeout=15, close_timeout=5)
        c = cls(ws)
        if hello:
            await c.hello(**hello_fields)
        return c

    async def _read(self):
        try:
            async for m in self.ws:
                if isinstance(m, (bytes, bytearray)):
                    item = Frame(m)
                else:
                    try:
                        item = json.loads(m)
                    except ValueError:
                        item = {"type": "__not_json__", "text": m}
                async with self.cond:
                    self.log.append(item)
                    self.cond.notify_all()
        except websockets.ConnectionClosed:
            pass
        finally:
            async with self.cond:
                self.closed = True
                self.cond.notify_all()

    def next_seq(self):
        self.seq += 1
        return self.seq

    def mark(self):
        return len(self.log)

    async def send(self, msg):
        await self.ws.send(msg if isinstance(msg, (str, bytes)) else json.dumps(msg))

    async def wait_for(self, pred, timeout=FRAME_TIMEOUT, since=0, what="a message"):
        """The first logged item from index `since` on that satisfies pred; AssertionError on timeout
        or when the connection closes first."""
        deadline = time.monotonic() + timeout
        i = since
        async with self.cond:
            while True:
                while i < len(self.log):
                    item = self.log[i]
                    i += 1
                    if pred(item):
                        return item
                if self.closed:
                    raise AssertionError(f"connection closed ({self.close_info()}) while waiting for {what}; "
                                         f"last messages: {self.tail()}")
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"no {what} within {timeout} s; last messages: {self.tail()}")
                try:
                    await asyncio.wait_for(self.cond.wait(), left)
                except asyncio.TimeoutError:
                    pass

    def tail(self, n=6):
        out = []
        for item in self.log[-n:]:
            out.append(repr(item) if isinstance(item, Frame) else json.dumps(item)[:300])
        return out

    def close_info(self):
        return f"code {self.ws.close_code}, reason {self.ws.close_reason!r}"

    async def wait_text(self, type_, since=0, seq=None, timeout=FRAME_TIMEOUT):
        def p(m):
            return isinstance(m, dict) and m.get("type") == type_ and (seq is None or m.get("seq") == seq)

        return await self.wait_for(p, timeout, since, what=f"'{type_}' message" + (f" with seq {seq}" if seq else ""))

    async def wait_frame(self, since=0, min_seq=None, kind=1, timeout=FRAME_TIMEOUT):
        """The first frame (kind 1) from `since` on whose header seq is >= min_seq (and not 'none')."""

        def p(m):
            return (isinstance(m, Frame) and m.kind == kind
                    and (min_seq is None or (m.seq != NO_SEQ and m.seq >= min_seq)))

        return await self.wait_for(p, timeout, since, what=f"frame (kind {kind}) answering seq >= {min_seq}")

    async def hello(self, **fields):
        seq = self.next_seq()
        at = self.mark()
        await self.send({"type": "hello", "seq": seq, "client": "iir-integration-test", **fields})
        self.welcome = await self.wait_text("welcome", since=at)
        return self.welcome

    async def request(self, msg, reply_type, timeout=FRAME_TIMEOUT):
        """Sends msg with a fresh seq; returns (seq, the reply of reply_type echoing it)."""
        seq = self.next_seq()
        at = self.mark()
        await self.send({**msg, "seq": seq})

        def p(m):
            return isinstance(m, dict) and m.get("seq") == seq and m.get("type") in (reply_type, "error")

        reply = await self.wait_for(p, timeout, at, what=f"'{reply_type}' reply to seq {seq}")
        if reply["type"] == "error" and reply_type != "error":
            raise AssertionError(f"{msg} got an error: {reply}")
        return seq, reply

    async def move_light(self, timeout=FRAME_TIMEOUT, **fields):
        """Sends a light message; returns (seq, the first frame answering it)."""
        seq = self.next_seq()
        at = self.mark()
        await self.send({"type": "light", "seq": seq, **fields})
        f = await self.wait_for(
            lambda m: (isinstance(m, Frame) and m.kind == 1 and m.seq != NO_SEQ and m.seq >= seq)
            or (isinstance(m, dict) and m.get("type") == "error" and m.get("seq") == seq),
            timeout, at, what=f"frame answering light seq {seq}")
        if isinstance(f, dict):
            raise AssertionError(f"light {fields} got an error: {f}")
        return seq, f

    async def close(self):
        try:
            await self.ws.close()
        except Exception:
            pass
        try:
            await asyncio.wait_for(self.reader, 5)
        except (asyncio.TimeoutError, asyncio.CancelledError):
            self.reader.cancel()

    def frames(self, since=0, kind=1):
        return [m for m in self.log[since:] if isinstance(m, Frame) and m.kind == kind]

    def texts(self, type_, since=0):
        return [m for m in self.log[since:] if isinstance(m, dict) and m.get("type") == type_]


# ------------------------------------------------------------------ main ----


class DaemonTest(unittest.IsolatedAsyncioTestCase):
    """A test case class sharing one daemon (started with DAEMON_ARGS) across its tests; the daemon
    must exit 0 on SIGINT with no sanitizer report when the class is done."""

    DAEMON_ARGS = ()

    @classmethod
    def setUpClass(cls):
        cls.daemon = Daemon(*FAST_ARGS, *cls.DAEMON_ARGS)

    @classmethod
    def tearDownClass(cls):
        stop_class_daemon(cls.daemon)

    def setUp(self):
        self._t0 = time.monotonic()

    def tearDown(self):
        print(f"[{time.monotonic() - self._t0:.1f} s] ", end="", flush=True)

    async def still_streaming(self, c, what=""):
        """After a bad message: the daemon is alive and a fresh light move gets a frame answering it."""
        self.assertTrue(self.daemon.alive(), f"daemon died after {what}: {self.daemon.stderr()[-3000:]}")
        base = c.welcome["state"]["light"]["position"]
        seq, f = await c.move_light(position=[base[0] + 0.01 * (c.seq % 7), base[1], base[2]])
        self.assertEqual(f.seq, seq, f"after {what}: the frame answers seq {f.seq}, expected the move's {seq}")
        return f


def main():
    global IIRD, SRC
    if len(sys.argv) < 3:
        print(f"usage: {sys.argv[0]} IIRD SOURCE_DIR [unittest args]", file=sys.stderr)
        sys.exit(64)
    logging.getLogger("asyncio").setLevel(logging.ERROR)  # unittest's debug loop warns of slow steps
    IIRD = os.path.abspath(sys.argv[1])
    SRC = os.path.abspath(sys.argv[2])
    unittest.main(module="__main__", argv=[sys.argv[0]] + sys.argv[3:], verbosity=2)

"""test_serve_hostile2.py -- `iird serve` against hostile or careless clients, second pass (issue 25,
findings 7 and 8): replies are never dropped (a burst of requests, superseded scene switches) and a
client that does not read is closed with a reason; scene names that lead outside the scenes directory;
scene errors that show server paths; signals a daemon must survive; the seed's advertised and accepted
maximum; frames RFC 6455 says fail the connection. Usage: test_serve_hostile2.py IIRD SOURCE_DIR"""

import asyncio
import base64
import json
import os
import shutil
import signal
import socket
import struct
import tempfile
import time
import unittest

import iirserve
from iirserve import FAST_ARGS, Client, Daemon, DaemonTest, metric, metrics


# ------------------------------------------------------------ raw WebSocket ----


def ws_frame(payload, first=0x81, masked=True):
    """A client frame: first byte `first` (FIN, RSV bits, opcode), payload masked unless told."""
    if isinstance(payload, str):
        payload = payload.encode()
    n = len(payload)
    mask_bit = 0x80 if masked else 0
    if n < 126:
        head = bytes([first, mask_bit | n])
    else:
        head = bytes([first, mask_bit | 126]) + struct.pack(">H", n)
    if not masked:
        return head + payload
    key = os.urandom(4)
    return head + key + bytes(b ^ key[i % 4] for i, b in enumerate(payload))


def msg_frame(msg, **kw):
    return ws_frame(json.dumps(msg), **kw)


class RawWS:
    """A WebSocket client on a plain socket, for what a library client will not do: framing tricks and
    not reading. Server frames are parsed as they come (text as JSON, binary as its length)."""

    def __init__(self, port, rcvbuf=None):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.connect(("127.0.0.1", port))
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           f"Sec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            b = self.sock.recv(1)
            if not b:
                raise AssertionError(f"handshake refused: {head!r}")
            head += b
        assert head.startswith(b"HTTP/1.1 101"), head
        self.buf = b""
        self.frames = []  # (opcode, payload bytes) in order
        self.eof_at = None  # monotonic time the server closed the TCP connection

    def send(self, data):
        self.sock.sendall(data)

    def _parse(self):
        while len(self.buf) >= 2:
            b0, b1 = self.buf[0], self.buf[1]
            n, at = b1 & 0x7F, 2
            if n == 126:
                if len(self.buf) < 4:
                    return
                n, at = struct.unpack(">H", self.buf[2:4])[0], 4
            elif n == 127:
                if len(self.buf) < 10:
                    return
                n, at = struct.unpack(">Q", self.buf[2:10])[0], 10
            if len(self.buf) < at + n:
                return
            self.frames.append((b0 & 0x0F, self.buf[at:at + n]))
            self.buf = self.buf[at + n:]

    def read(self, until, timeout):
        """Reads until until(self) is true, the server closes the connection or timeout seconds pass.
        Returns whether the condition was met."""
        deadline = time.monotonic() + timeout
        while not until(self):
            if self.eof_at is not None:
                return False
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            self.sock.settimeout(left)
            try:
                data = self.sock.recv(1 << 20)
            except socket.timeout:
                return False
            except ConnectionResetError:
                data = b""
            if not data:
                self.eof_at = time.monotonic()
            self.buf += data
            self._parse()
        return True

    def texts(self):
        return [json.loads(p) for op, p in self.frames if op == 1]

    def close_frame(self):
        """(code, reason) of the server's close frame, or None."""
        for op, p in self.frames:
            if op == 8:
                return (struct.unpack(">H", p[:2])[0] if len(p) >= 2 else None), p[2:].decode(errors="replace")
        return None

    def after_close(self):
        """The frames the server sent after its close frame."""
        ops = [op for op, _ in self.frames]
        return self.frames[ops.index(8) + 1:] if 8 in ops else []

    def close(self):
        self.sock.close()


def replies_by_seq(texts):
    out = {}
    for m in texts:
        if "seq" in m:
            out.setdefault(m["seq"], []).append(m)
    return out


async def wait_no_session(d, timeout=30):
    deadline = time.monotonic() + timeout
    while metric(await asyncio.to_thread(metrics, d.port), "iird_sessions") > 0:
        assert time.monotonic() < deadline, "the sessions gauge never came back to 0"
        await asyncio.sleep(0.05)


# ---------------------------------------------------------------- finding 7 ----


class RepliesTest(DaemonTest):
    async def test_every_reply_of_a_burst_arrives(self):
        """300 picks in one TCP write (replies queued faster than written): each gets its reply."""
        n = 300
        ws = await asyncio.to_thread(RawWS, self.daemon.port)
        try:
            burst = [msg_frame({"type": "hello", "seq": 1})]
            burst += [msg_frame({"type": "pick", "seq": 10 + i, "x": 128, "y": 96}) for i in range(n)]
            ws.send(b"".join(burst))

            def picks(w):
                return sum(1 for m in w.texts() if m.get("type") == "pick")

            await asyncio.to_thread(ws.read, lambda w: picks(w) >= n, 20)
            got = replies_by_seq([m for m in ws.texts() if m.get("type") in ("pick", "error")])
            missing = [10 + i for i in range(n) if 10 + i not in got]
            print(f"{picks(ws)} pick replies of {n}; missing {len(missing)}")
            self.assertEqual(missing, [], f"{len(missing)} of {n} pick replies never came")
            self.assertTrue(all(len(v) == 1 and v[0]["type"] == "pick" for v in got.values()))
            self.assertIsNone(ws.close_frame(), "a client that reads is not closed")
        finally:
            ws.close()

    async def test_quick_scene_switches_all_answered(self):
        """Four scene switches in a row: each seq gets one reply; the last is the scene shown."""
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            at = c.mark()
            names = ["cornell_box", "builtin", "cornell_box", "builtin", "cornell_box"]
            seqs = []
            for name in names:
                seqs.append(c.next_seq())
                await c.send({"type": "scene", "seq": seqs[-1], "name": name})
            last = await c.wait_for(lambda m: isinstance(m, dict) and m.get("seq") == seqs[-1],
                                    what=f"the reply to the last scene switch (seq {seqs[-1]})")
            self.assertEqual((last["type"], last["scene"], last.get("superseded")), ("state", names[-1], None), last)
            await asyncio.sleep(0.5)  # a reply that were merely late would come now
            got = replies_by_seq([m for m in c.log[at:] if isinstance(m, dict) and m.get("type") in ("state", "error")])
            answered = [s for s in seqs if len(got.get(s, [])) == 1]
            print(f"scene switches {seqs}: answered {answered}, superseded "
                  f"{[s for s in seqs if got.get(s) and got[s][0].get('superseded')]}")
            self.assertEqual(answered, seqs, f"each switch gets exactly one reply: {got.keys()}")
            for s in seqs[:-1]:
                m = got[s][0]
                if m.get("superseded"):
                    self.assertEqual(m["type"], "state")
            await self.still_streaming(c, "quick scene switches")
        finally:
            await c.close()


class NotReadingTest(DaemonTest):
    async def test_client_that_does_not_read_is_closed_with_a_reason(self):
        """Hellos (a ~30 KB welcome each) from a client that never reads: no reply is dropped; once
        too many wait, the session is closed with 1008 and a reason, after the replies before it."""
        d = self.daemon
        ws = await asyncio.to_thread(RawWS, d.port, 4096)
        try:
            n = 300  # > 4 MiB of welcomes; few enough that the daemon reads them all (a socket
            # closed with unread input is reset, and the client would lose what it had not read)
            ws.send(b"".join(msg_frame({"type": "hello", "seq": 1 + i}) for i in range(n)))
            deadline = time.monotonic() + 20
            while "does not read" not in d.stderr() and time.monotonic() < deadline:
                await asyncio.sleep(0.1)
            closed = await asyncio.to_thread(ws.read, lambda w: w.close_frame() is not None, 10)
            welcomes = [m["seq"] for m in ws.texts() if m.get("type") == "welcome"]
            print(f"{len(welcomes)} welcomes of {n} read, then close {ws.close_frame()}")
            self.assertTrue(closed, f"no close frame after {len(welcomes)} welcomes of {n}")
            code, reason = ws.close_frame()
            self.assertIn(code, (1008, 1013), reason)
            self.assertIn("does not read", reason)
            self.assertEqual(welcomes, list(range(1, len(welcomes) + 1)),
                             "the replies before the close are all there, in order (none dropped)")
            self.assertLess(len(welcomes), n)
        finally:
            ws.close()
        await wait_no_session(d)
        c = await Client.connect(d)  # the daemon serves on
        await c.wait_frame()
        await c.close()


# ---------------------------------------------------------------- finding 8 ----


class ScenesDirTest(unittest.IsolatedAsyncioTestCase):
    """A scenes directory with a scene inside, a symbolic link to a scene outside it, a link to
    /proc/self/environ and a broken OBJ."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="iird-scenes2-", dir=os.environ.get("IIR_TEST_TMP"))
        self.addCleanup(self.tmp.cleanup)
        root = self.tmp.name
        self.scenes = os.path.join(root, "scenes")
        os.makedirs(self.scenes)
        src = os.path.join(iirserve.SRC, "scenes", "cornell_box")
        shutil.copytree(src, os.path.join(self.scenes, "inside"), ignore=shutil.ignore_patterns("paths"))
        shutil.copytree(src, os.path.join(root, "outside", "escaped"), ignore=shutil.ignore_patterns("paths"))
        os.symlink(os.path.join(root, "outside", "escaped"), os.path.join(self.scenes, "escaped"))
        os.symlink("/proc/self/environ", os.path.join(self.scenes, "envleak.obj"))
        with open(os.path.join(self.scenes, "broken.obj"), "w") as f:
            f.write("v 0 0 0\nf 1 2 3\n")

    def daemon(self, *args):
        d = Daemon(*FAST_ARGS, "--scenes", self.scenes, *args, scenes=False)
        self.addCleanup(d.close)
        return d

    async def test_links_out_of_the_scenes_dir_refused(self):
        d = self.daemon()
        c = await Client.connect(d)
        try:
            listed = c.welcome["scenes"]
            print(f"listed: {listed}")
            self.assertIn("inside", listed)
            self.assertNotIn("escaped", listed)
            self.assertNotIn("envleak.obj", listed)
            for name in ("escaped", "envleak.obj"):
                seq, e = await c.request({"type": "scene", "name": name}, "error")
                self.assertEqual(e["type"], "error", f"scene {name} outside the directory was loaded: {e}")
                self.assertEqual(e["code"], "bad_field", e)
            seq, st = await c.request({"type": "scene", "name": "inside"}, "state")
            self.assertEqual(st["scene"], "inside")
        finally:
            await c.close()
        self.assertIn("escaped", d.stderr(), "the daemon logs what it did not list")
        d.stop_and_check(self)

    async def test_follow_links_option(self):
        d = self.daemon("--scenes-follow-links")
        c = await Client.connect(d)
        try:
            self.assertIn("escaped", c.welcome["scenes"])
            seq, st = await c.request({"type": "scene", "name": "escaped"}, "state")
            self.assertEqual(st["scene"], "escaped")
            seq, e = await c.request({"type": "scene", "name": "envleak.obj"}, "error")
            print(f"envleak.obj: {e.get('message')}")
            self.assertEqual(e["code"], "scene_error", e)
            self.assertNotIn("/", e["message"], f"a server path in the client's message: {e['message']}")
            self.assertNotIn("environ", e["message"])
        finally:
            await c.close()
        d.stop_and_check(self)

    async def test_scene_error_shows_no_path(self):
        d = self.daemon()
        c = await Client.connect(d)
        try:
            seq, e = await c.request({"type": "scene", "name": "broken.obj"}, "error")
            print(f"broken.obj: {e.get('message')}")
            self.assertEqual(e["code"], "scene_error", e)
            self.assertNotIn("/", e["message"], f"a server path in the client's message: {e['message']}")
            self.assertNotIn(self.tmp.name, e["message"])
            self.assertIn("broken.obj", e["message"], "the message names the scene")
            self.assertIn("vertex index out of range", e["message"], "and still says why")
        finally:
            await c.close()
        err = d.stderr()
        self.assertIn(os.path.join(os.path.realpath(self.scenes), "broken.obj"), err, "the path goes to the log")
        d.stop_and_check(self)


class SignalsTest(unittest.IsolatedAsyncioTestCase):
    async def test_stray_signals_do_not_kill(self):
        d = Daemon(*FAST_ARGS)
        self.addCleanup(d.close)
        sigs = [signal.SIGALRM, signal.SIGVTALRM, signal.SIGPROF, signal.SIGIO, signal.SIGPWR,
                signal.SIGUSR1, signal.SIGUSR2, signal.SIGPIPE, signal.SIGXFSZ, signal.SIGRTMIN,
                signal.SIGRTMIN + 5, signal.SIGRTMAX]
        if hasattr(signal, "SIGSTKFLT"):
            sigs.append(signal.SIGSTKFLT)
        for sig in sigs:
            d.proc.send_signal(sig)
            await asyncio.sleep(0.05)
            self.assertTrue(d.alive(), f"signal {sig} killed the daemon: exit {d.proc.returncode}")
        await asyncio.sleep(0.3)
        self.assertTrue(d.alive(), f"the daemon died: exit {d.proc.returncode}")
        c = await Client.connect(d)
        await c.wait_frame()
        await c.close()
        secs = d.stop_and_check(self)  # SIGINT still stops it cleanly
        self.assertLess(secs, 5)


class SeedTest(DaemonTest):
    async def test_one_exact_limit(self):
        c = await Client.connect(self.daemon)
        try:
            rows = [p for m in c.welcome["methods"] for p in m["params"] if p["name"] == "seed"]
            self.assertTrue(rows)
            top = 2**53 - 1
            for row in rows:
                self.assertIsInstance(row["max"], int, f"welcome seed max {row['max']!r} is not an exact integer")
                self.assertEqual((row["max"], row["live_max"]), (top, top), row)
            seq, st = await c.request({"type": "params", "seed": top}, "state")
            self.assertEqual(st["params"]["seed"], top, "the advertised maximum is accepted exactly")
            for v in ("9007199254740992", "9007199254740993", "18446744073709551615"):
                seq = c.next_seq()
                at = c.mark()
                await c.send('{"type":"params","seq":%d,"seed":%s}' % (seq, v))
                r = await c.wait_for(lambda m: isinstance(m, dict) and m.get("seq") == seq, since=at)
                self.assertEqual((r["type"], r.get("code"), r.get("field")), ("error", "out_of_range", "params.seed"),
                                 f"seed {v} above the advertised maximum: {r}")
            seq, st = await c.request({"type": "params", "seed": 7}, "state")
            self.assertEqual(st["params"]["seed"], 7)
        finally:
            await c.close()


class FramingTest(DaemonTest):
    """RFC 6455 5.2: RSV bits without an extension and reserved opcodes fail the connection."""

    async def bad_frame_fails(self, bad, idle):
        ws = await asyncio.to_thread(RawWS, self.daemon.port)
        try:
            ws.send(msg_frame({"type": "hello", "seq": 1, "client": "framing"}))
            if idle:  # a session with nothing to send: refine off, the first frame out
                ws.send(msg_frame({"type": "params", "seq": 2, "refine": False, "domain": False}))
                ok = await asyncio.to_thread(ws.read, lambda w: any(op == 2 for op, _ in w.frames), 20)
                self.assertTrue(ok, "no frame")
                await asyncio.sleep(1.0)
                ws.frames = []
            t0 = time.monotonic()
            ws.send(bad)
            await asyncio.to_thread(ws.read, lambda w: False, 8)
            took = (ws.eof_at or time.monotonic()) - t0
            close = ws.close_frame()
            print(f"{bad[:1].hex()} ({'idle' if idle else 'busy'}): close {close}, "
                  f"{len(ws.after_close())} frames after it, connection gone after {took:.2f} s")
            self.assertIsNotNone(close, "no close frame")
            self.assertEqual(close[0], 1002, close)
            self.assertEqual(ws.after_close(), [], "the server wrote after its close frame")
            self.assertIsNotNone(ws.eof_at, "the connection stayed open")
            self.assertLess(took, 1.5, f"the connection lasted {took:.2f} s after the bad frame")
        finally:
            ws.close()

    async def test_rsv_bits(self):
        for first in (0xC1, 0xA1, 0x91):  # text with RSV1, RSV2, RSV3
            await self.bad_frame_fails(msg_frame({"type": "pick", "x": 1, "y": 1}, first=first), idle=False)
        await self.bad_frame_fails(msg_frame({"type": "pick", "x": 1, "y": 1}, first=0xC1), idle=True)

    async def test_reserved_opcode(self):
        await self.bad_frame_fails(msg_frame({"type": "pick", "x": 1, "y": 1}, first=0x83), idle=False)
        await self.bad_frame_fails(ws_frame(b"x", first=0x8B), idle=True)

    @unittest.expectedFailure
    async def test_unmasked_frame(self):
        """Known gap: libwebsockets 4.1.6 (Debian 12) takes unmasked client frames and does not tell
        the protocol callback whether a frame was masked (one masked with the key 0 reaches it the
        same way), so iird cannot refuse them without parsing the stream itself. This test documents
        it; it passes (an unexpected success to remove the marker for) once lws closes them."""
        ws = await asyncio.to_thread(RawWS, self.daemon.port)
        try:
            ws.send(msg_frame({"type": "hello", "seq": 1}, masked=False))
            await asyncio.to_thread(ws.read, lambda w: w.close_frame() is not None, 3)
            self.assertEqual((ws.close_frame() or (None,))[0], 1002)
            self.assertNotIn("welcome", [m.get("type") for m in ws.texts()])
        finally:
            ws.close()


if __name__ == "__main__":
    iirserve.main()

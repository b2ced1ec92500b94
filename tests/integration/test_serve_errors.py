"""test_serve_errors.py -- every error of docs/protocol.md a client can trigger, through a real
WebSocket client: the reply's code, field and seq, nothing of a bad message applied, and frames still
answering a valid move after each one; not_ready, unauthorized (--token), busy (--max-sessions) and
rate_limited. Usage: test_serve_errors.py IIRD SOURCE_DIR"""

import asyncio
import json
import time

import websockets

import iirserve
from iirserve import NO_SEQ, Client, DaemonTest, Frame

ANY = object()  # the doc does not pin the field


class ErrorsTest(DaemonTest):
    async def asyncSetUp(self):
        self.c = await Client.connect(self.daemon)
        seq, self.state = await self.c.request({"type": "params", "width": 128, "height": 96, "refine": False},
                                             "state")
        await self.c.wait_frame(min_seq=seq)

    async def asyncTearDown(self):
        await self.c.close()

    async def bad(self, text, code, field=ANY, seq=None, what=None):
        """Sends raw text; waits for the first error after it; checks code, field and seq; then checks
        that the session still streams. seq: the seq the error must echo (None: must carry none)."""
        c = self.c
        what = what or text[:80]
        at = c.mark()
        await c.send(text)
        e = await c.wait_text("error", since=at)
        self.assertEqual(e.get("code"), code, f"{what}: {e}")
        if field is not ANY:
            if isinstance(field, tuple):
                self.assertIn(e.get("field"), field, f"{what}: {e}")
            else:
                self.assertEqual(e.get("field"), field, f"{what}: {e}")
        self.assertIn("field", e, f"{what}: error has a 'field' (null when none): {e}")
        self.assertIsInstance(e.get("message"), str, f"{what}: {e}")
        self.assertGreater(len(e["message"]), 5, f"{what}: a message a user can act on: {e}")
        if seq is None:
            self.assertNotIn("seq", e, f"{what}: no valid seq, none echoed: {e}")
        else:
            self.assertEqual(e.get("seq"), seq, f"{what}: {e}")
        await self.still_streaming(c, what)
        return e

    async def bad_msg(self, msg, code, field=ANY):
        seq = self.c.next_seq()
        return await self.bad(json.dumps({**msg, "seq": seq}), code, field, seq, what=json.dumps(msg)[:100])

    # ---- malformed messages ----

    async def test_bad_json(self):
        for text in ("not json", "[1, 2, 3]", '{"type":"light","cone_angle":50} trailing', '"light"', "null", "42",
                     '{"type":"light",', ""):
            await self.bad(text, "bad_json", None, what=f"bad json {text!r}")
        # Binary messages go only from server to client: not JSON text.
        await self.bad(b'{"type":"light","cone_angle":50}', "bad_json", None, what="a binary message")

    async def test_too_large(self):
        pad = "x" * (70 * 1024)
        await self.bad('{"type":"light","cone_angle":50,"pad":"' + pad + '"}', "too_large", what="70 KB message")
        # 65536 bytes exactly is allowed: a light message padded with spaces to the limit.
        base = '{"type":"light","seq":%d,"cone_angle":44}'
        seq = self.c.next_seq()
        msg = base % seq
        msg = msg[:-1] + " " * (65536 - len(msg)) + "}"
        self.assertEqual(len(msg), 65536)
        at = self.c.mark()
        await self.c.send(msg)
        f = await self.c.wait_for(lambda m: (isinstance(m, Frame) and m.seq != NO_SEQ and m.seq >= seq)
                                  or (isinstance(m, dict) and m.get("type") == "error"), since=at,
                                  what="frame answering a 65536-byte message")
        self.assertIsInstance(f, Frame, f"a 65536-byte message is within the limit: {f}")

    async def test_bad_type(self):
        seq = self.c.next_seq()
        await self.bad(json.dumps({"seq": seq, "cone_angle": 50}), "bad_type", "type", seq, "type missing")
        await self.bad_msg({"type": 7}, "bad_type", "type")
        await self.bad_msg({"type": None}, "bad_type", "type")
        await self.bad_msg({"type": "light", "position": [1, 2]}, "bad_type", "light.position")
        await self.bad_msg({"type": "light", "position": [1, 2, 3, 4]}, "bad_type", "light.position")
        await self.bad_msg({"type": "light", "position": "up"}, "bad_type", "light.position")
        await self.bad_msg({"type": "light", "position": [0, "1", 0]}, "bad_type",
                           ("light.position[1]", "light.position"))
        await self.bad_msg({"type": "light", "cone_angle": "50"}, "bad_type", "light.cone_angle")
        await self.bad_msg({"type": "params", "refine": 1}, "bad_type", "params.refine")
        await self.bad_msg({"type": "params", "method": 3}, "bad_type", "params.method")
        await self.bad_msg({"type": "camera", "fov": [40]}, "bad_type", "camera.fov")
        await self.bad_msg({"type": "hello", "client": 5}, "bad_type", "hello.client")
        await self.bad(json.dumps({"type": "light", "seq": "abc", "cone_angle": 50}), "bad_type", ("seq", "light.seq"), None,
                       "seq a string")

    async def test_unknown_type_and_field(self):
        await self.bad_msg({"type": "frobnicate"}, "unknown_type", "type")
        await self.bad_msg({"type": "welcome"}, "unknown_type", "type")  # a server message
        await self.bad_msg({"type": "light", "positon": [0, 1, 0]}, "unknown_field", "light.positon")
        await self.bad_msg({"type": "params", "width": 200, "widht": 200}, "unknown_field", "params.widht")
        await self.bad_msg({"type": "hello", "colour": "red"}, "unknown_field", "hello.colour")

    async def test_out_of_range(self):
        c = self.c
        lim = c.welcome["limits"]
        # JSON has no NaN: 1e400 overflows a double and is refused as not finite.
        seq = c.next_seq()
        await self.bad('{"type":"light","seq":%d,"position":[1e400,1,0]}' % seq, "out_of_range",
                       ("light.position[0]", "light.position"), seq, "1e400")
        seq = c.next_seq()
        await self.bad('{"type":"light","seq":%d,"cone_angle":-1e400}' % seq, "out_of_range", "light.cone_angle",
                       seq, "-1e400")
        await self.bad_msg({"type": "light", "position": [1e7, 1, 0]}, "out_of_range",
                           ("light.position[0]", "light.position"))
        await self.bad_msg({"type": "light", "cone_angle": 120}, "out_of_range", "light.cone_angle")
        await self.bad_msg({"type": "light", "cone_angle": 0}, "out_of_range", "light.cone_angle")
        await self.bad_msg({"type": "light", "intensity": -1}, "out_of_range", "light.intensity")
        await self.bad_msg({"type": "light", "intensity": [1, 2e6, 1]}, "out_of_range",
                           ("light.intensity[1]", "light.intensity"))
        await self.bad_msg({"type": "camera", "fov": 171}, "out_of_range", "camera.fov")
        await self.bad_msg({"type": "params", "width": lim["max_width"] + 1}, "out_of_range", "params.width")
        await self.bad_msg({"type": "params", "height": 15}, "out_of_range", "params.height")
        iir = next(m for m in c.welcome["methods"] if m["name"] == "iir")
        vpls = next(r for r in iir["params"] if r["name"] == "vpls")
        await self.bad_msg({"type": "params", "vpls": vpls["live_max"] + 1}, "out_of_range", "params.vpls")
        await self.bad_msg({"type": "params", "vpls": 0}, "out_of_range", "params.vpls")
        await self.bad_msg({"type": "params", "method": "nope"}, "out_of_range", "params.method")
        await self.bad_msg({"type": "params", "weights": "heavy"}, "out_of_range", "params.weights")
        await self.bad_msg({"type": "params", "quality": 101}, "out_of_range", "params.quality")
        await self.bad_msg({"type": "params", "interleave": 9}, "out_of_range", "params.interleave")
        await self.bad_msg({"type": "snapshot", "format": "gif"}, "out_of_range", "snapshot.format")
        await self.bad_msg({"type": "record", "action": "pause"}, "out_of_range", "record.action")
        await self.bad(json.dumps({"type": "light", "seq": 4294967295, "cone_angle": 50}), "out_of_range",
                       ("seq", "light.seq"), None, "seq 2^32-1")
        await self.bad(json.dumps({"type": "light", "seq": -1, "cone_angle": 50}), "out_of_range",
                       ("seq", "light.seq"), None, "seq -1")

    async def test_bad_field(self):
        p = self.state["light"]["position"]
        await self.bad_msg({"type": "light", "position": p, "target": p}, "bad_field", "light.target")
        seq, st = await self.c.request({"type": "params", "exposure": 0}, "state")  # still_streaming moved it
        now = st["light"]["position"]
        await self.bad_msg({"type": "light", "target": now}, "bad_field", "light.target")  # = current position
        await self.bad_msg({"type": "light", "direction": [0, -1, 0], "target": [0, 0, 0]}, "bad_field",
                           "light.target")
        await self.bad_msg({"type": "params", "kmin": 9, "kmax": 8}, "bad_field", ("params.kmin", "params.kmax"))
        vpls = self.state["params"]["vpls"]
        await self.bad_msg({"type": "params", "kmax": vpls + 1}, "bad_field", ("params.kmax", "params.vpls"))
        cam = self.state["camera"]["position"]
        await self.bad_msg({"type": "camera", "target": cam}, "bad_field", "camera.target")
        # "At least one field besides type/seq": the doc gives no code; the daemon says bad_field.
        await self.bad_msg({"type": "light"}, "bad_field")

    async def test_unsupported(self):
        await self.bad_msg({"type": "hello", "protocol": 2}, "unsupported", "hello.protocol")

    async def test_all_or_nothing(self):
        c = self.c
        before = self.state
        p = before["light"]["position"]
        await self.bad_msg({"type": "light", "position": [p[0] + 0.3, p[1], p[2]], "cone_angle": 100},
                           "out_of_range", "light.cone_angle")
        await self.bad_msg({"type": "params", "width": 200, "height": 100, "quality": 0}, "out_of_range",
                           "params.quality")
        # still_streaming moved the light by < 0.07 in x; the bad message would have moved it by 0.3.
        seq, st = await c.request({"type": "params", "exposure": 0}, "state")
        self.assertLess(abs(st["light"]["position"][0] - p[0]), 0.1, "a refused light message applied nothing")
        self.assertEqual(st["light"]["cone_angle"], before["light"]["cone_angle"])
        self.assertEqual((st["params"]["width"], st["params"]["height"]), (128, 96), "a refused params applied nothing")


class NotReadyTest(DaemonTest):
    async def test_not_ready_before_hello(self):
        c = await Client.connect(self.daemon, hello=False)
        try:
            for msg in ({"type": "light", "cone_angle": 50, "seq": 3}, {"type": "params", "width": 64, "seq": 4},
                        {"type": "pick", "x": 1, "y": 1, "seq": 5}):
                at = c.mark()
                await c.send(msg)
                e = await c.wait_text("error", since=at)
                self.assertEqual(e.get("code"), "not_ready", f"{msg}: {e}")
                self.assertEqual(e.get("seq"), msg["seq"])
            await asyncio.sleep(0.5)
            self.assertEqual(c.frames(), [], "no frames before hello")
            await c.hello()
            f = await c.wait_frame()
            f.check_header(self)
        finally:
            await c.close()


class TokenTest(DaemonTest):
    DAEMON_ARGS = ("--token", "s3cret")

    async def expect_refused(self, c, hello_fields):
        at = c.mark()
        await c.send({"type": "hello", "seq": 9, **hello_fields})
        e = await c.wait_text("error", since=at)
        self.assertEqual(e.get("code"), "unauthorized", f"hello {hello_fields}: {e}")
        await asyncio.wait_for(c.reader, 10)
        self.assertEqual(c.ws.close_code, 1008, f"hello {hello_fields}: closed with {c.close_info()}")
        self.assertEqual(c.frames(), [], "no frames without the token")

    async def test_unauthorized(self):
        c = await Client.connect(self.daemon, hello=False)
        at = c.mark()
        await c.send({"type": "light", "cone_angle": 50, "seq": 3})
        e = await c.wait_text("error", since=at)
        self.assertEqual(e.get("code"), "unauthorized", f"light before hello with --token: {e}")
        await self.expect_refused(c, {})
        c = await Client.connect(self.daemon, hello=False)
        await self.expect_refused(c, {"token": "wrong"})
        # A token over 256 bytes is refused (unauthorized, or out_of_range for the string's length).
        c = await Client.connect(self.daemon, hello=False)
        await c.send({"type": "hello", "seq": 9, "token": "s3cret" + "x" * 300})
        e = await c.wait_text("error")
        self.assertIn(e.get("code"), ("unauthorized", "out_of_range"), str(e))
        await asyncio.sleep(0.5)
        self.assertEqual(c.texts("welcome"), [])
        self.assertEqual(c.frames(), [])
        await c.close()
        c = await Client.connect(self.daemon, token="s3cret")
        try:
            f = await c.wait_frame()
            f.check_header(self)
        finally:
            await c.close()
        self.assertTrue(self.daemon.alive())


class BusyTest(DaemonTest):
    DAEMON_ARGS = ("--max-sessions", "1")

    async def test_busy(self):
        c1 = await Client.connect(self.daemon)
        try:
            await c1.wait_frame()
            c2 = await Client.connect(self.daemon, hello=False)
            e = await c2.wait_text("error")
            self.assertEqual(e.get("code"), "busy", str(e))
            await asyncio.wait_for(c2.reader, 10)
            self.assertEqual(c2.ws.close_code, 1013, f"busy closes with 1013: {c2.close_info()}")
            self.assertEqual(c2.frames(), [])
            seq, f = await c1.move_light(cone_angle=47)
            self.assertEqual(f.seq, seq, "the first session is unaffected")
        finally:
            await c1.close()
        # The slot is free again once the first session is gone.
        deadline = time.monotonic() + 10
        # (the slot stays taken until the closed session's worker has stopped: a connection in
        # between gets busy and 1013, possibly before its hello is even sent)
        while True:
            c3 = await Client.connect(self.daemon, hello=False)
            at = c3.mark()
            try:
                await c3.send({"type": "hello", "seq": 1})
                m = await c3.wait_for(lambda m: isinstance(m, dict) and m.get("type") in ("welcome", "error"), since=at)
            except websockets.exceptions.ConnectionClosed:
                m = {"type": "error", "code": "busy", "closed": c3.close_info()}
            await c3.close()
            if m["type"] == "welcome":
                break
            self.assertLess(time.monotonic(), deadline, f"the session slot was not freed: {m}")
            await asyncio.sleep(0.2)


class RateTest(DaemonTest):
    async def test_rate_limited(self):
        """1000 moves at once: beyond the burst of 500 they are dropped with one rate_limited error per
        second. How many were applied is counted by a recording (every applied light state is a
        keyframe): at most 500 + 250/s over the time the server can have taken to read them."""
        c = await Client.connect(self.daemon)
        try:
            seq, _ = await c.request({"type": "params", "width": 64, "height": 48, "refine": False}, "state")
            await c.wait_frame(min_seq=seq)
            base = c.welcome["state"]["light"]["position"]
            await c.request({"type": "record", "action": "start"}, "record")
            at = c.mark()
            t0 = time.monotonic()
            for i in range(1000):
                await c.send({"type": "light", "seq": c.next_seq(),
                              "position": [base[0] + 0.0005 * (i % 100), base[1], base[2]]})
            sent_s = time.monotonic() - t0
            e = await c.wait_text("error", since=at)
            self.assertEqual(e.get("code"), "rate_limited", str(e))
            self.assertNotIn("seq", e, "a rate_limited error answers no one message")
            await asyncio.sleep(2.5)  # refill the bucket
            window = time.monotonic() - t0
            seq, r = await c.request({"type": "record", "action": "stop"}, "record")
            limited = c.texts("error", at)
            self.assertTrue(all(x.get("code") == "rate_limited" for x in limited), str(limited[:3]))
            self.assertLessEqual(len(limited), int(window) + 2,
                                 f"one rate_limited per second, got {len(limited)} in {window:.1f} s")
            applied = r.get("keyframes", 0)
            print(f"rate: 1000 messages sent in {sent_s:.2f} s, {len(limited)} rate_limited errors, "
                  f"{applied} applied (recorded) within {window:.1f} s")
            self.assertGreater(applied, 0)
            self.assertLessEqual(applied, 500 + 250 * window + 5, "the bucket let through more than 500 + 250/s")
            self.assertGreater(len(c.frames(at)), 0, "frames kept coming during the flood")
            await self.still_streaming(c, "rate limiting")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

"""test_serve_stream.py -- `iird serve` streaming as docs/protocol.md promises it, through a real
WebSocket client: welcome, frame headers and JPEG payloads, frames that follow a moving light and echo
its seq, stats, the VPL domain, pick, params, scenes, snapshots, recording, latest-wins input and
progressive refinement. Errors are in test_serve_errors.py. Usage: test_serve_stream.py IIRD SRC"""

import asyncio
import io
import json
import math
import os
import subprocess
import tempfile

from PIL import Image

import iirserve
from iirserve import NO_SEQ, Client, DaemonTest, Frame, finite, mean_abs_diff, metric, metrics



def param_keys(welcome, method):
    """What a state's params hold: method, the stream settings and every parameter of the method,
    all from the welcome's tables."""
    rows = next(m["params"] for m in welcome["methods"] if m["name"] == method)
    return {"method"} | {r["name"] for r in welcome["settings"]} | {r["name"] for r in rows}


def declared(welcome, method):
    """The phases (in order) and counters ({name: kind}) method `method` declares in the welcome."""
    m = next(m for m in welcome["methods"] if m["name"] == method)
    return m["phases"], {c["name"]: c["kind"] for c in m["counters"]}


VPL_KEYS = {"count", "valid", "invalidated", "deleted", "inserted", "null", "regenerated", "shadowmaps",
            "descendants"}
STATS_NUMBERS = ("frame", "pass", "total_ms", "encode_ms", "latency_ms", "fps", "bytes", "dropped", "memory_bytes")

# Mean absolute 8-bit difference between the first and the last frame of the light path below.
# Measured on the built-in Cornell box at 256x192 (iir): about LIGHT_PATH_MEASURED; the test asks for a
# third of it, far above JPEG noise between two frames of the same state (< 1 level).
LIGHT_PATH_MEASURED = 27.0
LIGHT_PATH_MIN_DIFF = LIGHT_PATH_MEASURED / 3


def vec3(test, v, what):
    test.assertIsInstance(v, list, what)
    test.assertEqual(len(v), 3, what)
    for x in v:
        test.assertTrue(finite(x), f"{what}: {v}")


class StreamTest(DaemonTest):
    # ---- helpers ----

    def check_state(self, st, where, welcome):
        for k in ("scene", "light", "camera", "params"):
            self.assertIn(k, st, f"{where}: state lacks '{k}'")
        self.assertIsInstance(st["scene"], str)
        light, cam, params = st["light"], st["camera"], st["params"]
        for k in ("position", "direction", "intensity"):
            vec3(self, light.get(k), f"{where}: state.light.{k}")
        self.assertAlmostEqual(math.hypot(*light["direction"]), 1.0, places=3, msg=f"{where}: light direction unit")
        self.assertTrue(0 < light["cone_angle"] <= 90, f"{where}: cone_angle {light.get('cone_angle')}")
        for k in ("position", "target", "up"):
            vec3(self, cam.get(k), f"{where}: state.camera.{k}")
        self.assertTrue(1 <= cam["fov"] <= 170, f"{where}: fov {cam.get('fov')}")
        self.assertEqual(set(params), param_keys(welcome, params["method"]), f"{where}: params keys")
        self.assertIsInstance(params["refine"], bool)
        self.assertIsInstance(params["domain"], bool)

    def check_stats(self, s, welcome, frames=()):
        for k in STATS_NUMBERS:
            self.assertTrue(finite(s.get(k)), f"stats.{k} = {s.get(k)!r} is not a finite number: {s}")
            self.assertGreaterEqual(s[k], 0, f"stats.{k}")
        self.assertIsInstance(s.get("method"), str)
        self.assertIsInstance(s.get("converged"), bool)
        if "seq" not in s:  # the doc does not say; allowed only for a frame that answers no input yet
            f = [m for m in frames if m.id == s["frame"]]
            self.assertTrue(f and f[0].seq == NO_SEQ, f"stats without seq for a frame that has one: {s}")
        phases, counters = declared(welcome, s["method"])
        self.assertEqual(list(s.get("phases", {})), phases, f"stats.phases: {s['method']}'s, in order")
        self.assertEqual(set(s.get("counters", {})), set(counters), f"stats.counters: {s['method']}'s")
        for k, kind in counters.items():
            v = s["counters"][k]
            self.assertTrue(finite(v) and v >= 0 and (kind != "share" or v <= 1), f"counters.{k} = {v!r}")
            self.assertTrue(kind != "events" or isinstance(v, int), f"counters.{k} = {v!r} is a count")
        self.assertEqual(set(s.get("vpl", {})), VPL_KEYS, "stats.vpl keys")
        self.assertIsInstance(s.get("rays"), dict)
        self.assertGreater(len(s["rays"]), 0, "stats.rays is empty")
        for group in ("phases", "vpl", "rays"):
            for k, v in s[group].items():
                self.assertTrue(finite(v) and v >= 0, f"stats.{group}.{k} = {v!r}")
        self.assertGreater(s["bytes"], 0)
        self.assertGreater(s["memory_bytes"], 0)

    async def small(self, c, **extra):
        """Shrinks the session's frames (ASan is slow); returns the state reply."""
        seq, st = await c.request({"type": "params", "width": 256, "height": 192, **extra}, "state")
        await c.wait_frame(min_seq=seq)
        return st

    # ---- tests ----

    async def test_welcome(self):
        c = await Client.connect(self.daemon)
        try:
            w = c.welcome
            self.assertEqual(w.get("protocol"), 1)
            self.assertIsInstance(w.get("server"), str)
            self.assertTrue(w["server"].startswith("iird"), w["server"])
            self.assertIsInstance(w.get("session"), int)
            self.assertEqual(w.get("seq"), c.seq, "welcome echoes the hello's seq")
            for name in ("builtin", "cornell_box", "conference", "living_room"):
                self.assertIn(name, w.get("scenes", []), "welcome.scenes")
            names = [m.get("name") for m in w.get("methods", [])]
            for m in ("iir", "ir", "pt"):
                self.assertIn(m, names, "welcome.methods")
            for m in w["methods"]:
                self.assertIsInstance(m.get("summary"), str, f"method {m} has a summary")
            lim = w.get("limits", {})
            for k in ("max_width", "max_height"):
                self.assertIsInstance(lim.get(k), int, f"limits.{k}")
                self.assertGreater(lim[k], 16)
            self.assertEqual(lim.get("max_message_bytes"), 65536)
            self.assertEqual(lim.get("max_rate"), 250)
            self.check_state(w.get("state", {}), "welcome", w)
            self.assertEqual(w["state"]["params"]["method"], "iir", "default method")

            # A second hello: a fresh welcome, same session, state kept.
            p = w["state"]["light"]["position"]
            moved = [p[0] + 0.1, p[1] - 0.1, p[2]]
            await c.move_light(position=moved)
            w2 = await c.hello()
            self.assertEqual(w2["session"], w["session"], "second hello keeps the session")
            for a, b in zip(w2["state"]["light"]["position"], moved):
                self.assertAlmostEqual(a, b, places=4, msg="second hello keeps the state")

            # Two clients are two sessions.
            c2 = await Client.connect(self.daemon)
            self.assertNotEqual(c2.welcome["session"], w["session"])
            await c2.close()
        finally:
            await c.close()

    async def test_frames_decode(self):
        c = await Client.connect(self.daemon)
        try:
            st = c.welcome["state"]["params"]
            await c.wait_for(lambda m: len(c.frames()) >= 3, what="three frames")
            last_id = 0
            for f in c.frames():
                f.check_header(self)
                self.assertGreater(f.id, last_id, "frame ids increase")
                last_id = f.id
                self.assertEqual((f.width, f.height), (st["width"], st["height"]), "frame size = state size")
                im = f.image()
                self.assertEqual(im.format, "JPEG")
                self.assertEqual(im.size, (f.width, f.height), "JPEG size = header size")
            self.assertGreaterEqual(c.frames()[0].id, 1, "frame ids start at 1")
            self.assertGreater(iirserve.mean_level(c.frames()[-1].image()), 5, "the Cornell box is not black")
        finally:
            await c.close()

    async def test_light_path(self):
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            base = c.welcome["state"]["light"]["position"]
            images, diffs = [], []
            for i in range(10):
                u = i / 9.0
                pos = [base[0] - 0.6 + 1.2 * u, base[1] - 0.2 * u, base[2] - 0.3 + 0.6 * u]
                target = [-0.9 + 1.8 * u, 0.0, 0.5 - u]
                seq, f = await c.move_light(position=pos, target=target)
                self.assertEqual(f.seq, seq, "the frame echoes the move's seq")
                self.assertEqual(f.pass_, 0, "the first frame after input is interactive")
                f.check_header(self)
                stats = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                         and m.get("frame") == f.id, what=f"stats of frame {f.id}")
                self.assertEqual(stats["seq"], seq, "stats echo the frame's seq")
                images.append(f.image())
                if i:
                    diffs.append(mean_abs_diff(images[-2], images[-1]))
            total = mean_abs_diff(images[0], images[-1])
            print(f"light path: first-last mean |diff| {total:.2f} levels; steps {['%.1f' % d for d in diffs]}")
            self.assertGreater(total, LIGHT_PATH_MIN_DIFF, "frames change with the light")
            self.assertGreater(min(diffs), 0.05, "every move changes the frame")
        finally:
            await c.close()

    async def test_stats(self):
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            seq, f = await c.move_light(cone_angle=50)
            s = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                 and m.get("frame") == f.id, what="stats")
            self.check_stats(s, c.welcome)
            self.assertEqual(s["method"], "iir")
            self.assertEqual(s["seq"], seq)
            self.assertEqual(s["pass"], f.pass_)
            self.assertGreater(s["vpl"]["count"], 0)
            self.assertLessEqual(s["vpl"]["valid"], s["vpl"]["count"])
            self.assertGreaterEqual(s["total_ms"], 0.0)
            self.assertGreater(s["rays"].get("shadow", 0), 0, "direct light casts shadow rays")
            # every stats message of the session is well-formed
            for t in c.texts("stats"):
                self.check_stats(t, c.welcome, c.frames())
        finally:
            await c.close()

    async def test_stats_declared(self):
        """Each method's stats hold the phases and counters it declares (welcome.methods), and
        /metrics sums them by method: rsm's maps and its share `recomputed`, whitted's trace and
        its count `branches_cut`, radiosity's solve and display (not iir's vpls and indirect)."""
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            want = {"rsm": ["maps", "gbuffer", "direct", "indirect"], "whitted": ["trace"],
                    "radiosity": ["solve", "gbuffer", "direct", "display"]}
            for method, phases in want.items():
                self.assertEqual(declared(c.welcome, method)[0], phases, f"{method}'s phases")
                seq, _ = await c.request({"type": "params", "method": method}, "state")
                f = await c.wait_frame(min_seq=seq, timeout=120)
                s = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                     and m.get("frame") == f.id, what=f"{method}'s stats")
                self.check_stats(s, c.welcome)
                self.assertEqual(s["method"], method)
                self.assertGreater(s["phases"][phases[0]], 0, f"{method}: {phases[0]} took no time")
            self.assertIn("recomputed", declared(c.welcome, "rsm")[1])
            self.assertEqual(declared(c.welcome, "whitted")[1], {"branches_cut": "events"})
            samples = await asyncio.to_thread(metrics, self.daemon.port)
            for method, phases in want.items():
                for ph in phases:
                    v = metric(samples, "iird_phase_seconds_total", f'method="{method}",phase="{ph}"')
                    self.assertIsNotNone(v, f"/metrics has no {method} {ph}")
                self.assertGreater(metric(samples, "iird_phase_seconds_total",
                                          f'method="{method}",phase="{phases[0]}"'), 0)
            self.assertIsNone(metric(samples, "iird_phase_seconds_total", 'method="rsm",phase="vpls"'))
            self.assertIsNotNone(metric(samples, "iird_method_events_total",
                                        'method="whitted",counter="branches_cut"'))
        finally:
            await c.close()

    async def test_domain(self):
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            seq, f = await c.move_light(cone_angle=55)
            d = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "domain"
                                 and m.get("frame") == f.id, what=f"domain of frame {f.id}")
            eps = 1e-3
            vpls, sites, edges, cells = d.get("vpls"), d.get("sites"), d.get("edges"), d.get("cells")
            self.assertIsInstance(vpls, list)
            self.assertGreater(len(vpls), 0)
            for v in vpls:
                self.assertEqual(len(v), 3, f"vpl entry {v}")
                on_image = (0 <= v[0] <= f.width and 0 <= v[1] <= f.height) or (v[0] == -1 and v[1] == -1)
                self.assertTrue(on_image, f"vpl pixel {v} outside {f.width}x{f.height} and not [-1,-1]")
                self.assertEqual(v[2] & ~3, 0, f"vpl flags {v}")
            self.assertGreater(len(sites), 2, "iir has sites")
            ids = set()
            for s in sites:
                self.assertEqual(len(s), 4, f"site {s}")
                self.assertLessEqual(s[0] ** 2 + s[1] ** 2, 1 + eps, f"site {s} outside the unit disk")
                self.assertNotIn(s[2], ids, "site ids unique")
                ids.add(s[2])
            self.assertGreater(len(edges), 0)
            for e in edges:
                self.assertEqual(len(e), 2)
                self.assertTrue(0 <= e[0] < len(sites) and 0 <= e[1] < len(sites), f"edge {e} out of range")
                self.assertNotEqual(e[0], e[1])
            self.assertEqual(len(cells), len(sites), "one cell per site")
            for cell in cells:
                for p in cell:
                    self.assertLessEqual(p[0] ** 2 + p[1] ** 2, 1 + eps, f"cell point {p} outside the disk")
            # Removed sites may have left the cone (disk coordinates are in units of R = sin(cone)), but a
            # direction's projection is at most 1, so |s| <= 1 / sin(cone).
            r_max = 1 / math.sin(math.radians(55)) + eps
            for p in d.get("removed", []):
                self.assertLessEqual(math.hypot(p[0], p[1]), r_max, f"removed {p} beyond any direction")
            self.assertGreaterEqual(len(edges), len(sites) - 1, "a triangulation connects its sites")
            # a dot only where the image shows a VPL (issue 26, item 11d): never a null sample (it
            # sits at the light); seen from behind the back wall (a camera outside the box, its
            # target too, so it is not kept in the room), none: the wall's back hides them all
            nulls = [v for v in vpls if v[2] & 2]
            self.assertTrue(nulls and all(v[:2] == [-1, -1] for v in nulls), f"null samples on the image: {nulls[:4]}")
            self.assertTrue(any(v[0] >= 0 for v in vpls), "and the VPLs on the walls are")
            seq = c.next_seq()
            at = c.mark()
            await c.send({"type": "camera", "seq": seq, "position": [0, 1, -4], "target": [0, 1, -2]})
            f = await c.wait_frame(since=at, min_seq=seq)
            d = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "domain"
                                 and m.get("frame", 0) >= f.id, since=at, what=f"domain of frame {f.id}")
            seen = [v for v in d["vpls"] if v[0] >= 0]
            self.assertEqual(seen, [], "seen from behind the back wall, no VPL is on the image")
            await c.send({"type": "camera", "seq": c.next_seq(), "position": [0, 1, 3.9], "target": [0, 1, 0]})

            # domain: false stops them.
            seq, _ = await c.request({"type": "params", "domain": False}, "state")
            await c.wait_frame(min_seq=seq)
            at = c.mark()
            seq, f = await c.move_light(cone_angle=50)
            await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats" and m.get("frame") == f.id,
                             since=at, what="stats")
            later = [m for m in c.texts("domain", at) if m.get("frame", 0) >= f.id]
            self.assertEqual(later, [], "no domain messages with domain=false")
        finally:
            await c.close()

    async def test_pick(self):
        c = await Client.connect(self.daemon)
        try:
            p = c.welcome["state"]["params"]
            w, h = p["width"], p["height"]
            seq, r = await c.request({"type": "pick", "x": w / 2, "y": h / 2}, "pick")
            self.assertIs(r.get("hit"), True, f"the image centre of the Cornell box hits: {r}")
            vec3(self, r.get("position"), "pick.position")
            vec3(self, r.get("normal"), "pick.normal")
            self.assertAlmostEqual(math.hypot(*r["normal"]), 1.0, places=3, msg="pick normal is unit")
            self.assertTrue(finite(r.get("distance")) and r["distance"] > 0, f"pick distance {r.get('distance')}")
            cam = c.welcome["state"]["camera"]["position"]
            d = math.dist(cam, r["position"])
            self.assertAlmostEqual(d, r["distance"], delta=1e-3 * max(1, d), msg="distance = |hit - eye|")
            # A corner pixel also hits (the box fills the view); the last pixel is inside [0, w).
            seq, r = await c.request({"type": "pick", "x": w - 0.5, "y": h - 0.5}, "pick")
            self.assertIn(r.get("hit"), (True, False))
            for x, y, field in ((w, 0, "pick.x"), (0, h, "pick.y"), (-1, 5, "pick.x"), (5, -0.5, "pick.y")):
                seq, e = await c.request({"type": "pick", "x": x, "y": y}, "error")
                self.assertEqual(e.get("code"), "out_of_range", f"pick ({x}, {y}): {e}")
                self.assertEqual(e.get("field"), field, f"pick ({x}, {y}): {e}")
            await self.still_streaming(c, "bad picks")
        finally:
            await c.close()

    async def test_params_method_and_size(self):
        c = await Client.connect(self.daemon)
        try:
            seq, st = await c.request({"type": "params", "method": "ir", "width": 320, "height": 240}, "state")
            self.check_state(st, "state after params", c.welcome)
            self.assertEqual(st["params"]["method"], "ir")
            self.assertEqual((st["params"]["width"], st["params"]["height"]), (320, 240))
            f = await c.wait_frame(min_seq=seq)
            self.assertEqual((f.width, f.height), (320, 240), "frames of the new size")
            self.assertEqual(f.image().size, (320, 240))
            s = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats" and m.get("frame") == f.id,
                                 what="stats")
            self.assertEqual(s["method"], "ir")
            # Any subset: the rest stays.
            seq, st = await c.request({"type": "params", "quality": 30, "exposure": 1.5}, "state")
            self.assertEqual(st["params"]["method"], "ir")
            self.assertEqual(st["params"]["width"], 320)
            self.assertEqual(st["params"]["quality"], 30)
            self.assertAlmostEqual(st["params"]["exposure"], 1.5)
            f = await c.wait_frame(min_seq=seq)
            self.assertEqual(f.width, 320)
            # only the encoding changed: the frame is re-encoded, flagged, and its stats say no render
            # happened and the VPL set is the one shown before (issue 16). Refinement off: a quality
            # change that stops a refinement pass renders the frame afresh (the pass left the image
            # half done).
            seq, _ = await c.request({"type": "params", "refine": False}, "state")
            await c.wait_frame(min_seq=seq)
            seq, _ = await c.request({"type": "params", "quality": 40}, "state")
            f = await c.wait_frame(min_seq=seq)
            self.assertTrue(f.flags & 4, f"a quality/exposure change re-encodes: flags {f.flags:#x}")
            s = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats" and m.get("frame") == f.id,
                                 what="the re-encoded frame's stats")
            self.assertEqual(s["total_ms"], 0, s)
            self.assertEqual((s["vpl"]["inserted"], s["vpl"]["deleted"]), (0, 0), s)
            self.assertEqual(s["vpl"]["valid"], s["vpl"]["count"], s)
            seq, f = await c.move_light(cone_angle=41)
            self.assertFalse(f.flags & 4, "a light move renders")
        finally:
            await c.close()

    async def test_scene_change(self):
        c = await Client.connect(self.daemon)
        try:
            seq, _ = await c.request({"type": "params", "width": 96, "height": 64}, "state")
            await c.wait_frame(min_seq=seq)
            box_light = c.welcome["state"]["light"]["position"]
            seq, st = await c.request({"type": "scene", "name": "conference"}, "state", timeout=90)
            self.check_state(st, "state after scene", c.welcome)
            self.assertEqual(st["scene"], "conference")
            self.assertEqual((st["params"]["width"], st["params"]["height"]), (96, 64), "params survive a scene")
            self.assertNotEqual(st["light"]["position"], box_light, "the scene's own light")
            f = await c.wait_frame(min_seq=seq, timeout=90)
            self.assertEqual(f.image().size, (96, 64))
            for name in ("../etc", "nope/../../x", "a\\b"):
                seq, e = await c.request({"type": "scene", "name": name}, "error")
                self.assertEqual(e.get("code"), "bad_field", f"scene {name!r}: {e}")
                self.assertEqual(e.get("field"), "scene.name")
            # 'nope' is a plain name not in welcome.scenes: the doc does not say which code (out_of_range:
            # "a string not among the allowed ones"; bad_field: "a bad scene name"; scene_error); any error.
            seq, e = await c.request({"type": "scene", "name": "nope"}, "error")
            self.assertIn(e.get("code"), ("bad_field", "out_of_range", "scene_error"), f"scene 'nope': {e}")
            seq, st = await c.request({"type": "params", "quality": 50}, "state")
            self.assertEqual(st["scene"], "conference", "a refused scene leaves the current one")
            await self.still_streaming(c, "bad scene names")
            seq, st = await c.request({"type": "scene", "name": "builtin"}, "state", timeout=60)
            self.assertEqual(st["scene"], "builtin")
            for a, b in zip(st["light"]["position"], box_light):
                self.assertAlmostEqual(a, b, places=4, msg="back to the box's light")
        finally:
            await c.close()

    async def test_snapshot(self):
        c = await Client.connect(self.daemon)
        try:
            st = await self.small(c)
            w, h = st["params"]["width"], st["params"]["height"]
            for fmt in ("png", "exr"):
                at = c.mark()
                seq, s = await c.request({"type": "snapshot", "format": fmt}, "snapshot")
                self.assertEqual(s.get("format"), fmt)
                self.assertEqual((s.get("width"), s.get("height")), (w, h))
                for k in ("frame", "pass", "bytes"):
                    self.assertTrue(finite(s.get(k)), f"snapshot.{k}")
                i = c.log.index(s, at)
                b = await c.wait_frame(since=i + 1, kind=2)
                b.check_header(self, kind=2)
                self.assertEqual(b.payload_len, s["bytes"], "snapshot bytes = binary payload length")
                # The binary follows its text message: no other kind-2 message in between.
                if fmt == "png":
                    im = Image.open(io.BytesIO(b.payload))
                    self.assertEqual(im.format, "PNG")
                    self.assertEqual(im.size, (w, h))
                    self.assertGreater(iirserve.mean_level(im), 5)
                else:
                    self.assertEqual(b.payload[:4], b"\x76\x2f\x31\x01", "EXR magic 0x762f3101")
                    self.assertGreater(len(b.payload), w * h * 3 * 2 // 4, "an EXR of that size")
            seq, e = await c.request({"type": "snapshot", "format": "tiff"}, "error")
            self.assertEqual(e.get("code"), "out_of_range")
            self.assertEqual(e.get("field"), "snapshot.format")
            await self.still_streaming(c, "snapshots")
        finally:
            await c.close()

    async def test_record(self):
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            seq, e = await c.request({"type": "record", "action": "stop"}, "error")
            self.assertEqual((e.get("code"), e.get("field")), ("bad_field", "record.action"), "stop without start")
            seq, r = await c.request({"type": "record", "action": "start", "fps": 24}, "record")
            self.assertIs(r.get("recording"), True)
            base = c.welcome["state"]["light"]["position"]
            for i in range(6):
                await c.move_light(position=[base[0] - 0.3 + 0.1 * i, base[1], base[2]])
                await asyncio.sleep(0.05)
            seq, r = await c.request({"type": "record", "action": "stop"}, "record")
            self.assertGreaterEqual(r.get("keyframes", 0), 6, f"every applied light state is a keyframe: {r}")
            self.assertTrue(finite(r.get("duration")) and r["duration"] > 0.2, f"duration {r.get('duration')}")
            script = r.get("script")
            self.assertIsInstance(script, dict)
            self.assertEqual(script.get("fps"), 24)
            self.assertAlmostEqual(script.get("duration", -1), r["duration"], places=3)
            tracks = script.get("lights")
            self.assertIsInstance(tracks, list, "every light is a track of \"lights\"")
            self.assertEqual([t.get("name") for t in tracks], [L["name"] for L in c.welcome["state"]["lights"]])
            keys = tracks[0].get("keys")  # the moved light's (the box's only light)
            self.assertIsInstance(keys, list)
            self.assertEqual(len(keys), r["keyframes"])
            ts = [k.get("t") for k in keys]
            self.assertTrue(all(finite(t) for t in ts), ts)
            self.assertTrue(all(b > a for a, b in zip(ts, ts[1:])), f"key times strictly increase: {ts}")
            self.assertTrue(0 <= ts[0] and ts[-1] <= script["duration"] + 1e-6, ts)
            self.assertAlmostEqual(keys[-1]["position"][0], base[0] + 0.2, places=4, msg="last key = last move")
            self.accept_script(script)
        finally:
            await c.close()

    def accept_script(self, script):
        """Runs the recorded script through `iird render --anim` when it exists, else `iird bench --anim`
        (both read docs/animation-format.md)."""
        with tempfile.TemporaryDirectory(dir=os.environ.get("IIR_TEST_TMP")) as tmp:
            path = os.path.join(tmp, "rec.json")
            with open(path, "w") as f:
                json.dump(script, f)
            helptext = subprocess.run([iirserve.IIRD, "render", "--help"], capture_output=True, text=True).stdout
            if "--anim" in helptext:
                cmd = [iirserve.IIRD, "render", "--anim", path, "--out", tmp, "--size", "32x24", "--method", "iir",
                       "--frames", "0:2", "--vpls", "32", "--sm-res", "16", "--refine-passes", "1"]
            else:
                cmd = [iirserve.IIRD, "bench", "--anim", path, "--methods", "iir", "--frames", "3", "--ref-spp", "0",
                       "--size", "32x24"]
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
            self.assertEqual(r.returncode, 0, f"{' '.join(cmd)} refused the recorded script: {r.stderr}{r.stdout}")

    async def test_latest_wins(self):
        c = await Client.connect(self.daemon)
        try:
            await self.small(c)
            base = c.welcome["state"]["light"]["position"]
            at = c.mark()
            first = c.seq + 1
            for i in range(100):
                u = i / 99.0
                await c.send({"type": "light", "seq": c.next_seq(),
                              "position": [base[0] - 0.5 + u, base[1], base[2]]})
            last = c.seq
            f = await c.wait_frame(since=at, min_seq=last)
            self.assertEqual(f.seq, last, "the last frame answers the last seq")
            await asyncio.sleep(0.5)
            answering = [m for m in c.frames(at) if m.seq != NO_SEQ and first <= m.seq <= last and m.pass_ == 0]
            print(f"latest-wins: 100 moves -> {len(answering)} interactive frames")
            self.assertLess(len(answering), 30, "a burst renders only the newest input")
            seqs = [m.seq for m in c.frames(at) if m.seq != NO_SEQ]
            self.assertEqual(seqs, sorted(seqs), "frame seqs never go backwards")
            self.assertEqual(max(seqs), last)
            self.assertEqual(c.texts("error", at), [], "no errors for 100 valid moves")
        finally:
            await c.close()

    async def test_refinement(self):
        c = await Client.connect(self.daemon)
        try:
            seq, st = await c.request({"type": "params", "width": 64, "height": 48, "refine": True,
                                       "refine_passes": 3}, "state")
            seq, f = await c.move_light(cone_angle=45)
            at = c.log.index(f)
            conv = await c.wait_for(lambda m: isinstance(m, Frame) and m.kind == 1 and m.flags & 1,
                                    since=at, what="a converged frame")
            refined = [m for m in c.frames(at) if m.pass_ > 0]
            self.assertGreater(len(refined), 0, "refinement frames after input stops")
            for m in refined:
                self.assertTrue(m.flags & 2, f"refinement frame {m} has flag bit 1")
                self.assertEqual(m.seq, seq, "refinement frames show the same input")
            # a refined frame's stats keep the VPL set of the frame it refines (issue 16: not "0/256")
            frame_stats = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                           and m.get("frame") == f.id, what="the frame's stats")
            last = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                    and m.get("frame") == conv.id, what="the converged frame's stats")
            v, v0 = last["vpl"], frame_stats["vpl"]
            self.assertEqual((v["count"], v["valid"], v["null"]), (v0["count"], v0["count"], v0["null"]),
                             f"refined {v} vs frame {v0}")
            self.assertEqual((v["inserted"], v["deleted"], v["invalidated"]), (0, 0, 0), v)
            self.assertLessEqual(conv.pass_, 3, "converged within refine_passes")
            n = len(c.frames())
            await asyncio.sleep(1.0)
            self.assertEqual(len(c.frames()), n, "after converging the session idles (no frames)")
            # refine off: no pass > 0 frames
            seq, _ = await c.request({"type": "params", "refine": False}, "state")
            seq, f = await c.move_light(cone_angle=40)
            at = c.log.index(f)
            await asyncio.sleep(1.0)
            self.assertEqual([m for m in c.frames(at) if m.pass_ > 0], [], "no refinement with refine=false")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

"""test_serve_record.py -- recordings: a recorded script names the scene it was made on, and a scene
switch while recording hands the recording so far to the client (a `record` reply without seq, its
script naming the old scene) and goes on recording on the new scene, its first key the light the switch
reset to (issue 15, finding 8); a recording replays what the browser showed (issue 16): a session that
moves the light and the camera and changes the exposure is recorded, the script rendered with `iird
render --anim` at the session's size, and its first and last frames match the session's PNG snapshots
at the start and the stop; also on a scene without lights, whose made-up spot the script moves offline
too, and on a scene with two lights, one moved, one switched off (issue 11: a script records every
light, a "lights" track each). The script names the session's frame size and the daemon's scenes folder
(issue 26, item 10): `iird render --anim` of it, given neither --size nor --scenes and run from another
folder, renders the session's frames at the session's size; --size and --scenes still override.
Usage: test_serve_record.py IIRD SOURCE_DIR"""

import asyncio
import json
import os
import shutil
import subprocess
import tempfile

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, stop_class_daemon

# pt at a fixed sample count, no refinement: the session's frame and an offline frame of the same
# light, camera and settings are the same estimate (pt's samples depend on the seed and the pixel
# only). The two differ only where a recorded angle comes back an ulp off (cone and directions go
# through degrees and renormalisation). Measured (ASan build, 256x192, 4 spp): mean |difference| 0.0
# levels of 255 and at most 0 levels in any channel at both ends, i.e. identical PNGs;
# the bounds leave room for a pixel or two that an ulp may flip.
PT = {"method": "pt", "spp": 4, "bounces": 2, "seed": 1, "jitter": True, "refine": False}
PT_ARGS = ["--method", "pt", "--spp", "4", "--bounces", "2", "--seed", "1", "--jitter=true"]
MEAN_TOL = 0.05  # mean |difference| over RGB, 8-bit levels
FAR_TOL = 0.002  # share of channel values more than 8 levels apart


class RecordSceneTest(DaemonTest):
    async def test_scene_switch_while_recording(self):
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            await c.request({"type": "record", "action": "start", "fps": 30}, "record")
            base = c.welcome["state"]["light"]["position"]
            await c.move_light(position=[base[0] - 0.2, base[1], base[2]])
            at = c.mark()
            seq, st = await c.request({"type": "scene", "name": "cornell_box"}, "state", timeout=60)
            first = await c.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "record" and "script" in m,
                                     since=at, what="the recording up to the switch")
            self.assertEqual(first["script"].get("scene"), "builtin", first)
            self.assertIs(first.get("recording"), True, "the recording goes on")
            self.assertGreaterEqual(first.get("keyframes", 0), 2, first)
            seq, r = await c.request({"type": "record", "action": "stop"}, "record")
            script = r["script"]
            self.assertEqual(script.get("scene"), "cornell_box", script)
            # the folder the daemon finds cornell_box in (its --scenes), absolute, for render --anim
            self.assertEqual(script.get("scenes"), os.path.realpath(os.path.join(iirserve.SRC, "scenes")), script)
            self.assertNotIn("scenes", first["script"], "the built-in box needs no scenes folder")
            self.assertEqual([t["name"] for t in script["lights"]], ["spot"], script["lights"])
            key0 = script["lights"][0]["keys"][0]
            self.assertEqual(key0.get("t"), 0)
            for a, b in zip(key0["position"], st["lights"][0]["position"]):
                self.assertAlmostEqual(a, b, places=4, msg="the new recording starts at the reset light")
        finally:
            await c.close()



def image_diff(a, b):
    """(mean |a - b| over RGB in 8-bit levels, share of channel values more than 8 levels apart)."""
    a, b = a.convert("RGB"), b.convert("RGB")
    if a.size != b.size:
        raise AssertionError(f"image sizes differ: {a.size} vs {b.size}")
    pa, pb = a.tobytes(), b.tobytes()
    diffs = [abs(x - y) for x, y in zip(pa, pb)]
    return sum(diffs) / len(diffs), sum(d > 8 for d in diffs) / len(diffs)


def box_room(scenes, name, lights=None):
    """A scene folder `name` in scenes: the Cornell box's mesh, with a sidecar giving these lights
    (None: a sidecar with no lights that keeps the ceiling panel a static emitter, as the mesh alone
    once had it; without a sidecar it would become a movable area light)."""
    room = os.path.join(scenes, name)
    os.makedirs(room)
    box = os.path.join(iirserve.SRC, "scenes", "cornell_box")
    for f in ("CornellBox-Original.obj", "CornellBox-Original.mtl"):
        shutil.copy(os.path.join(box, f), room)
    if lights is None:
        with open(os.path.join(room, f"{name}.scene.json"), "w") as f:
            json.dump({"file": "CornellBox-Original.obj", "lights": []}, f)
    else:
        with open(os.path.join(room, f"{name}.scene.json"), "w") as f:
            json.dump({"file": "CornellBox-Original.obj", "materials": {"light": {"emission": 0}},
                       "camera": {"position": [0, 1, 3.9], "target": [0, 1, 0], "up": [0, 1, 0], "fov_y": 39.3},
                       "lights": lights}, f)
    return room


async def settled_snapshot(c, seq, generation):
    """A PNG snapshot of the frame answering input seq at state generation (refinement is off, so
    that frame is final)."""
    await c.wait_for(lambda m: isinstance(m, iirserve.Frame) and m.kind == 1 and m.seq != iirserve.NO_SEQ
                     and m.seq >= seq and m.generation >= generation, what=f"a frame answering seq {seq}")
    at = c.mark()
    sseq, reply = await c.request({"type": "snapshot", "format": "png"}, "snapshot")
    f = await c.wait_frame(since=at, kind=2)
    return f.image()


class RecordReplayTest(DaemonTest):
    async def test_replay_matches_snapshots(self):
        c = await Client.connect(self.daemon)
        await self.replay(c)

    async def test_replay_on_a_scene_without_lights(self):
        """The made-up spot (state.default_light) is the light the script moves offline too."""
        with tempfile.TemporaryDirectory(dir=os.environ.get("IIR_TEST_TMP")) as scenes:
            room = box_room(scenes, "dark_room")
            d = Daemon(*FAST_ARGS, "--scenes", scenes, "dark_room", scenes=False)
            try:
                c = await Client.connect(d)
                self.assertTrue(c.welcome["state"]["default_light"], "dark_room has no light of its own")
                await self.replay(c, scenes)
            finally:
                stop_class_daemon(d)

    async def test_replay_several_lights(self):
        """Two lights: the bulb moves and dims, the spot is switched off and its cone narrowed while
        off; the script has a track for each (the spot's keys say when it is off) and replays to
        the session's frames."""
        with tempfile.TemporaryDirectory(dir=os.environ.get("IIR_TEST_TMP")) as scenes:
            box_room(scenes, "two_room", [
                {"type": "spot", "name": "spot", "position": [0, 1.9, 0], "direction": [0, -1, 0], "cone_angle": 60,
                 "intensity": [4, 3, 1]},
                {"type": "point", "name": "bulb", "position": [0.5, 1.2, 0.3], "intensity": 2}])
            d = Daemon(*FAST_ARGS, "--scenes", scenes, "two_room", scenes=False)
            moves = [
                {"type": "light", "name": "bulb", "position": [-0.4, 1.0, 0.2]},
                {"type": "light", "name": "spot", "on": False},
                {"type": "camera", "position": [1.2, 1.1, 3.6], "target": [0, 1, 0]},
                {"type": "light", "name": "spot", "cone_angle": 40},
                {"type": "light", "name": "bulb", "intensity": 1.5, "position": [-0.3, 1.4, -0.2]},
            ]
            try:
                c = await Client.connect(d)
                script = await self.replay(c, scenes, moves, ["spot", "bulb"])
            finally:
                stop_class_daemon(d)
            spot = script["lights"][0]["keys"]
            said = [k["on"] for k in spot if "on" in k]  # given where it changes
            self.assertEqual(said[-1:], [False], f"the spot ends off: {spot}")
            self.assertIs(spot[0].get("on", True), True, spot[0])

    async def replay(self, c, scenes_dir=None, moves=None, lights=("spot",)):
        """Records c's session moving lights, camera and exposure, renders the script offline and
        compares its first and last frames with the session's snapshots; closes c and returns the
        script. lights: the names the script's light tracks must have."""
        try:
            await c.wait_frame()
            seq, st = await c.request({"type": "params", **PT, "exposure": 0}, "state")
            gen = st["generation"]
            w, h = st["params"]["width"], st["params"]["height"]
            first = await settled_snapshot(c, seq, gen)
            await c.request({"type": "record", "action": "start", "fps": 5}, "record")
            # the light moves and turns, the camera orbits and comes closer, the exposure goes up
            moves = moves or [
                {"type": "light", "position": [0.3, 1.7, 0.2], "direction": [-0.2, -1, -0.1]},
                {"type": "camera", "position": [1.2, 1.1, 3.6], "target": [0, 1, 0]},
                {"type": "light", "position": [-0.4, 1.6, -0.3], "target": [0.2, 0, 0.1], "cone_angle": 50},
                {"type": "params", "exposure": 1.5},
                {"type": "camera", "position": [1.8, 1.3, 2.9], "target": [0, 0.9, 0], "fov": 45},
            ]
            for m in moves:
                if m["type"] == "params":
                    seq, st = await c.request(m, "state")
                    gen = st["generation"]
                else:
                    seq = await self.send(c, m)
                await asyncio.sleep(0.4)
            last = await settled_snapshot(c, seq, gen)
            await asyncio.sleep(0.3)
            seq, r = await c.request({"type": "record", "action": "stop"}, "record")
        finally:
            await c.close()
        script = r["script"]
        for part in ("lights", "camera", "exposure"):
            self.assertIn(part, script, f"the script records the {part}")
        self.assertNotIn("light", script, "every light is a track of lights")
        self.assertEqual([t.get("name") for t in script["lights"]], list(lights), "the tracks name their lights")
        stops = [k["stops"] for k in script["exposure"]["keys"]]
        self.assertEqual(stops, [0, 1.5] if any(m["type"] == "params" for m in moves) else [0])
        self.assertGreaterEqual(len(script["camera"]["keys"]), 2)
        # where and how it was made: the session's frame size, the daemon's scenes folder (absolute)
        self.assertEqual(script.get("size"), [w, h], "the script names the session's frame size")
        if scenes_dir:
            self.assertEqual(script.get("scenes"), os.path.realpath(scenes_dir), "and the daemon's scenes folder")
        else:
            self.assertNotIn("scenes", script, "the built-in box needs no scenes folder")
        with tempfile.TemporaryDirectory(dir=os.environ.get("IIR_TEST_TMP")) as tmp:
            path = os.path.join(tmp, "recorded.json")
            with open(path, "w") as f:
                json.dump(script, f)
            out = os.path.join(tmp, "frames")
            # neither --size nor --scenes, and no ./scenes to fall back on: the script says both
            cmd = [iirserve.IIRD, "render", "--anim", path, "--out", out, *PT_ARGS]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=240, cwd=tmp)
            self.assertEqual(p.returncode, 0, f"{' '.join(cmd)}:\n{p.stdout}\n{p.stderr}")
            if scenes_dir:
                self.override(path, tmp, scenes_dir)
            frames = sorted(n for n in os.listdir(out) if n.endswith(".png"))
            self.assertEqual(len(frames), round(script["duration"] * script["fps"]) + 1, frames)
            from PIL import Image

            for name, want in ((frames[0], first), (frames[-1], last)):
                got = Image.open(os.path.join(out, name))
                self.assertEqual(got.size, want.size, f"{name}: the session's size")
                mean, far = image_diff(got, want)
                print(f"[{name}: mean |diff| {mean:.4f} levels, {100 * far:.3f}% over 8 levels] ", end="")
                self.assertLess(mean, MEAN_TOL, f"{name} differs from the snapshot")
                self.assertLess(far, FAR_TOL, f"{name} differs from the snapshot")
            # the first frame is not the last: the recording did move things
            mean, _ = image_diff(Image.open(os.path.join(out, frames[0])), Image.open(os.path.join(out, frames[-1])))
            self.assertGreater(mean, 5.0, "the first and last frames differ")
            shots = os.environ.get("IIR_RECORD_SHOTS")  # a picture for a note: snapshots | offline frames
            if shots:
                sheet = Image.new("RGB", (2 * w + 8, 2 * h + 8), (40, 40, 40))
                for row, (name, want) in enumerate(((frames[0], first), (frames[-1], last))):
                    sheet.paste(want.convert("RGB"), (0, row * (h + 8)))
                    sheet.paste(Image.open(os.path.join(out, name)).convert("RGB"), (w + 8, row * (h + 8)))
                sheet.save(shots)
        return script

    def override(self, path, tmp, scenes_dir):
        """--size and --scenes win over the script's: a frame at another size, and a scenes folder
        that lacks the scene refuses it (exit 3, naming the folder given)."""
        out = os.path.join(tmp, "small")
        cmd = [iirserve.IIRD, "render", "--anim", path, "--out", out, "--frames", "0:1", "--size", "64x48", *PT_ARGS]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=tmp)
        self.assertEqual(p.returncode, 0, f"{' '.join(cmd)}:\n{p.stdout}\n{p.stderr}")
        from PIL import Image

        with Image.open(os.path.join(out, "frame_00000.png")) as im:
            self.assertEqual(im.size, (64, 48), "--size overrides")
        empty = os.path.join(tmp, "no_scenes")
        os.makedirs(empty)
        cmd = [iirserve.IIRD, "render", "--anim", path, "--out", os.path.join(tmp, "none"), "--scenes", empty, *PT_ARGS]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=tmp)
        self.assertNotEqual(p.returncode, 0, f"--scenes overrides the script's folder:\n{p.stdout}\n{p.stderr}")

    async def send(self, c, m):
        seq = c.next_seq()
        at = c.mark()
        await c.send({**m, "seq": seq})
        f = await c.wait_for(lambda x: (isinstance(x, iirserve.Frame) and x.kind == 1 and x.seq != iirserve.NO_SEQ
                                        and x.seq >= seq)
                             or (isinstance(x, dict) and x.get("type") == "error" and x.get("seq") == seq),
                             since=at, what=f"a frame answering {m['type']} seq {seq}")
        if isinstance(f, dict):
            raise AssertionError(f"{m} got an error: {f}")
        return seq


if __name__ == "__main__":
    iirserve.main()

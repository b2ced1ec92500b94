"""test_serve_scene_state.py -- the state a client sees is the scene it picked (issue 16): a light moved
through the Cornell box's red wall or ceiling stays inside, and the `state` reply says where; a camera
orbited behind its walls stays in the room, in front of the wall, still looking at its target, and the
`state` reply says where (issue 26, item 11c); one looking at the box from anywhere before its opening
is kept as asked; every frame
carries the generation of the state it shows, and answers the newest input (a move sent right after a
scene switch too), so a client can drop frames of the previous method or
scene; a startup scene given as a path outside the scenes directory is in `welcome.scenes` and can be
picked again after switching away; a scene without lights says its spot is made up; the notes name what
the method leaves out (iir: an emissive material's indirect light).
Usage: test_serve_scene_state.py IIRD SOURCE_DIR"""

import json
import os
import shutil

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, stop_class_daemon

RED_WALL_X = -1.02  # the built-in box's red wall (slanted, x -1.01..-1.02); its ceiling is at y = 1.99


class LightBoundsTest(DaemonTest):
    async def move(self, c, **fields):
        """Sends a light move; returns (the state reply or None, the frame answering it)."""
        seq, f = await c.move_light(**fields)
        states = [m for m in c.texts("state") if m.get("seq") == seq]
        return (states[0] if states else None), f

    async def test_a_light_moved_through_the_wall_stays_inside(self):
        c = await Client.connect(self.daemon)
        try:
            st, _ = await self.move(c, position=[0.0, 1.5, 0.0])
            self.assertIsNone(st, f"a free move got a state reply: {st}")
            st, f = await self.move(c, position=[-1.11, 1.5, 0.0])
            self.assertIsNotNone(st, "a move through the red wall got no state reply")
            x = st["light"]["position"][0]
            self.assertTrue(RED_WALL_X < x < RED_WALL_X + 0.05, f"light x {x} after a move to -1.11")
            st, _ = await self.move(c, position=[0.0, 1.5, 0.0], target=[0.0, 0.0, 0.0])
            st, _ = await self.move(c, position=[0.0, 2.6, 0.0], target=[0.0, 0.0, 0.0])
            self.assertIsNotNone(st, "a move above the ceiling got no state reply")
            y = st["light"]["position"][1]
            self.assertTrue(1.9 < y < 1.99, f"light y {y} after a move to 2.6")
            d = st["light"]["direction"]
            self.assertLess(d[1], -0.99, f"the light aimed at the floor's centre points {d}")
        finally:
            await c.close()

    async def test_a_camera_orbited_behind_a_wall_stays_in_the_room(self):
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            cam = c.welcome["state"]["camera"]
            self.assertEqual(cam["target"], [0, 1, 0], cam)
            # before the opening (a small orbit): kept as asked, no state reply
            seq, f = await self.camera(c, position=[0.8, 1.2, 3.8])
            self.assertFalse([m for m in c.texts("state") if m.get("seq") == seq], "a free orbit got a state reply")
            # 90 degrees round, behind the red wall (x -1.02), then behind the back wall (z -1.04)
            for eye, inside in (([-3.9, 1.0, 0.0], lambda p: RED_WALL_X < p[0] < -0.8),
                                ([0.3, 1.1, -3.9], lambda p: -1.04 < p[2] < -0.8)):
                seq, f = await self.camera(c, position=eye)
                st = [m for m in c.texts("state") if m.get("seq") == seq]
                self.assertTrue(st, f"a camera behind a wall ({eye}) got no state reply")
                p, t = st[0]["camera"]["position"], st[0]["camera"]["target"]
                self.assertTrue(inside(p), f"the eye asked at {eye} is at {p}: not just inside the wall")
                # on the line from the target to the eye asked: still looking at the target
                a = [e - x for e, x in zip(eye, t)]
                b = [e - x for e, x in zip(p, t)]
                cos = sum(x * y for x, y in zip(a, b)) / (sum(x * x for x in a) * sum(y * y for y in b)) ** 0.5
                self.assertGreater(cos, 0.9999, f"the eye {p} left the line from the target to {eye}")
        finally:
            await c.close()

    async def camera(self, c, **fields):
        """Sends a camera move; returns (seq, the frame answering it)."""
        seq = c.next_seq()
        at = c.mark()
        await c.send({"type": "camera", "seq": seq, **fields})
        f = await c.wait_frame(since=at, min_seq=seq)
        return seq, f

    async def test_frames_carry_the_generation_of_their_state(self):
        c = await Client.connect(self.daemon)
        try:
            g0 = c.welcome["state"]["generation"]
            f = await c.wait_frame()
            self.assertEqual(f.generation, g0, "the first frame's generation")
            _, st = await c.request({"type": "params", "method": "pt", "spp": 1}, "state")
            self.assertEqual(st["generation"], g0 + 1, "params bumps the generation")
            at = c.mark()
            f = await c.wait_frame(since=at, min_seq=st["seq"])
            self.assertEqual(f.generation, g0 + 1, "the frame answering params")
            seq, f = await c.move_light(position=[0.1, 1.5, 0.0])
            self.assertEqual(f.generation, g0 + 1, "a light move keeps the generation")
            _, st = await c.request({"type": "scene", "name": "cornell_box"}, "state", timeout=60)
            self.assertEqual(st["generation"], g0 + 2, "a scene switch bumps the generation")
            f = await c.wait_frame(since=c.mark(), min_seq=st["seq"])
            self.assertEqual(f.generation, g0 + 2, "the frame of the new scene")
        finally:
            await c.close()

    async def test_a_move_sent_right_after_a_scene_switch_is_answered(self):
        """A light message that arrives while a switch loads moves the old scene's light (the switch
        resets it): the frames after the switch still answer it, the newest input, not the switch
        asked before it (a client waiting for its seq would wait for ever)."""
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            for name in ("cornell_box", "builtin"):
                at = c.mark()
                a, b = c.next_seq(), c.next_seq()
                await c.send({"type": "scene", "seq": a, "name": name})
                await c.send({"type": "light", "seq": b, "position": [0.2, 1.5, 0.1]})
                st = await c.wait_text("state", since=at, seq=a, timeout=60)
                self.assertEqual(st["scene"], name)
                f = await c.wait_frame(since=at, min_seq=b)
                self.assertGreaterEqual(f.generation, st["generation"], "the frame shows the new scene")
        finally:
            await c.close()


class StartupSceneTest(DaemonTest):
    """iird serve PATH with a scene outside the scenes directory (a user's own room)."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = os.path.join(os.environ.get("IIR_TEST_TMP", "/tmp"), f"scene-state-{os.getpid()}")
        shutil.rmtree(cls.tmp, ignore_errors=True)
        room = os.path.join(cls.tmp, "my_room")
        shutil.copytree(os.path.join(iirserve.SRC, "scenes", "cornell_box"), room,
                        ignore=shutil.ignore_patterns("paths"))
        dark = os.path.join(cls.tmp, "dark_room")
        os.makedirs(dark)
        for f in ("CornellBox-Original.obj", "CornellBox-Original.mtl"):
            shutil.copy(os.path.join(room, f), dark)
        # no lights: a "lights" array keeps the ceiling panel a static emitter (without a sidecar its
        # emissive material would become a movable area light, docs/scene-format.md section 3)
        with open(os.path.join(dark, "dark_room.scene.json"), "w") as f:
            json.dump({"file": "CornellBox-Original.obj", "lights": []}, f)
        cls.dark = dark
        cls.daemon = Daemon(*FAST_ARGS, room)

    @classmethod
    def tearDownClass(cls):
        stop_class_daemon(cls.daemon)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    async def test_the_startup_scene_can_be_picked_again(self):
        c = await Client.connect(self.daemon)
        try:
            self.assertEqual(c.welcome["state"]["scene"], "my_room")
            self.assertIn("my_room", c.welcome["scenes"], "the startup scene is not in the picker")
            self.assertIn("builtin", c.welcome["scenes"])
            _, st = await c.request({"type": "scene", "name": "builtin"}, "state", timeout=60)
            self.assertEqual(st["scene"], "builtin")
            _, st = await c.request({"type": "scene", "name": "my_room"}, "state", timeout=60)
            self.assertEqual(st["scene"], "my_room")
            self.assertFalse(st["default_light"], "my_room has the box's spot")
            f = await c.wait_frame(since=c.mark(), min_seq=st["seq"])
            self.assertEqual(f.generation, st["generation"])
        finally:
            await c.close()

    async def test_notes_name_what_the_method_leaves_out(self):
        """iir keeps VPLs for every light but none for emissive materials (the box's ceiling lamp,
        kept emitting here): its note names the material."""
        two = os.path.join(self.tmp, "two_lights")
        shutil.copytree(self.dark, two)
        with open(os.path.join(two, "two_lights.scene.json"), "w") as f:
            json.dump({"file": "CornellBox-Original.obj",
                       "lights": [{"type": "spot", "name": "spot", "position": [0, 1.9, 0], "direction": [0, -1, 0],
                                   "cone_angle": 60, "intensity": [4, 3, 1]},
                                  {"type": "point", "name": "bulb", "position": [0.5, 1.5, 0], "intensity": 1.5}]}, f)
        d = Daemon(*FAST_ARGS, two)
        try:
            c = await Client.connect(d)
            notes = c.welcome["state"]["notes"]
            self.assertEqual([(n["method"], n["kind"], n["name"]) for n in notes], [("iir", "material", "light")],
                             notes)
            self.assertIn("indirect", notes[0]["what"])
            _, st = await c.request({"type": "params", "method": "pt"}, "state")
            self.assertEqual(st["notes"], [], "pt renders every light")
            await c.close()
        finally:
            stop_class_daemon(d)

    async def test_a_scene_without_lights_says_its_spot_is_made_up(self):
        d = Daemon(*FAST_ARGS, self.dark)
        try:
            c = await Client.connect(d)
            self.assertTrue(c.welcome["state"]["default_light"], c.welcome["state"])
            await c.wait_frame()
            await c.close()
        finally:
            stop_class_daemon(d)


if __name__ == "__main__":
    iirserve.main()

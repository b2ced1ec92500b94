"""test_serve_lights.py -- a session holds every light of its scene (issue 11, "Several lights"): on a
Cornell box with a spot 'key', a point light 'bulb', a sun 'sky' and a glTF spot 'rim' (a sidecar in a
temporary scenes directory), `state.lights` lists them all (name, kind, on, pose) and `state.light` is
the one a `light` message without a name moves (the first spot); a `light` naming 'bulb' moves only the
bulb; `on: false`
renders it black (the frame's mean brightness drops) and `on: true` brings it back (the brightness
too), the intensity kept meanwhile; an unknown name is a bad_field error that lists the scene's lights;
a field another kind has (a cone on the bulb, a size on the spot) is refused naming the light; a sun
cannot be moved (its position is its disk over the scene) but turns, by direction or by position and
target; a glTF spot's inner cone is set within its cone, and narrows with it; a scene switch gives the
new scene's lights, all on.
Usage: test_serve_lights.py IIRD SOURCE_DIR"""

import json
import math
import os
import shutil

import iirserve
from iirserve import Client, Daemon, DaemonTest, FAST_ARGS, stop_class_daemon

KEY = {"type": "spot", "name": "key", "position": [0, 1.9, 0], "direction": [0, -1, 0], "cone_angle": 60,
       "intensity": [4, 3, 1]}
BULB = {"type": "point", "name": "bulb", "position": [0.5, 1.2, 0.3], "intensity": 3}
SKY = {"type": "sun", "name": "sky", "direction": [0.3, -1, -0.6], "intensity": 2}
RIM = {"type": "gltf_spot", "name": "rim", "position": [-0.6, 1.6, 0.5], "target": [0, 0, 0], "cone_angle": 30,
       "inner_angle": 10, "intensity": 1}
# iir, 256x192, the bulb on and off (RelWithDebInfo build, 2 cores): mean level 106.0 with every light,
# 55.0 with the bulb off, 106.3 on again (its set starts anew). A drop of a quarter at least is the
# bulb's share, far above frame-to-frame noise (< 1 level); on again the frame must come back within 5%.
DROP = 0.75
BACK = 0.05


def vec_close(a, b, tol=1e-4):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def by_name(state):
    return {L["name"]: L for L in state["lights"]}


class LightsTest(DaemonTest):
    @classmethod
    def setUpClass(cls):
        cls.tmp = os.path.join(os.environ.get("IIR_TEST_TMP", "/tmp"), f"serve-lights-{os.getpid()}")
        shutil.rmtree(cls.tmp, ignore_errors=True)
        box = os.path.join(iirserve.SRC, "scenes", "cornell_box")
        room = os.path.join(cls.tmp, "three_lights")
        os.makedirs(room)
        for f in ("CornellBox-Original.obj", "CornellBox-Original.mtl"):
            shutil.copy(os.path.join(box, f), room)
        with open(os.path.join(room, "three_lights.scene.json"), "w") as f:
            json.dump({"file": "CornellBox-Original.obj", "materials": {"light": {"emission": 0}},
                       "camera": {"position": [0, 1, 3.9], "target": [0, 1, 0], "up": [0, 1, 0], "fov_y": 39.3},
                       "lights": [KEY, BULB, SKY, RIM]}, f)
        shutil.copytree(box, os.path.join(cls.tmp, "cornell_box"), ignore=shutil.ignore_patterns("paths"))
        cls.daemon = Daemon(*FAST_ARGS, "--scenes", cls.tmp, room, scenes=False)

    @classmethod
    def tearDownClass(cls):
        stop_class_daemon(cls.daemon)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    async def state(self, c):
        """The session's state now (a second hello answers with welcome, the state kept)."""
        return (await c.hello())["state"]

    async def error(self, c, **fields):
        _, e = await c.request({"type": "light", **fields}, "error")
        self.assertEqual(e["type"], "error", f"light {fields} was accepted: {e}")
        return e

    async def test_state_lists_every_light(self):
        c = await Client.connect(self.daemon)
        try:
            st = c.welcome["state"]
            self.assertEqual([(L["name"], L["kind"], L["on"]) for L in st["lights"]],
                             [("key", "spot", True), ("bulb", "point", True), ("sky", "sun", True),
                              ("rim", "gltf_spot", True)], st["lights"])
            self.assertEqual(st["light"]["name"], "key", "a message without a name moves the first spot")
            L = by_name(st)
            self.assertEqual(L["key"]["cone_angle"], 60)
            self.assertTrue(vec_close(L["bulb"]["position"], BULB["position"]), L["bulb"])
            self.assertNotIn("cone_angle", L["bulb"], "a point light has no cone")
            self.assertNotIn("inner_angle", L["key"], "a cosine spot has no inner cone")
            self.assertEqual((L["rim"]["cone_angle"], L["rim"]["inner_angle"]), (30, 10), L["rim"])
            d = L["sky"]["direction"]
            n = math.sqrt(sum(x * x for x in SKY["direction"]))
            self.assertTrue(vec_close(d, [x / n for x in SKY["direction"]], 1e-5), d)
            self.assertFalse(st["default_light"])
            await c.wait_frame()
        finally:
            await c.close()

    async def test_a_named_light_moves_alone(self):
        c = await Client.connect(self.daemon)
        try:
            before = by_name(c.welcome["state"])
            await c.move_light(name="bulb", position=[-0.3, 1.0, 0.1])
            after = by_name(await self.state(c))
            self.assertTrue(vec_close(after["bulb"]["position"], [-0.3, 1.0, 0.1]), after["bulb"])
            for other in ("key", "sky", "rim"):
                self.assertEqual(after[other], before[other], f"moving the bulb changed {other}")
            await c.move_light(position=[0.1, 1.8, 0.0])  # no name: the key light, as before
            after = by_name(await self.state(c))
            self.assertTrue(vec_close(after["key"]["position"], [0.1, 1.8, 0.0]), after["key"])
            self.assertTrue(vec_close(after["bulb"]["position"], [-0.3, 1.0, 0.1]), after["bulb"])
        finally:
            await c.close()

    async def test_off_darkens_and_on_restores(self):
        c = await Client.connect(self.daemon)
        try:
            _, lit = await c.move_light(name="key", position=[0.0, 1.9, 0.0])
            _, dark = await c.move_light(name="bulb", on=False)
            st = by_name(await self.state(c))
            self.assertIs(st["bulb"]["on"], False)
            self.assertEqual(st["bulb"]["intensity"], [3, 3, 3], "an off light keeps its intensity")
            _, back = await c.move_light(name="bulb", on=True)
            a, b, r = (iirserve.mean_level(f.image()) for f in (lit, dark, back))
            print(f"mean level: all on {a:.2f}, bulb off {b:.2f}, back on {r:.2f}", end=" ")
            self.assertLess(b, DROP * a, "switching the bulb off did not darken the frame")
            self.assertLess(abs(r - a), BACK * a, "switching it on again did not restore the frame")
            self.assertIs(by_name(await self.state(c))["bulb"]["on"], True)
            # an intensity change while off is kept for when it is on again, and stays off
            await c.move_light(name="bulb", on=False)
            await c.move_light(name="bulb", intensity=2)
            st = by_name(await self.state(c))["bulb"]
            self.assertEqual((st["on"], st["intensity"]), (False, [2, 2, 2]), st)
            await c.move_light(name="bulb", on=True, intensity=3)
        finally:
            await c.close()

    async def test_unknown_name_lists_the_lights(self):
        c = await Client.connect(self.daemon)
        try:
            e = await self.error(c, name="lamp", position=[0, 1, 0])
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.name"), e)
            for name in ("'lamp'", "'key' (spot)", "'bulb' (point)", "'sky' (sun)", "'rim' (gltf_spot)"):
                self.assertIn(name, e["message"])
            e = await self.error(c, name="bulb")
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light"), "a name alone changes nothing")
            e = await self.error(c, name=7, on=True)
            self.assertEqual((e["code"], e["field"]), ("bad_type", "light.name"), e)
            e = await self.error(c, name="bulb", on="yes")
            self.assertEqual((e["code"], e["field"]), ("bad_type", "light.on"), e)
            await self.still_streaming(c, "refused light names")
        finally:
            await c.close()

    async def test_fields_of_another_kind_are_refused(self):
        c = await Client.connect(self.daemon)
        try:
            e = await self.error(c, name="bulb", cone_angle=30)
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.cone_angle"), e)
            self.assertIn("bulb", e["message"])
            e = await self.error(c, name="key", size=[1, 1])
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.size"), e)
            e = await self.error(c, name="key", inner_angle=10)
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.inner_angle"), e)
            e = await self.error(c, name="key", size=[1, 0])
            self.assertEqual((e["code"], e["field"]), ("out_of_range", "light.size[1]"), e)
        finally:
            await c.close()

    async def test_a_gltf_spot_has_an_inner_cone(self):
        c = await Client.connect(self.daemon)
        try:
            await c.move_light(name="rim", inner_angle=20)
            self.assertEqual(by_name(await self.state(c))["rim"]["inner_angle"], 20)
            e = await self.error(c, name="rim", inner_angle=40)
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.inner_angle"), e)
            e = await self.error(c, name="rim", cone_angle=20, inner_angle=25)
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.inner_angle"), e)
            await c.move_light(name="rim", cone_angle=15)
            rim = by_name(await self.state(c))["rim"]
            self.assertEqual((rim["cone_angle"], rim["inner_angle"]), (15, 15), "a narrower cone narrows the inner one")
            await c.move_light(name="rim", cone_angle=30, inner_angle=10)
        finally:
            await c.close()

    async def test_a_sun_turns_but_does_not_move(self):
        c = await Client.connect(self.daemon)
        try:
            sky = by_name(c.welcome["state"])["sky"]
            e = await self.error(c, name="sky", position=[0, 5, 0])
            self.assertEqual((e["code"], e["field"]), ("bad_field", "light.position"), e)
            self.assertIn("sun", e["message"])
            await c.move_light(name="sky", direction=[0, -1, 0])
            now = by_name(await self.state(c))["sky"]
            self.assertTrue(vec_close(now["direction"], [0, -1, 0]), now)
            self.assertEqual(now["position"], sky["position"], "a turned sun keeps its disk over the scene")
            # position and target: the way from one to the other; the position stays the disk's
            seq, f = await c.move_light(name="sky", position=[0, 3, 0], target=[1, 2, 0])
            replies = [m for m in c.texts("state") if m.get("seq") == seq]
            self.assertTrue(replies, "the position asked for was not used: a state reply says so")
            now = by_name(replies[0])["sky"]
            s = math.sqrt(0.5)
            self.assertTrue(vec_close(now["direction"], [s, -s, 0], 1e-5), now)
            self.assertEqual(now["position"], sky["position"])
        finally:
            await c.close()

    async def test_a_scene_switch_gives_its_lights(self):
        c = await Client.connect(self.daemon)
        try:
            await c.move_light(name="bulb", on=False)
            _, st = await c.request({"type": "scene", "name": "cornell_box"}, "state", timeout=60)
            self.assertEqual([(L["name"], L["on"]) for L in st["lights"]], [("spot", True)], st["lights"])
            e = await self.error(c, name="bulb", on=True)
            self.assertIn("'spot' (spot)", e["message"])
            _, st = await c.request({"type": "scene", "name": "three_lights"}, "state", timeout=60)
            self.assertEqual([L["on"] for L in st["lights"]], [True] * 4, "switched back: all on again")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

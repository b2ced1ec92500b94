"""test_serve_record.py -- recordings and scene switches (issue 15, finding 8): a recorded script names
the scene it was made on, and a scene switch while recording hands the recording so far to the client
(a `record` reply without seq, its script naming the old scene) and goes on recording on the new
scene, its first key the light the switch reset to. Usage: test_serve_record.py IIRD SOURCE_DIR"""

import iirserve
from iirserve import Client, DaemonTest


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
            key0 = script["light"]["keys"][0]
            self.assertEqual(key0.get("t"), 0)
            for a, b in zip(key0["position"], st["light"]["position"]):
                self.assertAlmostEqual(a, b, places=4, msg="the new recording starts at the reset light")
        finally:
            await c.close()


if __name__ == "__main__":
    iirserve.main()

"""test_serve_saves2.py -- saves that stay loadable and bounded (issue 25, finding 6). Ten scenes each saved
from the one before all load (a save names the first scene down the chain that iird did not write, so no
chain grows), and a save from a scene at the end of a chain of hand-written sidecars the loader could not
follow one link further is refused; a client address gets --save-rate saves a minute and the scenes
directory at most --max-saved-scenes saved scenes (those already there count), each refusal a clear error
that writes nothing; `welcome` lists the newest saved scenes only, with the count left out, and a `scenes`
request lists them all. And finding 5 through the daemon: --cache-max caps the form-factor cache and
/metrics counts it. Usage: test_serve_saves2.py IIRD SOURCE_DIR"""

import json
import os
import shutil
import tempfile
import time
import unittest

import iirserve
from iirserve import Client, Daemon


def write_sidecar(scenes, name, sidecar, age_s=0):
    """scenes/name/name.scene.json holding sidecar, its time age_s seconds ago."""
    os.makedirs(os.path.join(scenes, name))
    path = os.path.join(scenes, name, f"{name}.scene.json")
    with open(path, "w") as f:
        json.dump(sidecar, f)
    t = time.time() - age_s
    os.utime(path, (t, t))


async def reply_to(c, msg):
    """The reply echoing msg's seq: `state` for a scene switch, `save`, `scenes`, or an error."""
    seq = c.next_seq()
    at = c.mark()
    await c.send({**msg, "seq": seq})
    return await c.wait_for(lambda m: isinstance(m, dict) and m.get("seq") == seq
                            and m.get("type") in ("state", "save", "scenes", "error"),
                            60, at, what=f"the reply to {msg}")


class SavesTest(unittest.IsolatedAsyncioTestCase):
    """A daemon per test over a scenes directory of its own, holding a copy of the shipped Cornell box."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="iird-saves2-", dir=os.environ.get("IIR_TEST_TMP"))
        self.scenes = os.path.join(self.tmp.name, "scenes")
        os.makedirs(self.scenes)
        shutil.copytree(os.path.join(iirserve.SRC, "scenes", "cornell_box"), os.path.join(self.scenes, "cornell_box"))
        self.daemon = None

    def start(self, *args):
        self.daemon = Daemon(*iirserve.FAST_ARGS, "--scenes", self.scenes, "--allow-save", *args, scenes=False)

    def tearDown(self):
        try:
            if self.daemon:
                iirserve.stop_class_daemon(self.daemon)
        finally:
            self.tmp.cleanup()

    def folders(self):
        return sorted(n for n in os.listdir(self.scenes))

    async def test_chain_of_saves_loads(self):
        """chain1 saved from cornell_box, chainN from chain(N-1): every one loads, and names cornell_box."""
        self.start("--save-rate", "1000")
        c = await Client.connect(self.daemon)
        try:
            await c.request({"type": "scene", "name": "cornell_box"}, "state", timeout=60)
            for i in range(1, 11):
                seq, r = await c.request({"type": "save", "name": f"chain{i}"}, "save")
                self.assertEqual(r["sidecar"]["base"], "cornell_box", r["sidecar"])
                reply = await reply_to(c, {"type": "scene", "name": f"chain{i}"})
                self.assertNotEqual(reply["type"], "error", f"chain{i} does not load: {reply}")
            with open(os.path.join(self.scenes, "chain10", "chain10.scene.json")) as f:
                self.assertEqual(json.load(f)["base"], "cornell_box")
            print(f"[10 chained saves load; chain10's base: cornell_box] ", end="")
        finally:
            await c.close()

    async def test_save_refused_past_the_loader_limit(self):
        """hand0..hand7, hand-written (not only base, camera and lights), each based on the one before:
        hand7 loads (8 links), a scene saved from it would need 9 and is refused; nothing is written."""
        for i in range(8):
            write_sidecar(self.scenes, f"hand{i}", {"base": f"hand{i - 1}" if i else "cornell_box", "unit_scale": 1})
        self.start("--save-rate", "1000")
        c = await Client.connect(self.daemon)
        try:
            await c.request({"type": "scene", "name": "hand7"}, "state", timeout=60)
            before = self.folders()
            e = await reply_to(c, {"type": "save", "name": "over"})
            self.assertEqual((e["type"], e.get("code"), e.get("field")), ("error", "unsupported", "save.name"), e)
            self.assertIn("could not be loaded", e["message"])
            self.assertEqual(self.folders(), before, "a refused save writes nothing")
            # a scene saved from hand6 is 8 links and is written (based on hand6: hand-written)
            await c.request({"type": "scene", "name": "hand6"}, "state", timeout=60)
            seq, r = await c.request({"type": "save", "name": "fits"}, "save")
            self.assertEqual(r["sidecar"]["base"], "hand6")
            reply = await reply_to(c, {"type": "scene", "name": "fits"})
            self.assertNotEqual(reply["type"], "error", reply)
        finally:
            await c.close()

    async def test_rate_per_address(self):
        """--save-rate 3: two clients of one address save 3 scenes between them, the 4th is refused."""
        self.start("--save-rate", "3")
        a, b = await Client.connect(self.daemon), await Client.connect(self.daemon)
        try:
            got = []
            for i, c in enumerate((a, b, a, b, a)):
                got.append(await reply_to(c, {"type": "save", "name": f"r{i}"}))
            kinds = [r["type"] for r in got]
            print(f"[saves accepted of 5 at once: {kinds.count('save')}] ", end="")
            self.assertEqual(kinds, ["save", "save", "save", "error", "error"], got)
            self.assertEqual((got[3]["code"], got[3]["field"]), ("rate_limited", "save.name"), got[3])
            self.assertIn("--save-rate", got[3]["message"])
            self.assertEqual(self.folders(), ["cornell_box", "r0", "r1", "r2"])
        finally:
            await a.close()
            await b.close()

    async def test_total_cap(self):
        """--max-saved-scenes 4 with two saved scenes already there: two more, then refused."""
        write_sidecar(self.scenes, "old1", {"base": "builtin", "camera": {"position": [0, 1, 3]}}, 100)
        write_sidecar(self.scenes, "old2", {"base": "cornell_box"}, 50)
        self.start("--max-saved-scenes", "4", "--save-rate", "1000")
        c = await Client.connect(self.daemon)
        try:
            kinds = [(await reply_to(c, {"type": "save", "name": f"n{i}"})) for i in range(4)]
            self.assertEqual([r["type"] for r in kinds], ["save", "save", "error", "error"], kinds)
            self.assertEqual((kinds[2]["code"], kinds[2]["field"]), ("unsupported", "save.name"), kinds[2])
            self.assertIn("--max-saved-scenes", kinds[2]["message"])
            self.assertEqual(self.folders(), ["cornell_box", "n0", "n1", "old1", "old2"])
        finally:
            await c.close()

    async def test_welcome_lists_newest_saved(self):
        """60 saved scenes: welcome lists builtin, cornell_box and the 20 newest with scenes_more 40; the
        `scenes` request lists all 62; a save's reply lists the new one."""
        for i in range(60):
            write_sidecar(self.scenes, f"s{i:02d}", {"base": "builtin"}, 1000 - i)  # s59 newest
        self.start("--save-rate", "1000")
        c = await Client.connect(self.daemon)
        try:
            w = c.welcome
            size = len(json.dumps(w["scenes"]))
            print(f"[welcome lists {len(w['scenes'])} names ({size} bytes), scenes_more "
                  f"{w.get('scenes_more')}] ", end="")
            self.assertEqual(w["scenes"], ["builtin", "cornell_box"] + [f"s{i:02d}" for i in range(40, 60)])
            self.assertEqual(w.get("scenes_more"), 40)
            seq, r = await c.request({"type": "scenes"}, "scenes")
            self.assertEqual(sorted(r["scenes"]), sorted(["builtin", "cornell_box"] + [f"s{i:02d}" for i in range(60)]))
            seq, r = await c.request({"type": "save", "name": "zz_new"}, "save")
            self.assertIn("zz_new", r["scenes"])
            self.assertNotIn("s40", r["scenes"], "the oldest listed one makes room")
            self.assertEqual(r.get("scenes_more"), 41)
            # a scene welcome leaves out still loads by name
            reply = await reply_to(c, {"type": "scene", "name": "s00"})
            self.assertNotEqual(reply["type"], "error", reply)
        finally:
            await c.close()


class CacheMetricsTest(unittest.IsolatedAsyncioTestCase):
    """Finding 5 through the daemon: --cache-max reaches the radiosity cache's saves, and /metrics counts
    the folder. Two 600 KB cache files, then a radiosity session whose form factors are new (13 KB): the
    cap of 1M keeps the new file and the newer old one, and evicts the oldest."""

    async def test_cache_cap_and_metrics(self):
        with tempfile.TemporaryDirectory(prefix="iird-ffcache-", dir=os.environ.get("IIR_TEST_TMP")) as tmp:
            cache = os.path.join(tmp, "cache")
            os.makedirs(cache)
            for i, age in ((1, 300), (2, 200)):
                path = os.path.join(cache, f"{i:016x}.ff")
                with open(path, "wb") as f:
                    f.write(b"\0" * 600_000)
                os.utime(path, (time.time() - age, time.time() - age))
            d = Daemon(*iirserve.FAST_ARGS, "--cache-max", "1M", env_extra={"IIR_CACHE_DIR": cache})
            try:
                m = iirserve.metrics(d.port)
                before = [iirserve.metric(m, f"iird_ffcache_{k}") for k in ("files", "bytes", "max_bytes")]
                self.assertEqual(before, [2, 1_200_000, 1 << 20], "the folder before any save")
                c = await Client.connect(d)
                try:
                    seq, _ = await c.request({"type": "params", "method": "radiosity",
                                              "patch_area": 0.05, "hemicube_res": 8}, "state",
                                             timeout=60)
                    # a radiosity frame: its form factors are done and saved (closing earlier
                    # would stop their computation, and nothing would be saved)
                    await c.wait_frame(min_seq=seq, timeout=60)
                finally:
                    await c.close()
                m = iirserve.metrics(d.port)
                files, size, evicted = (iirserve.metric(m, f"iird_ffcache_{k}")
                                        for k in ("files", "bytes", "evictions_total"))
                names = sorted(os.listdir(cache))
                print(f"[cache before: 2 files, 1200000 bytes; after: {names}, {size:.0f} bytes, "
                      f"{evicted:.0f} evicted] ", end="")
                self.assertLessEqual(size, 1 << 20)
                self.assertEqual((files, evicted), (2, 1), "the oldest file goes, and only it")
                self.assertNotIn(f"{1:016x}.ff", names)
                self.assertIn(f"{2:016x}.ff", names)
            finally:
                iirserve.stop_class_daemon(d)


if __name__ == "__main__":
    iirserve.main()

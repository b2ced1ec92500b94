"""test_soak.py -- the short variant of tools/soak.py (issue #15) under ctest: the same code, with 8
clients for 10 s and 100 connect/close plus 100 hello-then-vanish cycles, RSS sampled every second, and
the RELAXED thresholds of tools/soak.py (ctest runs it on the ASan build, on a 2-core machine that
other builds share; they are documented there). `make soak` runs the full soak (32 clients, 60 s,
K = 1000) with the strict thresholds on the Release build. Usage: test_soak.py IIRD SOURCE_DIR"""

import os
import sys
import unittest

import iirserve

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
import soak  # noqa: E402


class SoakTest(unittest.IsolatedAsyncioTestCase):
    async def test_short_soak(self):
        r = await soak.soak(iirserve.IIRD, clients=8, seconds=10.0, cycles_k=100, warmup=3.0, rss_every=1.0,
                            lanes=4, profile="relaxed", log=lambda s: print(s, flush=True))
        text = soak.report(r)
        print(text, flush=True)
        failed = [c for c in r["criteria"] if not c["ok"]]
        self.assertFalse(failed, "soak criteria failed:\n" + "\n".join(
            f"{c['name']}: {c['figure']}" for c in failed) + "\niird stderr tail:\n" + r["stderr_tail"][-2000:])


if __name__ == "__main__":
    iirserve.main()

"""test_serve_http.py -- the plain HTTP side of `iird serve` (docs/protocol.md, HTTP): /healthz, /metrics
as Prometheus text with the documented metrics and counters that move with traffic, the client files,
404s and no path traversal. Usage: test_serve_http.py IIRD SOURCE_DIR"""

import asyncio
import json
import os
import re

import iirserve
from iirserve import Client, DaemonTest, http_get, metric, metrics, parse_metrics

DOCUMENTED = {
    "iird_sessions": "gauge",
    "iird_sessions_total": "counter",
    "iird_frames_sent_total": "counter",
    "iird_frames_dropped_total": "counter",
    "iird_frame_seconds": "histogram",
    "iird_bytes_sent_total": "counter",
    "iird_messages_total": "counter",
    "iird_errors_total": "counter",
    "iird_session_memory_bytes": "gauge",
    "iird_scenes_loaded": "gauge",
    "iird_uptime_seconds": "gauge",
}
ALWAYS = ("iird_sessions", "iird_sessions_total", "iird_frames_sent_total", "iird_frames_dropped_total",
          "iird_frame_seconds_count", "iird_frame_seconds_sum", "iird_bytes_sent_total", "iird_messages_total",
          "iird_scenes_loaded", "iird_uptime_seconds")


def get(port, path):
    return asyncio.to_thread(http_get, port, path)


class HttpTest(DaemonTest):
    async def test_healthz(self):
        status, ctype, body = await get(self.daemon.port, "/healthz")
        self.assertEqual(status, 200)
        self.assertTrue(ctype.startswith("application/json"), ctype)
        h = json.loads(body)
        self.assertEqual(h.get("status"), "ok")
        self.assertIsInstance(h.get("sessions"), int)
        self.assertTrue(iirserve.finite(h.get("uptime_s")) and h["uptime_s"] >= 0, str(h))
        c = await Client.connect(self.daemon)
        try:
            await c.wait_frame()
            h2 = json.loads((await get(self.daemon.port, "/healthz"))[2])
            self.assertGreaterEqual(h2["sessions"], 1, "an open session is counted")
            self.assertGreaterEqual(h2["uptime_s"], h["uptime_s"])
        finally:
            await c.close()

    async def test_metrics_format(self):
        c = await Client.connect(self.daemon)
        try:
            seq, _ = await c.request({"type": "params", "width": 64, "height": 48}, "state")
            await c.wait_frame(min_seq=seq)
            seq, e = await c.request({"type": "light", "cone_angle": 120}, "error")
            status, ctype, body = await get(self.daemon.port, "/metrics")
            self.assertEqual(status, 200)
            self.assertRegex(ctype, r"^text/plain; *version=0\.0\.4", "Prometheus text content type")
            text = body.decode()
            samples = parse_metrics(text)
            for name in ALWAYS:
                self.assertIsNotNone(metric(samples, name), f"/metrics lacks {name}")
            for name, kind in DOCUMENTED.items():
                self.assertRegex(text, rf"(?m)^# TYPE {name} {kind}$", f"# TYPE line of {name}")
            sid = c.welcome["session"]
            mem = metric(samples, "iird_session_memory_bytes", f'session="{sid}"')
            self.assertIsNotNone(mem, f"iird_session_memory_bytes{{session=\"{sid}\"}} for the open session")
            self.assertGreater(mem, 64 * 48 * 3, "a session's memory holds at least its frame")
            self.assertGreaterEqual(metric(samples, "iird_errors_total", 'code="out_of_range"') or 0, 1,
                                    "iird_errors_total{code=\"out_of_range\"} counts the error")
            self.assertGreaterEqual(metric(samples, "iird_scenes_loaded"), 1)
            self.assertGreaterEqual(metric(samples, "iird_sessions"), 1)
            # The histogram: cumulative buckets from 5 ms to 2.5 s and +Inf = count.
            buckets = [(re.search(r'le="([^"]+)"', lab).group(1), v) for n, lab, v in samples
                       if n == "iird_frame_seconds_bucket"]
            self.assertGreater(len(buckets), 3, "iird_frame_seconds has buckets")
            les = [float(le) for le, _ in buckets]
            self.assertEqual(les, sorted(les), "buckets in increasing le")
            self.assertAlmostEqual(les[0], 0.005, msg="first bucket 5 ms")
            self.assertIn(2.5, les, "a 2.5 s bucket")
            self.assertEqual(les[-1], float("inf"))
            counts = [v for _, v in buckets]
            self.assertEqual(counts, sorted(counts), "buckets are cumulative")
            self.assertEqual(counts[-1], metric(samples, "iird_frame_seconds_count"))
            self.assertGreater(counts[-1], 0)
        finally:
            await c.close()

    async def test_counters_increase(self):
        port = self.daemon.port
        m0 = await asyncio.to_thread(metrics, port)
        c = await Client.connect(self.daemon)
        try:
            for i in range(3):
                await c.move_light(cone_angle=50 + i)
            await c.request({"type": "pick", "x": 1e9, "y": 0}, "error")
        finally:
            await c.close()
        await asyncio.sleep(0.3)
        m1 = await asyncio.to_thread(metrics, port)
        for name, at_least in (("iird_frames_sent_total", 3), ("iird_messages_total", 5),
                               ("iird_sessions_total", 1), ("iird_frame_seconds_count", 3),
                               ("iird_bytes_sent_total", 3 * 1000)):
            self.assertGreaterEqual(metric(m1, name) - metric(m0, name), at_least, f"{name} increases")
        self.assertGreater(metric(m1, "iird_frame_seconds_sum"), metric(m0, "iird_frame_seconds_sum"))
        self.assertGreater(metric(m1, "iird_uptime_seconds"), metric(m0, "iird_uptime_seconds"))
        e0 = metric(m0, "iird_errors_total", 'code="out_of_range"') or 0
        self.assertGreaterEqual(metric(m1, "iird_errors_total", 'code="out_of_range"') - e0, 1)

    async def test_static_and_unknown_paths(self):
        port = self.daemon.port
        if os.path.exists(os.path.join(iirserve.SRC, "web", "index.html")):
            status, ctype, body = await get(port, "/")
            self.assertEqual(status, 200, "/ serves the client")
            self.assertTrue(ctype.startswith("text/html"), ctype)
            status, ctype, body = await get(port, "/index.html")
            self.assertEqual(status, 200)
        status, ctype, body = await get(port, "/js/protocol.js")
        self.assertEqual(status, 200, "/js/ serves the client's scripts")
        self.assertIn(b"export", body)
        status, _, _ = await get(port, "/no/such/file.txt")
        self.assertEqual(status, 404)
        for path in ("/../../../../etc/passwd", "/js/../../../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd"):
            status, _, body = await get(port, path)
            self.assertNotIn(b"root:", body, f"{path} leaks a file outside web/")
        h = json.loads((await get(port, "/healthz"))[2])
        self.assertEqual(h["status"], "ok")


if __name__ == "__main__":
    iirserve.main()

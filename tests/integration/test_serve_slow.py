"""test_serve_slow.py -- `iird serve` and a client that stops reading (docs/protocol.md, Session life 5:
"a slow client gets fewer frames, never a queue"; the server keeps one newest unsent frame, and every
reply). A client with a small receive buffer asks for large, noisy frames, stops reading and keeps
sending input to its session: the daemon sends it nothing more and drops frames instead of queueing
them, its memory does not grow, it does not spin, another client still gets frames promptly, no reply
is dropped (test_serve_hostile2.py: a client that lets too many wait is closed), and once the client
reads again it gets a frame answering its newest input. Usage: test_serve_slow.py IIRD SOURCE_DIR"""

import asyncio
import socket
import time

import websockets

import iirserve
from iirserve import FRAME_TIMEOUT, MAX_MSG, Client, DaemonTest, healthz, metric, metrics

# Large, noisy frames (path tracing at one sample per pixel, three bounces, bright exposure, JPEG
# quality 100): about 1.8 MB each at 1920x1080, so a few fill the kernel's socket buffers (about 2 MB
# of send queue was measured on loopback) within a second. Changing only `quality` re-encodes the
# last image (~0.1 s under ASan) without rendering, so toggling it makes frames quickly.
BIG = {"width": 1920, "height": 1080, "quality": 100, "method": "pt", "spp": 1, "bounces": 3,
       "exposure": 6, "refine": False, "domain": False}
RCVBUF = 4096  # the client's socket receive buffer (Linux doubles it)
FILL_TIMEOUT = 20.0  # seconds to fill the pipe until the server holds frames back
STALL_S = 3.0  # the measured stall
PROMPT_S = FRAME_TIMEOUT / 4  # another client's frame answers each move within this (5 s by default)
# RSS the daemon may gain over the stall beyond one frame's bytes: allocator noise. Measured under ASan
# over the 3 s stall (~150 messages): +0.9 MB, growing ~0.3 MB/s with the messages (ASan's quarantine
# keeps freed blocks; with ASAN_OPTIONS=quarantine_size_mb=0 it levels off near +0.5 MB). A queue of
# frames would add a frame's ~1.8 MB per re-encode, several per second.
RSS_SLACK_KB = 3 * 1024


def rss_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise AssertionError(f"no VmRSS in /proc/{pid}/status")


def cpu_s(pid):
    """User + system CPU seconds of the process so far."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / 100.0  # utime, stime in clock ticks (USER_HZ 100)


class SlowClientTest(DaemonTest):
    async def connect_slow(self):
        """A Client over a socket with a small receive buffer, set before connecting."""
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RCVBUF)
        s.setblocking(False)
        await asyncio.get_running_loop().sock_connect(s, ("127.0.0.1", self.daemon.port))
        ws = await websockets.connect(self.daemon.url, sock=s, max_size=MAX_MSG, open_timeout=15, close_timeout=5)
        c = Client(ws)
        await c.hello()
        return c

    async def sample(self):
        m = await asyncio.to_thread(metrics, self.daemon.port)
        return {"sent": metric(m, "iird_frames_sent_total"), "dropped": metric(m, "iird_frames_dropped_total"),
                "sessions": metric(m, "iird_sessions"), "rss": rss_kb(self.daemon.proc.pid),
                "cpu": cpu_s(self.daemon.proc.pid), "t": time.monotonic()}

    async def send_quality(self, c, i):
        seq = c.next_seq()
        await c.send({"type": "params", "seq": seq, "quality": 100 - i % 2})
        return seq

    async def fill_pipe(self, c, params_seqs):
        """Toggles quality (a new frame each) until the server holds frames back: frames dropped grew
        and frames sent stayed put for a second. Returns the /metrics sample then."""
        s0 = await self.sample()
        last = s0
        still_since = None
        i = 0
        while True:
            i += 1
            params_seqs.append(await self.send_quality(c, i))
            await asyncio.sleep(0.05)
            if i % 5:
                continue
            s = await self.sample()
            still_since = (still_since or s["t"]) if s["sent"] == last["sent"] else None
            last = s
            if s["dropped"] > s0["dropped"] and still_since and s["t"] - still_since >= 1.0:
                print(f"filled after {s['t'] - s0['t']:.1f} s: {s['sent'] - s0['sent']:.0f} frames sent, "
                      f"{s['dropped'] - s0['dropped']:.0f} dropped", end="; ")
                return s
            self.assertLess(s["t"] - s0["t"], FILL_TIMEOUT,
                            f"the server never held a frame back for a client that stopped reading: in "
                            f"{FILL_TIMEOUT} s frames sent went {s0['sent']:.0f} -> {s['sent']:.0f}, dropped "
                            f"{s0['dropped']:.0f} -> {s['dropped']:.0f}, RSS {s0['rss']} -> {s['rss']} kB")

    async def test_slow_client_gets_fewer_frames(self):
        slow = await self.connect_slow()
        fast = None
        try:
            seq, _ = await slow.request({"type": "params", **BIG}, "state")
            first = await slow.wait_frame(min_seq=seq)
            # its stats follow; then, with refinement and domain messages off, nothing more comes
            await slow.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats" and m.get("frame") == first.id,
                                since=slow.log.index(first), what="the first large frame's stats")
            frame_kb = first.size // 1024
            self.assertGreater(first.size, 500_000, f"frames this test needs to be large: {first!r} {first.size} B")
            await asyncio.sleep(0.2)

            # ---- the client stops reading; its input keeps going to the same session ----
            slow.ws.transport.pause_reading()
            logged = slow.mark()
            params_seqs = []
            filled = await self.fill_pipe(slow, params_seqs)
            choke_at = len(params_seqs)

            # ---- the measured stall: light moves and re-encodes, ~50 messages per second ----
            i = 0
            newest = None
            t_end = time.monotonic() + STALL_S
            while time.monotonic() < t_end:
                i += 1
                newest = slow.next_seq()
                await slow.send({"type": "light", "seq": newest, "cone_angle": 30 + i % 20})
                params_seqs.append(await self.send_quality(slow, i))
                newest = params_seqs[-1]
                await asyncio.sleep(0.04)
            after = await self.sample()
            stall_s = after["t"] - filled["t"]
            d_rss = after["rss"] - filled["rss"]
            cpu = (after["cpu"] - filled["cpu"]) / stall_s
            print(f"stall {stall_s:.1f} s, {2 * i} messages: frames sent +{after['sent'] - filled['sent']:.0f}, "
                  f"dropped +{after['dropped'] - filled['dropped']:.0f}, RSS {d_rss:+d} kB (frame {frame_kb} kB), "
                  f"CPU {100 * cpu:.0f} %", end="; ")
            self.assertEqual(len(slow.log), logged, "the test's client read nothing while paused")
            self.assertEqual(after["sent"], filled["sent"], "frames were sent to a client that does not read")
            self.assertGreater(after["dropped"], 0, "frames replaced before sending are counted")
            # docs/architecture.md: once a waiting frame has replaced another the worker waits, so a
            # client that stops reading stops the renders (no CPU): nothing more is made or dropped.
            self.assertEqual(after["dropped"], filled["dropped"], "frames were still rendered for a stalled client")
            self.assertEqual(after["sessions"], 1, "the stalled session stays open")
            self.assertFalse(slow.closed, f"the stalled client was disconnected: {slow.close_info()}")
            self.assertLess(d_rss, frame_kb + RSS_SLACK_KB,
                            f"the daemon's RSS grew {d_rss} kB in {stall_s:.1f} s of a stalled client "
                            f"(frames of {frame_kb} kB): a queue?")
            self.assertLess(cpu, 0.5, f"the daemon used {100 * cpu:.0f} % CPU while its only client was stalled")

            # ---- meanwhile another client still gets frames promptly ----
            fast = await Client.connect(self.daemon)
            waits = []
            for k in range(3):
                t0 = time.monotonic()
                seq, f = await fast.move_light(cone_angle=40 + k)
                waits.append(time.monotonic() - t0)
                self.assertEqual(f.seq, seq)
            print(f"other client's frames after {', '.join(f'{w:.2f}' for w in waits)} s", end="; ")
            self.assertLess(max(waits), PROMPT_S, "another client's frames are delayed by the stalled one")
            h = await asyncio.to_thread(healthz, self.daemon.port)
            self.assertEqual(h.get("sessions"), 2, f"both sessions open: {h}")

            # ---- the client reads again: a frame answering its newest input ----
            t0 = time.monotonic()
            slow.ws.transport.resume_reading()
            f = await slow.wait_frame(since=logged, min_seq=newest, timeout=FRAME_TIMEOUT + 10)
            print(f"resumed: newest input answered after {time.monotonic() - t0:.1f} s")
            f.check_header(self)
            self.assertEqual(f.image().size, (BIG["width"], BIG["height"]))
            await slow.wait_text("state", since=logged, seq=newest)
            stats = await slow.wait_for(lambda m: isinstance(m, dict) and m.get("type") == "stats"
                                        and m.get("frame") == f.id, since=logged, what="the newest frame's stats")

            # Replies are never dropped: every params sent after the pipe was full got its state reply,
            # in order (the old queue of 64 dropped the oldest).
            late = set(params_seqs[choke_at:])
            got = [m["seq"] for m in slow.texts("state", logged) if m.get("seq") in late]
            self.assertGreater(len(late), 64, "the stall sends more params than the old reply queue held")
            self.assertEqual(got, sorted(late), f"{len(got)} replies to {len(late)} params while stalled")
            self.assertEqual(got[-1], newest)

            # Every frame made is sent or counted as dropped: frame ids (1, 2, ...) received plus the
            # session's dropped count make the newest id; and frames were dropped while stalled.
            ids = [m.id for m in slow.frames()]
            self.assertEqual(ids, sorted(set(ids)), "frame ids increase")
            self.assertGreaterEqual(stats["dropped"], 1, f"the session's stats count dropped frames: {stats}")
            self.assertEqual(len(ids) + stats["dropped"], f.id,
                             f"{len(ids)} frames received + {stats['dropped']} dropped != newest frame id {f.id}")
        finally:
            if fast:
                await fast.close()
            await slow.close()


if __name__ == "__main__":
    iirserve.main()

#!/usr/bin/env python3
"""bench_stream_link.py — the stream encodings (issue 16, PROTOCOL.md 6.3) measured end to end:
a real $BUILD/bin/deformd, a 1,000,000-vertex grid session (1000 x 1000 over [0,1]^2), a grab
stroke of UPDATES updates sent back to back by an editor on the Unix socket, and one subscriber
on loopback TCP through a rate limiter this bench applies itself (a proxy forwarding the
daemon's bytes at the link rate, token bucket, 1 Gb/s and 100 Mb/s) asking for each encoding
(error bound 1e-5 of the bounding-box diagonal for the quantized ones).

Printed per (link, encoding): versions the subscriber received (the others were folded into
coalesced versions, stats client.<id>.coalesced), bytes per received version, the time from the
stroke's first update to the subscriber holding the final version, and versions/s received.
The versions/s here are bounded by whichever is slower: the link, or the editor's stroke on a
1M-vertex mesh (the brush field, commit and stream encodes on this machine, shared with other
work); bench_stream_enc isolates the encodings. Targets are printed by bench_stream_enc.
Environment: BUILD (default build), PYTHONPATH (client/python:tests/integration, see make bench).
"""
import math
import socket
import struct
import sys
import tempfile
import threading
import time

from conftest import Daemon
from deformd_client import Brush, Client, frame as fr, messages as m
from deformd_client import stream_enc as se

N = 1000
UPDATES = 8
LINKS = [("1 Gb/s", 1e9 / 8), ("100 Mb/s", 1e8 / 8)]
ENCODINGS = ["exact", "quantized", "quantized+zstd"]


def grid_ply(n):
    """Binary PLY of an n x n grid over [0,1]^2 with the bump of tests/bench/bench_grid.h."""
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n"
            % (n * n, 2 * (n - 1) * (n - 1))).encode()
    xs = [i / (n - 1) for i in range(n)]
    v = bytearray()
    for y in xs:
        for x in xs:
            v += struct.pack("<fff", x, y, 0.05 * (x - x * x) * (y - y * y) * 16)
    f = bytearray()
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            f += struct.pack("<BiiiBiii", 3, a, a + 1, a + n + 1, 3, a, a + n + 1, a + n)
    return head + bytes(v) + bytes(f)


class Limiter:
    """A TCP proxy on 127.0.0.1: client -> daemon unlimited, daemon -> client at `rate` bytes/s
    (token bucket, 64 KiB bursts)."""

    def __init__(self, port, rate):
        self.rate = rate
        self.srv = socket.socket()
        self.srv.bind(("127.0.0.1", 0))
        self.srv.listen(1)
        self.port = self.srv.getsockname()[1]
        self.target = port
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self):
        c, _ = self.srv.accept()
        d = socket.create_connection(("127.0.0.1", self.target))
        threading.Thread(target=self._pump, args=(c, d, None), daemon=True).start()
        threading.Thread(target=self._pump, args=(d, c, self.rate), daemon=True).start()

    @staticmethod
    def _pump(src, dst, rate):
        t0, sent = time.monotonic(), 0
        try:
            while True:
                b = src.recv(65536)
                if not b:
                    break
                dst.sendall(b)
                if rate:
                    sent += len(b)
                    ahead = sent / rate - (time.monotonic() - t0)
                    if ahead > 0:
                        time.sleep(ahead)
        except OSError:
            pass
        finally:
            for s in (src, dst):
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass


def run(d, sid, X, link, rate, encoding, err):
    enc = m.STREAM_ENCODINGS[encoding]
    lim = Limiter(d.tcp_port, rate)
    sub = Client.connect_tcp("127.0.0.1", lim.port, timeout=120, encoding=enc or None,
                             error=err if enc & m.STREAM_ENC_QUANTIZED else 0.0)
    sub.subscribe(sid)
    with d.unix_client(timeout=120) as ed:
        v0 = int(ed.stats(sid)["version"])
        t0 = time.monotonic()
        ed.brush_begin(sid, Brush(type="grab", center=X, move=(0.004, 0, 0.002), radius=0.1,
                                  nu=0.4))
        for k in range(2, UPDATES + 1):
            ed.brush_update(sid, move=(0.004 * k, 0, 0.002 * k))
        ed.brush_end(sid)
        last = v0 + UPDATES
        got, nbytes = 0, 0
        while True:   # raw frames: count versions and bytes, no decoding of the rows
            f = sub.recv_frame(120)
            if f is None:
                raise RuntimeError("%s %s: no frame within 120 s" % (link, encoding))
            nbytes += fr.HEADER_SIZE + len(f.payload)
            if f.more:
                continue
            got += 1
            p = f.payload
            if f.type == m.ZFRAME:
                inner = se.unwrap_zframe(f)
                p = inner.payload if inner.type != m.PROGRESS else inner.payload[32:]
            elif f.type == m.PROGRESS:
                p = p[32:]
            if struct.unpack_from("<Q", p, 8)[0] == last:
                break
        dt = time.monotonic() - t0
        st = ed.stats()
        coalesced = sum(v for k, v in st.items() if k.startswith("client.")
                        and k.endswith(".coalesced"))
    sub.close()
    print("  %-9s %-15s %2d of %d versions received (%2d coalesced), %10.0f bytes/version, "
          "final version after %6.2f s, %6.1f versions/s" % (link, encoding, got, UPDATES,
                                                             coalesced, nbytes / got, dt,
                                                             got / dt))


def main():
    tmp = tempfile.TemporaryDirectory(prefix="deformd-bench-")
    d = Daemon(tmp.name, "output_queue_limit = 1g\n", tcp=True)
    try:
        with d.unix_client(timeout=300) as c:
            sid = c.load_mesh(grid_ply(N), fmt=".ply", name="link").session_id
        err = 1e-5 * math.sqrt(2 + 0.05 ** 2)
        centre = (0.4, 0.45, 0.05)
        print("bench_stream_link: %d vertices, grab stroke of %d updates (radius 0.1), one TCP "
              "subscriber through a %s rate limiter, error bound %.3g" %
              (N * N, UPDATES, " / ".join(n for n, _ in LINKS), err))
        for link, rate in LINKS:
            for encoding in ENCODINGS:
                run(d, sid, centre, link, rate, encoding, err)
    finally:
        d.proc.terminate()
        d.proc.wait(30)
        tmp.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())

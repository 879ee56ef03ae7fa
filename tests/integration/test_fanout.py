"""Subscriber fan-out in slices (server/net/conn.h DF_CONN_FANOUT_SLICE_US): when writing every
subscriber's pending versions takes longer than one slice, the loop goes back to reading requests
and continues later. Checked here: the continuation happens under a real burst, and every
subscriber still gets every version, in order, reconstructing the daemon's exact positions."""
from deformd_client import Brush, MeshState, frame as fr, messages as m
from helpers import grid_obj, obj_bytes_positions
from rawwire import read_frames

SUBSCRIBERS = 32
BURST = 60  # pipelined updates, below max_pending_requests (64)


def test_sliced_fanout_delivers_every_version_in_order(daemon):
    data = grid_obj(40, 40)  # 1,600 vertices: 19 KB per dense version, 1.2 MB per subscriber
    X = obj_bytes_positions(data)
    with daemon.unix_client() as admin:
        sid = admin.load_mesh(data, fmt=".obj", name="fanout").session_id
        v0 = admin.get_mesh(sid).version
        resumed0 = admin.stats()["fanout_resumed"]
        subs = [daemon.unix_client() for _ in range(SUBSCRIBERS)]
        try:
            for c in subs:
                c.subscribe(sid)
            # The writer pipelines the whole burst in one write and waits for every ack; the
            # subscribers read nothing until it is over (their versions wait in the daemon).
            w = daemon.raw_unix(hello=True)
            begin = m.encode_brush(sid, Brush(center=X[0:3], move=(0.01, 0, 0), radius=0.3))
            w.sendall(fr.encode_frame(m.BRUSH_BEGIN, begin, request_id=1))
            burst = b"".join(
                fr.encode_frame(m.BRUSH_UPDATE,
                                m.encode_brush_update(sid, move=(0.01 + 0.002 * u, 0, 0.001 * u)),
                                request_id=2 + u) for u in range(BURST))
            w.sendall(burst)
            acks, _ = read_frames(w, timeout=30.0, want=1 + BURST)
            w.close()
            assert [f.request_id for f in acks] == list(range(1, 2 + BURST))
            assert not any(f.flags & fr.FLAG_ERROR for f in acks)
            final = admin.get_mesh(sid)
            assert final.version > v0
            for k, c in enumerate(subs):
                replica = MeshState(X)
                seen = []
                for ev in c.events(timeout=10.0):
                    assert replica.apply(ev), "subscriber %d: version %d not applied" % (
                        k, ev.version)
                    seen.append(ev.version)
                    if ev.version == final.version:
                        break
                assert seen == list(range(v0 + 1, final.version + 1)), "subscriber %d" % k
                assert replica.tobytes() == final.positions.tobytes(), "subscriber %d" % k
            resumed = admin.stats()["fanout_resumed"] - resumed0
        finally:
            for c in subs:
                c.close()
    # 32 x 19 KB per version cannot all be written within one 20 us slice.
    assert resumed >= 1, "the fan-out never yielded the loop"

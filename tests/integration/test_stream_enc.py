"""Negotiated stream encodings (issue 16; PROTOCOL.md 4.2, 4.40, 4.41): a client asks in HELLO
for quantized deltas with an absolute error bound E and / or zstd compression of stream frames.

Checked here, on one session edited by a grab stroke of several updates, a twist and a handle
move with progress iterates, against an exact subscriber on the same session (whose replica a
test elsewhere checks equal to GET_MESH):
  - every version a quantized client applies leaves its replica within E of the exact positions
    (displacements within E plus float32 rounding of the value, computed from the recorded
    frames), for quantized and quantized+zstd;
  - a zstd client's replica is byte-identical to the exact one at every version;
  - a resync (SNAPSHOT, or SUBSCRIBE FROM_VERSION, which answers a quantized client with a
    snapshot) makes the quantized replica exact, byte for byte with GET_MESH, and the stream
    continues within E from there;
  - a client with the original hello gets no trailer back and only DISPLACEMENT / PROGRESS
    frames; bad requests are refused with a message naming the field, nothing changes.
Nothing waits on time: every event awaited is named by its version."""
import struct

import pytest

from deformd_client import Brush, Client, DeformdError, MeshState
from deformd_client import errors as E
from deformd_client import messages as m
from deformd_client import stream as st
from deformd_client import stream_enc as se
from helpers import grid_obj

TIMEOUT = 30.0
ULP32 = 2.0 ** -23


def bbox_diag(xyz):
    lo = [min(xyz[k::3]) for k in range(3)]
    hi = [max(xyz[k::3]) for k in range(3)]
    return sum((h - l) ** 2 for l, h in zip(lo, hi)) ** 0.5


def edits(c, sid, X):
    """A grab stroke of several updates, a twist, a handle move with progress iterates."""
    c.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0.01, 0, 0.02), radius=0.3))
    for k in range(1, 5):
        c.brush_update(sid, move=(0.01 * k, 0.005 * k, 0.02))
    c.brush_end(sid)
    c.stroke(sid, Brush(type="twist", center=X[60:63], twist=(0, 0, 0.3), radius=0.25))
    c.set_handles(sid, [0, 7, 40], max_iters=6)
    c.move_handles(sid, [X[0:3], X[21:24], (X[120], X[121] + 0.04, X[122])], max_iters=6,
                   progress_every=2)


def collect(c, sid, last):
    """Stream events of session `sid` up to version `last`, in arrival order."""
    out = []
    while True:
        ev = c.next_event(TIMEOUT)
        assert ev is not None, "no event up to version %d within %.0f s" % (last, TIMEOUT)
        if isinstance(ev, st.Progress):
            ev = ev.disp
        if isinstance(ev, (st.Disp, se.QDisp)) and ev.session_id == sid:
            out.append(ev)
            if ev.version == last:
                return out


def within(state, exact, err, what):
    """|replica - exact| <= err plus the float32 rounding of the values, per component, for the
    displacements and the positions."""
    for name, a, b in (("disp", state.disp, exact.disp),
                       ("position", state.positions, exact.positions)):
        worst = max(abs(x - y) - err - 2 * ULP32 * max(abs(x), abs(y)) for x, y in zip(a, b))
        assert worst <= 0, "%s: %s off by %g beyond the bound %g" % (what, name, worst, err)


def exact_states(frames, base):
    """{version: MeshState copy} of an exact subscriber applying `frames` from base."""
    s = MeshState(base, 0)
    snaps = {}
    for d in frames:
        assert isinstance(d, st.Disp), "an exact client got %r" % type(d)
        if s.apply(d):
            snaps[s.version] = (list(s.disp), list(s.positions))
    return snaps


class Snap:
    def __init__(self, t):
        self.disp, self.positions = t


@pytest.mark.parametrize("encoding", ["quantized", "quantized+zstd"])
def test_quantized_replica_within_bound_at_every_version(make_daemon, encoding):
    d = make_daemon()
    enc = m.STREAM_ENCODINGS[encoding]
    with d.unix_client() as ed, d.unix_client() as ex:
        sid = ed.load_mesh(grid_obj(16, 16), fmt=".obj", name="enc").session_id
        mesh = ed.get_mesh(sid, base=True)
        X, base = mesh.positions, mesh.base
        err = 1e-3 * bbox_diag(X)
        q = Client.connect_unix(d.socket_path, timeout=TIMEOUT, encoding=enc, error=err)
        with q:
            assert q.server.has_stream and q.server.stream_encoding == enc
            assert q.server.error_bound == err
            assert ex.server.has_stream is False           # the original hello: no trailer
            ex.subscribe(sid)
            q.subscribe(sid, snapshot=True)
            first = collect(q, sid, 0)                     # the snapshot of version 0
            held = MeshState(base, 0)
            assert held.apply(first[-1])
            edits(ed, sid, X)
            last = int(ed.stats(sid)["version"])
            exact = exact_states(collect(ex, sid, last), base)
            evs = collect(q, sid, last)
            assert all(isinstance(e, se.QDisp) for e in evs)
            left_out = 0
            for e in evs:
                assert held.apply(e)
                within(held, Snap(exact[held.version]), err,
                       "%s version %d" % (encoding, held.version))
                left_out += e.count < e.nv
            assert held.version == last
            # the far field of the brush rounds to zero: some versions leave vertices out
            assert left_out > 0
            # a resync is exact: SNAPSHOT, byte for byte with GET_MESH
            assert held.apply(q.snapshot(sid))
            assert held.tobytes() == ed.get_mesh(sid).positions.tobytes()
            # ... and the stream continues within the bound from the exact state
            ed.stroke(sid, Brush(type="grab", center=X[30:33], move=(0, 0.03, 0), radius=0.3))
            v = last + 1
            exact.update(exact_states_from(ex, sid, v, exact[last], base))
            for e in collect(q, sid, v):
                assert held.apply(e)
            within(held, Snap(exact[v]), err, "%s after the resync" % encoding)


def exact_states_from(ex, sid, v, prev, base):
    s = MeshState(base, v - 1, prev[0])
    out = {}
    for e in collect(ex, sid, v):
        if s.apply(e):
            out[s.version] = (list(s.disp), list(s.positions))
    return out


def test_zstd_replica_is_exact_and_from_version_resync_of_quantized_is_a_snapshot(make_daemon):
    d = make_daemon()
    with d.unix_client() as ed, d.unix_client() as ex:
        sid = ed.load_mesh(grid_obj(16, 16), fmt=".obj", name="z").session_id
        mesh = ed.get_mesh(sid, base=True)
        X, base = mesh.positions, mesh.base
        z = Client.connect_unix(d.socket_path, timeout=TIMEOUT, encoding=m.STREAM_ENC_ZSTD)
        with z:
            ex.subscribe(sid)
            z.subscribe(sid)
            edits(ed, sid, X)
            last = int(ed.stats(sid)["version"])
            ex_evs, z_evs = collect(ex, sid, last), collect(z, sid, last)
            a, b = MeshState(base, 0), MeshState(base, 0)
            compressed = 0
            for e, f in zip(ex_evs, z_evs):
                assert isinstance(f, st.Disp) and a.apply(e) and b.apply(f)
                assert a.tobytes() == b.tobytes()
                compressed += f.wire_bytes < e.wire_bytes
            assert len(ex_evs) == len(z_evs) and compressed > 0
        err = 1e-4 * bbox_diag(X)
        q = Client.connect_unix(d.socket_path, timeout=TIMEOUT,
                                encoding=m.STREAM_ENC_QUANTIZED, error=err)
        with q:
            # FROM_VERSION of the current version: a replay would send nothing, but the
            # quantized connection gets a snapshot (the ring keeps exact frames only)
            info = q.subscribe(sid, from_version=last)
            snap = collect(q, sid, info.version)
            assert len(snap) == 1 and snap[0].kind == m.CHANGE_SNAPSHOT
            held = MeshState(base, 0)
            assert held.apply(snap[0])
            assert held.tobytes() == ed.get_mesh(sid).positions.tobytes()
            # STREAM_SHM carries exact frames: refused on this connection
            with pytest.raises(DeformdError) as ei:
                q.stream_shm(sid)
            assert ei.value.code == E.EUNSUPPORTED and "encoding" in str(ei.value)


@pytest.mark.parametrize("enc,bound,field", [
    (0x04, 0.0, "stream_encoding"),                      # unknown bit
    (int(m.STREAM_ENC_QUANTIZED), 0.0, "error_bound"),   # quantized without a bound
    (int(m.STREAM_ENC_QUANTIZED), float("nan"), "error_bound"),
    (int(m.STREAM_ENC_QUANTIZED), -1e-3, "error_bound"),
    (int(m.STREAM_ENC_ZSTD), 1e-3, "error_bound"),       # a bound without quantized
])
def test_bad_encoding_requests_are_refused(make_daemon, enc, bound, field):
    d = make_daemon()
    with d.unix_client(hello=False) as c:
        with pytest.raises(DeformdError) as ei:
            c.hello("bad", enc, bound)
        assert ei.value.code == E.EINVAL and field in str(ei.value)
        # nothing changed: the connection still takes a good hello, with the exact stream
        h = c.hello("good")
        assert h.has_stream is False
        sid = c.load_mesh(grid_obj(4, 4), fmt=".obj", name="ok").session_id
        c.subscribe(sid, snapshot=True)
        ev = c.next_event(TIMEOUT)
        assert isinstance(ev, st.Disp) and ev.kind == m.CHANGE_SNAPSHOT


def test_encoding_is_fixed_by_the_first_hello(make_daemon):
    d = make_daemon()
    with Client.connect_unix(d.socket_path, encoding=m.STREAM_ENC_ZSTD) as c:
        with pytest.raises(DeformdError) as ei:
            c.hello("again", int(m.STREAM_ENC_QUANTIZED), 1e-3)
        assert ei.value.code == E.ESTATE and "reconnect" in str(ei.value)
        assert c.hello("same", int(m.STREAM_ENC_ZSTD), 0.0).stream_encoding == m.STREAM_ENC_ZSTD


def test_raw_hello_trailer_bytes(make_daemon):
    """The hello trailer on the wire (PROTOCOL.md 4.2): u8 encoding, u8 reserved, f64 bound;
    the reply carries the same 10 bytes after the server name, and only then."""
    d = make_daemon()
    with d.unix_client(hello=False) as c:
        body = m.encode_hello(1, 1, 0, "raw") + struct.pack("<BBd", 3, 0, 2.5e-4)
        reply = c._one(m.HELLO, body)
        assert reply[-10:] == struct.pack("<BBd", 3, 0, 2.5e-4)
        assert m.decode_hello_reply(reply).stream_encoding == 3
    with d.unix_client(hello=False) as c:
        reply = c._one(m.HELLO, m.encode_hello(1, 1, 0, "raw"))
        h = m.decode_hello_reply(reply)
        assert not h.has_stream and len(reply) == 46 + 2 + len(h.server_name)


@pytest.mark.parametrize("encoding", ["exact", "quantized", "zstd", "quantized+zstd"])
def test_deformctl_watch_prints_the_bytes_of_each_version(make_daemon, encoding):
    """deformctl watch --encoding prints `bytes N` per version (and "bytes" in --json): the
    bytes a Python client with the same encoding received for that version."""
    import json
    import subprocess
    from conftest import DEFORMCTL
    d = make_daemon()
    enc = m.STREAM_ENCODINGS[encoding]
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(16, 16), fmt=".obj", name="w").session_id
        X = ed.get_mesh(sid).positions
        err = 1e-3 * bbox_diag(X)
        qargs = ["--error", repr(err)] if enc & m.STREAM_ENC_QUANTIZED else []
        py = Client.connect_unix(d.socket_path, timeout=TIMEOUT,
                                 encoding=enc if enc else None,
                                 error=err if enc & m.STREAM_ENC_QUANTIZED else 0.0)
        with py:
            py.subscribe(sid)
            n = 3
            for json_out in (False, True):
                p = subprocess.Popen([DEFORMCTL, "--socket", d.socket_path] +
                                     (["--json"] if json_out else []) +
                                     ["watch", str(sid), "--encoding", encoding, "--count",
                                      str(n)] + qargs,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                head = p.stdout.readline()      # printed once subscribed
                assert "watching" in head, head + p.stderr.read()
                v0 = int(ed.stats(sid)["version"])
                for k in range(n):
                    ed.stroke(sid, Brush(type="grab", center=X[3 * k:3 * k + 3],
                                         move=(0.01, 0, 0.02), radius=0.3))
                out, errs = p.communicate(timeout=TIMEOUT)
                assert p.returncode == 0, errs
                evs = collect(py, sid, v0 + n)
                want = {e.version: e.wire_bytes for e in evs}
                lines = out.splitlines()
                assert len(lines) == n
                for line in lines:
                    if json_out:
                        j = json.loads(line)
                        v, nbytes = j["version"], j["bytes"]
                    else:
                        f = line.split()
                        v, nbytes = int(f[1]), int(f[f.index("bytes") + 1])
                    assert nbytes == want[v] and nbytes > 0, line
        bad = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "watch", str(sid),
                              "--encoding", "quantized"], capture_output=True, text=True,
                             timeout=TIMEOUT)
        assert bad.returncode != 0 and "--error" in bad.stderr
        bad = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "watch", str(sid),
                              "--encoding", "lossy"], capture_output=True, text=True,
                             timeout=TIMEOUT)
        assert bad.returncode != 0 and "--encoding" in bad.stderr


@pytest.mark.parametrize("encoding", ["quantized", "zstd", "exact"])
def test_a_subscriber_that_cannot_keep_up_gets_coalesced_versions(make_daemon, encoding):
    """output_queue_limit 4 MiB: a subscriber whose hello asked for a stream encoding (exact
    included: the trailer with encoding 0) that does not read while
    40 versions are broadcast is not dropped and its queue does not grow past the limit: once
    its queue holds limit / 8 the versions are folded, and when its queue has drained it gets a
    coalesced version (base_version = the version it held); the chain of versions it receives
    brings its replica to the final version, within E (quantized) or exactly (zstd). stats counts the folded versions,
    daemon-wide and for that client, and shows every client's bytes_per_s."""
    d = make_daemon("output_queue_limit = 4m\n")
    enc = m.STREAM_ENCODINGS[encoding]
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(200, 200), fmt=".obj", name="slow").session_id
        X = ed.get_mesh(sid).positions
        err = 1e-6 * bbox_diag(X) if enc & m.STREAM_ENC_QUANTIZED else 0.0
        slow = Client.connect_unix(d.socket_path, timeout=TIMEOUT, encoding=enc, error=err)
        with slow:
            held = MeshState.sync(slow, sid)
            slow.subscribe(sid)
            ed.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.001),
                                      radius=0.5))
            n = 40
            for k in range(2, n + 1):
                ed.brush_update(sid, move=(0.001 * k, 0.0005 * k, 0.001 * k))
            ed.brush_end(sid)
            last = int(ed.stats(sid)["version"])
            assert last == n
            st = ed.stats()
            assert st["stream_coalesced_versions"] > 0, "nothing was coalesced"
            mine = [k for k in st if k.startswith("client.") and k.endswith(".coalesced")
                    and st[k] > 0]
            assert len(mine) == 1, mine
            assert all(st[k] >= 0 for k in st if k.endswith(".bytes_per_s"))
            assert sum(k.endswith(".bytes_per_s") for k in st) >= 2   # editor and slow
            folded = int(st[mine[0]])
            evs = collect(slow, sid, last)
            # a chain from the held version to the last; a coalesced version stands for the
            # versions folded into it (the queue may drain, and fill again, more than once)
            assert [e.base_version for e in evs] == [0] + [e.version for e in evs[:-1]]
            coalesced = [e for e in evs if e.version > e.base_version + 1]
            assert coalesced and evs[-1].version == last
            # a catch-up that folded a single version looks like an ordinary one (version =
            # base_version + 1), so the jumps account for at most the folded count
            jumps = sum(e.version - e.base_version for e in coalesced)
            assert jumps <= folded <= jumps + sum(1 for e in evs if e not in coalesced)
            for e in evs:
                assert held.apply(e)
            final = ed.get_mesh(sid)
            exact = MeshState(ed.get_mesh(sid, base=True).base, last)
            exact.apply(ed.snapshot(sid))
            if err:
                within(held, exact, err, "coalesced %s" % encoding)
            else:
                assert held.tobytes() == final.positions.tobytes()
            assert slow.ping(b"alive") == b"alive"           # not dropped


def test_distinct_error_bounds_per_session_are_limited(make_daemon):
    """Each distinct error bound is a group the daemon keeps per session (DF_QGROUP_MAX 15): a
    16th is refused with ELIMIT naming the limit, and the session streams on for the others."""
    d = make_daemon()
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(6, 6), fmt=".obj", name="groups").session_id
        cs = []
        try:
            for k in range(15):
                c = Client.connect_unix(d.socket_path, encoding=m.STREAM_ENC_QUANTIZED,
                                        error=1e-3 * (k + 1))
                cs.append(c)
                c.subscribe(sid)
            extra = Client.connect_unix(d.socket_path, encoding=m.STREAM_ENC_QUANTIZED,
                                        error=0.5)
            cs.append(extra)
            with pytest.raises(DeformdError) as ei:
                extra.subscribe(sid)
            assert ei.value.code == E.ELIMIT and "15" in str(ei.value)
            same = Client.connect_unix(d.socket_path, encoding=m.STREAM_ENC_QUANTIZED,
                                       error=1e-3)       # an existing group: admitted
            cs.append(same)
            same.subscribe(sid)
            assert int(ed.stats(sid)["subscribers"]) == 16
        finally:
            for c in cs:
                c.close()


def test_a_slow_deformctl_watch_encoding_exact_is_coalesced(make_daemon):
    """`deformctl watch --encoding exact` sends the stream trailer (encoding 0: exact float32), so
    when it cannot keep up (stopped with SIGSTOP while 40 dense versions of a 40,000-vertex grid
    are broadcast, output_queue_limit 4 MiB) the daemon folds versions for it instead of
    dropping it: stats count them for one client, and once it runs again it prints a chain of
    versions up to the last one with at least one jump (a coalesced version)."""
    import json
    import signal
    import subprocess
    from conftest import DEFORMCTL
    d = make_daemon("output_queue_limit = 4m\n")
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(200, 200), fmt=".obj", name="slowwatch").session_id
        X = ed.get_mesh(sid).positions
        p = subprocess.Popen([DEFORMCTL, "--socket", d.socket_path, "--json", "watch", str(sid),
                              "--encoding", "exact"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            head = json.loads(p.stdout.readline())          # printed once subscribed
            assert head["kind"] == "watching" and head["stream_encoding"] == "exact", head
            p.send_signal(signal.SIGSTOP)
            ed.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.001),
                                      radius=0.5))
            for k in range(2, 41):
                ed.brush_update(sid, move=(0.001 * k, 0.0005 * k, 0.001 * k))
            ed.brush_end(sid)
            last = int(ed.stats(sid)["version"])
            st = ed.stats()
            lagged = [k for k in st if k.startswith("client.") and k.endswith(".coalesced")
                      and st[k] > 0]
            assert len(lagged) == 1 and st["stream_coalesced_versions"] > 0, st
            p.send_signal(signal.SIGCONT)
            versions = []
            while not versions or versions[-1] < last:
                line = p.stdout.readline()
                assert line, "watch ended before version %d: %s" % (last, p.stderr.read())
                versions.append(json.loads(line)["version"])
            assert versions == sorted(set(versions)) and versions[-1] == last
            assert len(versions) < last, versions                  # some were folded
            assert p.poll() is None                                 # not dropped
        finally:
            p.send_signal(signal.SIGCONT)
            p.kill()
            p.communicate(timeout=TIMEOUT)


@pytest.mark.parametrize("start", [None, "1m"])
def test_stream_coalesce_start_sets_the_threshold(make_daemon, start):
    """stream_coalesce_start (deformd.conf(5)): with the default (output_queue_limit 256 MiB / 8 =
    32 MiB) a trailer client that does not read while 40 dense versions (~19 MB) are broadcast
    is sent every one of them; with stream_coalesce_start = 1m (resume 256k) the same run folds
    versions for it. Either way its chain of versions ends at the last one."""
    cfg = "" if start is None else "stream_coalesce_start = %s\nstream_coalesce_resume = 256k\n" % start
    d = make_daemon(cfg)
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(200, 200), fmt=".obj", name="thr").session_id
        X = ed.get_mesh(sid).positions
        slow = Client.connect_unix(d.socket_path, timeout=TIMEOUT, encoding=0)
        with slow:
            held = MeshState.sync(slow, sid)
            slow.subscribe(sid)
            ed.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.001),
                                      radius=0.5))
            for k in range(2, 41):
                ed.brush_update(sid, move=(0.001 * k, 0.0005 * k, 0.001 * k))
            ed.brush_end(sid)
            last = int(ed.stats(sid)["version"])
            folded = ed.stats()["stream_coalesced_versions"]
            evs = collect(slow, sid, last)
            for e in evs:
                assert held.apply(e)
            assert held.tobytes() == ed.get_mesh(sid).positions.tobytes()
            if start is None:
                assert folded == 0 and [e.version for e in evs] == list(range(1, last + 1))
            else:
                assert folded > 0 and len(evs) < last


def test_quantized_groups_are_charged_to_memory_max_mb(make_daemon):
    """Each quantized group (24 bytes a vertex: K of 3 int64) is charged to memory_max_mb (stats
    memory.stream_bytes): with 16 MiB and a 40,000-vertex session, subscribers with ever new
    error bounds are admitted until the budget is full, then refused with ELIMIT naming
    memory_max_mb (before the 15-group limit); the charge is returned when they leave."""
    d = make_daemon("memory_max_mb = 16\n")
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(200, 200), fmt=".obj", name="budget").session_id
        nv = len(ed.get_mesh(sid).positions) // 3
        per_group = 24 * nv
        cs = []
        refused = None
        try:
            for k in range(15):
                c = Client.connect_unix(d.socket_path, encoding=m.STREAM_ENC_QUANTIZED,
                                        error=1e-4 * (k + 1))
                cs.append(c)
                try:
                    c.subscribe(sid)
                except DeformdError as e:
                    refused = e
                    break
                assert ed.stats()["memory.stream_bytes"] == per_group * (k + 1)
            assert refused is not None, "15 groups fit in 16 MiB"
            assert refused.code == E.ELIMIT and "memory_max_mb" in str(refused), str(refused)
            admitted = len(cs) - 1
            assert admitted >= 1
            assert ed.stats()["memory.stream_bytes"] == per_group * admitted  # nothing for it
            for c in cs[:admitted]:          # leaving prunes each group (its reply is after)
                c.unsubscribe(sid)
            assert ed.stats()["memory.stream_bytes"] == 0
        finally:
            for c in cs:
                c.close()


@pytest.mark.parametrize("encoding", ["quantized", "quantized+zstd"])
def test_quantized_progress_iterates_carry_iteration_and_residual(make_daemon, encoding):
    """A handle move's PROGRESS iterates reach a quantized client as QDISP versions with the
    progress trailer (PROTOCOL.md 4.40, flags bit 0): status, final, iteration, objective,
    residual and elapsed_ms equal those an exact subscriber got in its PROGRESS events for the
    same versions; other versions have no trailer."""
    d = make_daemon()
    enc = m.STREAM_ENCODINGS[encoding]
    with d.unix_client() as ed:
        sid = ed.load_mesh(grid_obj(12, 12), fmt=".obj", name="prog").session_id
        X = ed.get_mesh(sid).positions
        err = 1e-4 * bbox_diag(X)
        ex = Client.connect_unix(d.socket_path, timeout=TIMEOUT)
        qc = Client.connect_unix(d.socket_path, timeout=TIMEOUT, encoding=enc, error=err)
        with ex, qc:
            ex.subscribe(sid)
            qc.subscribe(sid)
            edits(ed, sid, X)
            last = int(ed.stats(sid)["version"])
            want = {}
            while True:
                ev = ex.next_event(TIMEOUT)
                assert ev is not None
                v = ev.disp.version if isinstance(ev, st.Progress) else getattr(ev, "version", 0)
                if isinstance(ev, st.Progress):
                    want[v] = (int(ev.status), ev.final, ev.iteration, ev.objective, ev.residual,
                               ev.elapsed_ms)
                if v == last:
                    break
            assert want, "the move sent no progress iterate"
            got = {}
            for q in collect(qc, sid, last):
                assert isinstance(q, se.QDisp)
                if q.progress is not None:
                    p = q.progress
                    got[q.version] = (p.status, p.final, p.iteration, p.objective, p.residual,
                                      p.elapsed_ms)
            assert got == want

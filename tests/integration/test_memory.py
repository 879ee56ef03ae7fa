"""Bounded memory (issue 9, items 10-13) on the real daemon, each limit configured small: upload
buffers grow with the bytes that arrived (not the announced total_size) and are capped per upload
(max_upload_mb) and together (uploads_max_mb); sessions are checked against the memory budget
(memory_max_mb) before they are created; shared-memory rings are sized to their session and
capped together (shm_total_bytes); the undo history drops its oldest steps beyond
history_max_mb and stays exact. Every refusal is ELIMIT naming the setting, changes nothing, and
the daemon keeps serving. Stats (and deformctl stats) show the usage against the budget."""
import json
import os
import struct
import subprocess
from array import array

import pytest

from conftest import DEFORMCTL
from deformd_client import Brush, Client, DeformdError, errors as E, frame as fr, messages as m
from helpers import grid_obj

MiB = 1 << 20


def padded_obj(size: int, n: int = 4) -> bytes:
    """A valid n x n grid OBJ padded with comment lines to exactly `size` bytes."""
    body = grid_obj(n, n)
    pad = size - len(body)
    assert pad >= 2
    lines = []
    while pad > 0:
        k = min(pad, 1000)
        lines.append(b"#" + b"x" * (k - 2) + b"\n" if k >= 2 else b"\n")
        pad -= k
    data = b"".join(lines) + body
    assert len(data) == size
    return data


def plane_ply(nv: int) -> bytes:
    """Binary PLY of nv vertices on a line-free plane strip and one triangle (a cheap big mesh)."""
    xyz = array("f", [0.0] * (3 * nv))
    xyz[0::3] = array("f", [i / nv for i in range(nv)])
    xyz[1::3] = array("f", [(i * 7919 % nv) / nv for i in range(nv)])
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n" % nv).encode()
    return head + xyz.tobytes() + struct.pack("<Biii", 3, 0, 1, 2)


def send_chunk(c: Client, rid: int, total: int, offset: int, data: bytes, more: bool) -> None:
    c.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "up", "", total, 0, offset,
                                           data), fr.FLAG_MORE if more else 0, rid)


def barrier(c: Client) -> None:
    """Returns once the daemon has handled everything `c` sent before: during an upload any other
    request is answered EPROTO_CHUNK (the upload stays), in order with the chunks."""
    with pytest.raises(DeformdError) as ei:
        c.ping(b"sync")
    assert ei.value.code == E.EPROTO_CHUNK


def elimit(fn) -> str:
    with pytest.raises(DeformdError) as ei:
        fn()
    assert ei.value.code == E.ELIMIT, ei.value
    return str(ei.value)


def test_upload_buffer_grows_with_the_bytes_that_arrived(make_daemon):
    """Item 10: a 1 GiB total_size with 1 MiB sent holds about 1 MiB, not 1 GiB (the daemon
    used to malloc(total_size) at the first chunk); it doubles at most as more arrives, and
    a failed upload returns its bytes."""
    d = make_daemon()
    with d.unix_client() as up, d.unix_client() as obs:
        assert obs.stats()["memory.uploads_bytes"] == 0
        chunk = b"#" * MiB
        send_chunk(up, 7, 1 << 30, 0, chunk, True)
        barrier(up)
        s = obs.stats()
        assert s["uploads_in_flight"] == 1
        assert MiB <= s["memory.uploads_bytes"] <= 2 * MiB, s["memory.uploads_bytes"]
        assert s["memory_used_bytes"] >= s["memory.uploads_bytes"]
        send_chunk(up, 7, 1 << 30, MiB, chunk, True)
        barrier(up)
        assert 2 * MiB <= obs.stats()["memory.uploads_bytes"] <= 4 * MiB
        # a chunk that does not continue the upload drops it, and its buffer
        send_chunk(up, 7, 1 << 30, 5 * MiB, chunk, True)
        with pytest.raises(DeformdError) as ei:
            up.wait_reply(7, 10.0)
        assert ei.value.code == E.EPROTO_CHUNK
        s = obs.stats()
        assert (s["uploads_in_flight"], s["memory.uploads_bytes"]) == (0, 0)
        assert up.ping(b"ok") == b"ok"


def test_upload_caps_refuse_with_elimit_and_change_nothing(make_daemon):
    """Item 10: max_upload_mb caps one upload (also reported as hello's max_mesh_bytes);
    uploads_max_mb caps the buffers of all uploads in flight together: the chunk that would pass
    it fails with ELIMIT naming the setting, the other upload completes, and a retry succeeds."""
    d = make_daemon("max_upload_mb = 2\nuploads_max_mb = 3\n")
    data = padded_obj(2 * MiB)
    head, tail = data[:3 * MiB // 2], data[3 * MiB // 2:]
    with d.unix_client() as a, d.unix_client() as b:
        assert a.server.max_mesh_bytes == 2 * MiB
        send_chunk(a, 3, 2 * MiB + 1, 0, b"#" * 100, True)
        with pytest.raises(DeformdError) as ei:
            a.wait_reply(3, 10.0)
        assert ei.value.code == E.ELIMIT and "max_upload_mb" in ei.value.message, ei.value
        assert a.ping(b"1") == b"1"
        send_chunk(a, 4, len(data), 0, head, True)
        barrier(a)
        send_chunk(b, 4, len(data), 0, head, True)
        barrier(b)
        send_chunk(a, 4, len(data), len(head), tail, False)     # 3.5 MiB in flight > 3
        with pytest.raises(DeformdError) as ei:
            a.wait_reply(4, 10.0)
        assert ei.value.code == E.ELIMIT and "uploads_max_mb" in ei.value.message, ei.value
        assert a.list_sessions() == []
        s = a.stats()
        assert s["uploads_in_flight"] == 1 and s["memory.uploads_bytes"] == len(head)
        assert s["memory_refused"] == 1
        send_chunk(b, 4, len(data), len(head), tail, False)
        assert b.wait_reply(4, 30.0)[-1].payload                # b's upload completes
        assert a.load_mesh(data, fmt=".obj", name="retry").nv == 16
        assert len(a.list_sessions()) == 2
        assert a.stats()["memory.uploads_bytes"] == 0


def test_memory_budget_refuses_a_session_and_deformctl_shows_usage(make_daemon):
    """Item 13: a mesh whose session would not fit memory_max_mb is refused (ELIMIT naming it)
    before the session exists; smaller ones still load; stats and deformctl stats show usage
    against the budget."""
    d = make_daemon("memory_max_mb = 16\n")
    with d.unix_client() as c:
        s0 = c.stats()
        assert s0["memory_max_bytes"] == 16 * MiB
        msg = elimit(lambda: c.load_mesh(plane_ply(120000), fmt=".ply", name="big"))
        assert "memory_max_mb" in msg and "120000 vertices" in msg, msg
        assert c.list_sessions() == []
        s1 = c.stats()
        assert s1["memory.sessions_bytes"] == 0 and s1["memory_refused"] == 1
        assert s1["sessions"] == 0
        info = c.load_mesh(grid_obj(10, 10), fmt=".obj", name="small")
        s2 = c.stats()
        assert 0 < s2["memory.sessions_bytes"] < s2["memory_used_bytes"] <= 16 * MiB
        ss = c.stats(info.session_id)
        assert ss["memory_bytes"] == s2["memory_used_bytes"]   # the only charge
        assert c.ping(b"alive") == b"alive"
    where = ["--socket", d.socket_path]
    p = subprocess.run([DEFORMCTL] + where + ["--json", "stats"], capture_output=True, text=True,
                       timeout=30, stdin=subprocess.DEVNULL)
    assert p.returncode == 0, p.stderr
    st = json.loads(p.stdout)
    assert st["memory_max_bytes"] == 16 * MiB and 0 < st["memory_used_bytes"] <= 16 * MiB
    p = subprocess.run([DEFORMCTL] + where + ["stats"], capture_output=True, text=True,
                       timeout=30, stdin=subprocess.DEVNULL)
    assert p.returncode == 0, p.stderr
    assert "memory_used_bytes" in p.stdout and "memory_max_bytes" in p.stdout
    assert "memory:" in p.stdout          # the summary line: used of max


def ring_size(nv: int, cap: int = 64 << 20) -> int:
    """deformd's ring for a session of nv vertices (server/net/shm.h df_shm_ring_size)."""
    want = -(-128 * (12 * nv + 128) // (64 << 10)) * (64 << 10)
    return min(max(want, 64 << 10), cap)


def test_shm_rings_are_sized_to_the_session_and_capped_in_total(make_daemon):
    """Item 11: a 100-vertex session gets a 192 KiB ring, not shm_ring_bytes (64 MiB: 32 small
    sessions used to fill 2 GiB of /dev/shm); with shm_total_bytes = 512k a third ring is
    refused (ELIMIT naming it), that subscriber keeps its socket stream, and closing a session
    frees its ring's share."""
    d = make_daemon("shm_total_bytes = 512k\n")
    ring = ring_size(100)
    assert ring == 192 << 10
    with d.unix_client() as c:
        sids = [c.load_mesh(grid_obj(10, 10), fmt=".obj", name="r%d" % i).session_id
                for i in range(3)]
        for sid in sids:
            c.subscribe(sid)
        infos = [c.stream_shm(sid) for sid in sids[:2]]
        assert [i.capacity for i in infos] == [ring, ring]
        assert c.stats()["memory.shm_bytes"] == 2 * (ring + m.SHM_HEADER_BYTES)
        msg = elimit(lambda: c.stream_shm(sids[2]))
        assert "shm_total_bytes" in msg, msg
        assert c.stats(sids[2])["shm_subscribers"] == 0
        c.stroke(sids[2], Brush(center=(0.5, 0.5, 0.0), move=(0, 0, 0.01), radius=5.0))
        ev = c.next_event(5.0)
        assert ev.session_id == sids[2] and ev.version == 1      # still on the socket
        c.close_session(sids[0])
        assert not os.path.exists(infos[0].path)
        assert c.stats()["memory.shm_bytes"] == ring + m.SHM_HEADER_BYTES
        assert c.stream_shm(sids[2]).capacity == ring


def test_history_budget_drops_the_oldest_steps_and_undo_stays_exact(make_daemon):
    """Item 12: with history_max_mb = 1 a 10,000-vertex session (240 KB per position copy) drops
    its oldest undo steps to stay within the budget. Strokes are kept as recipes (a few hundred
    bytes); history_replay_ms = 0 makes every stroke a checkpoint, so each one also holds a
    packed link to the previous state (every vertex moves a little: tens of KB) beside the
    current state and the anchor (2 x 240 KB): 12 strokes do not fit, the oldest are dropped
    (stats), the held ones are recipes with one checkpoint per state, and undo and redo restore
    the published positions exactly over the whole depth."""
    d = make_daemon("history_max_mb = 1\nhistory_replay_ms = 0\n")
    strokes = 12
    with d.unix_client() as c:
        sid = c.load_mesh(grid_obj(100, 100), fmt=".obj", name="hist").session_id
        shots = [c.get_mesh(sid).positions.tobytes()]
        for k in range(1, strokes + 1):
            c.stroke(sid, Brush(center=(0.5, 0.5, 0.0), move=(0.001 * k, -0.002, 0.003 * k),
                                radius=5.0, nu=0.4))
            shots.append(c.get_mesh(sid).positions.tobytes())
        s = c.stats(sid)
        depth = int(s["undo_depth"])
        assert 1 <= depth < strokes, s
        assert s["history_steps_dropped"] == strokes - depth
        assert 2 * 240000 < s["history_bytes"] <= MiB
        assert s["history_undo_bytes"] == s["history_bytes"] - 240000
        assert s["history_recipe_steps"] == depth and s["history_xor_steps"] == 0
        assert s["history_checkpoints"] == depth + 1
        g = c.stats()
        assert g["history.steps_dropped"] == strokes - depth and g["history.limit_bytes"] == MiB
        assert g["memory.history_bytes"] == s["history_bytes"]
        for k in range(strokes - 1, strokes - 1 - depth, -1):
            c.undo(sid)
            assert c.get_mesh(sid).positions.tobytes() == shots[k]
        with pytest.raises(DeformdError) as ei:
            c.undo(sid)
        assert ei.value.code == E.ESTATE
        for k in range(strokes - depth + 1, strokes + 1):
            c.redo(sid)
            assert c.get_mesh(sid).positions.tobytes() == shots[k]
        s = c.stats(sid)
        assert s["redo_depth"] == 0 and s["history_replay_mismatches"] == 0


def test_history_shrinks_to_the_memory_budget_and_gives_way_to_sessions(make_daemon):
    """Items 12-13: when memory_max_mb (16) is tighter than history_max_mb, strokes still
    commit: the history drops its oldest steps to stay within what the budget has left, the
    total stays within memory_max_bytes, and undo/redo stay exact. A new session that only fits
    without that history gets the room (old undo steps of idle sessions give way first); one that
    does not fit even then is refused and nothing changes. Strokes are kept as recipes;
    history_replay_ms = 0 gives each a checkpoint link (tens of KB), so strokes go on until the
    budget bites (within 60 strokes, below the 64-state depth cap), then two more."""
    d = make_daemon("memory_max_mb = 16\nhistory_max_mb = 1024\nhistory_replay_ms = 0\n")
    with d.unix_client() as c:
        sid = c.load_mesh(grid_obj(200, 200), fmt=".obj", name="tight").session_id
        shots = [c.get_mesh(sid).positions.tobytes()]
        extra, strokes = 2, 0
        while extra > 0 and strokes < 60:
            strokes += 1
            k = strokes
            c.stroke(sid, Brush(center=(0.5, 0.5, 0.0), move=(0.001 * k, 0.002, -0.001 * k),
                                radius=5.0, nu=0.4))
            shots.append(c.get_mesh(sid).positions.tobytes())
            if c.stats(sid)["history_steps_dropped"] >= 1:
                extra -= 1
        s, g = c.stats(sid), c.stats()
        assert g["memory_used_bytes"] <= g["memory_max_bytes"] == 16 * MiB
        assert s["history_steps_dropped"] >= 1 and s["undo_depth"] >= 1, s
        assert s["undo_depth"] + s["history_steps_dropped"] == strokes
        assert g["memory_refused"] == 0          # history never refuses: it drops
        c.undo(sid)
        assert c.get_mesh(sid).positions.tobytes() == shots[strokes - 1]
        c.redo(sid)
        assert c.get_mesh(sid).positions.tobytes() == shots[strokes]
        # a second session of the same size fits only without the first one's undo steps
        sid2 = c.load_mesh(grid_obj(200, 200), fmt=".obj", name="second").session_id
        s, g = c.stats(sid), c.stats()
        assert s["undo_depth"] == 0 and s["history_steps_dropped"] == strokes
        assert g["memory_used_bytes"] <= g["memory_max_bytes"]
        assert c.get_mesh(sid).positions.tobytes() == shots[strokes]      # positions kept
        msg = elimit(lambda: c.load_mesh(grid_obj(200, 200), fmt=".obj", name="third"))
        assert "memory_max_mb" in msg, msg
        assert sorted(i.session_id for i in c.list_sessions()) == [sid, sid2]

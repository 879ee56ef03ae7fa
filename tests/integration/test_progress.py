"""Progress of long work (PROTOCOL.md 4.37): WORK_PROGRESS events for a request that asked for
them (load option PROGRESS, handles / handle_move options PROGRESS), in order, all before the
reply, none after it and none for requests that did not ask; deformctl's plain progress lines
when stderr is not a terminal. The big mesh is generated here (a 548 x 548 grid: 300,304
vertices, ~22 MB of OBJ text), and the expected totals are its byte size and the move's budget."""
import os
import re
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import WorkProgress, WorkStage
from helpers import grid_obj

BIG_N = 548  # 548^2 = 300,304 vertices


@pytest.fixture(scope="module")
def big_obj(tmp_path_factory):
    path = tmp_path_factory.mktemp("big") / "big.obj"
    n = BIG_N
    out = ["v %.6f %.6f 0" % (i / (n - 1), j / (n - 1)) for j in range(n) for i in range(n)]
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i + 1
            out.append("f %d %d %d\nf %d %d %d" % (a, a + 1, a + n + 1, a, a + n + 1, a + n))
    path.write_text("\n".join(out) + "\n")
    return path


def check_stream(events, stages):
    """Events of one request: stages in the given order, `done` never decreasing within a stage
    (never above a known total), exactly one final event per stage and it is the stage's last.
    Returns {stage: final event}."""
    seen = [e.stage for e in events]
    order = [s for i, s in enumerate(seen) if i == 0 or seen[i - 1] != s]
    assert order == stages, order        # each stage once, contiguous, in order
    finals = {}
    for st in stages:
        evs = [e for e in events if e.stage == st]
        dones = [e.done for e in evs]
        assert dones == sorted(dones), (st, dones)
        assert all(e.total == 0 or e.done <= e.total for e in evs)
        assert [e.final for e in evs] == [False] * (len(evs) - 1) + [True], (st, evs)
        assert all(e.elapsed_ms >= 0 for e in evs)
        finals[st] = evs[-1]
    return finals


def no_late_events(c, rid):
    """After the reply of request `rid`: a ping's reply comes after anything the daemon queued
    before it, so a WORK_PROGRESS of `rid` sent after the reply would be queued by now."""
    c.ping(b"x")
    late = [e for e in c.events(timeout=0) if isinstance(e, WorkProgress)]
    assert late == [], late


def test_large_load_reports_upload_and_parse_before_the_reply(daemon, big_obj):
    data = big_obj.read_bytes()
    events = []
    with daemon.unix_client(timeout=120) as c:
        rid = c._next_id
        info = c.load_mesh(data, fmt=".obj", file_name="big.obj", progress=events.append)
        assert info.nv == BIG_N * BIG_N
        assert all(e.request_id == rid and e.session_id == 0 for e in events)
        finals = check_stream(events, [WorkStage.UPLOAD, WorkStage.PARSE])
        for st in (WorkStage.UPLOAD, WorkStage.PARSE):
            assert finals[st].done == finals[st].total == len(data)
        # Rate limit: within a stage, two events (the final one aside) are at least 50 ms
        # apart on the daemon's own clock, which each event's elapsed_ms reads (no client
        # clock involved)
        for st in (WorkStage.UPLOAD, WorkStage.PARSE):
            ms = [e.elapsed_ms for e in events if e.stage == st and not e.final]
            assert all(b - a >= 50 - 1e-6 for a, b in zip(ms, ms[1:])), (st, ms)
        no_late_events(c, rid)
        # the same load without a callback asks for nothing and gets nothing
        c.load_mesh(data[:1000].rsplit(b"\n", 1)[0] + b"\nf 1 2 3\n", fmt=".obj")
        assert [e for e in c.events(timeout=0) if isinstance(e, WorkProgress)] == []
        c.close_session(info.session_id)


def test_path_load_reports_parse(make_daemon, big_obj):
    d = make_daemon("allow_paths = %s\n" % big_obj.parent)
    events = []
    with d.unix_client(timeout=120) as c:
        info = c.load_mesh(path=str(big_obj), progress=events.append)
        assert info.nv == BIG_N * BIG_N
        finals = check_stream(events, [WorkStage.PARSE])   # no upload: the daemon reads it
        assert finals[WorkStage.PARSE].done == finals[WorkStage.PARSE].total == \
            os.path.getsize(big_obj)


def test_handles_and_move_report_factorize_and_solve(daemon):
    n = 30
    with daemon.unix_client(timeout=120) as c:
        sid = c.load_mesh(grid_obj(n, n), fmt=".obj").session_id
        handles = [0, n - 1, n * n - 1]
        fac = []
        c.set_handles(sid, handles, tol=0.0, max_iters=150, progress=fac.append)
        f = check_stream(fac, [WorkStage.FACTORIZE])[WorkStage.FACTORIZE]
        assert (f.done, f.total, f.session_id) == (1, 1, sid)
        mesh = c.get_mesh(sid)
        targets = [[mesh.positions[3 * h + k] + (0.2 if k == 2 and h == n * n - 1 else 0)
                    for k in range(3)] for h in handles]
        solve = []
        rid = c._next_id
        res = c.move_handles(sid, targets, progress=solve.append)
        assert res.iterations == 150          # tol 0: the whole budget
        s = check_stream(solve, [WorkStage.SOLVE])[WorkStage.SOLVE]
        assert (s.done, s.total, s.request_id) == (res.iterations, 150, rid)
        no_late_events(c, rid)
        # a budget cut short: the final event carries the iterations run, below the total
        solve = []
        res = c.move_handles(sid, targets, max_iters=40, progress=solve.append)
        s = check_stream(solve, [WorkStage.SOLVE])[WorkStage.SOLVE]
        assert (s.done, s.total) == (res.iterations, 40)
        # without `progress` nothing is asked and nothing comes
        c.move_handles(sid, targets, max_iters=5)
        c.set_handles(sid, handles, max_iters=5)
        assert [e for e in c.events(timeout=0) if isinstance(e, WorkProgress)] == []
        # a refused move (no such handle count) ends with its error and no final event
        solve = []
        with pytest.raises(Exception):
            c.move_handles(sid, targets[:2], progress=solve.append)
        assert all(not e.final for e in solve)


LINE = re.compile(r"^deformctl (\w+): (\w+) (\d+)/(\d+) (\w+) \((\d+)%\)( done)?$")


def parse_lines(stderr):
    rows = []
    for line in stderr.splitlines():
        m = LINE.match(line)
        assert m, line
        cmd, stage, done, total, unit, pct, fin = m.groups()
        assert int(pct) == int(100 * int(done) / int(total))
        rows.append((cmd, stage, int(done), int(total), unit, bool(fin)))
    return rows


def test_deformctl_plain_progress_lines(daemon, big_obj, tmp_path):
    def ctl(*args):
        p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path] + [str(a) for a in args],
                           capture_output=True, text=True, timeout=180,
                           stdin=subprocess.DEVNULL)
        assert p.returncode == 0, (args, p.stdout, p.stderr)
        return p
    size = os.path.getsize(big_obj)
    p = ctl("load", big_obj, "--progress", "lines")
    sid = int(p.stdout.strip())
    rows = parse_lines(p.stderr)
    assert [r[1] for r in rows if r[5]] == ["upload", "parse"]
    assert rows[-1] == ("load", "parse", size, size, "bytes", True)
    assert ("load", "upload", size, size, "bytes", True) in rows
    assert all(r[0] == "load" and r[4] == "bytes" for r in rows)
    assert ctl("load", big_obj, "--progress", "none").stderr == ""
    ctl("close", sid)
    # handles and move on a small grid: factorize, then solve with the move's budget
    n = 12
    g = tmp_path / "g.obj"
    g.write_bytes(grid_obj(n, n))
    gid = int(ctl("load", g, "--progress", "none").stdout.strip())
    hf = tmp_path / "h.txt"
    hf.write_text("0\n%d\n" % (n * n - 1))
    rows = parse_lines(ctl("handles", gid, "--energy", "arap", "--handles", hf, "--tol", "0",
                           "--iters", "60", "--progress", "lines").stderr)
    assert rows[-1] == ("handles", "factorize", 1, 1, "steps", True)
    tf = tmp_path / "t.txt"
    tf.write_text("0 0 0\n1 1 0.3\n")
    p = ctl("--json", "move", gid, "--targets", tf, "--progress", "lines")
    rows = parse_lines(p.stderr)
    assert rows[-1] == ("move", "solve", 60, 60, "iterations", True)
    assert [r[2] for r in rows] == sorted(r[2] for r in rows)
    p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path, "move", str(gid),
                        "--targets", str(tf), "--progress", "sometimes"], capture_output=True,
                       text=True, timeout=30, stdin=subprocess.DEVNULL)
    assert p.returncode == 2 and "--progress" in p.stderr


def test_pinned_stroke_reports_its_lu(daemon):
    from deformd_client import Brush
    with daemon.unix_client(timeout=60) as c:
        sid = c.load_mesh(grid_obj(20, 20), fmt=".obj").session_id
        pins = [(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)]
        brush = Brush(type="grab", center=(0.5, 0.5, 0.0), move=(0, 0, 0.1), radius=0.4,
                      pinned=pins)
        fac = []
        rid = c._next_id
        c.brush_begin(sid, brush, progress=fac.append)   # non-zero load: the begin builds it
        f = check_stream(fac, [WorkStage.FACTORIZE])[WorkStage.FACTORIZE]
        assert (f.done, f.total, f.request_id, f.session_id) == (1, 1, rid, sid)
        assert fac[0].done == 0 or len(fac) == 1
        no_late_events(c, rid)
        upd = []
        c.brush_update(sid, move=(0, 0, 0.2), progress=upd.append)   # the same LU: no events
        assert upd == []
        c.brush_end(sid)
        # a stroke that did not ask gets nothing, also when its begin builds an LU
        moved = Brush(type="grab", center=(0.5, 0.5, 0.0), move=(0, 0, 0.1), radius=0.4,
                      pinned=[(0.0, 0.0, 0.0)])
        c.stroke(sid, moved)
        assert [e for e in c.events(timeout=0) if isinstance(e, WorkProgress)] == []

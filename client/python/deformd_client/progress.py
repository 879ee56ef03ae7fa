"""WORK_PROGRESS events (PROTOCOL.md 4.37): how far a long request has got (upload, parse, solver
build, solve), sent only for requests that asked for them. Client.load_mesh / load_file /
set_handles / move_handles take a `progress` callback that receives each WorkProgress as it
arrives, before the request's reply; without a callback nothing is asked for."""
import struct
from typing import Callable
from dataclasses import dataclass

from .schema import WorkOpt, WorkStage
from .wire import ProtocolError, Reader

WORK_OPT_PROGRESS = WorkOpt.PROGRESS

STAGE_NAMES = {int(s): s.name.lower() for s in WorkStage}   # 1: "upload", ...


@dataclass
class WorkProgress:
    """One WORK_PROGRESS event: `stage` (a WorkStage, or a plain int for a stage newer than this
    client), `done` of `total` units (bytes for upload / parse, steps for factorize, iterations
    for solve; total 0 when unknown), `final` True on the stage's last event, `elapsed_ms` since
    the stage began, `request_id` the request it reports on, `session_id` 0 while a load has
    no session yet."""
    session_id: int
    stage: int
    final: bool
    done: int
    total: int
    elapsed_ms: float
    request_id: int = 0

    @property
    def stage_name(self) -> str:
        """"upload", "parse", "factorize", "solve", or "stage N" for an unknown stage."""
        return STAGE_NAMES.get(int(self.stage), "stage %d" % int(self.stage))

    @property
    def fraction(self) -> float:
        """done / total in [0, 1] (0 when total is unknown)."""
        return min(1.0, self.done / self.total) if self.total else 0.0


def decode_work_progress(p: bytes, request_id: int = 0) -> WorkProgress:
    r = Reader(p, "work_progress")
    sid, stage, final, res, done, total, ms = r.take("QBBHQQd")
    r.end()
    if res != 0:
        raise ProtocolError("work_progress: reserved field %d" % res)
    if stage < 1 or final > 1 or (total and done > total) or not ms >= 0 or ms == float("inf"):
        raise ProtocolError("work_progress: stage %d final %d done %d total %d elapsed %r"
                            % (stage, final, done, total, ms))
    try:
        stage = WorkStage(stage)
    except ValueError:
        pass
    return WorkProgress(sid, stage, bool(final), done, total, ms, request_id)


def encode_work_progress(w: WorkProgress) -> bytes:
    return struct.pack("<QBBHQQd", w.session_id, int(w.stage), 1 if w.final else 0, 0, w.done,
                       w.total, w.elapsed_ms)


# A progress callback (load_mesh, load_file, set_handles, move_handles): one WorkProgress a call.
ProgressFn = Callable[["WorkProgress"], None]

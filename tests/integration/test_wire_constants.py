"""Drift check of the wire constants (issue 10): the C headers (proto/messages.h, proto/frame.h,
proto/wire_error.h, core/common/df_error.h) are the reference; the Python client's constants and
the tables of proto/PROTOCOL.md (3 message types, 7 errors, 8 limits) must say the same. Needs no
daemon: it parses the files of the checkout.
"""
import os
import re

import pytest

from deformd_client import errors as pe
from deformd_client import frame as pf
from deformd_client import messages as pm

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def read(rel: str) -> str:
    with open(os.path.join(ROOT, rel)) as f:
        return f.read()


def strip_comments(c: str) -> str:
    return re.sub(r"/\*.*?\*/", " ", c, flags=re.S)


def c_int(expr: str, known: dict) -> int:
    """Value of a C integer constant expression of the headers: literals with u/ull suffixes,
    shifts, +-, parentheses and names defined earlier."""
    e = re.sub(r"\b(0[xX][0-9a-fA-F]+|\d+)[uUlL]+\b", r"\1", expr.strip())
    e = re.sub(r"\b[A-Z_][A-Z0-9_]*\b", lambda m: str(known[m.group(0)]), e)
    if not re.fullmatch(r"[0-9a-fA-Fx()<>+\-*| ]+", e):
        raise ValueError("not a constant expression: %r" % expr)
    return int(eval(e, {"__builtins__": {}}))   # digits and operators only (checked above)


def c_constants() -> dict:
    """DF_* #defines and enum members of the wire headers, by name."""
    known = {}
    for rel in ("core/common/df_error.h", "proto/frame.h", "proto/wire_error.h",
                "proto/messages.h"):
        text = strip_comments(read(rel))
        for name, expr in re.findall(r"^#define (DF_[A-Z0-9_]+)[ \t]+([^\n]+)$", text, re.M):
            try:
                known[name] = c_int(expr, known)
            except (KeyError, ValueError, SyntaxError):
                pass   # not an integer constant (e.g. a macro with arguments)
        for body in re.findall(r"enum\s*\w*\s*\{(.*?)\}", text, re.S):
            for name, expr in re.findall(r"(DF_[A-Z0-9_]+)\s*=\s*([^,]+)", body):
                known[name] = c_int(expr, known)
    return known


C = c_constants()


def test_parser_sees_the_headers():
    assert C["DF_MAX_PINNED_POINTS"] == 2048 and C["DF_MAX_MESH_BYTES"] == 1 << 30
    assert C["DF_MSG_HELLO"] == 1 and C["DF_EPROTO_CHUNK"] == -110
    assert C["DF_MAX_ERROR_MSG_LEN"] == 255


# Limits the Python client enforces itself: each must exist there and match.
PY_LIMITS = ["MAX_MESH_VERTICES", "MAX_MESH_ELEMENTS", "MAX_MESH_BYTES", "MAX_PENDING_REQUESTS",
             "MAX_NAME_LEN", "MAX_PATH_LEN", "MAX_PING_BYTES", "MAX_PINNED_POINTS",
             "MAX_BRUSH_STEPS", "MAX_FALLOFF", "MAX_HANDLES", "MAX_AFFINE_SETS",
             "STREAM_CHUNK_BYTES"]


@pytest.mark.parametrize("name", PY_LIMITS)
def test_python_limit_matches_c(name):
    assert getattr(pm, name) == C["DF_" + name], \
        "deformd_client.messages.%s = %r, proto/messages.h DF_%s = %r" % (
            name, getattr(pm, name), name, C["DF_" + name])


def test_every_shared_name_matches():
    """Any DF_X of the headers that the Python modules also define as X has the same value."""
    drift = []
    for mod in (pm, pf, pe):
        for cname, value in C.items():
            short = cname[3:]                      # DF_MAX_FALLOFF -> MAX_FALLOFF
            names = {short, short[4:]} if short.startswith("MSG_") else {short}
            for py in names:                       # DF_MSG_HELLO -> HELLO
                v = getattr(mod, py, None)
                if isinstance(v, int) and not isinstance(v, bool) and v != value:
                    drift.append("%s.%s = %r vs %s = %r" % (mod.__name__, py, v, cname, value))
    assert not drift, "\n".join(drift)


def test_frame_constants():
    assert pf.FRAME_MAGIC == C["DF_FRAME_MAGIC"]
    assert pf.PROTO_VERSION == C["DF_PROTO_VERSION"]
    assert pf.HEADER_SIZE == C["DF_FRAME_HEADER_SIZE"]
    assert pf.MAX_FRAME_PAYLOAD == C["DF_MAX_FRAME_PAYLOAD"]
    for f in ("REPLY", "EVENT", "ERROR", "MORE"):
        assert getattr(pf, "FLAG_" + f) == C["DF_FLAG_" + f], f


def test_message_types_both_ways():
    c_types = {k[len("DF_MSG_"):]: v for k, v in C.items() if k.startswith("DF_MSG_")}
    py_types = {name.upper(): t for t, name in pm.TYPE_NAMES.items()}
    assert py_types == c_types


def error_codes() -> dict:
    """The DF_E* codes of core/common/df_error.h and proto/wire_error.h (negative), by name."""
    return {k[3:]: v for k, v in C.items() if re.fullmatch(r"DF_E[A-Z_]+", k) and v < 0}


def test_error_codes_both_ways():
    c_codes = error_codes()
    py_codes = {name: code for code, name in pe.ERROR_NAMES.items() if code != 0}
    assert py_codes == c_codes
    for name, code in c_codes.items():
        assert getattr(pe, name) == code, name


@pytest.mark.parametrize("prefix, table, upper_max", [
    ("DF_BRUSH_", pm.BRUSH_TYPES, "DF_BRUSH_TYPE_MAX"),
    ("DF_INTEG_", pm.INTEGRATORS, None),
    ("DF_BP_", pm.BRUSH_PARAMS, "DF_BP_MAX"),
    ("DF_ENERGY_", pm.ENERGIES, "DF_ENERGY_MAX"),
])
def test_named_enums(prefix, table, upper_max):
    c_enum = {k[len(prefix):].lower(): v for k, v in C.items()
              if k.startswith(prefix) and not k.endswith("_MAX")}
    assert table == c_enum
    if upper_max:
        assert max(table.values()) == C[upper_max]


def test_value_enums():
    assert {v: k for k, v in pm.CHANGE_NAMES.items()} == {
        k[len("DF_CHANGE_"):].lower(): v for k, v in C.items()
        if k.startswith("DF_CHANGE_") and k != "DF_CHANGE_MAX"}
    assert {v: k for k, v in pm.MOVE_STATUS_NAMES.items()} == {
        k[len("DF_MOVE_"):].lower(): v for k, v in C.items()
        if k.startswith("DF_MOVE_") and k not in ("DF_MOVE_STATUS_MAX",)
        and not k.startswith("DF_MOVE_ITERS")}
    for f in ("KELVINLET", "ADMM", "PATH_LOAD", "AUTH", "SPARSE_STREAM", "TCP", "HID",
              "SHM_STREAM"):
        assert getattr(pm, "FEAT_" + f) == C["DF_FEAT_" + f], f
    assert pm.FMT_TETGEN == C["DF_FMT_MAX"]
    assert (pm.LOAD_INLINE, pm.LOAD_PATH) == (C["DF_LOAD_INLINE"], C["DF_LOAD_PATH"])
    assert (pm.DISP_DENSE, pm.DISP_SPARSE) == (C["DF_DISP_DENSE"], C["DF_DISP_SPARSE"])
    for s in ("POSITIONS", "BASE", "REST", "ELEMENTS", "FACES"):
        assert getattr(pm, "SECTION_" + s) == C["DF_SECTION_" + s], s
    assert pm.GET_MESH_REST == C["DF_GET_MESH_REST"] and pm.GET_MESH_BASE == C["DF_GET_MESH_BASE"]
    assert pm.SUBSCRIBE_SNAPSHOT == C["DF_SUBSCRIBE_SNAPSHOT"]


# ---------------------------------------------------------------- PROTOCOL.md tables

def md_section(num: str) -> str:
    text = read("proto/PROTOCOL.md")
    m = re.search(r"^## %s\..*?(?=^## )" % re.escape(num), text, re.M | re.S)
    assert m, "PROTOCOL.md has no section %s" % num
    return m.group(0)


def md_rows(section: str):
    for line in section.splitlines():
        if line.startswith("|") and not re.fullmatch(r"[\s:|-]+", line):
            yield [c.strip() for c in line.strip().strip("|").split("|")]


def test_protocol_md_message_types():
    rows = {r[1]: int(r[0], 16) for r in md_rows(md_section("3")) if r[0].startswith("0x")}
    c_types = {k[len("DF_MSG_"):]: v for k, v in C.items() if k.startswith("DF_MSG_")}
    assert rows == c_types


def test_protocol_md_error_codes():
    rows = {r[1]: int(r[0]) for r in md_rows(md_section("7")) if re.fullmatch(r"-\d+", r[0])}
    c_codes = error_codes()
    assert rows == c_codes


def md_value(cell: str) -> int:
    """'8,388,608' / '64 MiB' / '1 GiB' / '255 bytes' -> int."""
    m = re.fullmatch(r"([\d,]+)\s*(MiB|GiB|bytes)?", cell.strip())
    assert m, "unreadable value %r" % cell
    return int(m.group(1).replace(",", "")) << {"MiB": 20, "GiB": 30}.get(m.group(2), 0)


def test_protocol_md_limits():
    seen = 0
    for r in md_rows(md_section("8")):
        if not r[0].startswith("DF_"):
            continue
        names = [n.strip() for n in r[0].split("/")]
        values = [v.strip() for v in r[1].replace(" bytes", "").split("/")]
        assert len(names) == len(values), r
        for n, v in zip(names, values):
            assert md_value(v) == C[n], "PROTOCOL.md section 8: %s = %s, header says %d" % (
                n, v, C[n])
            seen += 1
    assert seen >= 15

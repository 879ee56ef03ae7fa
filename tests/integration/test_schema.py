"""One wire schema: proto/wire_schema.h (and core/admm/admm_defaults.h for the ADMM defaults) is
the one source of the protocol's numbers. This compiles tests/integration/schema_dump.c, which
prints every entry of those headers, and fails on any drift of
  - the Python client (deformd_client.schema: IntEnum / IntFlag classes, limits, defaults, and the
    Brush / HandleParams defaults and flat aliases of messages.py),
  - proto/PROTOCOL.md: the message type tables of section 3 (types and bodies), the enum and bit
    columns of section 4 and 1.1, the limits table of section 8,
  - the C headers: no limit is defined outside the schema.
  - the error codes: core/common/df_error.h + proto/wire_error.h vs deformd_client.errors and
    PROTOCOL.md section 7.
It also checks that the daemon advertises only features that exist."""
import enum
import math
import os
import re
import subprocess

import pytest

from deformd_client import Client, schema
from deformd_client import errors as pe
from deformd_client import frame as pf
from deformd_client import messages as m

ROOT = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
PROTOCOL_MD = os.path.join(ROOT, "proto", "PROTOCOL.md")
SCHEMA_H = os.path.join(ROOT, "proto", "wire_schema.h")
PY_NAME = {"2D": "TWO_D"}   # C names that are not Python identifiers


@pytest.fixture(scope="module")
def dump(tmp_path_factory):
    exe = str(tmp_path_factory.mktemp("schema") / "schema_dump")
    cc = os.environ.get("CC", "cc")
    subprocess.run([cc, "-std=c11", "-Wall", "-Wextra", "-Werror", "-I", ROOT, "-o", exe,
                    os.path.join(ROOT, "tests", "integration", "schema_dump.c")], check=True,
                   stdin=subprocess.DEVNULL)
    out = subprocess.run([exe], check=True, capture_output=True, text=True).stdout
    d = {"type": [], "enum": {}, "limit": {}, "const": {}, "brush_default": {},
         "admm_default": {}, "admm_nh_default": {}}
    for line in out.splitlines():
        f = line.split("\t")
        if f[0] == "type":
            d["type"].append((f[1], int(f[2]), f[3], f[4], f[5], f[6]))
        elif f[0] == "enum":
            cls, kind, prefix, name, value = f[1:]
            e = d["enum"].setdefault(cls, {"kind": kind, "prefix": prefix, "members": {}})
            e["members"][name] = int(value)
        elif f[0] == "magic":
            d["const"][f[1]] = f[2].encode()
        elif f[0] in ("limit", "const"):
            d[f[0]][f[1]] = int(f[2])
        else:
            d[f[0]][f[1]] = float(f[2])
    assert d["type"] and d["enum"] and d["limit"], out
    return d


# ------------------------------------------------------------------ C schema vs Python
def test_message_types_and_bodies_match(dump):
    c = {name: value for name, value, *_ in dump["type"]}
    assert {t.name: int(t) for t in schema.MsgType} == c
    for name, value, lower, req, rep, ev in dump["type"]:
        body = lambda b: None if b == "NONE" else b.lower()  # noqa: E731
        assert schema.BODIES[schema.MsgType[name]] == (body(req), body(rep), body(ev)), name
        assert m.TYPE_NAMES[value] == lower and getattr(m, name) == value


def test_every_enum_matches(dump):
    py_enums = {c for c, v in vars(schema).items() if isinstance(v, type)
                and issubclass(v, enum.Enum) and v.__module__ == schema.__name__}
    assert set(dump["enum"]) == py_enums - {"MsgType"}
    for cls, e in dump["enum"].items():
        py = getattr(schema, cls)
        assert issubclass(py, enum.IntFlag if e["kind"] == "flags" else enum.IntEnum), cls
        want = {PY_NAME.get(n, n): v for n, v in e["members"].items()}
        assert {x.name: int(x) for x in py} == want, cls


def test_limits_and_constants_match(dump):
    assert schema.LIMITS == {k[3:]: v for k, v in dump["limit"].items()}
    for k, v in dump["limit"].items():
        assert getattr(m, k[3:]) == v, k          # the flat aliases of messages.py
    c = dump["const"]
    assert (schema.FRAME_MAGIC, schema.PROTO_VERSION, schema.FRAME_HEADER_SIZE) == (
        c["DF_FRAME_MAGIC"], c["DF_PROTO_VERSION"], c["DF_FRAME_HEADER_SIZE"])
    assert (schema.SHM_MAGIC, schema.SHM_HEADER_BYTES, schema.SHM_MIN_CAPACITY,
            schema.SHM_MAX_CAPACITY) == (c["DF_SHM_MAGIC"], c["DF_SHM_HEADER_BYTES"],
                                         c["DF_SHM_MIN_CAPACITY"], c["DF_SHM_MAX_CAPACITY"])
    assert "DF_FEAT_RESERVED" not in c     # bit 6 is HID again (schema.Feature.HID)


def test_every_limit_define_is_listed_once():
    text = open(SCHEMA_H).read()
    defined = set(re.findall(r"^#define (DF_(?:MAX_\w+|STREAM_CHUNK_BYTES)) ", text, re.M))
    listed = set(re.findall(r"X\((DF_\w+)\)", text))
    assert defined == listed
    defined |= set(re.findall(r"^#define (DF_(?:SHM|FRAME|PROTO)_\w+) ", text, re.M))
    # nothing else in the tree restates them
    for top in ("core", "proto", "server", "client", "tests"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, top)):
            for fn in files:
                p = os.path.join(dirpath, fn)
                if fn.endswith((".c", ".h")) and p != SCHEMA_H:
                    src = open(p, errors="replace").read()
                    for name in defined:
                        assert not re.search(r"#define %s\b" % name, src), (p, name)


def test_defaults_match(dump):
    bd = dict(schema.BRUSH_DEFAULTS)
    assert {k: float(v) for k, v in bd.items()} == dump["brush_default"]
    b = m.Brush()
    assert b.type == schema.BrushType(int(dump["brush_default"]["type"])).name.lower()
    assert b.integrator == schema.Integrator(int(dump["brush_default"]["integrator"])).name.lower()
    for k in ("dim", "falloff", "steps", "radius", "ratio", "nu", "strength"):
        assert getattr(b, k) == dump["brush_default"][k], k
    assert {k: float(v) for k, v in schema.ADMM_DEFAULTS.items()} == dump["admm_default"]
    assert {k: float(v) for k, v in schema.ADMM_DEFAULTS_NEOHOOKEAN.items()} == \
        dump["admm_nh_default"]
    for energy in ("arap", "neohookean"):
        p = m.HandleParams.for_energy(energy)
        want = dict(dump["admm_default"])
        if energy == "neohookean":
            want.update(dump["admm_nh_default"])
        for k, v in want.items():
            assert float(getattr(p, k)) == v and not math.isnan(v), (energy, k)


def _c_names(dump):
    """Every C name the dump knows, DF_X -> value."""
    c = dict(dump["limit"])
    c.update(dump["const"])
    for name, value, *_ in dump["type"]:
        c["DF_MSG_" + name] = value
    for e in dump["enum"].values():
        for name, value in e["members"].items():
            c[e["prefix"] + name] = value
    return c


def test_every_shared_name_matches(dump):
    """Any DF_X of the schema that a Python module also defines as X (DF_MSG_HELLO: HELLO)
    has the same value."""
    drift = []
    for mod in (m, pf, pe, schema):
        for cname, value in _c_names(dump).items():
            short = cname[3:]
            for py in ({short, short[4:]} if short.startswith("MSG_") else {short}):
                v = getattr(mod, py, None)
                if isinstance(v, int) and not isinstance(v, bool) and v != value:
                    drift.append("%s.%s = %r vs %s = %r" % (mod.__name__, py, v, cname, value))
    assert not drift, "\n".join(drift)


def _c_error_codes():
    """The negative DF_E* codes of core/common/df_error.h and proto/wire_error.h, by name."""
    out = {}
    for rel in ("core/common/df_error.h", "proto/wire_error.h"):
        text = open(os.path.join(ROOT, rel)).read()
        out.update({k[3:]: int(v) for k, v in re.findall(r"\b(DF_E[A-Z_]+)\s*=\s*(-\d+)", text)})
    assert out["EINVAL"] == -1 and out["EPROTO_CHUNK"] == -110
    return out


def test_error_codes_match():
    c = _c_error_codes()
    assert {name: code for code, name in pe.ERROR_NAMES.items() if code != 0} == c
    for name, code in c.items():
        assert getattr(pe, name) == code, name
    doc = {r[1]: int(r[0]) for r in _rows(_section(_doc(), "7. Errors"))
           if re.fullmatch(r"-\d+", r[0])}
    assert doc == c, "PROTOCOL.md section 7 vs the C error codes"


# ------------------------------------------------------------------ PROTOCOL.md
def _doc():
    return open(PROTOCOL_MD, encoding="utf-8").read()


def _rows(text):
    for line in text.splitlines():
        if line.startswith("|") and not line.startswith("|--") and not line.startswith("|-"):
            yield [c.strip() for c in line.strip().strip("|").split("|")]


def _section(doc, heading):
    """Text of the section whose heading line starts with `heading`, up to the next heading."""
    m_ = re.search(r"^#+ %s.*?$(.*?)(?=^#+ )" % re.escape(heading), doc, re.M | re.S)
    assert m_, "PROTOCOL.md has no section %r" % heading
    return m_.group(1)


def test_protocol_md_type_tables(dump):
    doc = _section(_doc(), "3. Message types")
    seen = {}
    for cells in _rows(doc):
        if not re.fullmatch(r"0x[0-9A-Fa-f]{4}", cells[0]):
            continue
        first = [re.match(r"[a-z_]+", c).group(0) for c in cells[2:]]
        assert cells[1] not in seen, "%s listed twice" % cells[1]
        seen[cells[1]] = (int(cells[0], 16), first)
    c = {name: (value, req, rep, ev) for name, value, _, req, rep, ev in dump["type"]}
    assert set(seen) == set(c), "PROTOCOL.md section 3 vs proto/wire_schema.h"
    for name, (value, bodies) in seen.items():
        cv, req, rep, ev = c[name]
        assert value == cv, name
        if len(bodies) == 2:                 # request table: request body, reply body
            assert bodies == [req.lower(), rep.lower()], name
        elif name == "ERROR":                # carries the error body (flag ERROR)
            assert bodies == ["error"]
        else:                                # event table: body
            assert bodies == [ev.lower()], name


# (section heading, field, schema class, flags?, values left out of that field)
ENUM_FIELDS = [
    ("1.1", "flags", "FrameFlag", True, ()),
    ("4.2b", "features", "Feature", True, ()),
    ("4.5", "source", "LoadSource", False, ()),
    ("4.5", "format", "Format", False, ()),
    ("4.5", "options", "LoadOpt", True, ()),
    ("4.8", "flags", "SubscribeFlag", True, ()),
    ("4.9 ", "kind", "MeshKind", False, ()),
    ("4.12", "type", "BrushType", False, ()),
    ("4.12", "integrator", "Integrator", False, ()),
    ("4.12", "pin_flags", "PinFlag", True, ()),
    ("4.14", "param", "BrushParam", False, ()),
    ("4.12", "use_session", "BrushStateField", True, ()),
    ("4.14a", "mask", "BrushStateField", True, ()),
    ("4.14a", "type", "BrushType", False, ()),
    ("4.14a", "integrator", "Integrator", False, ()),
    ("4.14b", "origin_kind", "Origin", False, ()),
    ("4.14c", "origin_kind", "Origin", False, ()),
    ("4.14c", "flags", "CursorFlag", True, ()),
    ("4.15", "energy", "Energy", False, ()),
    ("4.17", "status", "MoveStatus", False, ("RUNNING",)),
    ("4.18", "flags", "GetMeshFlag", True, ()),
    ("4.19", "kind", "MeshKind", False, ()),
    ("4.19", "section", "MeshSection", False, ()),
    ("4.21", "kind", "ChangeKind", False, ()),
    ("4.21", "encoding", "DispEncoding", False, ()),
    ("4.22", "status", "MoveStatus", False, ()),
    ("4.30", "class", "DevClass", False, ()),
    ("4.30", "backend", "DevBackend", False, ()),
    ("4.30", "state", "DevState", False, ()),
    ("4.3 auth", "method", "AuthMethod", False, ()),
    ("4.36", "mode", "AccessMode", False, ()),
    ("4.35", "flags", "AccessFlag", True, ()),
    ("4.12", "options", "WorkOpt", True, ("KELVINLET_GUESS", "POLISH")),  # handle_move only
    ("4.15", "options", "WorkOpt", True, ("KELVINLET_GUESS", "POLISH")),  # handle_move only
    ("4.16", "options", "WorkOpt", True, ()),
    ("4.37", "stage", "WorkStage", False, ()),
    ("4.38", "flags", "PeerFlag", True, ()),
    ("4.38", "transport", "Transport", False, ()),
    ("4.2 ", "stream_encoding", "StreamEnc", True, ()),
]


def _norm(s):
    return re.sub(r"[-`_]", "", s.lower()).replace(" ", "")


def _documented(cell, flags):
    """{value: text} of the enum values or bits a table cell lists ("1 grab, 2 twist",
    "bit 0 `REPLY`, bit 1 ...", "bit 0 KELVINLET, 1 ADMM"); reserved bits are left out."""
    out = {}
    for item in re.split(r"[,;]", cell):
        item = item.strip()
        if flags:
            hit = re.search(r"bit (\d+):? (.+)", item) or re.match(r"(\d+) ([A-Z].*)", item)
        else:
            hit = re.match(r"(\d+) (.+)", item)
        if hit and "reserved" not in hit.group(2):
            v = int(hit.group(1))
            out[1 << v if flags else v] = hit.group(2)
    return out


@pytest.mark.parametrize("heading,field,cls,flags,left_out", ENUM_FIELDS,
                         ids=["%s-%s" % (f[0].strip(), f[1]) for f in ENUM_FIELDS])
def test_protocol_md_enum_columns(dump, heading, field, cls, flags, left_out):
    sec = _section(_doc(), heading)
    cells = [c for c in _rows(sec) if len(c) >= 4 and c[2] == field]
    assert len(cells) == 1, "PROTOCOL.md %s: field %s" % (heading, field)
    doc = _documented(cells[0][3], flags)
    members = {n: v for n, v in dump["enum"][cls]["members"].items() if n not in left_out}
    assert set(doc) == set(members.values()), "PROTOCOL.md %s %s: %s vs %s" % (
        heading, field, doc, members)
    for name, value in members.items():
        assert _norm(name) in _norm(doc[value]), "PROTOCOL.md %s %s: %d is %r, schema %s" % (
            heading, field, value, doc[value], name)


def _size(text):
    text = text.replace(",", "").replace("bytes", "").strip()
    n, _, unit = text.partition(" ")
    return int(n) << {"": 0, "KiB": 10, "MiB": 20, "GiB": 30}[unit.strip()]


def test_protocol_md_limits_table(dump):
    sec = _section(_doc(), "8. Limits")
    doc = {}
    for cells in _rows(sec):
        if not cells[0].startswith("DF_"):
            continue
        names = [n.strip() for n in cells[0].split("/")]
        values = [v.strip() for v in cells[1].split("/")]
        assert len(names) == len(values), cells
        for n, v in zip(names, values):
            doc[n] = _size(v)
    assert doc == dump["limit"], "PROTOCOL.md section 8 vs proto/wire_schema.h"


def test_protocol_md_feature_bit_6_is_hid():
    cell = [c for c in _rows(_section(_doc(), "4.2b")) if len(c) >= 4 and c[2] == "features"][0]
    assert re.search(r"\b6 HID\b", cell[3]) and "reserved" not in cell[3], cell[3]


# ------------------------------------------------------------------ the daemon
def test_daemon_advertises_only_existing_features(daemon):
    with Client.connect_unix(daemon.socket_path) as c:
        f = c.server.features
    assert f & ~sum(schema.Feature) == 0, hex(f)
    assert schema.Feature(f) & schema.Feature.KELVINLET


def test_no_limit_constant_goes_unenforced():
    """Every DF_*MAX* / DF_*LIMIT* constant of a C header is used somewhere besides its own
    #define (a wire limit: somewhere besides the schema, which only lists it): a limit nothing
    checks is a promise nothing keeps (DF_CONN_MAX_SUBS, DF_CLIENT_MAX_REPLY_BYTES and
    DF_HISTORY_DEFAULT_MAX were removed for that)."""
    srcs = {}
    for top in ("core", "proto", "server", "client"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, top)):
            for fn in files:
                if fn.endswith((".c", ".h")):
                    p = os.path.join(dirpath, fn)
                    srcs[p] = open(p, errors="replace").read()
    unused = []
    for p, text in srcs.items():
        if not p.endswith(".h"):
            continue
        for name in re.findall(r"^#define (DF_\w*(?:MAX|LIMIT)\w*)[ (]", text, re.M):
            if name.startswith("DF_WIRE_"):
                continue                     # the schema's own list macros
            pat = re.compile(r"\b%s\b" % name)
            if p == SCHEMA_H:
                uses = sum(len(pat.findall(t)) for q, t in srcs.items() if q != p)
            else:
                uses = sum(len(pat.findall(t)) for t in srcs.values()) - 1
            if uses < 1:
                unused.append("%s: %s" % (os.path.relpath(p, ROOT), name))
    assert not unused, unused

"""TCP key authentication (issue 12, access control item 2; PROTOCOL.md 4.3): with key_file every
TCP connection completes the HMAC-SHA256 challenge-response before anything but HELLO / PING /
AUTH runs; a wrong key is refused (EPROTO_AUTH, closed) and changes nothing; failures are
rate-limited per peer address (count-based: auth_fail_burst with a refill of an hour, so no
timing is involved); Unix-socket clients need no key; bad key files refuse start-up. The
worked example of PROTOCOL.md 4.3 is recomputed by the Python client and by proto/auth_mac.c."""
import hashlib
import hmac
import os
import re
import secrets
import socket
import struct
import subprocess

import pytest

from conftest import BUILD, DEFORMCTL, DEFORMD, ROOT
from deformd_client import AuthError, Client, DeformdError, auth, errors as E, messages as m
from deformd_client import frame as fr, schema
from helpers import grid_obj
from rawwire import wait_closed

START_TIMEOUT_S = 15.0


def write_key(path, text=None, mode=0o600) -> bytes:
    text = secrets.token_hex(32) if text is None else text
    with open(path, "w") as f:
        f.write(text + "\n")
    os.chmod(path, mode)
    return text.encode()


@pytest.fixture
def keyed(make_daemon, tmp_path):
    """A daemon with a key (TCP on loopback): (daemon, key file path, key bytes)."""
    kf = str(tmp_path / "deformd.key")
    key = write_key(kf)
    d = make_daemon("key_file = %s\n" % kf, tcp=True)
    return d, kf, key


def tcp(d, **kw) -> Client:
    return Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, **kw)


def test_hello_announces_auth_and_requires_it_on_tcp_only(keyed):
    d, kf, key = keyed
    with tcp(d) as c:
        assert c.server.auth_required == 1 and c.server.features & schema.Feature.AUTH
    with d.unix_client() as c:
        assert c.server.auth_required == 0 and c.server.features & schema.Feature.AUTH
        assert c.list_sessions() == []       # the Unix socket needs no key


def test_unauthenticated_requests_are_refused_and_not_executed(keyed):
    d, kf, key = keyed
    with tcp(d) as c:
        assert c.ping(b"alive") == b"alive"  # PING works before AUTH
        for call in (lambda: c.list_sessions(),
                     lambda: c.load_mesh(grid_obj(4, 4), name="sneaky"),
                     lambda: c.stats()):
            with pytest.raises(DeformdError) as ei:
                call()
            assert ei.value.code == E.ErrorCode.EPROTO_AUTH, ei.value
            assert "authentication required" in str(ei.value)
    with d.unix_client() as c:
        assert c.list_sessions() == []        # the load did not happen
        assert c.stats()["auth_ok"] == 0


def test_right_key_works_from_python(keyed):
    d, kf, key = keyed
    with tcp(d, key_file=kf) as c:
        assert c.authenticated
        info = c.load_mesh(grid_obj(5, 4), name="mine")
        assert [s.name for s in c.list_sessions()] == ["mine"]
        assert c.stats()["auth_ok"] == 1
        c.close_session(info.session_id)
    with tcp(d, key=key) as c:              # the key itself works too
        assert c.authenticated and c.list_sessions() == []


def test_wrong_key_is_refused_closed_and_changes_nothing(keyed):
    d, kf, key = keyed
    with d.unix_client() as u:
        u.load_mesh(grid_obj(4, 4), name="keep")
        before = [(s.session_id, s.name, s.version) for s in u.list_sessions()]
    c = tcp(d, hello=True)
    with pytest.raises(DeformdError) as ei:
        c.authenticate(secrets.token_hex(32).encode())
    assert ei.value.code == E.ErrorCode.EPROTO_AUTH and "does not match" in str(ei.value)
    assert wait_closed(c.sock, 10.0), "the server kept a connection with a wrong key open"
    c.close()
    with d.unix_client() as u:
        assert [(s.session_id, s.name, s.version) for s in u.list_sessions()] == before
        st = u.stats()
        assert (st["auth_failed"], st["auth_ok"]) == (1, 0)
    log = d.log()
    assert "authentication failed" in log and "127.0.0.1" in log
    assert key.decode() not in log


def test_protocol_misuse_gets_clear_errors(keyed):
    d, kf, key = keyed
    with tcp(d) as c:
        A = schema.AuthMethod
        for method, token, code in ((A.HMAC_PROOF, bytes(32), E.ErrorCode.ESTATE),
                                    (A.HMAC_CHALLENGE, b"short", E.ErrorCode.EINVAL),
                                    (9, bytes(32), E.ErrorCode.EINVAL)):
            with pytest.raises(DeformdError) as ei:
                c.auth(method, token)
            assert ei.value.code == code, ei.value
        c.authenticate(key)                  # still usable: none of those was a failed proof
        with pytest.raises(DeformdError) as ei:
            c.auth(schema.AuthMethod.HMAC_CHALLENGE, bytes(32))
        assert ei.value.code == E.ErrorCode.ESTATE
        assert c.list_sessions() == []


def test_server_proof_is_the_server_mac(keyed):
    """The exchange step by step: the server's MAC is HMAC(K, Ns || Nc || server context),
    computed here with hmac/hashlib directly."""
    d, kf, key = keyed
    with tcp(d) as c:
        nc = secrets.token_bytes(32)
        method, ns = c.auth(schema.AuthMethod.HMAC_CHALLENGE, nc)
        assert method == schema.AuthMethod.HMAC_CHALLENGE and len(ns) == 32 and ns != nc
        mc = hmac.new(key, ns + nc + b"deformd-auth-v1 client", hashlib.sha256).digest()
        method, ms = c.auth(schema.AuthMethod.HMAC_PROOF, mc)
        assert method == schema.AuthMethod.HMAC_PROOF
        assert ms == hmac.new(key, ns + nc + b"deformd-auth-v1 server", hashlib.sha256).digest()
        assert c.list_sessions() == []


def test_failures_are_rate_limited_per_address(make_daemon, tmp_path):
    kf = str(tmp_path / "k")
    key = write_key(kf)
    d = make_daemon("key_file = %s\nauth_fail_burst = 3\nauth_fail_refill_s = 3600\n" % kf,
                    tcp=True)
    wrong = secrets.token_hex(32).encode()
    for _ in range(3):
        c = tcp(d)
        with pytest.raises(DeformdError) as ei:
            c.authenticate(wrong)
        assert ei.value.code == E.ErrorCode.EPROTO_AUTH
        c.close()
    c = tcp(d)                               # the fourth try: refused even with the right key
    with pytest.raises(DeformdError) as ei:
        c.authenticate(key)
    assert ei.value.code == E.ErrorCode.ELIMIT
    assert "too many failed authentications from 127.0.0.1" in str(ei.value)
    assert re.search(r"retry in \d+ s", str(ei.value))
    assert wait_closed(c.sock, 10.0)
    c.close()
    with d.unix_client() as u:
        st = u.stats()
        assert (st["auth_failed"], st["auth_limited"], st["auth_ok"]) == (3, 1, 0)
        assert u.list_sessions() == []
    assert "too many failed authentications from 127.0.0.1" in d.log()


def start_fails(tmp_path, *args):
    r = subprocess.run([DEFORMD, "--foreground", "--socket", str(tmp_path / "d.sock")] +
                       list(args), stdin=subprocess.DEVNULL, capture_output=True,
                       timeout=START_TIMEOUT_S, env=dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path)))
    assert r.returncode != 0
    assert not os.path.exists(tmp_path / "d.sock")
    return r.stderr.decode("utf-8", "replace")


@pytest.mark.parametrize("case", ["world_readable", "too_short", "missing", "directory"])
def test_bad_key_files_refuse_start(tmp_path, case):
    kf = str(tmp_path / "k")
    if case == "world_readable":
        write_key(kf, mode=0o644)
        needle = "readable or writable by others (mode 0644)"
    elif case == "too_short":
        write_key(kf, text="x" * 31)
        needle = "key of 31 bytes is too short"
    elif case == "missing":
        needle = "No such file"
    else:
        os.mkdir(kf)
        needle = "not a regular file"
    err = start_fails(tmp_path, "--key-file", kf)
    assert ("key file %s" % kf) in err and needle in err, err


def test_python_refuses_a_world_readable_key_file(tmp_path):
    kf = str(tmp_path / "k")
    write_key(kf, mode=0o604)
    with pytest.raises(AuthError) as ei:
        auth.load_key(kf)
    assert "readable or writable by others" in str(ei.value)


# ------------------------------------------------------------------ PROTOCOL.md worked example
def _doc_example():
    doc = open(os.path.join(ROOT, "proto", "PROTOCOL.md"), encoding="utf-8").read()
    sec = doc[doc.index("### 4.3 auth"):doc.index("### 4.4 ping")]
    key = re.search(r"K is the 64 ASCII bytes `([0-9a-f]{64})`", sec).group(1).encode()
    mc = bytes.fromhex(re.search(r"^Mc = ([0-9a-f]{64})$", sec, re.M).group(1))
    ms = bytes.fromhex(re.search(r"^Ms = ([0-9a-f]{64})$", sec, re.M).group(1))
    frame_hex = re.findall(r"^```\n(44 46 4d 44.*?)```", sec, re.M | re.S)[0]
    hexes = []
    for ln in frame_hex.splitlines():        # each line: hex byte pairs, then a label
        for tok in ln.split():
            if not re.fullmatch(r"[0-9a-f]{2}", tok):
                break
            hexes.append(tok)
    frame = bytes.fromhex(" ".join(hexes))
    return key, mc, ms, frame


def test_worked_example_matches_python_and_c(tmp_path):
    key, mc, ms, frame = _doc_example()
    assert key == bytes(range(32)).hex().encode()
    nc, ns = bytes(range(0x20, 0x40)), bytes(range(0x40, 0x60))
    # Python: the client's helper and hmac/hashlib spelled out
    assert auth.mac(key, ns, nc, "client") == mc
    assert auth.mac(key, ns, nc, "server") == ms
    assert hmac.new(key, ns + nc + b"deformd-auth-v1 client", hashlib.sha256).digest() == mc
    # the frame is the proof request with request id 3
    assert frame == fr.encode_frame(m.AUTH, m.encode_auth(2, mc), 3)
    assert len(frame) == 64
    # C: proto/auth_mac.c through a small program linked with the proto layer
    exe = str(tmp_path / "auth_mac_cli")
    san = os.environ.get("SAN_FLAGS", "").split()   # `make asan` / `make tsan`: instrumented libs
    subprocess.run([os.environ.get("CC", "cc"), "-std=c11", "-Wall", "-Wextra", "-Werror"] + san +
                   ["-I", ROOT, "-o", exe,
                    os.path.join(ROOT, "tests", "integration", "auth_mac_cli.c"),
                    os.path.join(BUILD, "lib", "libdf_proto.a"),
                    os.path.join(BUILD, "lib", "libdf_common.a"), "-lcrypto"],
                   check=True, stdin=subprocess.DEVNULL)
    for role, want in (("client", mc), ("server", ms)):
        out = subprocess.run([exe, key.decode(), ns.hex(), nc.hex(), role], check=True,
                             capture_output=True, text=True).stdout.strip()
        assert bytes.fromhex(out) == want, role


# ------------------------------------------------------------------ deformctl / C client
def ctl(d, *args, env_key=None):
    env = dict(os.environ)
    env.pop("DEFORMD_KEY_FILE", None)
    if env_key:
        env["DEFORMD_KEY_FILE"] = env_key
    return subprocess.run([DEFORMCTL] + list(args), capture_output=True, text=True, env=env,
                          stdin=subprocess.DEVNULL, timeout=60)


def test_deformctl_key_file_option_env_and_errors(keyed, tmp_path):
    d, kf, key = keyed
    hp = "127.0.0.1:%d" % d.tcp_port
    obj = tmp_path / "g.obj"
    obj.write_bytes(grid_obj(4, 3))
    r = ctl(d, "--tcp", hp, "--key-file", kf, "load", str(obj), "--name", "viactl")
    assert r.returncode == 0, r.stderr
    r = ctl(d, "--tcp", hp, "list", env_key=kf)                   # $DEFORMD_KEY_FILE
    assert r.returncode == 0 and "viactl" in r.stdout, r.stderr
    r = ctl(d, "list", "--tcp", hp, "--key-file", kf, "--json")    # after the command
    assert r.returncode == 0 and "viactl" in r.stdout, r.stderr
    r = ctl(d, "--tcp", hp, "list")                                 # no key
    assert r.returncode == 1 and "--key-file" in r.stderr and "requires authentication" in r.stderr
    wrong = str(tmp_path / "wrong.key")
    write_key(wrong)
    r = ctl(d, "--tcp", hp, "--key-file", wrong, "close", "viactl")
    assert r.returncode == 1 and "EPROTO_AUTH" in r.stderr + r.stdout, (r.stdout, r.stderr)
    loose = str(tmp_path / "loose.key")
    write_key(loose, text=key.decode(), mode=0o644)
    r = ctl(d, "--tcp", hp, "--key-file", loose, "close", "viactl")
    assert r.returncode == 2 and "readable or writable by others" in r.stderr, r.stderr
    with d.unix_client() as c:                                       # nothing was closed
        assert [s.name for s in c.list_sessions()] == ["viactl"]
        st = c.stats()
        assert (st["auth_ok"], st["auth_failed"]) == (3, 1)
    r = ctl(d, "--socket", d.socket_path, "list")                   # Unix: no key needed
    assert r.returncode == 0 and "viactl" in r.stdout, r.stderr


# ------------------------------------------------------------------ mutual: an impostor server
class Impostor:
    """A TCP server that speaks HELLO and AUTH but does not know the key: it accepts any client
    proof and answers with a MAC made from another key. Serves one connection in a thread and
    records whether a request other than HELLO/AUTH arrived after its proof."""

    def __init__(self):
        import threading
        self.lsock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.lsock.bind(("127.0.0.1", 0))
        self.lsock.listen(1)
        self.port = self.lsock.getsockname()[1]
        self.after_proof = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _reply(self, conn, f, body):
        conn.sendall(fr.encode_frame(f.type, body, f.request_id, schema.FrameFlag.REPLY))

    def _serve(self):
        conn, _ = self.lsock.accept()
        conn.settimeout(30)
        dec = fr.FrameDecoder()
        proved = False
        try:
            while True:
                data = conn.recv(65536)
                if not data:
                    return
                for f in dec.feed(data):
                    if f.type == m.HELLO:
                        body = struct.pack("<HHIIIIIIQQBB", 1, 1, int(schema.Feature.AUTH |
                                           schema.Feature.TCP), 1 << 20, 1000, 1000, 64, 64,
                                           1 << 20, 1 << 20, 1, 0) + m.pack_str("impostor")
                        self._reply(conn, f, body)
                    elif f.type == m.AUTH:
                        method, token = m.decode_auth(f.payload)
                        self._reply(conn, f, m.encode_auth(method, secrets.token_bytes(32)))
                        proved = proved or method == schema.AuthMethod.HMAC_PROOF
                    elif proved:
                        self.after_proof.append(f.type)
                        return
        finally:
            conn.close()
            self.lsock.close()


def test_clients_refuse_a_server_that_cannot_prove_the_key(tmp_path):
    kf = str(tmp_path / "k")
    key = write_key(kf)
    imp = Impostor()
    c = Client.connect_tcp("127.0.0.1", imp.port, timeout=30.0, hello=True)
    with pytest.raises(AuthError) as ei:
        c.authenticate(key)
    assert "did not prove" in str(ei.value)
    imp.thread.join(30)
    assert imp.after_proof == []
    imp = Impostor()
    r = subprocess.run([DEFORMCTL, "--tcp", "127.0.0.1:%d" % imp.port, "--key-file", kf, "list"],
                       capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=60)
    assert r.returncode == 1 and "did not prove that it knows the key" in r.stderr, r.stderr
    imp.thread.join(30)
    assert imp.after_proof == []        # deformctl sent no request to the impostor


def test_handshake_timeout_covers_auth(make_daemon, tmp_path):
    """An unauthenticated TCP connection cannot hold its slot (PING keeps a connection from the
    idle timeout, so the handshake timeout also waits for AUTH)."""
    kf = str(tmp_path / "k")
    key = write_key(kf)
    d = make_daemon("key_file = %s\nhandshake_timeout_s = 1\nidle_timeout_s = 0\n" % kf, tcp=True)
    good = tcp(d, key=key)
    lurker = tcp(d)                      # HELLO done, never authenticates
    f = None
    while f is None or f.type != m.ERROR:   # waits for the ERROR event (up to the client timeout)
        f = lurker.recv_frame(timeout=15.0)
        assert f is not None, "no ERROR event from the handshake timeout"
    code, msg = m.decode_error(f.payload)
    assert code == E.ErrorCode.ELIMIT and "not authenticated" in msg, msg
    assert wait_closed(lurker.sock, 10.0)
    lurker.close()
    assert good.ping(b"still") == b"still"
    assert good.list_sessions() == []
    good.close()


def test_non_loopback_with_a_key_alone_is_refused(tmp_path):
    """A key alone does not open a non-loopback address: TLS is needed too (test_tls.py)."""
    kf = str(tmp_path / "k")
    write_key(kf)
    err = start_fails(tmp_path, "--key-file", kf, "--tcp", "0.0.0.0:0")
    assert "without encryption (tls_cert/tls_key)" in err and "set key_file" in err, err

"""TLS on TCP (issue 12, access control item 2): with tls_cert / tls_key the daemon's TCP listener
speaks TLS 1.3 (memory BIOs under libuv, server/net/tls.c); key authentication runs inside it.
A throwaway CA and server certificate are made with the openssl CLI into tmp_path for each test
module. Checked: Python, deformctl and (through deformctl) the C library do a load / stroke / get
round trip over TLS + key; a certificate from another CA and a wrong host name are refused by
every client; a plaintext client gets no service (logged with its address, closed) while the
daemon keeps serving; a non-loopback address without key + TLS refuses start with what to set;
bad certificate / key files refuse start; a large GET_MESH over TLS is byte-identical to the
Unix socket's."""
import os
import secrets
import socket
import ssl
import subprocess

import pytest

from conftest import DEFORMCTL, DEFORMD
from deformd_client import Client, messages as m
from deformd_client import frame as fr
from helpers import grid_obj, obj_bytes_positions

START_TIMEOUT_S = 15.0


def openssl(*args, cwd):
    subprocess.run(["openssl"] + list(args), cwd=cwd, check=True, capture_output=True,
                   stdin=subprocess.DEVNULL, timeout=60)


def make_ca(d, name):
    """A self-signed CA in directory d: (ca.pem, ca.key) paths."""
    openssl("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
            "-nodes", "-keyout", name + ".key", "-out", name + ".pem", "-days", "2",
            "-subj", "/CN=" + name, cwd=d)
    return os.path.join(d, name + ".pem"), os.path.join(d, name + ".key")


def make_server_cert(d, ca, name, san="DNS:localhost,IP:127.0.0.1"):
    """A server certificate signed by CA `ca` (pem, key) for `san`: (cert, key) paths, key 0600."""
    openssl("req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
            "-keyout", name + ".key", "-out", name + ".csr", "-subj", "/CN=deformd-test", cwd=d)
    with open(os.path.join(d, name + ".ext"), "w") as f:
        f.write("subjectAltName=%s\nextendedKeyUsage=serverAuth\n" % san)
    openssl("x509", "-req", "-in", name + ".csr", "-CA", ca[0], "-CAkey", ca[1],
            "-CAcreateserial", "-out", name + ".pem", "-days", "2", "-extfile", name + ".ext",
            cwd=d)
    key = os.path.join(d, name + ".key")
    os.chmod(key, 0o600)
    return os.path.join(d, name + ".pem"), key


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    d = str(tmp_path_factory.mktemp("pki"))
    ca = make_ca(d, "ca")
    other = make_ca(d, "otherca")
    cert = make_server_cert(d, ca, "server")
    return {"dir": d, "ca": ca[0], "other_ca": other[0], "cert": cert[0], "key": cert[1],
            "other_cert": make_server_cert(d, other, "impostor")}


def write_key(path):
    with open(path, "w") as f:
        f.write(secrets.token_hex(32) + "\n")
    os.chmod(path, 0o600)


@pytest.fixture
def tls_daemon(make_daemon, pki, tmp_path):
    """A daemon with TLS and a key on loopback TCP: (daemon, key file)."""
    kf = str(tmp_path / "deformd.key")
    write_key(kf)
    d = make_daemon("key_file = %s\ntls_cert = %s\ntls_key = %s\n" % (kf, pki["cert"], pki["key"]),
                    tcp=True, tls_ca=pki["ca"])
    return d, kf


def ctl(*args, env=None):
    e = dict(os.environ)
    for k in ("DEFORMD_KEY_FILE", "DEFORMD_TLS_CA"):
        e.pop(k, None)
    e.update(env or {})
    return subprocess.run([DEFORMCTL] + list(args), capture_output=True, text=True, env=e,
                          stdin=subprocess.DEVNULL, timeout=60)


def test_python_round_trip_over_tls_with_key(tls_daemon, pki):
    d, kf = tls_daemon
    with Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=kf,
                            tls_ca=pki["ca"]) as c:
        assert isinstance(c.sock, ssl.SSLSocket) and c.sock.version() == "TLSv1.3"
        assert c.authenticated
        info = c.load_mesh(grid_obj(6, 5), name="tls")
        ack = c.stroke(info.session_id, m.Brush(type="grab", center=(0.5, 0.5, 0.0),
                                                move=(0.0, 0.0, 0.1), radius=0.4))
        over_tls = c.get_mesh(info.session_id)
    with d.unix_client() as u:
        assert u.list_sessions()[0].version == ack.version
        plain = u.get_mesh(info.session_id)
    assert list(over_tls.positions) == list(plain.positions)
    assert list(over_tls.positions) != list(obj_bytes_positions(grid_obj(6, 5)))  # it moved


def test_deformctl_and_c_library_over_tls(tls_daemon, pki, tmp_path):
    d, kf = tls_daemon
    hp = "127.0.0.1:%d" % d.tcp_port
    obj = tmp_path / "g.obj"
    obj.write_bytes(grid_obj(5, 4))
    r = ctl("--tcp", hp, "--key-file", kf, "--tls-ca", pki["ca"], "load", str(obj), "--name", "c")
    assert r.returncode == 0, r.stderr
    r = ctl("--tcp", hp, "--key-file", kf, "brush", "c", "--type", "grab", "--center",
            "0.5,0.5,0", "--move", "0,0,0.1", "--radius", "0.4",
            env={"DEFORMD_TLS_CA": pki["ca"]})
    assert r.returncode == 0, r.stderr
    out = tmp_path / "out.obj"
    r = ctl("--tcp", hp, "--key-file", kf, "--tls-ca", pki["ca"], "get", "c", "--out", str(out))
    assert r.returncode == 0, r.stderr
    ref = tmp_path / "ref.obj"
    r = ctl("--socket", d.socket_path, "get", "c", "--out", str(ref))
    assert r.returncode == 0, r.stderr
    assert out.read_bytes() == ref.read_bytes()
    with d.unix_client() as u:
        assert u.list_sessions()[0].version == 1


def test_clients_refuse_a_certificate_of_another_ca_or_name(tls_daemon, pki):
    d, kf = tls_daemon
    with pytest.raises(ssl.SSLCertVerificationError):
        Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=kf,
                           tls_ca=pki["other_ca"])
    with pytest.raises(ssl.SSLCertVerificationError):    # the certificate names localhost
        Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=kf,
                           tls_ca=pki["ca"], server_hostname="deformd.example")
    hp = "127.0.0.1:%d" % d.tcp_port
    r = ctl("--tcp", hp, "--key-file", kf, "--tls-ca", pki["other_ca"], "list")
    assert r.returncode != 0 and "certificate" in r.stderr, r.stderr
    with d.unix_client() as u:
        assert u.stats()["auth_ok"] == 0     # nothing got as far as the key


def test_plaintext_client_is_closed_and_logged_daemon_keeps_serving(tls_daemon, pki):
    d, kf = tls_daemon
    s = socket.create_connection(("127.0.0.1", d.tcp_port), timeout=30.0)
    s.sendall(fr.encode_frame(m.HELLO, m.encode_hello(1, 1, 0, "plain"), 1))
    got = b""
    while True:                              # the daemon answers with an alert at most, then EOF
        data = s.recv(65536)
        if not data:
            break
        got += data
    s.close()
    assert not got.startswith(fr.encode_frame(m.HELLO, b"", 1)[:4])   # no deformd frame
    assert "TLS handshake failed" in d.log() and "127.0.0.1" in d.log()
    with Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=kf,
                            tls_ca=pki["ca"]) as c:
        assert c.ping(b"still here") == b"still here"
    with pytest.raises(OSError):             # a Python client without TLS: closed, an error
        Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=kf)


def test_large_get_mesh_over_tls_is_byte_identical_to_unix(tls_daemon, pki):
    d, kf = tls_daemon
    with d.unix_client() as u:
        sid = u.load_mesh(grid_obj(300, 300), name="big").session_id   # 90k vertices, ~2 MB
        u.stroke(sid, m.Brush(type="grab", center=(0.3, 0.3, 0.0), move=(0.0, 0.0, 0.05),
                              radius=0.3))
        ref = [f.payload for f in u.request(m.GET_MESH, m.encode_get_mesh(sid, 0))]
    with Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=60.0, key_file=kf,
                            tls_ca=pki["ca"]) as c:
        got = [f.payload for f in c.request(m.GET_MESH, m.encode_get_mesh(sid, 0))]
    assert sum(len(p) for p in ref) > 1 << 20
    assert got == ref


def start_fails(tmp_path, *args):
    r = subprocess.run([DEFORMD, "--foreground", "--socket", str(tmp_path / "d.sock")] +
                       list(args), stdin=subprocess.DEVNULL, capture_output=True,
                       timeout=START_TIMEOUT_S, env=dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path)))
    assert r.returncode != 0
    assert not os.path.exists(tmp_path / "d.sock")
    return r.stderr.decode("utf-8", "replace")


@pytest.mark.parametrize("have", ["nothing", "key", "tls"])
def test_non_loopback_without_key_and_tls_refuses_start(tmp_path, pki, have):
    kf = str(tmp_path / "k")
    write_key(kf)
    args = ["--tcp", "0.0.0.0:0"]
    if have == "key":
        args += ["--key-file", kf]
    if have == "tls":
        args += ["--tls-cert", pki["cert"], "--tls-key", pki["key"]]
    err = start_fails(tmp_path, *args)
    assert "refusing a non-loopback address" in err, err
    assert "key_file" in err and "tls_cert/tls_key" in err, err


def test_non_loopback_with_key_and_tls_starts(make_daemon, pki, tmp_path):
    kf = str(tmp_path / "k")
    write_key(kf)
    d = make_daemon("key_file = %s\ntls_cert = %s\ntls_key = %s\ntcp = 0.0.0.0:0\n"
                    % (kf, pki["cert"], pki["key"]))
    with d.unix_client() as u:
        assert u.ping(b"up") == b"up"
    assert "refusing" not in d.log()


@pytest.mark.parametrize("case", ["world_readable", "missing", "mismatch", "not_pem", "only_cert"])
def test_bad_tls_files_refuse_start(tmp_path, pki, case):
    cert, key = pki["cert"], str(tmp_path / "k.pem")
    with open(pki["key"]) as f:
        text = f.read()
    with open(key, "w") as f:
        f.write(text)
    os.chmod(key, 0o600)
    if case == "world_readable":
        os.chmod(key, 0o644)
        needle = "can be read by others (mode 0644)"
    elif case == "missing":
        key = str(tmp_path / "nope.pem")
        needle = "No such file"
    elif case == "mismatch":
        cert = pki["other_cert"][0]
        needle = "does not match the certificate"
    elif case == "not_pem":
        with open(key, "w") as f:
            f.write("not a key\n")
        needle = "not a PEM private key"
    args = ["--tls-cert", cert] + ([] if case == "only_cert" else ["--tls-key", key])
    err = start_fails(tmp_path, *args)
    if case == "only_cert":
        assert "set both tls_cert and tls_key" in err, err
    else:
        assert needle in err and ("tls_key %s" % key) in err, err


def test_handshake_timeout_covers_the_tls_handshake(make_daemon, pki, tmp_path):
    """A peer that starts a TLS record and stops is closed by handshake_timeout_s."""
    kf = str(tmp_path / "k")
    write_key(kf)
    d = make_daemon("key_file = %s\ntls_cert = %s\ntls_key = %s\nhandshake_timeout_s = 1\n"
                    % (kf, pki["cert"], pki["key"]), tcp=True, tls_ca=pki["ca"])
    s = socket.create_connection(("127.0.0.1", d.tcp_port), timeout=30.0)
    s.sendall(b"\x16\x03\x01\x02\x00")       # a handshake record header, no body
    while s.recv(65536):                     # wait for the close (EOF), whatever comes first
        pass
    s.close()
    assert "handshake timeout" in d.log()
    with d.unix_client() as u:
        assert u.stats()["clients_handshake_timeout"] == 1

"""`make install` and the pkg-config file: install into a temporary prefix, build a program that
lives outside the repository with `cc app.c $(pkg-config --cflags --libs deformclient)`, and run
it against the real daemon (hello, ping, inline mesh upload, session list)."""
import os
import subprocess

REPO = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))

APP = r"""
#include <stdio.h>
#include <string.h>
#include <deformclient.h>

int main(int argc, char **argv)
{
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    df_client *c = NULL;
    df_error e;
    df_msg_session_info info;
    double rtt = 0;
    if (argc != 2 || df_client_connect_unix(argv[1], "install-test", &c, &e) != DF_OK) {
        fprintf(stderr, "connect: %s\n", argc == 2 ? e.msg : "usage");
        return 1;
    }
    if (df_client_ping(c, "hi", 2, &rtt, &e) != DF_OK ||
        df_client_load_mesh_bytes(c, "quad", DF_FMT_OBJ, obj, strlen(obj), 0, &info, &e) != DF_OK) {
        fprintf(stderr, "request: %s\n", e.msg);
        df_client_close(c);
        return 1;
    }
    printf("session %llu nv %u ne %u\n", (unsigned long long)info.session_id, info.nv, info.ne);
    df_client_close(c);
    return 0;
}
"""


def test_installed_client_library_builds_and_talks_to_the_daemon(daemon, tmp_path):
    prefix = tmp_path / "prefix"
    build = os.environ.get("BUILD", "build")
    # `-o all`: install what the suite's build made, never rebuild it here with other flags
    subprocess.run(["make", "-s", "-C", REPO, "-o", "all", "install", "BUILD=" + build,
                    "PREFIX=%s" % prefix], check=True, stdout=subprocess.DEVNULL)
    for rel in ["bin/deformd", "bin/deformctl", "include/deformd/deformclient.h",
                "lib/libdeformclient.a", "lib/pkgconfig/deformclient.pc",
                "lib/systemd/system/deformd.service", "lib/systemd/system/deformd.socket"]:
        assert (prefix / rel).exists(), rel
    unit = (prefix / "lib/systemd/system/deformd.service").read_text()
    assert "ExecStart=%s/bin/deformd " % prefix in unit
    # every document a unit refers to is installed where the unit says
    docs = [line.split("=", 1)[1] for u in ("deformd.service", "deformd.socket")
            for line in (prefix / "lib/systemd/system" / u).read_text().splitlines()
            if line.startswith("Documentation=")]
    assert docs, "no Documentation= line"
    for url in docs:
        for doc in url.split():
            if doc.startswith("man:"):  # man:deformd.conf(5) -> share/man/man5/deformd.conf.5
                name, sec = doc[len("man:"):].rstrip(")").split("(")
                assert (prefix / "share/man" / ("man" + sec) / ("%s.%s" % (name, sec))).is_file(), doc
                continue
            assert doc.startswith("file://%s/" % prefix), doc
            assert os.path.isfile(doc[len("file://"):]), doc
    assert (prefix / "share/doc/deformd/PROTOCOL.md").is_file()
    # only the public header and what it includes; only the libraries the client needs
    headers = sorted(str(h.relative_to(prefix / "include/deformd"))
                     for h in (prefix / "include/deformd").rglob("*.h"))
    assert "deformclient.h" in headers
    for h in headers:
        assert h == "deformclient.h" or h.startswith(("proto/", "core/common/", "core/mesh/")), h
    libs = sorted(p.name for p in (prefix / "lib").glob("*.a"))
    assert libs == ["libdeformclient.a", "libdf_common.a", "libdf_mesh.a", "libdf_proto.a"], libs

    env = dict(os.environ, PKG_CONFIG_PATH=str(prefix / "lib/pkgconfig"))
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "deformclient"], env=env,
                           check=True, capture_output=True, text=True).stdout.split()
    assert "-I%s/include/deformd" % prefix in flags
    src = tmp_path / "app.c"
    src.write_text(APP)
    exe = tmp_path / "app"
    # built away from the repository: only the installed headers and libraries are visible;
    # `make asan` sets SAN_FLAGS because the installed archives are then instrumented
    san = os.environ.get("SAN_FLAGS", "").split()
    subprocess.run(["cc", "-std=c11", "-Wall", "-Wextra", "-Werror"] + san + [str(src), "-o", str(exe)]
                   + flags, check=True, cwd=str(tmp_path))
    out = subprocess.run([str(exe), daemon.socket_path], check=True, capture_output=True,
                         text=True, timeout=30).stdout
    words = out.split()
    assert words[0] == "session" and int(words[1]) > 0, out
    assert words[2:] == ["nv", "4", "ne", "2"], out


def test_uninstall_removes_everything_install_installed(tmp_path):
    """install then uninstall into a DESTDIR: no file is left, and no directory but the prefix
    path itself; a file of someone else's in an installed directory survives."""
    dest = tmp_path / "dest"
    build = os.environ.get("BUILD", "build")
    prefix = "/usr/local"
    make = ["make", "-s", "-C", REPO, "-o", "all", "BUILD=" + build, "DESTDIR=%s" % dest,
            "PREFIX=%s" % prefix]
    subprocess.run(make + ["install"], check=True, stdout=subprocess.DEVNULL)
    installed = [p for p in dest.rglob("*") if not p.is_dir()]
    for rel in ["bin/deformd", "share/man/man8/deformd.8", "share/man/man5/deformd.conf.5",
                "share/man/man1/deformctl.1", "lib/udev/rules.d/70-deformd.rules",
                "lib/sysusers.d/deformd.conf", "lib/systemd/system/deformd.service"]:
        assert (dest / prefix.lstrip("/") / rel) in installed, rel
    subprocess.run(make + ["uninstall"], check=True, stdout=subprocess.DEVNULL)
    left = sorted(str(p.relative_to(dest)) for p in dest.rglob("*"))
    assert left == ["usr", "usr/local"], left

    keep = dest / "usr/local/bin/someone-elses-tool"
    keep.parent.mkdir(parents=True)
    keep.write_text("x")
    subprocess.run(make + ["install"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(make + ["uninstall"], check=True, stdout=subprocess.DEVNULL)
    left = sorted(str(p.relative_to(dest)) for p in dest.rglob("*"))
    assert left == ["usr", "usr/local", "usr/local/bin", "usr/local/bin/someone-elses-tool"], left

"""The Makefile's entry points as a newcomer meets them (issue 10): `make run`, the README's first
command, installs the Debian packages (target deps) before it compiles anything, as `make test`
does. Checked with a dry run (make -n) into an empty build folder: nothing is built or installed.
"""
import os
import subprocess
import tempfile

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def dry_run(target: str, build: str) -> str:
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    r = subprocess.run(["make", "-n", "-C", ROOT, target, "BUILD=" + build], env=env,
                       stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       timeout=120)
    out = r.stdout.decode("utf-8", "replace")
    assert r.returncode == 0, out[-3000:]
    return out


@pytest.mark.parametrize("target", ["run", "test"])
def test_target_installs_deps_before_compiling(target):
    with tempfile.TemporaryDirectory(prefix="deformd-make-") as build:
        out = dry_run(target, build)
    lines = out.splitlines()
    deps = [i for i, l in enumerate(lines) if "apt-get install" in l]
    compiles = [i for i, l in enumerate(lines) if " -c " in l and l.split()[0] in ("cc", "gcc")]
    assert deps, "make %s never installs the Debian packages:\n%s" % (target, out[:2000])
    assert compiles, "make -n %s compiles nothing?\n%s" % (target, out[:2000])
    assert deps[0] < compiles[0], "make %s compiles before installing the packages" % target

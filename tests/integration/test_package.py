"""The Python client is a package: client/python installs with pip from the checkout, offline
(no index, no build isolation: setuptools comes from the system), and the installed copy imports
and works on its own, with the standard library only."""
import os
import subprocess
import sys

import deformd_client

REPO = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
PKG = os.path.join(REPO, "client", "python")


def test_tests_import_the_in_tree_package():
    assert os.path.realpath(deformd_client.__file__).startswith(
        os.path.join(PKG, "deformd_client"))


def test_pip_installs_the_package_offline(tmp_path):
    target = tmp_path / "site"
    env = dict(os.environ, PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1",
               PIP_NO_CACHE_DIR="1", TMPDIR=str(tmp_path))
    env.pop("PYTHONPATH", None)
    # pip builds in a copy of the source tree so the checkout stays clean (no build/, egg-info).
    src = tmp_path / "src"
    subprocess.run(["cp", "-r", PKG, str(src)], check=True)
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index",
                        "--no-build-isolation", "--target", str(target), str(src)],
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, env=env,
                       cwd=str(tmp_path))
    assert r.returncode == 0, r.stdout + r.stderr
    mods = sorted(os.listdir(target / "deformd_client"))
    assert "client.py" in mods and "messages.py" in mods, mods
    code = ("import deformd_client, sys\n"
            "from deformd_client import Client, Brush, MeshState, messages\n"
            "print(deformd_client.__file__)\n"
            "print(int(messages.HELLO))\n"
            "bad = [m for m in sys.modules if m.split('.')[0] in ('numpy', 'pytest')]\n"
            "print(','.join(bad) or 'stdlib-only')\n")
    # -s: no user site; PYTHONPATH is the install target only (cwd is outside the checkout).
    out = subprocess.run([sys.executable, "-s", "-c", code], stdin=subprocess.DEVNULL,
                         capture_output=True, text=True, cwd=str(tmp_path),
                         env=dict(env, PYTHONPATH=str(target)))
    assert out.returncode == 0, out.stderr
    lines = out.stdout.split()
    assert lines[0].startswith(str(target)), lines
    assert lines[1] == "1"
    assert lines[2] == "stdlib-only"

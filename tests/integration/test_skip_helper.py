"""The integration suite's skip helper (conftest.skip_or_fail, issue 10): a test whose
prerequisite is missing (here the shared meshes folder) is skipped outside CI and fails under
CI=true. The probe below is run in a child pytest with MESHES pointing nowhere."""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PROBE = os.path.join(HERE, "test_skip_helper.py") + "::test_meshes_probe"


def test_meshes_probe(meshes):
    """Passes where the shared meshes are (the normal suite); the child runs below lack them."""
    assert os.path.isdir(meshes)


def run_probe(ci):
    env = dict(os.environ)
    env["MESHES"] = "/nonexistent/deformd-meshes"
    env.pop("CI", None)
    if ci is not None:
        env["CI"] = ci
    r = subprocess.run([sys.executable, "-m", "pytest", PROBE, "-q", "-rs", "-p",
                        "no:cacheprovider"], cwd=os.path.dirname(os.path.dirname(HERE)),
                       env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, timeout=120)
    return r.returncode, r.stdout.decode("utf-8", "replace")


def test_missing_meshes_skip_outside_ci():
    rc, out = run_probe(None)
    assert rc == 0, out
    assert "1 skipped" in out and "/nonexistent/deformd-meshes" in out, out
    rc, out = run_probe("false")
    assert rc == 0 and "1 skipped" in out, out


def test_missing_meshes_fail_under_ci():
    rc, out = run_probe("true")
    assert rc == 1, out
    assert ("1 failed" in out or "1 error" in out) and "skipped" not in out, out
    assert "CI=true" in out and "/nonexistent/deformd-meshes" in out, out


def run_tests_sh(tmp_path, ci, suites="unit"):
    """tests/run_tests.sh over a fake build whose one unit binary passes 2 tests and skips 1."""
    unit = tmp_path / "tests" / "unit" / "fake"
    unit.mkdir(parents=True)
    t = unit / "test_fake"
    t.write_text("#!/bin/sh\necho '[  PASSED  ] 2 test(s).'\necho '[  SKIPPED ] 1 test(s), "
                 "listed below:'\nexit 0\n")
    t.chmod(0o755)
    env = dict(os.environ, BUILD=str(tmp_path), SUITES=suites)
    env.pop("CI", None)
    if ci is not None:
        env["CI"] = ci
    root = os.path.dirname(os.path.dirname(HERE))
    r = subprocess.run(["bash", os.path.join(root, "tests", "run_tests.sh")], cwd=root, env=env,
                       stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, timeout=120)
    out = r.stdout.decode("utf-8", "replace")
    return r.returncode, out.strip().splitlines()[-1], out


def test_run_tests_counts_skips_outside_ci(tmp_path):
    rc, last, out = run_tests_sh(tmp_path, None)
    assert last == "2 passed, 0 failed, 1 skipped" and rc == 0, out


def test_run_tests_counts_skips_as_failures_under_ci(tmp_path):
    rc, last, out = run_tests_sh(tmp_path, "true")
    assert last == "2 passed, 1 failed" and rc != 0, out


def test_run_tests_fails_an_unbuilt_suite_under_ci(tmp_path):
    rc, last, out = run_tests_sh(tmp_path, "true", "unit fuzz")   # no fuzz binaries in tmp_path
    assert last == "2 passed, 2 failed" and rc != 0, out
    assert "no fuzz binaries" in out, out

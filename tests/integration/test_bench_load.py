"""Smoke run of the load and abuse bench (tests/bench/bench_load.c, issue 12) inside make test:
a few seconds, 50 well-behaved clients, 5 slowloris and 5 non-readers against a daemon with the
store on. Checks what must hold whatever the machine's speed: the bench ran to the end, no
well-behaved client was dropped or got an error reply, strokes were acknowledged, the daemon
survived and exited 0 on SIGTERM. Its latency and throughput figures are printed, never asserted
(timing lives in make bench)."""
import os
import re
import subprocess

import pytest

from conftest import BUILD, DEFORMD

BENCH = os.path.join(BUILD, "bench", "bench_load")


def figure(out, name):
    """(value, verdict) of the bench line 'name  value [unit] (target ...) ok|MISS'."""
    m = re.search(r"^\s*%s\s+([-0-9.]+)\s.*\((?:target [^)]*)\)\s+(ok|MISS)$" % re.escape(name),
                  out, re.M)
    assert m, "no '%s' line in:\n%s" % (name, out)
    return float(m.group(1)), m.group(2)


def test_bench_load_smoke():
    for exe in (BENCH, DEFORMD):
        if not os.access(exe, os.X_OK):
            pytest.fail("%s is missing: build it first (make -j2)" % exe, pytrace=False)
    env = dict(os.environ, DF_BENCH_LOAD_SECONDS="4", DF_BENCH_LOAD_CLIENTS="50",
               DF_BENCH_LOAD_ABUSERS="5", DF_BENCH_LOAD_QUEUE="64k",
               DF_BENCH_LOAD_HANDSHAKE_S="10",  # well-behaved HELLOs never race it (sanitizers)
               DEFORMD_BIN=DEFORMD)
    r = subprocess.run([BENCH], capture_output=True, text=True, timeout=300, env=env)
    out = r.stdout + r.stderr
    print(out)
    assert r.returncode == 0, out
    assert figure(out, "well-behaved clients dropped") == (0.0, "ok")
    assert figure(out, "daemon alive through the run, exits 0 on SIGTERM") == (1.0, "ok")
    m = re.search(r"strokes (\d+) .*error replies (\d+)", out)
    assert m and int(m.group(1)) > 0 and int(m.group(2)) == 0, out
    m = re.search(r"daemon STATS: .*requests_failed (\d+) .*store_errors (\d+)", out)
    assert m and m.group(1) == "0" and m.group(2) == "0", out

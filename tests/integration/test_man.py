"""The man pages (man/): deformd(8), deformd.conf(5), deformctl(1) cover what the programs
accept, taken from the sources and the real --help outputs, and render without warnings."""
import os
import re
import shutil
import subprocess

import pytest

from conftest import DEFORMCTL, DEFORMD, ROOT, skip_or_fail

PAGES = {"deformd": "server/man/deformd.8", "deformd.conf": "server/man/deformd.conf.5",
         "deformctl": "client/deformctl/deformctl.1"}  # beside their program


def page_text(name: str) -> str:
    """The page's source with roff escapes of hyphens and fonts removed."""
    with open(os.path.join(ROOT, PAGES[name])) as f:
        t = f.read()
    return re.sub(r"\\f[BIRP]", "", t).replace("\\-", "-").replace("\\&", "")


def help_of(*args) -> str:
    return subprocess.run(list(args), capture_output=True, text=True, timeout=30).stdout


def config_keys_from_source() -> set:
    """Every key df_config_set accepts: the int-key table and the strcmp(key, "...") branches of
    server/config.c, and the hid.* keys of the table in server/hid/hid_config.h."""
    with open(os.path.join(ROOT, "server", "config.c")) as f:
        src = f.read()
    keys = set(re.findall(r'\{"([a-z_]+)", offsetof\(df_server_config', src))
    keys |= set(re.findall(r'strcmp\(key, "([a-z_]+)"\) == 0', src))
    with open(os.path.join(ROOT, "server", "hid", "hid_config.h")) as f:
        hid = f.read().split("*   key ", 1)[1].split("Errors:", 1)[0]
    hid_keys = set()
    for line in hid.splitlines():
        m = re.match(r"\s*\*\s{3}([a-z_][a-z_ ,.]*?)\s+(all|knob|3d-mouse|pen|device|pen/knob)",
                     line)
        if m:
            for k in re.split(r"[ ,.]+", m.group(1)):
                if k:
                    hid_keys.add(k)
    hid_keys.discard("invert_x")  # "invert_x .. invert_rz": spelled out below
    hid_keys |= {"invert_" + a for a in ("x", "y", "z", "rx", "ry", "rz")}
    for line in hid.splitlines():  # "radius_min ... ; radius_max > 0": second keys in a row
        hid_keys |= set(re.findall(r";\s+([a-z_]+) >", line))
    return keys, hid_keys


def test_every_config_key_is_in_deformd_conf_5():
    keys, hid_keys = config_keys_from_source()
    assert len(keys) >= 25 and "log_level" in keys and "allow_paths" in keys, keys
    assert "nu_min" in hid_keys and "ffb_hz" in hid_keys and "led_max_radius" in hid_keys
    text = page_text("deformd.conf")
    documented = set(re.findall(r"^\.(?:B|BR)\s+(.*)$", text, re.M))
    words = set()
    for d in documented:
        words |= set(re.findall(r"[a-z_][a-z0-9_.]*", d))
    missing = sorted(k for k in keys | hid_keys if k not in words)
    assert not missing, "not in deformd.conf(5): %s" % missing
    # and every key named in deformd --help's --config list
    h = help_of(DEFORMD, "--help")
    listed = h.split("--config FILE", 1)[1].split("--foreground", 1)[0]
    for k in re.findall(r"\b([a-z]+_[a-z_]+|socket|tcp|threads|hid)\b", listed):
        assert k in words, k


def test_every_deformd_option_is_in_deformd_8():
    opts = set(re.findall(r"^  (?:-h, )?(--[a-z-]+)", help_of(DEFORMD, "--help"), re.M))
    assert {"--socket", "--check-config", "--hid-replay", "--help"} <= opts, opts
    text = page_text("deformd")
    for o in opts:
        assert re.search(r"^\.(?:B|BI|BR)\s+.*%s\b" % re.escape(o), text, re.M), o
    for sig in ("SIGHUP", "SIGTERM"):
        assert sig in text


def test_every_deformctl_command_and_option_is_in_deformctl_1():
    h = help_of(DEFORMCTL, "--help")
    cmds = re.findall(r"^  ([a-z][a-z-]*)\s+[A-Z]", h.split("Commands:", 1)[1].split("Global", 1)[0],
                      re.M)
    assert len(cmds) >= 15 and "devices" in cmds, cmds
    text = page_text("deformctl")
    sections = dict(re.findall(r"^\.SS (\S+)\n(.*?)(?=^\.S[SH] )", text, re.M | re.S))
    for c in cmds:
        assert c in sections, "deformctl(1) has no section for %s" % c
        ch = help_of(DEFORMCTL, c, "--help")
        opts = set(re.findall(r"^  (--[a-z0-9-]+)", ch.split("Options:", 1)[1]
                              .split("Global options", 1)[0], re.M)) - {"--help"}
        for o in opts:
            assert o in sections[c], "%s %s not in deformctl(1)" % (c, o)
    for g in ("--socket", "--tcp", "--json"):
        assert g in text


@pytest.mark.parametrize("page", sorted(PAGES))
def test_man_page_renders_without_warnings(page):
    if not shutil.which("man"):
        skip_or_fail("man (man-db) is not installed")
    env = dict(os.environ, MANWIDTH="80", LC_ALL="C.UTF-8", MAN_KEEP_FORMATTING="")
    r = subprocess.run(["man", "--warnings", "-l", os.path.join(ROOT, PAGES[page])],
                       capture_output=True, text=True, env=env, timeout=60)
    assert r.returncode == 0, r.stderr
    assert r.stderr == "", r.stderr
    assert page.split(".")[0].upper() in r.stdout

"""systemd/: the units verify (`systemd-analyze verify`), the service's sandbox rates <= 2.0
(`systemd-analyze security --offline=true`), the udev rules are well formed and grant exactly the
devices deformd drives, and deformd works under the unit's restrictions.

systemd is not PID 1 here (a container), so the service cannot run under systemd itself. What
is exercised instead, as close as this allows:
  - `test_daemon_serves_under_the_units_seccomp_filter`: deformd runs under the unit's system-call
    filter (the unit's own SystemCallFilter= lines expanded by `systemd-analyze syscall-filter`,
    SystemCallErrorNumber=EPERM, native architecture only), its RestrictAddressFamilies= (socket()
    of any other family refused) and MemoryDenyWriteExecute= (mmap W+X, mprotect/pkey_mprotect
    +X refused), NoNewPrivileges=, an empty capability bounding set and UMask=0077, loaded through
    libseccomp (python3-seccomp) before exec, and serves a workload touching every subsystem
    (HID backends and replay threads, a path load, strokes, undo, a shared-memory stream, stats,
    SIGHUP, SIGTERM);
  - `test_every_path_the_daemon_touches_is_allowed_by_the_unit`: the same workload under strace;
    every file it writes lies where the unit leaves the file system writable, every device node it
    opens is one DevicePolicy=closed + DeviceAllow= lets through, nothing under ProtectHome= and
    no /proc entry outside ProcSubset=pid is read when the unit sets it (it does not: Embree reads
    /proc/meminfo, which this test found).
Not exercised: the mount namespace itself (ProtectSystem=, PrivateTmp=, ...), the user switch
(User=deformd) and the device cgroup, which need systemd as PID 1."""
import errno
import os
import re
import shutil
import signal
import socket
import subprocess
import time

import pytest

from conftest import DEFORMD, ROOT, skip_or_fail
from deformd_client import Brush, Client
from hid_files import grid_obj

SYSTEMD = os.path.join(ROOT, "systemd")
# man pages beside their programs (Makefile MAN_PAGES), laid out as a MANPATH tree for verify
MAN_PAGES = ["server/man/deformd.8", "server/man/deformd.conf.5", "client/deformctl/deformctl.1"]
HID_DIR = os.environ.get("HID_DATA", os.path.join(ROOT, "..", "shared", "hid"))
MAX_EXPOSURE = 2.0


def need(tool: str) -> str:
    path = shutil.which(tool)
    if not path:
        skip_or_fail("%s is not installed (make deps installs it)" % tool)
    return path


def unit_lines(name: str, key: str):
    """The values of every `key=` line of systemd/<name>."""
    with open(os.path.join(SYSTEMD, name)) as f:
        return [l.split("=", 1)[1].strip() for l in f if l.startswith(key + "=")]


def units_copy(tmp_path, edit=None):
    """The units in tmp_path with ExecStart= pointing at the build's deformd (verify checks that
    the binary exists), optionally with `edit` applied to the service text."""
    with open(os.path.join(SYSTEMD, "deformd.service")) as f:
        svc = f.read().replace("/usr/local/bin/deformd", DEFORMD)
    if edit:
        svc = edit(svc)
    (tmp_path / "deformd.service").write_text(svc)
    shutil.copy(os.path.join(SYSTEMD, "deformd.socket"), tmp_path / "deformd.socket")
    return [str(tmp_path / "deformd.service"), str(tmp_path / "deformd.socket")]


def man_tree(root) -> str:
    """A MANPATH directory under root with man<section>/ links to the repo's pages."""
    for page in MAN_PAGES:
        sec = os.path.join(root, "man" + page.rsplit(".", 1)[1])
        os.makedirs(sec, exist_ok=True)
        link = os.path.join(sec, os.path.basename(page))
        if not os.path.lexists(link):
            os.symlink(os.path.join(ROOT, page), link)
    return str(root)


def verify(paths):
    # Documentation=man:... pages are looked up on MANPATH
    env = dict(os.environ, MANPATH=man_tree(os.path.join(os.path.dirname(paths[0]), "man")))
    r = subprocess.run([need("systemd-analyze"), "verify"] + paths, capture_output=True,
                       text=True, env=env, timeout=120)
    return r.returncode, (r.stdout + r.stderr).strip()


def test_units_verify(tmp_path):
    rc, out = verify(units_copy(tmp_path))
    assert rc == 0 and out == "", out
    # the check itself catches a broken unit
    bad = tmp_path / "bad"
    bad.mkdir()
    rc, out = verify(units_copy(bad, lambda s: s.replace("ProtectHome=yes", "ProtectHome=maybe")
                                .replace("[Service]", "[Service]\nExecStartPre=relative/path")))
    assert rc != 0 or out != ""


def exposure(path: str) -> float:
    r = subprocess.run([need("systemd-analyze"), "security", "--offline=true", path],
                       capture_output=True, text=True, timeout=120)
    m = re.search(r"Overall exposure level for \S+: (\d+\.\d+)", r.stdout)
    assert m, r.stdout + r.stderr
    return float(m.group(1))


def test_service_exposure_is_at_most_2(tmp_path):
    svc, _ = units_copy(tmp_path)
    score = exposure(svc)
    print("deformd.service: exposure %.1f (limit %.1f)" % (score, MAX_EXPOSURE))
    assert score <= MAX_EXPOSURE
    # the parser reads a real score: the unit without its sandbox rates far worse
    bare = tmp_path / "bare"
    bare.mkdir()
    keep = ("ExecStart=", "Type=", "[", "Description=")
    svc_bare, _ = units_copy(bare, lambda s: "\n".join(
        l for l in s.splitlines() if l.startswith(keep)) + "\n")
    assert exposure(svc_bare) > 8.0


# ---- udev rules ---------------------------------------------------------------------------
RULES = os.path.join(SYSTEMD, "70-deformd.rules")
MATCH_KEYS = {"ACTION", "SUBSYSTEM", "SUBSYSTEMS", "KERNEL", "KERNELS", "ATTR", "ATTRS", "ENV",
              "DRIVERS", "TAG"}
ASSIGN_KEYS = {"GROUP", "MODE", "OWNER", "TAG", "ENV", "GOTO", "LABEL", "RUN"}
TOKEN = re.compile(r'\s*([A-Z]+)(\{[A-Za-z0-9_]+\})?\s*(==|!=|\+=|-=|:=|=)\s*"([^"]*)"\s*(,|$)')


def parse_rules(text: str):
    """udev rules syntax (udev(7)): one rule per line of comma-separated KEY[{attr}]OP"value"
    tokens; match keys with == / !=, assignments with = += :=. Returns [(lineno, tokens)];
    raises AssertionError naming the line of a malformed token. (Debian 12's udevadm has no
    `verify`: it came in systemd 254.)"""
    rules = []
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        pos, toks = 0, []
        while pos < len(s):
            m = TOKEN.match(s, pos)
            assert m, "%s:%d: malformed token at column %d: %s" % (RULES, n, pos + 1, s[pos:])
            key, attr, op, val = m.group(1), (m.group(2) or "")[1:-1], m.group(3), m.group(4)
            if op in ("==", "!="):
                assert key in MATCH_KEYS, "%s:%d: %s is not a match key" % (RULES, n, key)
            else:
                assert key in ASSIGN_KEYS, "%s:%d: %s cannot be assigned" % (RULES, n, key)
            if key == "MODE":
                assert re.fullmatch(r"0[0-7]{3}", val), "%s:%d: MODE %s" % (RULES, n, val)
            if key in ("ATTR", "ATTRS", "ENV"):
                assert attr, "%s:%d: %s needs {name}" % (RULES, n, key)
            toks.append((key, attr, op, val))
            pos = m.end()
        rules.append((n, toks))
    return rules


def granted(rules, dev) -> bool:
    """Whether a device (dict: SUBSYSTEM, KERNELS (list of ancestor names), ATTR, ENV, ACTION)
    ends with GROUP="deformd" under the rules (fnmatch globs as udev, GOTO/LABEL honoured)."""
    from fnmatch import fnmatchcase
    group, skip_to = None, None
    for _, toks in rules:
        if skip_to:
            if any(k == "LABEL" and v == skip_to for k, _, _, v in toks):
                skip_to = None
            continue
        ok = True
        for key, attr, op, val in toks:
            if op not in ("==", "!="):
                continue
            if key == "KERNELS":
                hit = any(fnmatchcase(k, val) for k in dev["KERNELS"])
            elif key in ("ATTR", "ATTRS"):
                hit = fnmatchcase(dev.get("ATTR", {}).get(attr, ""), val)
            elif key == "ENV":
                hit = fnmatchcase(dev.get("ENV", {}).get(attr, ""), val)
            else:
                hit = fnmatchcase(dev.get(key, ""), val)
            ok = ok and (hit if op == "==" else not hit)
        if not ok:
            continue
        for key, attr, op, val in toks:
            if key == "GROUP" and op in ("=", ":="):
                group = val
            if key == "GOTO":
                skip_to = val
    return group == "deformd"


def hidraw(vid: int, pid: int, bus: int = 3):
    return {"ACTION": "add", "SUBSYSTEM": "hidraw",
            "KERNELS": ["hidraw3", "%04X:%04X:%04X.0007" % (bus, vid, pid), "1-2:1.0", "1-2"]}


def test_udev_rules_parse_and_grant_the_driven_devices_only():
    with open(RULES) as f:
        rules = parse_rules(f.read())
    groups = {v for _, t in rules for k, _, op, v in t if k == "GROUP"}
    assert groups == {"deformd"}
    with open(os.path.join(SYSTEMD, "deformd.sysusers.conf")) as f:
        sysusers = [l.split() for l in f if l.strip() and not l.startswith("#")]
    assert ["u", "deformd"] == sysusers[0][:2]  # the group the rules name exists
    assert unit_lines("deformd.service", "Group") == ["deformd"]
    assert unit_lines("deformd.socket", "SocketGroup") == ["deformd"]
    # every recorded knob, 3D mouse and force-feedback joystick (VID:PID from the file names of
    # ../shared/hid, USB and Bluetooth) is granted ...
    driven = [f for f in os.listdir(HID_DIR) if re.match(
        r"(microsoft-surface-dial|huion-keydial|huion-dial|3dconnexion|microsoft-sidewinder)", f)] \
        if os.path.isdir(HID_DIR) else []
    if not driven:
        skip_or_fail("no HID recordings at %s" % HID_DIR)
    for f in driven:
        vid, pid = (int(x, 16) for x in re.search(r"_([0-9a-f]{4})-([0-9a-f]{4})_", f).groups())
        bus = 5 if "_bt" in f else 3
        assert granted(rules, hidraw(vid, pid, bus)), f
    # ... and the PowerMate's USB device node; not its interface, not a keyboard, not a removal
    pm = {"ACTION": "add", "SUBSYSTEM": "usb", "KERNELS": ["1-3"],
          "ATTR": {"idVendor": "077d", "idProduct": "0410"}, "ENV": {"DEVTYPE": "usb_device"}}
    assert granted(rules, pm)
    assert not granted(rules, dict(pm, ENV={"DEVTYPE": "usb_interface"}))
    assert not granted(rules, hidraw(0x046D, 0xC31C))  # a Logitech keyboard
    assert not granted(rules, hidraw(0x1B96, 0x1000))  # a touchscreen's pen: commented out
    assert not granted(rules, dict(hidraw(0x045E, 0x091B), ACTION="remove"))
    with pytest.raises(AssertionError):
        parse_rules('SUBSYSTEM=="hidraw", GROUP=="deformd"\n')  # a match on an assignment key


# ---- the daemon under the unit's restrictions --------------------------------------------
def syscall_group(name: str, cache={}) -> set:
    if name not in cache:
        out = subprocess.run([need("systemd-analyze"), "syscall-filter", name],
                             capture_output=True, text=True, check=True, timeout=60).stdout
        calls = set()
        for line in out.splitlines()[1:]:
            t = line.strip()
            if t and not t.startswith("#"):
                calls |= syscall_group(t) if t.startswith("@") else {t}
        cache[name] = calls
    return cache[name]


def unit_syscalls() -> set:
    """The allow list the unit's SystemCallFilter= lines give (systemd.exec(5): the first line
    is an allow list, so @default is added; ~ lines remove, later plain lines add)."""
    allow = None
    for v in unit_lines("deformd.service", "SystemCallFilter"):
        deny = v.startswith("~")
        names = set()
        for item in v.lstrip("~").split():
            names |= syscall_group(item) if item.startswith("@") else {item}
        if allow is None:
            assert not deny
            allow = names | syscall_group("@default")
        elif deny:
            allow -= names
        else:
            allow |= names
    return allow


def sandbox_preexec():
    """Returns a preexec_fn installing the unit's restrictions in the child before exec."""
    try:
        import seccomp
    except ImportError:
        skip_or_fail("python3-seccomp is not installed (make deps installs it)")
    assert unit_lines("deformd.service", "SystemCallErrorNumber") == ["EPERM"]
    assert unit_lines("deformd.service", "SystemCallArchitectures") == ["native"]
    assert unit_lines("deformd.service", "MemoryDenyWriteExecute") == ["yes"]
    assert unit_lines("deformd.service", "CapabilityBoundingSet") == [""]
    fams = unit_lines("deformd.service", "RestrictAddressFamilies")[0].split()
    umask = int(unit_lines("deformd.service", "UMask")[0], 8)
    allow = unit_syscalls()
    filt = seccomp.SyscallFilter(defaction=seccomp.ERRNO(errno.EPERM))
    special = {"socket", "mmap", "mprotect", "pkey_mprotect", "shmat"}
    for name in sorted(allow - special):
        try:
            filt.add_rule(seccomp.ALLOW, name)
        except Exception:  # not a system call of this architecture (e.g. chown32)
            pass
    for fam in fams:
        filt.add_rule(seccomp.ALLOW, "socket", seccomp.Arg(0, seccomp.EQ, getattr(socket, fam)))
    prot_w, prot_x, shm_exec = 0x2, 0x4, 0o100000
    if "mmap" in allow:
        filt.add_rule(seccomp.ALLOW, "mmap", seccomp.Arg(2, seccomp.MASKED_EQ, prot_x, 0))
        filt.add_rule(seccomp.ALLOW, "mmap", seccomp.Arg(2, seccomp.MASKED_EQ, prot_w, 0))
    for name in ("mprotect", "pkey_mprotect"):
        if name in allow:
            filt.add_rule(seccomp.ALLOW, name, seccomp.Arg(2, seccomp.MASKED_EQ, prot_x, 0))
    if "shmat" in allow:
        filt.add_rule(seccomp.ALLOW, "shmat", seccomp.Arg(2, seccomp.MASKED_EQ, shm_exec, 0))
    import ctypes
    libc = ctypes.CDLL(None, use_errno=True)

    def preexec():
        os.umask(umask)
        if os.geteuid() == 0:  # CapabilityBoundingSet= (empty): exec then grants nothing
            for cap in range(64):
                if libc.prctl(24, cap, 0, 0, 0) != 0 and ctypes.get_errno() == errno.EINVAL:
                    break  # PR_CAPBSET_DROP: past the last capability
        filt.load()  # sets NoNewPrivileges (libseccomp's default)
    return preexec


def workload_env(tmp_path):
    """The daemon's environment. Under `make asan`, LeakSanitizer cannot run under strace
    (ptrace) or the unit's system-call filter (its exit-time scan dies with a fatal error), so
    leak detection is off for these two sandbox runs only; every other test still checks leaks."""
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path / "run"))
    env["ASAN_OPTIONS"] = ":".join(filter(None, [env.get("ASAN_OPTIONS", ""), "detect_leaks=0"]))
    return env


def workload(tmp_path, wrap=None, preexec=None):
    """Starts deformd (optionally under `wrap` + argv, with `preexec`), runs requests touching
    every subsystem, SIGHUP, SIGTERM; returns (exit status, log)."""
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    (meshes / "grid.obj").write_bytes(grid_obj(8, 1.5))  # 81 vertices over [-1.5, 1.5]^2
    # a knob and a pen (whose strokes need Embree's ray cast onto the mesh)
    replay = ",".join(os.path.join(HID_DIR, f) for f in (
        "microsoft-surface-dial_045e-091b_bt.hid", "ntrig-duosense-pen_1b96-1000_usb.hid"))
    if not all(os.path.isfile(f) for f in replay.split(",")):
        skip_or_fail("no HID recordings at %s" % HID_DIR)
    conf = tmp_path / "deformd.conf"
    conf.write_text("allow_paths = %s\nhid = on\nhid_replay = %s\nhid_replay_speed = 0\n"
                    "hid_replay_end = hold\nlog_level = debug\n" % (meshes, replay))
    sock = str(tmp_path / "run" / "deformd.sock")
    os.mkdir(tmp_path / "run")
    log_path = tmp_path / "deformd.log"
    argv = (wrap or []) + [DEFORMD, "--foreground", "--config", str(conf), "--socket", sock]
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, preexec_fn=preexec,
                                env=workload_env(tmp_path))
    try:
        deadline = time.monotonic() + 30
        while "listening on" not in log_path.read_text(errors="replace"):
            assert proc.poll() is None, log_path.read_text(errors="replace")
            assert time.monotonic() < deadline, log_path.read_text(errors="replace")
            time.sleep(0.02)
        with Client.connect_unix(sock, timeout=60) as c:
            assert c.ping(b"sandbox") == b"sandbox"
            info = c.load_mesh(path=str(meshes / "grid.obj"), fmt=".obj")
            sid = info.session_id
            pen = [x for x in c.devices_list() if x.class_name == "pen"]
            assert len(pen) == 1, pen
            ident = [1.0 if i % 5 == 0 else 0.0 for i in range(16)]  # orthographic, [-1, 1]^2
            c.device_view(pen[0].device_id, sid, ident, [0, 0, 960, 720])
            c.subscribe(sid)  # starts the replays
            shm = c.stream_shm(sid)
            assert shm is not None
            deadline = time.monotonic() + 60  # the pen's first stroke: a ray hit the mesh
            while c.stats(pen[0].device_id)["strokes_ended"] < 1:
                assert time.monotonic() < deadline, c.stats(pen[0].device_id)
                time.sleep(0.02)
            # a second session (the pen stays on the first, its view's): strokes, undo, handles
            sid2 = c.load_mesh(grid_obj(8, 1.5), fmt=".obj").session_id
            c.stroke(sid2, Brush(center=(0.5, 0.5, 0.0), move=(0.0, 0.0, 0.05), radius=0.3))
            c.undo(sid2)
            c.redo(sid2)
            c.set_handles(sid2, [0, 8, 40, 72, 80])  # ADMM: CHOLMOD, OpenBLAS, OpenMP
            res = c.move_handles(sid2, [(-1.5, -1.5, 0), (1.5, -1.5, 0), (0, 0, 0.3),
                                       (-1.5, 1.5, 0), (1.5, 1.5, 0)], max_iters=50)
            assert res is not None
            stats = c.stats()
            assert stats, "no stats"
            devs = c.devices_list()
            assert any(d.vid == 0x045E and d.pid == 0x091B for d in devs), devs
            c.close_session(sid)
        target = proc.pid
        if wrap:  # signal deformd, not the wrapper (strace)
            with open("/proc/%d/task/%d/children" % (proc.pid, proc.pid)) as f:
                target = int(f.read().split()[0])
        at = len(log_path.read_text(errors="replace"))
        os.kill(target, signal.SIGHUP)
        deadline = time.monotonic() + 30
        while "configuration reloaded" not in log_path.read_text(errors="replace")[at:]:
            assert time.monotonic() < deadline and proc.poll() is None, log_path.read_text()
            time.sleep(0.02)
        os.kill(target, signal.SIGTERM)
        rc = proc.wait(60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return rc, log_path.read_text(errors="replace")


def test_daemon_serves_under_the_units_seccomp_filter(tmp_path):
    rc, log = workload(tmp_path, preexec=sandbox_preexec())
    assert rc == 0, log[-4000:]
    for bad in ("Operation not permitted", "Bad system call", "[error]"):
        assert bad not in log, log[-4000:]


def test_the_filter_is_in_force(tmp_path):
    """The sandbox of the test above refuses what the unit refuses (so that test can fail): a
    child under it cannot open an AF_PACKET socket, map W+X memory or call a @privileged call."""
    code = ("import socket, mmap, os, errno\n"
            "try:\n socket.socket(socket.AF_PACKET, socket.SOCK_RAW); print('packet ok')\n"
            "except OSError as e: print('packet', e.errno)\n"
            "try:\n mmap.mmap(-1, 4096, prot=mmap.PROT_READ|mmap.PROT_WRITE|mmap.PROT_EXEC);"
            " print('wx ok')\n"
            "except OSError as e: print('wx', e.errno)\n"
            "try:\n os.setuid(os.getuid()); print('setuid ok')\n"
            "except OSError as e: print('setuid', e.errno)\n"
            "s = socket.socket(socket.AF_UNIX); print('unix ok')\n")
    r = subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True,
                       preexec_fn=sandbox_preexec(), timeout=60)
    lines = r.stdout.split("\n")
    assert lines[:4] == ["packet %d" % errno.EPERM, "wx %d" % errno.EPERM,
                         "setuid %d" % errno.EPERM, "unix ok"], r.stdout + r.stderr


STRACE_CALLS = "open,openat,openat2,creat,mkdir,mkdirat,unlink,unlinkat,rename,renameat," \
               "renameat2,truncate,chmod,fchmodat,mknod,mknodat,link,linkat,symlink,symlinkat," \
               "bind,access,faccessat,faccessat2,stat,lstat,newfstatat,statx,readlink,readlinkat"
WRITE_FLAGS = ("O_WRONLY", "O_RDWR", "O_CREAT", "O_TRUNC")
WRITE_CALLS = ("creat", "mkdir", "mkdirat", "unlink", "unlinkat", "rename", "renameat",
               "renameat2", "truncate", "chmod", "fchmodat", "mknod", "mknodat", "link",
               "linkat", "symlink", "symlinkat", "bind")
# DevicePolicy=closed: the pseudo devices systemd always allows (systemd.resource-control(5))
CLOSED_POLICY_DEVICES = ("/dev/null", "/dev/zero", "/dev/full", "/dev/random", "/dev/urandom",
                         "/dev/tty", "/dev/ptmx", "/dev/pts/")


def test_every_path_the_daemon_touches_is_allowed_by_the_unit(tmp_path):
    need("strace")
    trace = tmp_path / "strace.txt"
    rc, log = workload(tmp_path, wrap=["strace", "-f", "-qq", "-o", str(trace), "-e",
                                       "trace=" + STRACE_CALLS, "-e", "signal=none"])
    assert rc == 0, log[-4000:]
    calls = 0
    # the unit's writable places: RuntimeDirectory= (here: the test's run dir standing for
    # /run/deformd), StateDirectory=, PrivateTmp='s /tmp, /dev/shm (POSIX shared memory)
    run_dir = str(tmp_path / "run") + "/"
    writable = (run_dir, "/var/lib/deformd/", "/dev/shm/", "/tmp/")
    shm_dir = ("/dev/shm/", "/dev/shm")  # a file system, not a device node
    devices = tuple(p for p in CLOSED_POLICY_DEVICES)
    allow_dev = unit_lines("deformd.service", "DeviceAllow")
    assert sorted(allow_dev) == ["char-hidraw rw", "char-usb_device rw"], allow_dev
    devices += ("/dev/hidraw", "/dev/bus/usb/")
    proc_subset_pid = unit_lines("deformd.service", "ProcSubset") == ["pid"]
    problems = []
    for line in trace.read_text().splitlines():
        m = re.match(r'\d+\s+(\w+)\((?:AT_FDCWD|\d+|-\d+),?\s*"([^"]*)"(.*)\)\s+=\s+(-?\d+)',
                     line) or re.match(r'\d+\s+(\w+)\("([^"]*)"(.*)\)\s+=\s+(-?\d+)', line)
        if not m:
            m2 = re.match(r'\d+\s+bind\(\d+, \{sa_family=AF_UNIX, sun_path="([^"]*)"\}.*=\s+0',
                          line)
            if m2:
                calls += 1
                if not m2.group(1).startswith(writable):
                    problems.append("bind outside writable paths: " + line)
            continue
        call, path, rest, ret = m.groups()
        calls += 1
        if not path.startswith("/"):
            continue  # relative to a descriptor already checked, or "" (AT_EMPTY_PATH)
        writes = call in WRITE_CALLS or any(f in rest for f in WRITE_FLAGS)
        if path.startswith(("/home/", "/root/", "/run/user/")):
            problems.append("ProtectHome= hides it: " + line)
        if proc_subset_pid and path.startswith("/proc/") and not re.match(r"/proc/(self|thread-self|\d+)(/|$)",
                                                        path):
            if int(ret) >= 0:
                problems.append("ProcSubset=pid hides it: " + line)
        if path.startswith("/dev/") and not path.startswith(shm_dir) and call.startswith(
                "open") and int(ret) >= 0 and not path.startswith(devices):
            problems.append("DevicePolicy=closed refuses it: " + line)
        if writes and int(ret) >= 0 and not path.startswith(writable) and not (
                path.startswith("/dev/") and path.startswith(devices)):
            problems.append("read-only under ProtectSystem=strict: " + line)
    assert calls > 50, trace.read_text()[:3000]
    assert not problems, "\n".join(problems)


def test_socket_activation_with_systemd_socket_activate(tmp_path):
    """deformd.socket's job done by systemd-socket-activate: it listens, starts deformd (the
    unit's ExecStart options) on the first connection and passes the socket in LISTEN_FDS;
    deformd serves on it, reports READY=1 / STOPPING=1 on $NOTIFY_SOCKET, and leaves the
    socket file (systemd's) in place when it stops."""
    tool = need("systemd-socket-activate")
    sock = str(tmp_path / "deformd.sock")
    conf = tmp_path / "deformd.conf"
    conf.write_text("log_level = info\n")
    notify_path = str(tmp_path / "notify")
    notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    notify.bind(notify_path)
    notify.settimeout(30)
    exec_start = unit_lines("deformd.service", "ExecStart")[0].split()
    assert exec_start[1:3] == ["--foreground", "--config"], exec_start
    log_path = tmp_path / "deformd.log"
    with open(log_path, "wb") as log:
        # the store in this test's own directory (systemd-socket-activate passes on only the
        # -E variables: without it deformd would open the user's default store)
        proc = subprocess.Popen([tool, "-l", sock, "-E", "NOTIFY_SOCKET=" + notify_path,
                                 "-E", "XDG_STATE_HOME=" + str(tmp_path / "state"), DEFORMD,
                                 "--foreground", "--config", str(conf), "--socket", "none"],
                                stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while not os.path.exists(sock):  # systemd-socket-activate listening
            assert proc.poll() is None and time.monotonic() < deadline, log_path.read_text()
            time.sleep(0.02)
        with Client.connect_unix(sock, timeout=60) as c:  # starts deformd
            assert c.ping(b"activated") == b"activated"
        assert notify.recv(4096) == b"READY=1"
        text = log_path.read_text()
        assert "using socket-activated fd" in text and "listening on unix:%s" % sock in text, text
        proc.send_signal(signal.SIGTERM)  # it exec'd deformd: this is deformd now
        assert proc.wait(60) == 0, log_path.read_text()
        assert notify.recv(4096) == b"STOPPING=1"
        assert os.path.exists(sock)  # not deformd's to remove
    finally:
        notify.close()
        if proc.poll() is None:
            proc.kill()
            proc.wait()

"""Helpers of the Blender-side test scripts (run inside Blender by tests/integration/
test_blender.py): arguments after `--`, installing and enabling the add-on from the built zip,
a test mesh, positions as numpy, a second user's client (the vendored Python client), waiting on
the add-on's socket (select, never a sleep) and reports raised by operators."""
import argparse
import json
import select
import sys

import addon_utils
import bpy
import numpy as np

ADDON = "deformd_blender"


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--zip", required=True)
    p.add_argument("--case", default="")
    p.add_argument("--socket", default="")
    p.add_argument("--out", default="")
    p.add_argument("--daemon-pid", type=int, default=0)
    p.add_argument("--tcp", default="")          # HOST:PORT of the daemon's TLS + key TCP
    p.add_argument("--key-file", default="")
    p.add_argument("--tls-ca", default="")
    p.add_argument("--wrong-key-file", default="")
    return p.parse_args(argv)


def install(zip_path):
    """Installs the zip into the (temporary) user scripts folder and enables it: the add-on
    module, as an artist would get it."""
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    mod = addon_utils.enable(ADDON, default_set=True, handle_error=_raise)
    assert mod is not None, "the add-on did not enable"
    return mod


def _raise(exc):
    raise exc


def disable():
    addon_utils.disable(ADDON, default_set=True, handle_error=_raise)


def grid_object(name="grid", n=24, size=2.0):
    """A displaced n x n grid (not planar), rotated and scaled: object space != world space."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n, y_subdivisions=n, size=size)
    obj = bpy.context.active_object
    obj.name = name
    co = positions(obj)
    co[:, 2] = (0.1 * np.sin(3 * co[:, 0] + 2 * co[:, 1])).astype(np.float32)
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    obj.rotation_euler = (0.3, 0.0, 0.7)
    obj.scale = (2.0, 2.0, 2.0)
    return obj


def positions(obj):
    out = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)


def client(mod, path):
    """A second user: the vendored Python client on the same daemon."""
    return mod.deformd_client.Client.connect_unix(path, timeout=10.0, name="second-user")


def daemon_positions(c2, sid):
    return np.frombuffer(c2.get_mesh(sid).positions, dtype=np.float32).reshape(-1, 3)


def state(mod):
    return mod.connection.STATE


def sync_until(mod, sid, version):
    """deformd.sync (the timer's code) until session `sid` is at `version`, waiting on the
    add-on's socket in between."""
    st = state(mod)
    while st.mirrors[sid].version < version:
        wait_readable(st.client, "version %d" % version)
        bpy.ops.deformd.sync()


def wait_readable(c, what):
    """Returns when client c has something to poll: events it already queued (a blocking
    request of the add-on reads events too) or data on its socket."""
    if c.pending_events():
        return
    r, _, _ = select.select([c.sock], [], [], 10.0)
    assert r, "%s did not arrive within 10 s" % what


def report_of(op, **kw):
    """Runs an operator that must fail with a report; returns the report text."""
    try:
        op(**kw)
    except RuntimeError as e:
        text = str(e)
        assert "Traceback" not in text and "Python:" not in text, text
        assert text.startswith("Error: "), text
        return text[len("Error: "):].strip()
    raise AssertionError("%s did not report an error" % op.idname_py())


def write_out(path, **data):
    if path:
        with open(path, "w") as f:
            json.dump(data, f)

"""Add-on preferences: where the daemon is, its key, the large-mesh overlay threshold."""
import bpy

ADDON = __name__.split(".")[0]


class DeformdPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON

    address: bpy.props.StringProperty(
        name="Daemon address", default="unix:/run/user/1000/deformd.sock",
        description="unix:PATH (the daemon's socket) or HOST:PORT (TCP)")
    key_file: bpy.props.StringProperty(
        name="Key file", default="", subtype="FILE_PATH",
        description="Shared key for a daemon that requires authentication (TCP); empty: none")
    tls_ca: bpy.props.StringProperty(
        name="TLS CA", default="", subtype="FILE_PATH",
        description="PEM file of the CA that signed the daemon's tls_cert: TCP goes over TLS "
                    "1.3, the certificate must name the host; empty: plain TCP")
    overlay_threshold: bpy.props.IntProperty(
        name="Overlay above (vertices)", default=300000, min=0,
        description="Meshes with more vertices show live strokes as a GPU point overlay and "
                    "write the mesh when the stream pauses (and at most every Write interval)")
    write_interval: bpy.props.FloatProperty(
        name="Write interval (s)", default=0.5, min=0.0, soft_max=5.0,
        description="Overlay mode: write the mesh at least this often during a long stroke")
    brush_pixels: bpy.props.IntProperty(
        name="Brush size (px)", default=60, min=2, max=2000,
        description="Sculpt operator: the brush radius on screen, unprojected at the hit depth")
    twist_per_pixel: bpy.props.FloatProperty(
        name="Twist per pixel (rad)", default=0.01, min=0.0001, max=1.0)

    def draw(self, context):
        col = self.layout.column()
        for p in ("address", "key_file", "tls_ca", "overlay_threshold", "write_interval", "brush_pixels",
                  "twist_per_pixel"):
            col.prop(self, p)


def get(context=None):
    """This add-on's preferences (defaults object when the add-on is loaded unregistered)."""
    ctx = context or bpy.context
    addon = ctx.preferences.addons.get(ADDON)
    return addon.preferences if addon is not None else None


CLASSES = (DeformdPreferences,)

"""Writes userpref.blend with the splash screen off into $BLENDER_USER_CONFIG (run headless
before the GUI test, so that the GUI Blender starts straight into the 3D view)."""
import bpy

bpy.context.preferences.view.show_splash = False
bpy.context.preferences.use_preferences_save = False
bpy.ops.wm.save_userpref()
print("bl_userpref: saved")

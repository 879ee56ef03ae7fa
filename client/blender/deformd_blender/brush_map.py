"""Blender's Elastic Deform brush -> the session brush (Kelvinlets: both implement de Goes & James
2017, so the settings correspond where the brush models are the same).

Blender elastic_deform_type    deformd brush          falloff   ratio
  GRAB                          grab                   1         (2)
  GRAB_BISCALE                  grab                   2         2   (Blender's radii r, 2r)
  GRAB_TRISCALE                 grab                   3         2   (r, 2r, 4r)
  SCALE                         scale                  1
  TWIST                         twist                  1
elastic_deform_volume_preservation -> nu, clamped to 0.5 (Blender allows up to 0.9; nu > 0.5 is
not an elastic material and the daemon refuses it). Brush strength -> strength. Blender's brush
radius is in pixels: the sculpt operator unprojects it at the hit depth (radius is per stroke).
No counterpart: the brush curve / falloff shape, the texture, dyntopo, symmetry options other
than one mirror plane, auto-masking, the pen-pressure toggles (strength stays constant).
"""
from typing import Dict

NU_MAX = 0.5
ELASTIC_TYPES = {
    "GRAB": ("grab", 1), "GRAB_BISCALE": ("grab", 2), "GRAB_TRISCALE": ("grab", 3),
    "SCALE": ("scale", 1), "TWIST": ("twist", 1),
}
MULTISCALE_RATIO = 2.0


def from_elastic(deform_type: str, volume_preservation: float, strength: float) -> Dict:
    """Session brush fields for an Elastic Deform setting; ValueError for an unknown type."""
    if deform_type not in ELASTIC_TYPES:
        raise ValueError("elastic deform type %r has no deformd brush (known: %s)"
                         % (deform_type, ", ".join(sorted(ELASTIC_TYPES))))
    btype, falloff = ELASTIC_TYPES[deform_type]
    out = {"type": btype, "falloff": falloff, "nu": min(float(volume_preservation), NU_MAX),
           "strength": float(strength)}
    if falloff > 1:
        out["ratio"] = MULTISCALE_RATIO
    return out


def from_brush(brush) -> Dict:
    """from_elastic for a bpy Brush (sculpt_tool 'ELASTIC_DEFORM'); ValueError for another
    tool."""
    if getattr(brush, "sculpt_tool", "") != "ELASTIC_DEFORM":
        raise ValueError("brush %r is not an Elastic Deform brush" % getattr(brush, "name", "?"))
    return from_elastic(brush.elastic_deform_type, brush.elastic_deform_volume_preservation,
                        brush.strength)

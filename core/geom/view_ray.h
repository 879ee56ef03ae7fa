/* view_ray.h — a viewport pixel to a ray in mesh space (the pen's ray, issue 11).
 *
 * A DCC publishes its view as DEVICE_VIEW (PROTOCOL.md): view_proj, a row-major 4x4 matrix taking
 * mesh (object) coordinates to clip coordinates in the OpenGL convention (column vectors:
 * clip = M * (x, y, z, 1), clip z in [-w, w], NDC = clip / w, NDC x right, y up, z -1 at the near
 * plane), and viewport {x, y, width, height} in pixels with y growing down from the top of the
 * window (window systems' convention, not glViewport's bottom-left origin). Pure math, any
 * thread. */
#ifndef DF_GEOM_VIEW_RAY_H
#define DF_GEOM_VIEW_RAY_H

#include "core/common/df_error.h"

/* The ray through the window point (px, py) (continuous pixel coordinates: the centre of pixel
 * column i is i + 0.5; the viewport spans [x, x + width] x [y, y + height]; points outside it are
 * allowed and extrapolate): org = the point on the near plane (NDC z = -1) that projects to
 * (px, py), dir = the unit vector from it towards the points behind it (NDC z increasing), both in
 * mesh space, through the inverse of view_proj (computed in double). Works for perspective and
 * orthographic projections (also an infinite far plane). Errors: DF_EINVAL (NULL, a non-finite
 * input, width or height <= 0, view_proj singular or ill-conditioned (|det| below 1e-12 of its
 * rows' norm product), or (px, py) mapping to a point at infinity): org and dir untouched. */
int df_view_ray(const double view_proj[16], const double viewport[4], double px, double py,
                double org[3], double dir[3], df_error *err);

/* A pen's normalized position (nx, ny: 0..1 of its logical X / Y range, y down like the tablet's)
 * onto the viewport: px = x + nx width, py = y + ny height. Errors: DF_EINVAL (NULL, non-finite,
 * width or height <= 0); outputs untouched. */
int df_view_pen_pixel(const double viewport[4], double nx, double ny, double *px, double *py,
                      df_error *err);

/* The inverse of the row-major 4x4 matrix m into inv (double, adjugate / determinant). Returns
 * DF_OK, or DF_EINVAL when m has a non-finite entry or is singular / ill-conditioned (|det| below
 * 1e-12 times the product of its rows' Euclidean norms); inv untouched then. No df_error: callers
 * word the message. */
int df_mat4_inverse(const double m[16], double inv[16]);

#endif

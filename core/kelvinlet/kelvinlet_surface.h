/* kelvinlet_surface.h — surface-aware brushes: a Kelvinlet field attenuated by the distance
 * along the mesh from the brush centre (the paper's stated limitation: a grab on one finger
 * moves the next, which is close in space but far along the surface).
 *
 * Weight of vertex v (positions x, brush centre c, radius eps, falloff order n):
 *   g_v = (|c - x_s| + dist(s, v)) / SLACK   s: the vertex nearest to c, dist along the mesh
 *                                            edges (core/mesh/geodesic.h)
 *   r_v = |x_v - c|
 *   a_v = min(1, ((r_v^2 + eps^2) / (g_v^2 + eps^2))^(p/2)),  p = 2n - 1
 * SLACK = sqrt(2) absorbs the edge graph's own detour (a path along edges is up to sqrt(2)
 * longer than the straight line on a grid triangulated along one diagonal), so a flat or
 * gently curved sheet is not attenuated; a surface detour beyond that is.
 * I.e. the field's far-field decay (1/r for order 1, 1/r^3 for order 2, ...) re-taken at the
 * geodesic instead of the straight-line distance. a_v = 1 where the surface path is the
 * straight line (the brush acts as without the option), a_v = 0 exactly on parts not
 * connected to s (their displacement is exactly zero: they stay at rest bit for bit), and in
 * between a_v falls as the surface detour grows. The weights depend only on positions, centre,
 * radius and order: computing them once per stroke start (per session and centre vertex in the
 * daemon) and multiplying each displacement keeps strokes deterministic. */
#ifndef DF_KELVINLET_SURFACE_H
#define DF_KELVINLET_SURFACE_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_KELVINLET_SURFACE_SLACK 1.4142135623730951  /* edge-path / straight-line allowance */

/* Attenuation weights (above). In: xyz (nv x 3 positions), dist[nv] (edge-graph distances from
 * vertex src, INFINITY where unreachable: df_mesh_geodesic_from), src, centre[3], radius > 0,
 * order in [1, DF_KELVINLET_MAX_ORDER]. Out: w[nv] in [0, 1] (float32: what multiplies the
 * float32 displacements). Errors: DF_EINVAL (NULL, nv <= 0, src out of range, radius or order
 * out of range, non-finite centre); w untouched on error. Any thread. */
int df_kelvinlet_surface_weights(const double *xyz, int32_t nv, const double *dist, int32_t src,
                                 const double *centre, double radius, int order, float *w,
                                 df_error *err);

/* disp[3 v + k] *= w[v] for nv vertices (in place; a weight of 0 gives exactly +0 motion,
 * a weight of 1 leaves the bits unchanged). */
void df_kelvinlet_surface_mask(float *disp, const float *w, size_t nv);

#endif

/* hid_pen_target.h — where a pen points on a session's surface (issue 11, pens).
 *
 * A per-session cache for the pen's ray cast: the session's surface faces (a triangle mesh's
 * triangles, a tet mesh's boundary triangles) in an Embree scene (core/geom/raycast.h), built on
 * the first query and refitted whenever the session's version differs from the one it was last
 * fitted to. The pen's normalized position becomes a pixel of the view a client published
 * (DEVICE_VIEW: view_proj + viewport), that pixel a ray (core/geom/view_ray.h), the ray's nearest
 * hit the brush centre.
 *
 * Thread: loop thread only (it reads s->cur, which only the loop's commit writes); starts no
 * threads (Embree runs single-threaded, see raycast.h). One cache per session; free it before the
 * session's mesh goes away. Memory: a double and a float copy of the positions plus Embree's BVH,
 * not charged to the memory budget. Cost (bench_raycast, ~140k vertices): the first query builds
 * the scene on the calling thread (~100 ms), a changed version refits it (~3 ms), a cast is well
 * under 1 us. */
#ifndef DF_SERVER_HID_PEN_TARGET_H
#define DF_SERVER_HID_PEN_TARGET_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

typedef struct df_pen_cache df_pen_cache;

/* Makes an (empty: no scene yet) cache for the topology of `mesh` (kind, nv, elements; mesh->V is
 * not read). Triangle meshes use their triangles (2D meshes too: they lie in z = 0), tet meshes
 * their boundary (computed here). Errors: DF_EINVAL (NULL, an invalid mesh), DF_EUNSUPPORTED (a
 * polyline: "a polyline session has no surface for a pen to point at"; or no surface faces),
 * DF_ENOMEM. On success *out owns the cache (df_pen_cache_free); the mesh is not kept. */
int df_pen_cache_create(const df_mesh *mesh, df_pen_cache **out, df_error *err);

/* Casts the pen at (nx, ny) (normalized 0..1 of its X / Y range, y down) through the view
 * (view_proj row-major 4x4 mesh -> clip, OpenGL; viewport x, y, width, height in pixels, y down:
 * see core/geom/view_ray.h) onto the surface at positions `pos` (the session's current positions,
 * nv x 3 with nv the mesh's, double) of session version `version`. The first call builds the
 * scene, later calls refit it when `version` differs from the last fitted one (same version: the
 * positions are assumed unchanged and not read). Returns 1 with center = the nearest hit (mesh
 * coordinates), 0 when the ray misses the surface (center untouched), or a negative DF_E* code:
 * DF_EINVAL (NULL, a non-finite view/viewport/nx/ny, width or height <= 0, singular view_proj;
 * a non-finite position), DF_EINTERNAL / DF_ENOMEM (Embree), with nothing changed. */
int df_pen_target(df_pen_cache *pc, const double *pos, uint64_t version,
                  const double view_proj[16], const double viewport[4], double nx, double ny,
                  double center[3], df_error *err);

/* Checks a view a client publishes for a pen (DEVICE_VIEW) before it is stored: the ray through
 * the viewport's centre must exist (core/geom/view_ray.h's rules: finite, width and height > 0,
 * view_proj invertible). DF_OK, or DF_EINVAL with view_ray's reason ("... singular ..."). Pure. */
int df_pen_view_check(const double view_proj[16], const double viewport[4], df_error *err);

/* Releases the cache and its scene; NULL-safe. */
void df_pen_cache_free(df_pen_cache *pc);

#endif

/* raycast.h — nearest ray / triangle-mesh hit through Embree 3 (the pen's ray cast, issue 11).
 *
 * A df_raycast holds an Embree scene of one triangle mesh. Embree works in float32: the double
 * positions are converted once per create/refit (every coordinate must be finite and within
 * float range). The topology (the faces) is fixed at create; df_raycast_refit moves the
 * vertices and refits the BVH (geometry build quality RTC_BUILD_QUALITY_REFIT in a dynamic,
 * compact scene) instead of rebuilding it. Triangle meshes in 3D and 2D (z = 0) work as they
 * are; for a tet mesh pass its boundary faces (df_mesh_boundary_faces, core/mesh/operators.h);
 * polylines have no surface.
 *
 * Threads: core starts no threads of its own (OpenMP inside kernels only). Embree 3 (Debian's
 * build uses TBB tasking) is configured with "threads=1,user_threads=1,start_threads=0,
 * set_affinity=0": every BVH build and refit runs on the thread that calls df_raycast_create /
 * df_raycast_refit, in a TBB arena of one slot, so no worker thread is ever started
 * (tests/unit/geom/test_raycast.c checks that the process's thread count does not grow over
 * builds, refits and frees). Embree enforces the count with a process-wide
 * tbb::global_control, which caps any other TBB user in the process too (deformd has none).
 *
 * Device: one Embree device for the process, made on the first df_raycast_create (pthread_once)
 * and never released: releasing Embree's last device makes TBB start a thread (measured with
 * Debian's Embree 3.13 / oneTBB 2021.8), which would break the promise above, and a device per
 * object would release one with every df_raycast_free. It stays reachable until exit (leak
 * checkers do not report it). Embree errors are collected per calling thread (thread-local), so
 * objects on different threads do not mix their messages. No other global state.
 *
 * Thread safety: df_raycast_hit may run concurrently from any number of threads on the same
 * df_raycast (Embree's intersect is read-only on a committed scene); create, refit and free must
 * not overlap any other call on the same object. Different objects are independent. */
#ifndef DF_GEOM_RAYCAST_H
#define DF_GEOM_RAYCAST_H

#include <stdint.h>

#include "core/common/df_error.h"

typedef struct df_raycast df_raycast;

/* The nearest hit of a ray. point = (1 - u - v) V[F[3f]] + u V[F[3f+1]] + v V[F[3f+2]] computed
 * in double on the double positions of the last create/refit; t, u, v are refined in double on
 * the hit face (the ray / face-plane intersection, u and v clamped into the triangle), so
 * point ~= org + t * dir (equal up to the clamp at an edge). t is in units of |dir| (dir need not
 * be unit length). */
typedef struct df_ray_hit {
    double t, point[3];
    int32_t face;          /* row of F (0-based) */
    double u, v;           /* barycentrics of corners 1 and 2 of that face */
} df_ray_hit;

/* Builds the scene of the triangle mesh V (nv x 3, row-major, double) / F (nf x 3, 0-based
 * indices) on the shared Embree device (made by the first call). The positions are copied
 * (converted to float); V and F are not kept. Degenerate faces are allowed (they are never hit).
 * The build runs on the calling thread.
 * Errors: DF_EINVAL (NULL arrays, nv < 1, nf < 1, an index out of [0, nv), a coordinate NaN/Inf or
 * beyond float range: the message names the row), DF_ENOMEM, DF_EINTERNAL (Embree failed: the
 * message carries Embree's error). On success *out owns the scene (df_raycast_free); on error
 * *out is untouched. */
int df_raycast_create(const double *V, int32_t nv, const int32_t *F, int32_t nf,
                      df_raycast **out, df_error *err);

/* Moves the vertices to V (nv x 3 as at create: same count, same faces) and refits the BVH on the
 * calling thread. Errors: DF_EINVAL (NULL, a coordinate NaN/Inf or beyond float range: nothing
 * changed, the previous positions stay in force), DF_EINTERNAL (Embree failed: the object then
 * answers every hit with a miss until a successful refit). */
int df_raycast_refit(df_raycast *rc, const double *V, df_error *err);

/* Casts the ray org + t dir, t in [0, inf), and returns 1 with the nearest hit in *hit, or 0 on a
 * miss (*hit untouched), also for a NULL/zero/non-finite dir or org, or a NULL rc/hit. Never fails
 * otherwise. Both sides of a face are hit (no back-face culling). */
int df_raycast_hit(const df_raycast *rc, const double org[3], const double dir[3],
                   df_ray_hit *hit);

/* Number of vertices / faces the object was created with (0 for NULL). */
int32_t df_raycast_nv(const df_raycast *rc);
int32_t df_raycast_nf(const df_raycast *rc);

/* Releases the scene (the shared device stays); NULL-safe. */
void df_raycast_free(df_raycast *rc);

#endif

/* stroke_recipe.h — a Kelvinlet stroke's contribution kept as its request, recomputed on demand.
 *
 * A stroke (server/handlers/h_brush.c) sets positions = base + m, where m is the float32 motion
 * m = fl32(x0 + d) - x0 of the stroke-start points x0 = fl32(start positions) along the field d
 * of the stroke's brush under its cumulative load. When `base` is the state the stroke began
 * from (no concurrent change rebased it), the stroke's result is a pure function of that start
 * state and of the recipe below: a few hundred bytes instead of 24 bytes per moved vertex.
 * The undo history and the store keep a recipe plus a checksum of the state it produced; a
 * replay that does not reproduce the checksum is an error, never a silently different mesh.
 *
 * The motion step (df_stroke_motion) is the one h_brush.c publishes with, so a replay runs
 * exactly the live arithmetic. Pure: any thread, no session access. */
#ifndef DF_SERVER_STROKE_RECIPE_H
#define DF_SERVER_STROKE_RECIPE_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/kelvinlet/kelvinlet.h"
#include "core/mesh/operators.h"

#define DF_STROKE_LOAD_N 16 /* move[3] twist[3] scale matrix[9] */

typedef struct df_stroke_recipe {
    df_kelvinlet_brush brush;     /* as evaluated (knob overrides applied); its tip, omega, s and
                                   * grad are ignored: the load sets them; brush.surface = 1: a
                                   * surface-aware stroke (replay needs the mesh adjacency) */
    double strength;              /* multiplies the load */
    double load[DF_STROKE_LOAD_N];/* the cumulative load of the stroke's last begin/update */
    uint32_t n_pins;              /* pinned points, 0..DF_KELVINLET_MAX_PINS */
    int pin_flags;                /* DF_KELVINLET_PIN_* (0 without pins) */
    double *pins;                 /* n_pins x 3, owned (NULL when none) */
} df_stroke_recipe;

/* The brush `b` loaded with `strength` x `load`: tip = k move, omega = k twist, s = k scale,
 * grad = k matrix (row-major). Writes *out (may alias b). */
void df_stroke_loaded_brush(const df_kelvinlet_brush *b, double strength,
                            const double load[DF_STROKE_LOAD_N], df_kelvinlet_brush *out);

/* The motion step of a stroke over n floats: m = (x0 + d) - x0 in float32 (0 where d is below
 * x0's resolution), written over d, and pos = base + (double)m. Arrays distinct. */
void df_stroke_motion(const float *x0, float *d, const double *base, double *pos, size_t n);

/* Recomputes the stroke from state `from` (3 * nv doubles) into `to` (3 * nv doubles, may not
 * alias from): x0 = fl32(from), d = the recipe's field at x0 (a fresh pin solve when pinned),
 * to = from + m. `threads` as df_kelvinlet_prepared.threads (results do not depend on it).
 * `planar`: a 2D session, where a field moving any z is refused (as the live stroke is).
 * Errors: those of the Kelvinlet engine (DF_EINVAL, DF_ESINGULAR, DF_ELIMIT), DF_ENOMEM;
 * `to` unspecified on error. */
int df_stroke_recipe_replay(const df_stroke_recipe *r, const double *from, int32_t nv,
                            int planar, int threads, double *to, df_error *err);

/* The same with the session mesh: `adj` its vertex adjacency (df_mesh_vertex_adjacency,
 * n_rows = nv) and `rest` its load-time positions (df_mesh.V, nv x 3); both may be NULL for a
 * recipe whose brush.surface is 0. A surface-aware recipe's field is masked by
 * df_stroke_surface_mask with the distances of df_stroke_surface_dist, exactly as the live
 * stroke. df_stroke_recipe_replay refuses a surface-aware recipe (DF_EINVAL: it needs the
 * mesh). Same errors, plus DF_EINVAL for an adjacency of another size. */
int df_stroke_recipe_replay_mesh(const df_stroke_recipe *r, const double *from, int32_t nv,
                                 const df_mesh_sparse *adj, const double *rest, int planar,
                                 int threads, double *to, df_error *err);

/* Surface-aware strokes, step 1 (once per stroke start): the vertex *src nearest to the brush
 * centre c[3] among the stroke-start points x0 (nv x 3 float32, widened to double), and the
 * edge-graph distances dist[nv] from it over the mesh at rest (`rest`, nv x 3: distances along
 * the surface as loaded, so they depend on the centre vertex only and are cached per session
 * and vertex). Errors: DF_EINVAL, DF_ENOMEM (core/mesh/geodesic.h). */
int df_stroke_surface_dist(const df_mesh_sparse *adj, const double *rest, const float *x0,
                           int32_t nv, const double *c, int32_t *src, double *dist,
                           df_error *err);

/* The vertex of x0 (nv x 3 float32, widened to double) nearest to c[3]: step 1's *src. */
int32_t df_stroke_surface_src(const float *x0, int32_t nv, const double *c);

/* Step 2 (each publish): multiplies the field d (nv x 3 float32, in place) by the weights of
 * core/kelvinlet/kelvinlet_surface.h for brush b (its centre, radius and order) at the points
 * x0 with the distances of step 1. Parts not connected to src get exactly 0. Errors:
 * DF_EINVAL, DF_ENOMEM; d untouched on error. */
int df_stroke_surface_mask(const df_kelvinlet_brush *b, const float *x0, int32_t nv,
                           const double *dist, int32_t src, float *d, df_error *err);

/* df_stroke_recipe_replay_mesh with caller-provided scratch: `scratch` holds 6 * nv floats (x0
 * and the field), reused across calls instead of two allocations per replay; adj and rest may
 * be NULL for a recipe whose brush.surface is 0. Same results, same errors. */
int df_stroke_recipe_replay_with(const df_stroke_recipe *r, const double *from, int32_t nv,
                                 const df_mesh_sparse *adj, const double *rest, int planar,
                                 int threads, float *scratch, double *to, df_error *err);

/* Serializes a recipe into a new malloc'd blob (*out, *len bytes): u32 magic 'DSR3', i32 type,
 * dim, order, integrator, steps, mirror, moving, surface, arith (the brush's arithmetic
 * version, kelvinlet.h: its arith, or DF_KELVINLET_ARITH_CURRENT for 0, so a replay by a later
 * build evaluates the very arithmetic that produced the recorded checksum), f64 ratio, radius,
 * nu, centre[3], mirror_point[3], mirror_normal[3], strength, load[16], u32 n_pins, i32
 * pin_flags, then 3 x n_pins f64 pins; native-endian, packed (DF_STROKE_RECIPE_FIXED +
 * 24 n_pins bytes). Version 2 ('DSR2', DF_STROKE_RECIPE_FIXED_V2 + 24 n_pins) is the same
 * without `arith` and version 1 ('DSR1', DF_STROKE_RECIPE_FIXED_V1 + 24 n_pins) also without
 * `surface`; decode still reads both (surface 0 for version 1, arith DF_KELVINLET_ARITH_1: what
 * the builds that wrote them evaluated).
 * Errors: DF_EINVAL (n_pins over the maximum, pins NULL with n_pins > 0, brush.arith outside
 * 0..DF_KELVINLET_ARITH_CURRENT), DF_ENOMEM. */
#define DF_STROKE_RECIPE_FIXED 280
#define DF_STROKE_RECIPE_FIXED_V2 276
#define DF_STROKE_RECIPE_FIXED_V1 272
int df_stroke_recipe_encode(const df_stroke_recipe *r, uint8_t **out, size_t *len,
                            df_error *err);

/* Parses a blob of df_stroke_recipe_encode (version 3, 2 or 1) into *r (pins malloc'd; free
 * with df_stroke_recipe_free); r->brush.arith is always set (1..DF_KELVINLET_ARITH_CURRENT).
 * Errors: DF_EFORMAT (wrong magic or length, n_pins over the maximum, surface not 0/1, an
 * arithmetic version this build does not know, a NaN), DF_ENOMEM; *r zeroed on error. */
int df_stroke_recipe_decode(const uint8_t *b, size_t len, df_stroke_recipe *r, df_error *err);

/* Frees the recipe's pins and zeroes it. NULL-safe. */
void df_stroke_recipe_free(df_stroke_recipe *r);

/* A 64-bit checksum of n doubles' bit patterns (every bit counts: -0.0 != 0.0, NaN payloads).
 * Not cryptographic: it detects a replay that differs, not an adversary. */
uint64_t df_positions_checksum(const double *p, size_t n);

#endif

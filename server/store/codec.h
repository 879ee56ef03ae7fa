/* codec.h — the store's blob layouts (store.h schema): position deltas (delta.h), the session
 * brush, the handle set. Native-endian, packed field by field (no struct padding on disk).
 * Pure: any thread.
 *
 * delta (changes.delta): the position delta layout of server/session/delta.h (raw or packed;
 *   the undo history's checkpoint links use it too). Brush versions of unrebased strokes are
 *   journaled as their recipe instead (record.h, journal.h): recomputed and checksum-verified
 *   at restore; deltas remain for everything else.
 * brush (sessions.brush, changes.aux of a brush change): u8 type, falloff, integrator,
 *   has_mirror, u16 steps, then f64 radius, nu, strength, ratio, mirror_point[3],
 *   mirror_normal[3] (86 bytes).
 * handles (sessions.handles, changes.aux of a handle-set change): i32 energy, f64 w, s, rho,
 *   tol, i32 max_iters, f64 youngs, poisson, i32 area_weighting, accelerate, anderson_m,
 *   f64 strain_min, strain_max, bending, i32 threads (the df_admm_params), i32 nh, n_affine,
 *   max_iters (the set's), nh x i32 handles, then per affine set: i32 n, m, f64 A[9], b[3],
 *   n x i32 verts. */
#ifndef DF_SERVER_STORE_CODEC_H
#define DF_SERVER_STORE_CODEC_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/session/brush_state.h"
#include "server/session/delta.h"
#include "server/session/session.h"

#define DF_CODEC_BRUSH_BYTES 86
/* Packs / unpacks the session brush (unpack: DF_EFORMAT when len is wrong). */
void df_codec_brush_pack(const df_brush_state *b, uint8_t out[DF_CODEC_BRUSH_BYTES]);
int df_codec_brush_unpack(const uint8_t *p, size_t len, df_brush_state *out, df_error *err);

/* Encodes a handle set (params, handles, affine sets; not its solver) into a new malloc'd blob.
 * Errors: DF_ENOMEM. */
int df_codec_handles_encode(const df_handleset *hs, uint8_t **out, size_t *len, df_error *err);

/* Decodes a handle-set blob into a new df_handleset (solver NULL: rebuilt on first use),
 * checking every index against nv. Errors: DF_EFORMAT, DF_ENOMEM. Free with
 * df_handleset_free. */
int df_codec_handles_decode(const uint8_t *p, size_t len, int32_t nv, df_handleset **out,
                            df_error *err);

#endif

/* delta.h — the position delta codec: the difference between two states of a session's
 * positions, exact to the bit. Shared by the durable store (server/store/codec.h: the change
 * log) and the undo history (history.h: links between checkpoints). Native-endian. Pure: any
 * thread.
 *
 * A delta (the store's changes.delta, the undo history's checkpoint links) is one of two
 * layouts told apart by the first u32:
 *   raw: u32 count, u32 nv, then either (count == nv, dense) 3 * nv doubles, or count u32
 *     vertex indices (ascending) followed by 3 * count doubles: the NEW exact double positions
 *     of the vertices whose position differs bit-wise from the previous state.
 *   packed: u32 DF_CODEC_PACKED_MARKER (0xFFFFFFFF: no raw count, count <= nv < 2^31), i32 nv,
 *     u32 count (>= 1), then one zstd frame (content size and checksum in the frame) of a
 *     28 * count byte payload: the gaps between consecutive changed indices (index - previous
 *     - 1, the first from -1) as 4 byte planes of count bytes (plane b = byte b of every gap,
 *     little-endian significance), then the 3 * count XORs of the old and new double bit
 *     patterns as 8 byte planes of 3 * count bytes.
 *   Why: a brush stroke moves every vertex it reaches, so the raw layout is dense (24 bytes per
 *   vertex) even for a local stroke. The server rounds a stroke's motion to float32 over a
 *   float32 start (h_brush.c), so most vertices far from the brush do not move at all and the
 *   ones that do differ in a few mantissa bits: the XOR's high byte planes are zero and the
 *   gap planes nearly constant, which zstd (level DF_CODEC_ZSTD_LEVEL) shrinks many times over.
 *   XOR keeps it lossless and bit-exact for every bit pattern (NaN payloads, -0.0, denormals)
 *   and needs no recomputation at restore (which recording a stroke as its request plus
 *   checkpoints would, with a checksum and a fallback). The encoder writes whichever layout is
 *   smaller, raw below DF_CODEC_PACK_MIN_VERTICES changed vertices; readers accept both, so a
 *   store written before the packed layout restores unchanged. */
#ifndef DF_SERVER_SESSION_DELTA_H
#define DF_SERVER_SESSION_DELTA_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_CODEC_PACKED_MARKER 0xFFFFFFFFu
#define DF_CODEC_PACKED_HEADER 12
#define DF_CODEC_ZSTD_LEVEL 3          /* zstd's default: ~2x the speed of 9 at ~the same size */
#define DF_CODEC_PACK_MIN_VERTICES 16  /* fewer changed vertices: raw (a frame costs ~20 bytes) */

/* Encodes the delta from `old` to `now` (3 * nv doubles each, bit-wise compare) into a new
 * malloc'd blob *out of *len bytes, the smaller of the raw and packed layouts (count 0: a raw
 * header only). Cost: one pass over the positions, then 28 bytes per changed vertex of scratch
 * and one zstd compression of it. Errors: DF_ENOMEM, DF_EINTERNAL (zstd failed). */
int df_codec_delta_encode(const double *old, const double *now, int32_t nv, uint8_t **out,
                          size_t *len, df_error *err);

/* Applies a delta blob (either layout) to `pos` (3 * nv doubles, the state the delta was
 * taken from: a packed delta XORs into it). *changed (may be NULL) = its count. The blob is
 * checked in full (decompressed, checksum, sizes, every index) before `pos` is written.
 * Errors: DF_EFORMAT (wrong nv, truncated, index out of range or not ascending, a corrupt
 * compressed frame), DF_ENOMEM; pos untouched on error. */
int df_codec_delta_apply(const uint8_t *b, size_t len, double *pos, int32_t nv,
                         uint32_t *changed, df_error *err);

#endif

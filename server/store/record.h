/* record.h — the change log's recipe record (store.h schema 3: changes.recipe): a brush version
 * or a stroke's end kept as the stroke's request instead of a position delta (journal.h).
 *
 * Layout (native-endian, packed): u32 magic DF_RECORD_MAGIC ('DJR1'), u32 recipe_len, u64
 * base_version, u64 checksum, u64 replay_ns, then recipe_len bytes of a
 * df_stroke_recipe_encode blob (server/session/stroke_recipe.h). DF_RECORD_HEADER + recipe_len
 * bytes in all.
 *   base_version  the session version whose positions the stroke began from (the replay's
 *                 input: restore.h keeps that state while records reference it)
 *   checksum      df_positions_checksum of the 3 x nv positions after the change (a brush
 *                 version: the replay's output; a stroke's end: the state it commits)
 *   replay_ns     the live field evaluation's measured time (the restore's cost estimate)
 * Pure: any thread. */
#ifndef DF_SERVER_STORE_RECORD_H
#define DF_SERVER_STORE_RECORD_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_RECORD_MAGIC 0x31524a44u /* "DJR1" little-endian */
#define DF_RECORD_HEADER 32

typedef struct df_recipe_record {
    uint64_t base_version;
    uint64_t checksum;
    uint64_t replay_ns;
    const uint8_t *recipe;   /* the encoded recipe (borrowed: the caller's, or inside the blob
                              * decoded) */
    size_t recipe_len;
} df_recipe_record;

/* Writes record `r` into a new malloc'd blob (*out, *len bytes). Errors: DF_EINVAL (no recipe,
 * or one over 4 GiB), DF_ENOMEM. */
int df_record_encode(const df_recipe_record *r, uint8_t **out, size_t *len, df_error *err);

/* Reads a record blob of `len` bytes into *r (r->recipe points into b: valid while b is). Only
 * the framing is checked (magic, lengths); the recipe is checked by df_stroke_recipe_decode.
 * Errors: DF_EFORMAT (too short, wrong magic, recipe length not the rest of the blob). */
int df_record_decode(const uint8_t *b, size_t len, df_recipe_record *r, df_error *err);

#endif

/* shm_ring.h — layout of the shared-memory stream ring (PROTOCOL.md 6.1) and its two halves:
 * the writer (the daemon appends event frames) and the reader (a client copies one out by the
 * position an SHM_REF gives). Pure memory operations on a mapping the caller owns: no I/O.
 *
 * The ring is a file of DF_SHM_HEADER_BYTES + capacity bytes. A stream position p (bytes since the
 * ring was made, never reused) lives at data offset p % capacity; a frame never wraps. Before
 * overwriting, the writer raises valid_from past every position it is about to reuse, then
 * fences; a reader copies, fences, and re-checks valid_from, so a frame overwritten while it was
 * being copied is detected, never returned. */
#ifndef DF_PROTO_SHM_RING_H
#define DF_PROTO_SHM_RING_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

/* DF_SHM_MAGIC, DF_SHM_HEADER_BYTES, DF_SHM_MIN_CAPACITY, DF_SHM_MAX_CAPACITY: the ring file's
 * numbers are wire numbers, in proto/wire_schema.h. */
#include "proto/wire_schema.h"
enum {                                      /* header field offsets */
    DF_SHM_OFF_HEADER_BYTES = 8,            /* u32 */
    DF_SHM_OFF_CAPACITY = 16,               /* u64 */
    DF_SHM_OFF_SESSION = 24,                /* u64 */
    DF_SHM_OFF_VALID_FROM = 32,             /* u64, atomic */
    DF_SHM_OFF_HEAD = 40                    /* u64, atomic */
};

/* The writer's own copy of the ring state. Readers share the mapping (and a process of the same
 * user could scribble on it), so the writer never reads its bookkeeping back from it: it keeps
 * capacity, head and valid_from here and only publishes them to the header. */
typedef struct df_shm_writer {
    uint8_t *base;       /* mapping of DF_SHM_HEADER_BYTES + capacity bytes, 8-byte aligned */
    uint64_t capacity;   /* data bytes */
    uint64_t head;       /* stream position after the last frame */
    uint64_t valid_from; /* positions below it may be overwritten */
} df_shm_writer;

/* Writes a fresh header into `base` (zero-filled by the caller): magic, sizes, session id,
 * valid_from = head = 0; and sets up `w` to append to it. */
void df_shm_writer_init(df_shm_writer *w, uint8_t *base, uint64_t capacity, uint64_t session_id);

/* Checks a mapped header of `map_bytes` bytes: magic, header_bytes, capacity (equal to
 * `capacity`, and the map large enough to hold it) and session id. DF_OK or DF_EFORMAT with a
 * message naming the field. */
int df_shm_ring_check(const uint8_t *base, size_t map_bytes, uint64_t capacity,
                      uint64_t session_id, df_error *err);

/* Writer: appends `len` bytes (1 <= len <= w->capacity) and returns the frame's stream position.
 * Single writer; readers may be copying concurrently. */
uint64_t df_shm_writer_append(df_shm_writer *w, const uint8_t *frame, uint32_t len);

/* Reader: copies the frame at stream position `pos` of `len` bytes into `out` (cap >= len) from
 * the ring at `base` of `capacity` data bytes (the reader's own copy, checked at attach: never
 * re-read from the shared header). Returns DF_OK, DF_ENOTFOUND when the frame was overwritten
 * before or during the copy (lost: resync with a snapshot), or DF_EFORMAT when (pos, len) cannot
 * be a frame of this ring. */
int df_shm_ring_read(const uint8_t *base, uint64_t capacity, uint64_t pos, uint32_t len,
                     uint8_t *out, df_error *err);

#endif

/* shm_ring.c — shared-memory stream ring writer and reader (see shm_ring.h). */
#include "proto/shm_ring.h"

#include <stdatomic.h>
#include <string.h>

#include "proto/buf.h"

/* The two atomic header words, as seen by this process. The mapping is 8-byte aligned (mmap
 * returns pages), and lock-free 64-bit atomics are plain loads and stores on the targets we run
 * on, so another process mapping the same bytes sees them as the spec describes. */
static _Atomic uint64_t *word(const uint8_t *base, size_t off)
{
    return (_Atomic uint64_t *)(uintptr_t)(base + off);
}

void df_shm_writer_init(df_shm_writer *w, uint8_t *base, uint64_t capacity, uint64_t session_id)
{
    *w = (df_shm_writer){.base = base, .capacity = capacity};
    memcpy(base, DF_SHM_MAGIC, 8);
    df_le32_store(base + DF_SHM_OFF_HEADER_BYTES, DF_SHM_HEADER_BYTES);
    df_le32_store(base + 12, 0);
    df_le64_store(base + DF_SHM_OFF_CAPACITY, capacity);
    df_le64_store(base + DF_SHM_OFF_SESSION, session_id);
    atomic_store_explicit(word(base, DF_SHM_OFF_VALID_FROM), 0, memory_order_relaxed);
    atomic_store_explicit(word(base, DF_SHM_OFF_HEAD), 0, memory_order_release);
}

int df_shm_ring_check(const uint8_t *base, size_t map_bytes, uint64_t capacity,
                      uint64_t session_id, df_error *err)
{
    if (map_bytes < DF_SHM_HEADER_BYTES || memcmp(base, DF_SHM_MAGIC, 8) != 0)
        return df_error_set(err, DF_EFORMAT, "shm ring: bad magic");
    if (df_le32_load(base + DF_SHM_OFF_HEADER_BYTES) != DF_SHM_HEADER_BYTES)
        return df_error_set(err, DF_EFORMAT, "shm ring: header_bytes %u, expected %u",
                            df_le32_load(base + DF_SHM_OFF_HEADER_BYTES), DF_SHM_HEADER_BYTES);
    uint64_t cap = df_le64_load(base + DF_SHM_OFF_CAPACITY);
    if (cap != capacity || cap < DF_SHM_MIN_CAPACITY || cap > DF_SHM_MAX_CAPACITY ||
        map_bytes - DF_SHM_HEADER_BYTES < cap)
        return df_error_set(err, DF_EFORMAT,
                            "shm ring: capacity %llu does not match %llu / a %zu-byte mapping",
                            (unsigned long long)cap, (unsigned long long)capacity, map_bytes);
    if (df_le64_load(base + DF_SHM_OFF_SESSION) != session_id)
        return df_error_set(err, DF_EFORMAT, "shm ring: belongs to session %llu, not %llu",
                            (unsigned long long)df_le64_load(base + DF_SHM_OFF_SESSION),
                            (unsigned long long)session_id);
    return DF_OK;
}

uint64_t df_shm_writer_append(df_shm_writer *w, const uint8_t *frame, uint32_t len)
{
    uint64_t cap = w->capacity, pos = w->head;
    if (pos % cap + len > cap) pos += cap - pos % cap; /* never wrap a frame: next lap */
    /* Positions [pos + len - cap, ...) of the previous lap are about to be overwritten. */
    if (pos + len > cap && pos + len - cap > w->valid_from) {
        w->valid_from = pos + len - cap;
        atomic_store_explicit(word(w->base, DF_SHM_OFF_VALID_FROM), w->valid_from,
                              memory_order_relaxed);
    }
    atomic_thread_fence(memory_order_release); /* valid_from before any overwriting store */
    memcpy(w->base + DF_SHM_HEADER_BYTES + pos % cap, frame, len);
    w->head = pos + len;
    atomic_store_explicit(word(w->base, DF_SHM_OFF_HEAD), w->head, memory_order_release);
    return pos;
}

int df_shm_ring_read(const uint8_t *base, uint64_t capacity, uint64_t pos, uint32_t len,
                     uint8_t *out, df_error *err)
{
    uint64_t cap = capacity;
    if (len == 0 || len > cap || pos % cap + len > cap)
        return df_error_set(err, DF_EFORMAT, "shm ref: %u bytes at position %llu do not fit "
                            "a %llu-byte ring", len, (unsigned long long)pos,
                            (unsigned long long)cap);
    if (pos + len > atomic_load_explicit(word(base, DF_SHM_OFF_HEAD), memory_order_acquire))
        return df_error_set(err, DF_EFORMAT, "shm ref: position %llu not written yet",
                            (unsigned long long)pos);
    _Atomic uint64_t *vf = word(base, DF_SHM_OFF_VALID_FROM);
    if (pos < atomic_load_explicit(vf, memory_order_acquire))
        return df_error_set(err, DF_ENOTFOUND, "shm ref: frame at %llu already overwritten",
                            (unsigned long long)pos);
    memcpy(out, base + DF_SHM_HEADER_BYTES + pos % cap, len);
    atomic_thread_fence(memory_order_acquire); /* the copy before the re-check */
    if (pos < atomic_load_explicit(vf, memory_order_relaxed))
        return df_error_set(err, DF_ENOTFOUND, "shm ref: frame at %llu overwritten while read",
                            (unsigned long long)pos);
    return DF_OK;
}

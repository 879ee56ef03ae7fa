/* sbuf.h — reference-counted immutable byte buffers.
 *
 * An encoded frame is built once into a df_sbuf and shared by every subscriber's output queue;
 * the last unref frees it. The count is atomic, so buffers may be created on worker threads and
 * released on the loop thread. */
#ifndef DF_SERVER_SBUF_H
#define DF_SERVER_SBUF_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

typedef struct df_sbuf {
    atomic_int refs;
    size_t len;          /* bytes used in data */
    size_t cap;          /* bytes allocated at data */
    uint8_t *data;       /* inline storage after the struct, or an adopted malloc'd block */
    int owned;           /* 1: data is a separate malloc'd block freed with the buffer */
} df_sbuf;

/* A new buffer with room for `cap` bytes (b->cap may be larger: a kept block of up to 1.25 cap
 * when cap >= 1 MiB), len = 0, one reference. NULL when out of memory. Thread-safe. */
df_sbuf *df_sbuf_new(size_t cap);

/* Wraps a malloc'd block of `len` bytes (ownership moves to the new buffer, which frees it on the
 * last unref). NULL when out of memory (then `data` is NOT freed: the caller still owns it). */
df_sbuf *df_sbuf_adopt(uint8_t *data, size_t len);

/* Adds a reference; returns `b` (NULL-safe). */
df_sbuf *df_sbuf_ref(df_sbuf *b);

/* Drops a reference, freeing the buffer at zero (NULL-safe); a buffer of df_sbuf_new of 1 MiB or
 * more is kept for reuse by df_sbuf_new instead (at most 6 blocks, 96 MiB: sbuf.c). */
void df_sbuf_unref(df_sbuf *b);

#endif

/* buf.h — a growable byte buffer and little-endian scalar writers for the wire format.
 *
 * Encoders append to a df_buf; the server and clients send `data[0 .. len)`. Writers that take a
 * df_error return DF_OK or DF_ENOMEM (buffer unchanged on failure). The unchecked df_buf_put_*
 * helpers require that capacity was reserved first with df_buf_reserve (encoders reserve the
 * exact size of a message, then write without further checks). */
#ifndef DF_PROTO_BUF_H
#define DF_PROTO_BUF_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

typedef struct df_buf {
    uint8_t *data; /* malloc'd bytes, NULL while cap == 0 */
    size_t len;    /* bytes written */
    size_t cap;    /* bytes allocated */
} df_buf;

/* Initialises an empty buffer (no allocation). */
void df_buf_init(df_buf *b);

/* Frees the storage and re-initialises `b` (safe on an initialised or zeroed buffer). */
void df_buf_free(df_buf *b);

/* Sets len to 0, keeping the storage for reuse. */
void df_buf_reset(df_buf *b);

/* Ensures room for `extra` more bytes after len (grows geometrically). Returns DF_OK, or
 * DF_ENOMEM / DF_ELIMIT (len + extra overflows size_t) with `b` unchanged. */
int df_buf_reserve(df_buf *b, size_t extra, df_error *err);

/* Appends `n` bytes from `p` (may be NULL when n == 0). DF_OK or DF_ENOMEM, `b` unchanged on
 * failure. */
int df_buf_append(df_buf *b, const void *p, size_t n, df_error *err);

/* Unchecked appends, little-endian; capacity must have been reserved. Floats are written as
 * their IEEE-754 bit patterns. */
void df_buf_put_u8(df_buf *b, uint8_t v);
void df_buf_put_u16(df_buf *b, uint16_t v);
void df_buf_put_u32(df_buf *b, uint32_t v);
void df_buf_put_u64(df_buf *b, uint64_t v);
void df_buf_put_i32(df_buf *b, int32_t v);
void df_buf_put_f32(df_buf *b, float v);
void df_buf_put_f64(df_buf *b, double v);
void df_buf_put_bytes(df_buf *b, const void *p, size_t n);

/* Little-endian loads/stores at an arbitrary (unaligned) address. */
uint16_t df_le16_load(const uint8_t *p);
uint32_t df_le32_load(const uint8_t *p);
uint64_t df_le64_load(const uint8_t *p);
void df_le16_store(uint8_t *p, uint16_t v);
void df_le32_store(uint8_t *p, uint32_t v);
void df_le64_store(uint8_t *p, uint64_t v);

#endif

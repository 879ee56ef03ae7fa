/* codec_util.h — internal helpers shared by the message codecs (not part of the public API).
 *
 * df_rd is a bounds-checked little-endian cursor over one payload. The first failure is sticky:
 * it records DF_EPROTO_TRUNCATED (or the validation code) in `rc` and `err`, and every later
 * read returns 0, so a decoder can read all fields and test `r.rc` once. Messages are prefixed
 * with the message name given at df_rd_init ("brush: radius: ..."). */
#ifndef DF_PROTO_CODEC_UTIL_H
#define DF_PROTO_CODEC_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/buf.h"

typedef struct df_rd {
    const uint8_t *p;  /* payload */
    size_t n;          /* payload bytes */
    size_t off;        /* read position */
    const char *msg;   /* message name for error text */
    df_error *err;     /* may be NULL */
    int rc;            /* DF_OK until the first failure */
} df_rd;

/* Starts reading payload p[0 .. n) of message `msg`. */
void df_rd_init(df_rd *r, const uint8_t *p, size_t n, const char *msg, df_error *err);

/* Records a failure (first one wins) with a "msg: field: ..." text; returns r->rc. */
int df_rd_fail(df_rd *r, int code, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* 1 when `k` more bytes are present, else records DF_EPROTO_TRUNCATED and returns 0. */
int df_rd_need(df_rd *r, size_t k, const char *field);

/* 1 when at least `count` rows of `row_bytes` remain (checked without overflow) so arrays can be
 * allocated safely; else records DF_EPROTO_TRUNCATED naming the count. */
int df_rd_need_rows(df_rd *r, uint64_t count, size_t row_bytes, const char *field);

uint8_t df_rd_u8(df_rd *r, const char *field);
uint16_t df_rd_u16(df_rd *r, const char *field);
uint32_t df_rd_u32(df_rd *r, const char *field);
uint64_t df_rd_u64(df_rd *r, const char *field);
float df_rd_f32(df_rd *r, const char *field);
double df_rd_f64(df_rd *r, const char *field);

/* Reads a u16 reserved field and fails with DF_EPROTO_RESERVED unless it is 0. */
void df_rd_reserved16(df_rd *r, const char *field);
void df_rd_reserved8(df_rd *r, const char *field);

/* Reads a u16-length string of at most `max` bytes without NUL bytes into dst (cap max + 1). */
void df_rd_str(df_rd *r, char *dst, size_t max, const char *field);

/* Reads a u16-length string of at most `max` bytes into a malloc'd NUL-terminated copy
 * (*dst = NULL for length 0). */
void df_rd_str_alloc(df_rd *r, char **dst, size_t max, const char *field);

/* Returns a pointer to the next `k` bytes (NULL and failure if short) and skips them. */
const uint8_t *df_rd_bytes(df_rd *r, size_t k, const char *field);

/* Finishes: DF_EPROTO_TRAILING when bytes remain; returns r->rc. */
int df_rd_end(df_rd *r);

/* Reads `count` u32 vertex indices into a malloc'd int32 array (*dst), each < `bound`;
 * count must have been checked against the payload with df_rd_need_rows. */
void df_rd_indices(df_rd *r, int32_t **dst, uint32_t count, uint32_t bound, const char *field);

/* Wire size of a string (u16 length + bytes); writes one (capacity reserved). */
size_t df_str_size(const char *s);
void df_put_str(df_buf *b, const char *s);

/* Encoder-side validation helpers: DF_EINVAL with "msg: field ..." unless the check holds. */
int df_check_finite(const double *v, size_t n, const char *msg, const char *field, df_error *err);
int df_check_str(const char *s, size_t max, const char *msg, const char *field, df_error *err);

/* malloc(count * size) with overflow check; returns NULL for count 0 (not an error). Records
 * DF_ENOMEM in r when allocation fails. */
void *df_rd_alloc(df_rd *r, size_t count, size_t size, const char *field);

/* Reserves `size` bytes in out and returns rc (shared encoder prologue). */
int df_enc_reserve(df_buf *out, size_t size, const char *msg, df_error *err);

/* A list body: u32 count, then count items, each a variable-size row of at least `min_row`
 * wire bytes. Describes one list message for df_list_encode / df_list_decode. The callbacks
 * take one item (an element of an array of `item_size`-byte structs):
 *   check: validates item i (error text names the message); DF_OK or a df_error code.
 *   size:  wire bytes of the item (it has passed check).
 *   put:   writes the item (capacity reserved).
 *   get:   reads the item through the sticky cursor (failure recorded in r). */
typedef struct df_list_codec {
    const char *msg;    /* message name for error text: "device_list" */
    const char *noun;   /* items in the limit error: "devices" */
    uint32_t limit;     /* most items allowed */
    size_t item_size;   /* sizeof one in-memory item */
    size_t min_row;     /* fewest wire bytes of one item (bounds the count before allocating) */
    int (*check)(const void *item, uint32_t i, df_error *err);
    size_t (*size)(const void *item);
    void (*put)(df_buf *out, const void *item);
    void (*get)(df_rd *r, void *item);
} df_list_codec;

/* Encodes `count` items (array `items`, may be NULL only when count is 0) as a list body into
 * out. Errors: DF_ELIMIT "msg: N noun exceed limit L"; DF_EINVAL for NULL items or the first
 * item that fails check; reserve failure. Nothing is written on error. Caller's thread. */
int df_list_encode(const df_list_codec *c, uint32_t count, const void *items, df_buf *out,
                   df_error *err);

/* Decodes a list body p[0 .. n) into a malloc'd array *items (NULL when count is 0) of *count
 * items; the caller owns it (free()). Errors: truncation/trailing bytes, DF_ELIMIT
 * for count > limit (checked before any allocation, as is count x min_row against n),
 * DF_ENOMEM, or the first item's check error; *count and *items are unchanged on error. */
int df_list_decode(const df_list_codec *c, const uint8_t *p, size_t n, uint32_t *count,
                   void **items, df_error *err);

/* Defines `static const df_list_codec codec` for a list of `item_t` (message `msg`, limit error
 * noun `noun`, at most `limit` items of at least `min_row` wire bytes) from typed item
 * functions CHECK(const item_t *, uint32_t index, df_error *) -> int, SIZE(const item_t *) ->
 * size_t, PUT(df_buf *, const item_t *), GET(df_rd *, item_t *), and the codec functions
 * df_msg_<name>_encode / _decode of messages.h for list type `list_t` ({count, items}). */
#define DF_LIST_CODEC_DEFINE(name, list_t, item_t, codec, msg, noun, limit, min_row, CHECK, SIZE, \
                             PUT, GET)                                                           \
    static int codec##_check(const void *it, uint32_t i, df_error *err)                         \
    {                                                                                            \
        return CHECK((const item_t *)it, i, err);                                                \
    }                                                                                            \
    static size_t codec##_size(const void *it) { return SIZE((const item_t *)it); }              \
    static void codec##_put(df_buf *out, const void *it) { PUT(out, (const item_t *)it); }       \
    static void codec##_get(df_rd *r, void *it) { GET(r, (item_t *)it); }                        \
    static const df_list_codec codec = {msg,          noun,          limit,        sizeof(item_t), \
                                        min_row,      codec##_check, codec##_size, codec##_put,   \
                                        codec##_get};                                            \
    int df_msg_##name##_encode(const list_t *m, df_buf *out, df_error *err)                      \
    {                                                                                            \
        return df_list_encode(&codec, m->count, m->items, out, err);                             \
    }                                                                                            \
    int df_msg_##name##_decode(const uint8_t *p, size_t n, list_t *m, df_error *err)             \
    {                                                                                            \
        void *items = NULL;                                                                      \
        int rc = df_list_decode(&codec, p, n, &m->count, &items, err);                           \
        if (!rc)                                                                                 \
            m->items = items;                                                                    \
        return rc;                                                                               \
    }

#endif

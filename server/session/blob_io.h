/* blob_io.h — a bounded little writer and reader of native-endian blob fields, shared by the
 * blob codecs (session/delta.c, store/codec.c). Header-only (static inline), pure.
 *
 * Writer: the caller sizes w->p for everything it puts (no bound check: layouts are fixed).
 * Reader: a read past r->n sets r->bad, zero-fills the value and leaves r->at; every later read
 * fails the same way, so a codec reads all its fields and checks r->bad once. */
#ifndef DF_SERVER_BLOB_IO_H
#define DF_SERVER_BLOB_IO_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct df_wbuf {
    uint8_t *p;  /* the blob being written */
    size_t n;    /* bytes written so far */
} df_wbuf;

typedef struct df_rbuf {
    const uint8_t *p;  /* the blob being read, n bytes */
    size_t n, at;      /* its size; the next byte to read */
    int bad;           /* 1 once a read went past n */
} df_rbuf;

/* Appends k bytes of v. */
static inline void df_wput(df_wbuf *w, const void *v, size_t k)
{
    memcpy(w->p + w->n, v, k);
    w->n += k;
}
static inline void df_wput_i32(df_wbuf *w, int32_t v) { df_wput(w, &v, 4); }
static inline void df_wput_f64(df_wbuf *w, double v) { df_wput(w, &v, 8); }

/* Reads k bytes into v (zeros and r->bad past the end). */
static inline void df_rget(df_rbuf *r, void *v, size_t k)
{
    if (r->bad || k > r->n - r->at) {
        r->bad = 1;
        memset(v, 0, k);
        return;
    }
    memcpy(v, r->p + r->at, k);
    r->at += k;
}
static inline int32_t df_rget_i32(df_rbuf *r)
{
    int32_t v;
    df_rget(r, &v, 4);
    return v;
}
static inline double df_rget_f64(df_rbuf *r)
{
    double v;
    df_rget(r, &v, 8);
    return v;
}

#endif

/* sbuf.c — reference-counted byte buffers (see sbuf.h). */
#include "server/net/sbuf.h"

#include <stdlib.h>

df_sbuf *df_sbuf_new(size_t cap)
{
    if (cap > SIZE_MAX - sizeof(df_sbuf)) return NULL;
    df_sbuf *b = malloc(sizeof *b + (cap ? cap : 1));
    if (!b) return NULL;
    atomic_init(&b->refs, 1);
    b->len = 0;
    b->cap = cap;
    b->data = (uint8_t *)(b + 1);
    b->owned = 0;
    return b;
}

df_sbuf *df_sbuf_adopt(uint8_t *data, size_t len)
{
    df_sbuf *b = malloc(sizeof *b);
    if (!b) return NULL;
    atomic_init(&b->refs, 1);
    b->len = b->cap = len;
    b->data = data;
    b->owned = 1;
    return b;
}

df_sbuf *df_sbuf_ref(df_sbuf *b)
{
    if (b) atomic_fetch_add(&b->refs, 1);
    return b;
}

void df_sbuf_unref(df_sbuf *b)
{
    if (b && atomic_fetch_sub(&b->refs, 1) == 1) {
        if (b->owned) free(b->data);
        free(b);
    }
}

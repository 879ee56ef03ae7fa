/* msg_stats.c — stats reply body (messages.h).
 * u32 count, count x { str key (1..DF_MAX_STATS_KEY_LEN bytes of [a-z0-9_.]), f64 value } */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

static int stat_check(const df_msg_stat *s, uint32_t i, df_error *err)
{
    size_t len = strnlen(s->key, DF_MAX_STATS_KEY_LEN + 1);
    if (len < 1 || len > DF_MAX_STATS_KEY_LEN)
        return df_error_set(err, DF_EINVAL, "stats: key %u length %zu not in 1..%u", i, len,
                            DF_MAX_STATS_KEY_LEN);
    for (size_t k = 0; k < len; k++) {
        char c = s->key[k];
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.'))
            return df_error_set(err, DF_EINVAL, "stats: key %u has byte 0x%02x outside "
                                "[a-z0-9_.]", i, (unsigned char)c);
    }
    if (!isfinite(s->value))
        return df_error_set(err, DF_EINVAL, "stats: value of \"%s\" is %g (must be finite)",
                            s->key, s->value);
    return DF_OK;
}

static size_t stat_size(const df_msg_stat *s)
{
    return df_str_size(s->key) + 8;
}

static void stat_put(df_buf *out, const df_msg_stat *s)
{
    df_put_str(out, s->key);
    df_buf_put_f64(out, s->value);
}

static void stat_get(df_rd *r, df_msg_stat *s)
{
    df_rd_str(r, s->key, DF_MAX_STATS_KEY_LEN, "key");
    s->value = df_rd_f64(r, "value");
}

/* row: u16 key length, >= 1 key byte, f64 value */
DF_LIST_CODEC_DEFINE(stats, df_msg_stats, df_msg_stat, STATS_LIST, "stats", "entries",
                     DF_MAX_STATS_ENTRIES, 2 + 1 + 8, stat_check, stat_size, stat_put, stat_get)

void df_msg_stats_free(df_msg_stats *m)
{
    if (!m)
        return;
    free(m->items);
    m->items = NULL;
    m->count = 0;
}

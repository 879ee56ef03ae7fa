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

int df_msg_stats_encode(const df_msg_stats *m, df_buf *out, df_error *err)
{
    if (m->count > DF_MAX_STATS_ENTRIES)
        return df_error_set(err, DF_ELIMIT, "stats: %u entries exceed limit %u", m->count,
                            DF_MAX_STATS_ENTRIES);
    if (m->count && !m->items)
        return df_error_set(err, DF_EINVAL, "stats: items is NULL with count %u", m->count);
    size_t size = 4;
    for (uint32_t i = 0; i < m->count; i++) {
        int rc = stat_check(&m->items[i], i, err);
        if (rc)
            return rc;
        size += df_str_size(m->items[i].key) + 8;
    }
    int rc = df_enc_reserve(out, size, "stats", err);
    if (rc)
        return rc;
    df_buf_put_u32(out, m->count);
    for (uint32_t i = 0; i < m->count; i++) {
        df_put_str(out, m->items[i].key);
        df_buf_put_f64(out, m->items[i].value);
    }
    return DF_OK;
}

int df_msg_stats_decode(const uint8_t *p, size_t n, df_msg_stats *m, df_error *err)
{
    df_rd r;
    df_rd_init(&r, p, n, "stats", err);
    uint32_t count = df_rd_u32(&r, "count");
    if (!r.rc && count > DF_MAX_STATS_ENTRIES)
        df_rd_fail(&r, DF_ELIMIT, "count", "%u entries exceed limit %u", count,
                   DF_MAX_STATS_ENTRIES);
    df_rd_need_rows(&r, count, 2 + 1 + 8, "count");
    df_msg_stat *items = df_rd_alloc(&r, count, sizeof *items, "items");
    for (uint32_t i = 0; i < count && !r.rc; i++) {
        df_rd_str(&r, items[i].key, DF_MAX_STATS_KEY_LEN, "key");
        items[i].value = df_rd_f64(&r, "value");
        if (!r.rc)
            r.rc = stat_check(&items[i], i, err);
    }
    int rc = df_rd_end(&r);
    if (rc) {
        free(items);
        return rc;
    }
    m->count = count;
    m->items = items;
    return DF_OK;
}

void df_msg_stats_free(df_msg_stats *m)
{
    if (!m)
        return;
    free(m->items);
    m->items = NULL;
    m->count = 0;
}

/* slot.c — Redis Cluster addressing: CRC16 slots, seed lists, redirects (see slot.h). */
#include "server/cluster/slot.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

uint16_t df_slot_crc16(const void *buf, size_t len)
{
    const uint8_t *p = buf;
    uint16_t crc = 0;
    for (size_t i = 0; i < len; i++) {
        crc ^= (uint16_t)(p[i] << 8);
        for (int b = 0; b < 8; b++)
            crc = (crc & 0x8000) ? (uint16_t)((crc << 1) ^ 0x1021) : (uint16_t)(crc << 1);
    }
    return crc;
}

int df_slot_of_key(const char *key, size_t len)
{
    const char *open = memchr(key, '{', len);
    if (open) {
        size_t from = (size_t)(open - key) + 1;
        const char *close = memchr(open + 1, '}', len - from);
        if (close && close > open + 1) { /* a non-empty tag */
            key = open + 1;
            len = (size_t)(close - open - 1);
        }
    }
    return df_slot_crc16(key, len) & (DF_SLOTS - 1);
}

/* "HOST:PORT" of len bytes into *a. 0 when malformed. */
static int parse_addr(const char *s, size_t len, df_redis_node_addr *a)
{
    const char *colon = NULL;
    for (size_t i = 0; i < len; i++) {
        if (s[i] == ':') colon = s + i;
        if (s[i] == ' ' || s[i] == ',' || !s[i]) return 0;
    }
    if (!colon) return 0;
    size_t hl = (size_t)(colon - s), pl = len - hl - 1;
    if (hl >= DF_REDIS_HOST_MAX || pl < 1 || pl > 5) return 0;
    char port[8];
    memcpy(port, colon + 1, pl);
    port[pl] = '\0';
    char *end = NULL;
    long p = strtol(port, &end, 10);
    if (*end || p < 1 || p > 65535 || port[0] == '+' || port[0] == '-') return 0;
    memcpy(a->host, s, hl);
    a->host[hl] = '\0';
    a->port = (int)p;
    return 1;
}

int df_slot_parse_seeds(const char *url, df_redis_node_addr *out, size_t cap, size_t *n,
                        df_error *err)
{
    *n = 0;
    if (cap > DF_REDIS_SEEDS_MAX) cap = DF_REDIS_SEEDS_MAX;
    if (strncmp(url, "redis://", 8) != 0)
        return df_error_set(err, DF_EINVAL, "cluster: '%s' is not redis://HOST:PORT[,HOST:PORT"
                            "...]", url);
    const char *p = url + 8;
    for (;;) {
        while (*p == ' ') p++;
        if (*n > 0 && strncmp(p, "redis://", 8) == 0) p += 8;
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        while (len && p[len - 1] == ' ') len--;
        if (*n == cap)
            return df_error_set(err, DF_EINVAL, "cluster: more than %zu seed nodes in '%s'", cap,
                                url);
        if (!len || !parse_addr(p, len, &out[*n]) || !out[*n].host[0])
            return df_error_set(err, DF_EINVAL, "cluster: seed %zu of '%s' is not HOST:PORT "
                                "(port 1..65535)", *n + 1, url);
        (*n)++;
        if (!end) return DF_OK;
        p = end + 1;
    }
}

int df_slot_parse_redirect(const char *str, size_t len, int *slot, df_redis_node_addr *to)
{
    int kind = DF_REDIR_NONE;
    size_t skip = 0;
    if (len > 6 && !memcmp(str, "MOVED ", 6)) kind = DF_REDIR_MOVED, skip = 6;
    else if (len > 4 && !memcmp(str, "ASK ", 4)) kind = DF_REDIR_ASK, skip = 4;
    if (!kind) return DF_REDIR_NONE;
    const char *p = str + skip, *e = str + len;
    long s = 0;
    int digits = 0;
    while (p < e && *p >= '0' && *p <= '9' && digits < 6) s = s * 10 + (*p++ - '0'), digits++;
    if (!digits || s >= DF_SLOTS || p >= e || *p != ' ') return DF_REDIR_NONE;
    p++;
    df_redis_node_addr a;
    /* ":PORT" (host unknown) is allowed here: parse_addr takes an empty host */
    if (!parse_addr(p, (size_t)(e - p), &a)) return DF_REDIR_NONE;
    *slot = (int)s;
    *to = a;
    return kind;
}

/* auth_limit.c — token buckets of failed authentications per address (see auth_limit.h). */
#include "server/net/auth_limit.h"

#include <stdio.h>
#include <string.h>

void df_auth_limit_init(df_auth_limit *l, int burst, int refill_s)
{
    memset(l, 0, sizeof *l);
    l->refill_ms = (uint64_t)(refill_s < 1 ? 1 : refill_s) * 1000;
    l->cap_ms = (uint64_t)(burst < 1 ? 1 : burst) * l->refill_ms;
}

/* The slot's credit at now_ms (a time before its last failure counts as that time). */
static uint64_t credit(const df_auth_limit *l, const df_auth_limit_slot *s, uint64_t now_ms)
{
    uint64_t gained = now_ms > s->t_ms ? now_ms - s->t_ms : 0;
    return gained >= l->cap_ms - s->credit_ms ? l->cap_ms : s->credit_ms + gained;
}

static df_auth_limit_slot *find(df_auth_limit *l, const char *host)
{
    for (int i = 0; i < DF_AUTH_LIMIT_SLOTS; i++)
        if (l->slots[i].host[0] && strcmp(l->slots[i].host, host) == 0) return &l->slots[i];
    return NULL;
}

uint64_t df_auth_limit_wait(df_auth_limit *l, const char *host, uint64_t now_ms)
{
    df_auth_limit_slot *s = find(l, host);
    if (!s) return 0;
    uint64_t c = credit(l, s, now_ms);
    return c >= l->refill_ms ? 0 : l->refill_ms - c;
}

void df_auth_limit_fail(df_auth_limit *l, const char *host, uint64_t now_ms)
{
    df_auth_limit_slot *s = find(l, host);
    uint64_t c;
    if (s) {
        c = credit(l, s, now_ms);
    } else {
        df_auth_limit_slot *oldest = &l->slots[0];
        for (int i = 0; i < DF_AUTH_LIMIT_SLOTS && !s; i++) {
            if (!l->slots[i].host[0]) s = &l->slots[i];
            else if (l->slots[i].t_ms < oldest->t_ms) oldest = &l->slots[i];
        }
        if (!s) s = oldest;
        snprintf(s->host, sizeof s->host, "%s", host);
        c = l->cap_ms;
    }
    s->credit_ms = c >= l->refill_ms ? c - l->refill_ms : 0;
    s->t_ms = now_ms;
}

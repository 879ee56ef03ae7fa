/* auth_limit.c — token buckets of failed authentications per address (see auth_limit.h). */
#include "server/net/auth_limit.h"

#include <stdio.h>
#include <string.h>

void df_auth_limit_init(df_auth_limit *l, int burst, int refill_s)
{
    memset(l, 0, sizeof *l);
    l->burst_milli = (uint64_t)(burst < 1 ? 1 : burst) * 1000;
    l->refill_ms = (uint64_t)(refill_s < 1 ? 1 : refill_s) * 1000;
}

/* Brings the slot's bucket to now_ms. */
static void refill(const df_auth_limit *l, df_auth_limit_slot *s, uint64_t now_ms)
{
    if (now_ms > s->t_ms) {
        uint64_t add = (now_ms - s->t_ms) * 1000 / l->refill_ms;
        s->tokens_milli = s->tokens_milli + add > l->burst_milli ? l->burst_milli
                                                                 : s->tokens_milli + add;
    }
    s->t_ms = now_ms;
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
    refill(l, s, now_ms);
    if (s->tokens_milli >= 1000) return 0;
    uint64_t need = 1000 - s->tokens_milli; /* milli-tokens; one per refill_ms / 1000 ms */
    uint64_t ms = (need * l->refill_ms + 999) / 1000;
    return ms ? ms : 1;
}

void df_auth_limit_fail(df_auth_limit *l, const char *host, uint64_t now_ms)
{
    df_auth_limit_slot *s = find(l, host);
    if (!s) {
        df_auth_limit_slot *oldest = &l->slots[0];
        for (int i = 0; i < DF_AUTH_LIMIT_SLOTS && !s; i++) {
            if (!l->slots[i].host[0]) s = &l->slots[i];
            else if (l->slots[i].t_ms < oldest->t_ms) oldest = &l->slots[i];
        }
        if (!s) s = oldest;
        snprintf(s->host, sizeof s->host, "%s", host);
        s->tokens_milli = l->burst_milli;
        s->t_ms = now_ms;
    }
    refill(l, s, now_ms);
    s->tokens_milli = s->tokens_milli >= 1000 ? s->tokens_milli - 1000 : 0;
}

/* history_ckpt.c — the undo history's steps, checkpoints (anchor + packed links) and drops
 * (see history.h and history_int.h). */
#include "server/session/history_int.h"

#include <stdlib.h>
#include <string.h>

#include "server/session/stroke_recipe.h" /* df_positions_checksum only */
#include "server/session/delta.h"        /* the packed delta layout of links */

size_t hi_step_bytes(const df_history_step *s)
{
    if (s->kind == DF_HISTORY_RECIPE) return s->len + sizeof *s;
    return (size_t)s->count * (3 * sizeof(uint64_t) + (s->idx ? sizeof(uint32_t) : 0)) +
           sizeof *s;
}

void hi_step_free(df_history_step *s)
{
    free(s->idx);
    free(s->x);
    free(s->blob);
    memset(s, 0, sizeof *s);
}

/* The bit pattern of a double and back (memcpy: no aliasing through other pointer types). */
static inline uint64_t bits(const double *p)
{
    uint64_t u;
    memcpy(&u, p, sizeof u);
    return u;
}

static inline void xor_into(double *p, uint64_t x)
{
    uint64_t u = bits(p) ^ x;
    memcpy(p, &u, sizeof u);
}

/* XORs step `s` into `state` (forwards or backwards: the same operation). */
static void xor_apply(const df_history_step *s, double *state, size_t n)
{
    _Static_assert(sizeof(double) == sizeof(uint64_t), "double is 64 bits");
    if (!s->idx) {
        for (size_t i = 0; i < n; i++) xor_into(state + i, s->x[i]);
        return;
    }
    for (uint32_t k = 0; k < s->count; k++)
        for (int c = 0; c < 3; c++)
            xor_into(state + 3 * (size_t)s->idx[k] + c, s->x[3 * (size_t)k + c]);
}

int hi_step_xor(const double *a, const double *b, size_t n, df_history_step *st, df_error *err)
{
    memset(st, 0, sizeof *st);
    size_t nv = n / 3, changed = 0;
    for (size_t i = 0; i < n; i += 3)
        changed += ((bits(a + i) ^ bits(b + i)) | (bits(a + i + 1) ^ bits(b + i + 1)) |
                    (bits(a + i + 2) ^ bits(b + i + 2))) != 0;
    if (changed == 0) return DF_OK;
    int dense = changed * (3 * sizeof(uint64_t) + sizeof(uint32_t)) >= n * sizeof(uint64_t);
    st->count = (uint32_t)(dense ? nv : changed);
    st->x = malloc(3 * (size_t)st->count * sizeof *st->x);
    if (!dense) st->idx = malloc((size_t)st->count * sizeof *st->idx);
    if (!st->x || (!dense && !st->idx)) {
        hi_step_free(st);
        return df_error_set(err, DF_ENOMEM, "history: out of memory (%zu changed vertices)",
                            changed);
    }
    if (dense) {
        for (size_t i = 0; i < n; i++) st->x[i] = bits(a + i) ^ bits(b + i);
        return DF_OK;
    }
    uint32_t k = 0;
    for (size_t i = 0; i < nv; i++) {
        uint64_t x0 = bits(a + 3 * i) ^ bits(b + 3 * i),
                 x1 = bits(a + 3 * i + 1) ^ bits(b + 3 * i + 1),
                 x2 = bits(a + 3 * i + 2) ^ bits(b + 3 * i + 2);
        if (!(x0 | x1 | x2)) continue;
        st->idx[k] = (uint32_t)i;
        st->x[3 * (size_t)k] = x0;
        st->x[3 * (size_t)k + 1] = x1;
        st->x[3 * (size_t)k + 2] = x2;
        k++;
    }
    return DF_OK;
}

int hi_forward(const df_history *h, int k, double *a, double *tmp, void **scratch,
               uint64_t *replays, int *mismatch, df_error *err)
{
    const df_history_step *s = &h->steps[k];
    if (s->kind == DF_HISTORY_XOR) {
        xor_apply(s, a, h->n);
        return DF_OK;
    }
    if (!h->replay)
        return df_error_set(err, DF_ESTATE, "history: step %d is a recipe and no replay is set",
                            k);
    int rc = h->replay(h->replay_ctx, s->blob, s->len, a, tmp, scratch, err);
    (*replays)++;
    if (rc != DF_OK) return rc;
    uint64_t sum = df_positions_checksum(tmp, h->n);
    if (sum != s->sum) {
        *mismatch = 1;
        return df_error_set(err, DF_EINTERNAL,
                            "history: replaying step %d does not reproduce the state it "
                            "recorded (checksum %016llx, recorded %016llx)",
                            k, (unsigned long long)sum, (unsigned long long)s->sum);
    }
    memcpy(a, tmp, h->n * sizeof *a);
    return DF_OK;
}

int hi_anchor_read(const df_history *h, double *out, int *bad, df_error *err)
{
    if (h->anchor) {
        memcpy(out, h->anchor, h->n * sizeof *out);
        return DF_OK;
    }
    df_error e = {0};
    int rc = DF_EINTERNAL;
    if (h->apack && h->ref) {
        memcpy(out, h->ref, h->n * sizeof *out);
        rc = df_codec_delta_apply(h->apack, h->apack_len, out, (int32_t)(h->n / 3), NULL, &e);
        if (rc == DF_ENOMEM) return df_error_set(err, DF_ENOMEM, "history: %s", e.msg);
    }
    if (rc == DF_OK && df_positions_checksum(out, h->n) == h->asum) return DF_OK;
    if (bad) *bad = 1;
    return df_error_set(err, DF_EINTERNAL,
                        "history: the undo checkpoint (%zu bytes packed against the rest "
                        "shape) does not decode to the state it recorded (%s)", h->apack_len,
                        rc != DF_OK ? (h->apack && h->ref ? e.msg : "no reference")
                                    : "checksum differs: corrupt, or the reference changed");
}

int hi_anchor_pack(const df_history *h, const double *state, uint8_t **blob, size_t *len,
                   uint64_t *sum, df_error *err)
{
    *blob = NULL;
    *len = 0;
    int rc = df_codec_delta_encode(h->ref, state, (int32_t)(h->n / 3), blob, len, err);
    if (rc != DF_OK) return rc;
    *sum = df_positions_checksum(state, h->n);
    return DF_OK;
}

void hi_anchor_set(df_history *h, double *a, uint8_t *blob, size_t len, uint64_t sum)
{
    double *olda = h->anchor;
    uint8_t *oldb = h->apack;
    if (blob) {
        if (a != olda) free(a);
        a = NULL;
    }
    h->anchor = a;
    h->apack = blob;
    if (olda != a) free(olda);
    if (oldb != blob) free(oldb);
    h->apack_len = blob ? len : 0;
    h->asum = blob ? sum : 0;
}

int hi_ck_state(const df_history *h, int i, double *out, int *bad, df_error *err)
{
    int rc = hi_anchor_read(h, out, bad, err);
    if (rc != DF_OK) return rc;
    for (int l = h->nck - 2; l >= i; l--) {
        rc = df_codec_delta_apply(h->links[l].blob, h->links[l].len, out, (int32_t)(h->n / 3),
                                  NULL, err);
        if (rc != DF_OK) return rc;
    }
    return DF_OK;
}

int hi_link_make(const double *newer, const double *older, size_t n, df_history_link *l,
                 df_error *err)
{
    memset(l, 0, sizeof *l);
    return df_codec_delta_encode(newer, older, (int32_t)(n / 3), &l->blob, &l->len, err);
}

void hi_link_free(df_history_link *l)
{
    free(l->blob);
    memset(l, 0, sizeof *l);
}

void hi_ck_clear(df_history *h)
{
    for (int i = 0; i + 1 < h->nck; i++) hi_link_free(&h->links[i]);
    hi_anchor_set(h, NULL, NULL, 0, 0);
    h->nck = 0;
}

void hi_account(df_history *h)
{
    size_t b = h->n * sizeof(double) + (h->anchor ? h->n * sizeof(double) : h->apack_len);
    for (int i = 0; i + 1 < h->nck; i++) b += h->links[i].len + sizeof h->links[i];
    for (int i = 0; i < h->count; i++) b += hi_step_bytes(&h->steps[i]);
    h->bytes = b;
}

void hi_tidy(df_history *h)
{
    if (!h->nck) return;
    for (int i = 0; i < h->count; i++)
        if (h->steps[i].kind == DF_HISTORY_RECIPE) return;
    hi_ck_clear(h);
}

void hi_truncate(df_history *h, int from)
{
    for (int i = from; i < h->count; i++) hi_step_free(&h->steps[i]);
    h->count = from;
    /* Only a lone ck[0] can lie above the current state, with XOR steps only below it. */
    if (h->nck && h->ck[h->nck - 1] > from) hi_ck_clear(h);
    hi_tidy(h);
}

/* Removes steps [0, k) from the array (freed), shifting the rest and every checkpoint down. */
static void shift_steps(df_history *h, int k)
{
    for (int i = 0; i < k; i++) hi_step_free(&h->steps[i]);
    memmove(h->steps, h->steps + k, (size_t)(h->count - k) * sizeof *h->steps);
    memset(h->steps + h->count - k, 0, (size_t)k * sizeof *h->steps);
    h->count -= k;
    h->cur -= k;
    h->dropped += (uint64_t)k;
    for (int i = 0; i < h->nck; i++) h->ck[i] -= k;
}

void hi_drop_prefix(df_history *h, int upto)
{
    int at = -1;
    for (int i = 0; i < h->nck; i++)
        if (h->ck[i] == upto) at = i;
    if (at < 0) { /* upto == cur: the current state becomes the only checkpoint */
        double *a = h->anchor ? h->anchor : malloc(h->n * sizeof *a);
        for (int i = 0; i + 1 < h->nck; i++) hi_link_free(&h->links[i]);
        hi_anchor_set(h, a, NULL, 0, 0); /* a full copy: the next plan packs it */
        h->nck = a ? 1 : 0;
        if (a) {
            memcpy(a, h->state, h->n * sizeof *a);
            h->ck[0] = upto;
        } else { /* no memory for an anchor: nothing below the current state stays reachable */
            for (int i = upto; i < h->count; i++) hi_step_free(&h->steps[i]);
            h->count = upto;
        }
    } else if (at > 0) {
        for (int i = 0; i < at; i++) hi_link_free(&h->links[i]);
        memmove(h->links, h->links + at, (size_t)(h->nck - 1 - at) * sizeof *h->links);
        memmove(h->ck, h->ck + at, (size_t)(h->nck - at) * sizeof *h->ck);
        h->nck -= at;
    }
    shift_steps(h, upto);
    hi_tidy(h);
}

void hi_drop_below_current(df_history *h)
{
    hi_ck_clear(h);
    hi_drop_prefix(h, h->cur);
}

int hi_drop_oldest(df_history *h)
{
    uint64_t d0 = h->dropped;
    if (!h->nck || h->ck[0] > 0) { /* step 0 is below every RECIPE step: an XOR step */
        shift_steps(h, 1);
    } else if (h->nck >= 2) {      /* the oldest checkpoint segment */
        hi_drop_prefix(h, h->ck[1]);
    } else if (h->cur == 1) {      /* nothing left below: the current state is the anchor */
        hi_drop_prefix(h, 1);
    } else {                       /* the anchor is state 0: move it up one step */
        double *tmp = malloc(h->n * sizeof *tmp), *a = malloc(h->n * sizeof *a);
        void *scratch = NULL;
        uint64_t replays = 0;
        int mismatch = 0, rc = tmp && a ? hi_anchor_read(h, a, &mismatch, NULL) : DF_ENOMEM;
        if (rc == DF_OK) rc = hi_forward(h, 0, a, tmp, &scratch, &replays, &mismatch, NULL);
        uint8_t *blob = NULL;
        size_t len = 0;
        uint64_t sum = 0;
        if (rc == DF_OK && h->ref && hi_anchor_pack(h, a, &blob, &len, &sum, NULL) != DF_OK)
            blob = NULL; /* kept as a full copy: the next plan packs it */
        if (rc == DF_OK) hi_anchor_set(h, a, blob, len, sum);
        else free(a);
        free(tmp);
        free(scratch);
        h->replays += replays;
        h->mismatches += (uint64_t)mismatch;
        if (rc == DF_OK) {
            shift_steps(h, 1);
            h->ck[0] = 0; /* the anchor moved up with it */
        } else {
            hi_drop_prefix(h, h->cur);
        } /* the anchor is unusable: keep what is certain */
    }
    hi_tidy(h);
    return (int)(h->dropped - d0);
}

int hi_enforce(df_history *h)
{
    uint64_t d0 = h->dropped;
    hi_account(h);
    while (h->cur > 0 && (h->count > h->max_states - 1 || h->bytes > h->max_bytes)) {
        hi_drop_oldest(h);
        hi_account(h);
    }
    return (int)(h->dropped - d0);
}

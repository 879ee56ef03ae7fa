/* history.c — undo/redo stack of committed positions: plans made on a worker, installed on the
 * loop thread, XOR and RECIPE steps under a byte budget (see history.h; steps, checkpoints and
 * drops are in history_ckpt.c). */
#include "server/session/history.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/session/history_int.h"
#include "server/session/stroke_recipe.h" /* df_positions_checksum only */

#define DF_HISTORY_DEFAULT_BUDGET_NS 1000000000ull

int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err)
{
    if (!h) return df_error_set(err, DF_EINVAL, "history: NULL");
    memset(h, 0, sizeof *h);
    if (!pos || n == 0 || n % 3 != 0 || n / 3 > UINT32_MAX || max_states < 2)
        return df_error_set(err, DF_EINVAL, "history: bad arguments (n %zu, max %d)", n,
                            max_states);
    h->steps = calloc((size_t)max_states, sizeof *h->steps);
    h->ck = calloc((size_t)max_states + 1, sizeof *h->ck);
    h->links = calloc((size_t)max_states, sizeof *h->links);
    h->state = malloc(n * sizeof *h->state);
    if (!h->steps || !h->ck || !h->links || !h->state) {
        free(h->steps);
        free(h->ck);
        free(h->links);
        free(h->state);
        memset(h, 0, sizeof *h);
        return df_error_set(err, DF_ENOMEM, "history: out of memory (%zu doubles)", n);
    }
    memcpy(h->state, pos, n * sizeof *h->state);
    h->max_states = max_states;
    h->n = n;
    h->bytes = n * sizeof(double);
    h->max_bytes = SIZE_MAX;
    h->replay_budget_ns = DF_HISTORY_DEFAULT_BUDGET_NS;
    return DF_OK;
}

void df_history_set_replay(df_history *h, df_history_replay_fn fn, void *ctx,
                           uint64_t budget_ns)
{
    if (!h) return;
    h->replay = fn;
    h->replay_ctx = ctx;
    h->replay_budget_ns = budget_ns;
}

int df_history_set_reference(df_history *h, const double *ref, df_error *err)
{
    if (!h || !h->state) return df_error_set(err, DF_EINVAL, "history: NULL");
    int rc = DF_OK;
    if (h->apack) { /* decoded against the old reference while it is still valid */
        double *a = malloc(h->n * sizeof *a);
        int bad = 0;
        rc = a ? hi_anchor_read(h, a, &bad, err)
               : df_error_set(err, DF_ENOMEM, "history: out of memory (checkpoint)");
        if (rc == DF_OK) {
            hi_anchor_set(h, a, NULL, 0, 0);
        } else {
            free(a);
            if (bad) {
                h->mismatches++;
                hi_drop_below_current(h); /* the current state becomes the anchor */
            }
        }
    }
    if (rc == DF_OK || h->anchor || !h->nck) h->ref = ref;
    h->gen++;
    hi_account(h);
    return rc;
}

void df_history_reset(df_history *h, const double *pos)
{
    if (!h || !h->state || !pos) return;
    for (int i = 0; i < h->count; i++) hi_step_free(&h->steps[i]);
    hi_ck_clear(h);
    h->count = h->cur = 0;
    memcpy(h->state, pos, h->n * sizeof *h->state);
    h->gen++;
    hi_account(h);
}

void df_history_free(df_history *h)
{
    if (!h) return;
    for (int i = 0; i < h->count; i++) hi_step_free(&h->steps[i]);
    hi_ck_clear(h);
    free(h->steps);
    free(h->ck);
    free(h->links);
    free(h->state);
    memset(h, 0, sizeof *h);
}

int df_history_set_max_bytes(df_history *h, size_t max_bytes)
{
    if (!h || !h->state) return 0;
    h->max_bytes = max_bytes;
    int d = hi_enforce(h);
    if (d) h->gen++;
    return d;
}

void df_history_plan_free(df_history_plan *p)
{
    if (!p) return;
    hi_step_free(&p->step);
    free(p->anchor);
    free(p->apack);
    hi_link_free(&p->link);
    memset(p, 0, sizeof *p);
}

static uint64_t now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint64_t)t.tv_sec * 1000000000ull + (uint64_t)t.tv_nsec;
}

/* Replay cost of the RECIPE steps [from, to). */
static uint64_t cost(const df_history *h, int from, int to)
{
    uint64_t c = 0;
    for (int k = from; k < to; k++)
        if (h->steps[k].kind == DF_HISTORY_RECIPE) c += h->steps[k].cost_ns;
    return c;
}

static double *copy_of(const double *p, size_t n)
{
    double *c = malloc(n * sizeof *c);
    if (c) memcpy(c, p, n * sizeof *c);
    return c;
}

/* The plan's new anchor `state`: packed against h->ref or a full copy. */
static int plan_anchor(const df_history *h, const double *state, df_history_plan *p,
                       df_error *err)
{
    if (h->ref) return hi_anchor_pack(h, state, &p->apack, &p->apack_len, &p->asum, err);
    if (!(p->anchor = copy_of(state, h->n)))
        return df_error_set(err, DF_ENOMEM, "history: out of memory (checkpoint)");
    return DF_OK;
}

/* When the plan leaves the anchor as it is and it is a full copy although a reference is set
 * (the loop thread made it): packs it (plan->repack). A failure only leaves it a full copy. */
static void plan_repack(const df_history *h, df_history_plan *p)
{
    if (!h->ref || !h->anchor || p->anchor || p->apack) return;
    if (hi_anchor_pack(h, h->anchor, &p->apack, &p->apack_len, &p->asum, NULL) == DF_OK)
        p->repack = 1;
}

/* Plans a checkpoint at `target` (the state after step `last`, a RECIPE step of cost `extra`
 * not held yet, or 0 when held) when the replay cost since the newest checkpoint is over
 * budget: the plan's new anchor = target (plan_anchor), plan->link from it to the current
 * anchor. An anchor that does not decode: no checkpoint, plan->bad_anchor (the install drops
 * what it made unreachable). */
static int plan_checkpoint(const df_history *h, int nck, int last, uint64_t extra,
                           const double *target, df_history_plan *p, df_error *err)
{
    if (nck < 1 || h->ck[nck - 1] > last) return DF_OK;
    if (cost(h, h->ck[nck - 1], last) + extra <= h->replay_budget_ns) return DF_OK;
    double *old = malloc(h->n * sizeof *old);
    if (!old) return df_error_set(err, DF_ENOMEM, "history: out of memory (checkpoint)");
    df_error e;
    int rc = hi_anchor_read(h, old, &p->bad_anchor, &e);
    if (rc != DF_OK) {
        free(old);
        return p->bad_anchor ? DF_OK : df_error_set(err, rc, "%s", e.msg);
    }
    rc = hi_link_make(target, old, h->n, &p->link, err);
    if (rc == DF_OK) rc = plan_anchor(h, target, p, err);
    free(old);
    p->new_ck = rc == DF_OK;
    return rc;
}

/* The RECIPE step turning h->state into pos by `blob`, when a replay reproduces pos bitwise
 * (else plan->fallback: 1 the replay failed, 2 it differed). */
static int plan_recipe(const df_history *h, const double *pos, const uint8_t *blob, size_t len,
                       df_history_plan *p, df_error *err)
{
    double *tmp = malloc(h->n * sizeof *tmp);
    if (!tmp) return df_error_set(err, DF_ENOMEM, "history: out of memory (replay)");
    df_error e;
    void *scratch = NULL;
    uint64_t (*tick)(void) = h->clock_ns ? h->clock_ns : now_ns;
    /* the cost recorded is a replay's, not first-touching fresh memory (the scratch, tmp) */
    int rc = h->replay(h->replay_ctx, NULL, 0, NULL, NULL, &scratch, &e); /* prepare */
    memset(tmp, 0, h->n * sizeof *tmp);
    uint64_t t0 = tick();
    if (rc == DF_OK) rc = h->replay(h->replay_ctx, blob, len, h->state, tmp, &scratch, &e);
    uint64_t t = tick() - t0;
    p->replays++;
    int same = rc == DF_OK && memcmp(tmp, pos, h->n * sizeof *tmp) == 0;
    free(scratch);
    free(tmp);
    if (!same) {
        p->fallback = rc == DF_OK ? 2 : 1;
        return DF_OK;
    }
    if (!(p->step.blob = malloc(len ? len : 1)))
        return df_error_set(err, DF_ENOMEM, "history: out of memory (recipe)");
    memcpy(p->step.blob, blob, len);
    p->step.kind = DF_HISTORY_RECIPE;
    p->step.len = len;
    p->step.sum = df_positions_checksum(pos, h->n);
    p->step.cost_ns = t ? t : 1;
    return DF_OK;
}

int df_history_plan_commit(const df_history *h, const double *pos, const uint8_t *blob,
                           size_t len, df_history_plan *p, df_error *err)
{
    if (!p) return df_error_set(err, DF_EINVAL, "history: NULL plan");
    memset(p, 0, sizeof *p);
    if (!h || !h->state || !pos || (len && !blob))
        return df_error_set(err, DF_EINVAL, "history: bad arguments");
    p->gen = h->gen;
    if (memcmp(h->state, pos, h->n * sizeof *pos) == 0) {
        p->nochange = p->valid = 1;
        return DF_OK;
    }
    int rc = DF_OK;
    if (blob && h->replay) rc = plan_recipe(h, pos, blob, len, p, err);
    else p->fallback = blob ? 1 : 0;
    if (rc == DF_OK && p->step.kind != DF_HISTORY_RECIPE)
        rc = hi_step_xor(h->state, pos, h->n, &p->step, err);
    if (rc == DF_OK && p->step.kind == DF_HISTORY_RECIPE) {
        /* the checkpoints go with the redo tail when it holds every RECIPE step (hi_truncate:
         * then only a lone one can be above the current state) */
        int nck = 0;
        for (int k = 0; k < h->cur && !nck; k++)
            if (h->steps[k].kind == DF_HISTORY_RECIPE) nck = h->nck;
        if (nck == 0) { /* the first checkpoint: the state the recipe starts from */
            rc = plan_anchor(h, h->state, p, err);
        } else {
            rc = plan_checkpoint(h, nck, h->cur, p->step.cost_ns, pos, p, err);
        }
    }
    if (rc != DF_OK) {
        df_history_plan_free(p);
        return rc;
    }
    plan_repack(h, p);
    p->valid = 1;
    return DF_OK;
}

/* Undo to j = cur - 1 into out (see history.h: XOR from the current state, else replay from
 * the newest checkpoint <= j, moving the anchor down when it is above j). */
static int plan_undo(const df_history *h, double *out, double *tmp, void **scratch,
                     df_history_plan *p, df_error *err)
{
    int j = h->cur - 1, i = -1, rc = DF_OK;
    for (int c = 0; c < h->nck; c++)
        if (h->ck[c] <= j) i = c;
    p->keep_ck = h->nck;
    if (h->nck >= 2 && h->ck[h->nck - 1] > j) { /* the anchor moves to ck[max(i, 0)] */
        p->keep_ck = (i < 0 ? 0 : i) + 1;
        if (!(p->anchor = malloc(h->n * sizeof *p->anchor)))
            return df_error_set(err, DF_ENOMEM, "history: out of memory (checkpoint)");
        rc = hi_ck_state(h, p->keep_ck - 1, p->anchor, &p->mismatch, err);
        if (rc != DF_OK) {
            if (p->mismatch) p->bad_step = -1; /* the anchor */
            return rc;
        }
    }
    if (h->steps[j].kind == DF_HISTORY_XOR) {
        memcpy(out, h->state, h->n * sizeof *out);
        rc = hi_forward(h, j, out, tmp, scratch, &p->replays, &p->mismatch, err); /* both ways */
    } else { /* a RECIPE step: ck[0] <= j (history.h), so i >= 0 */
        if (p->anchor) memcpy(out, p->anchor, h->n * sizeof *out);
        else if ((rc = hi_anchor_read(h, out, &p->mismatch, err)) != DF_OK && p->mismatch)
            p->bad_step = -1;
        for (int k = h->ck[i]; rc == DF_OK && k < j; k++) {
            rc = hi_forward(h, k, out, tmp, scratch, &p->replays, &p->mismatch, err);
            if (p->mismatch) p->bad_step = k;
        }
    }
    if (rc == DF_OK && p->anchor && h->ref) { /* the moved anchor, packed */
        rc = hi_anchor_pack(h, p->anchor, &p->apack, &p->apack_len, &p->asum, err);
        if (rc == DF_OK) {
            free(p->anchor);
            p->anchor = NULL;
        }
    }
    return rc;
}

int df_history_plan_move(const df_history *h, int dir, double *out, df_history_plan *p,
                         df_error *err)
{
    if (!p) return df_error_set(err, DF_EINVAL, "history: NULL plan");
    memset(p, 0, sizeof *p);
    if (!h || !h->state || !out || (dir != -1 && dir != 1))
        return df_error_set(err, DF_EINVAL, "history: bad arguments");
    if (dir < 0 ? h->cur == 0 : h->cur >= h->count)
        return df_error_set(err, DF_ESTATE, dir < 0 ? "nothing to undo" : "nothing to redo");
    p->dir = dir;
    p->gen = h->gen;
    double *tmp = malloc(h->n * sizeof *tmp);
    if (!tmp) return df_error_set(err, DF_ENOMEM, "history: out of memory (undo)");
    void *scratch = NULL;
    int rc;
    if (dir < 0) {
        rc = plan_undo(h, out, tmp, &scratch, p, err);
    } else {
        memcpy(out, h->state, h->n * sizeof *out);
        rc = hi_forward(h, h->cur, out, tmp, &scratch, &p->replays, &p->mismatch, err);
        if (p->mismatch) p->bad_step = h->cur;
        if (rc == DF_OK && h->steps[h->cur].kind == DF_HISTORY_RECIPE)
            rc = plan_checkpoint(h, h->nck, h->cur + 1, 0, out, p, err);
    }
    free(scratch);
    free(tmp);
    if (rc != DF_OK) {
        int mismatch = p->mismatch, bad = p->bad_step;
        uint64_t replays = p->replays;
        df_history_plan_free(p);
        p->dir = dir; /* what df_history_repair needs */
        p->gen = h->gen;
        p->mismatch = mismatch;
        p->bad_step = bad;
        p->replays = replays;
        return rc;
    }
    plan_repack(h, p);
    p->valid = 1;
    return DF_OK;
}

/* Appends the plan's new checkpoint (at h->cur) to h. */
static void take_anchor(df_history *h, df_history_plan *p)
{
    hi_anchor_set(h, p->anchor, p->apack, p->apack_len, p->asum);
    p->anchor = NULL;
    p->apack = NULL;
}

static void push_checkpoint(df_history *h, df_history_plan *p)
{
    if (!p->new_ck) return;
    h->links[h->nck - 1] = p->link;
    memset(&p->link, 0, sizeof p->link);
    h->ck[h->nck++] = h->cur;
    take_anchor(h, p);
}

int df_history_install(df_history *h, df_history_plan *p, const double *state, df_error *err)
{
    if (!h || !h->state || !p || !state)
        return df_error_set(err, DF_EINVAL, "history: bad arguments");
    if (!p->valid || p->gen != h->gen)
        return df_error_set(err, DF_ESTATE, "history: the plan is %s",
                            p->valid ? "stale (the history changed since)" : "not valid");
    h->replays += p->replays;
    if (p->nochange) {
        df_history_plan_free(p);
        return DF_OK;
    }
    h->mismatches += p->fallback == 2;
    if (p->dir == 0) {
        hi_truncate(h, h->cur);
        if (p->step.kind == DF_HISTORY_RECIPE && h->nck == 0) { /* the first checkpoint */
            take_anchor(h, p);
            h->ck[0] = h->cur;
            h->nck = 1;
        }
        h->steps[h->count++] = p->step;
        memset(&p->step, 0, sizeof p->step);
        h->cur = h->count;
        push_checkpoint(h, p);
    } else if (p->dir < 0) {
        if (!p->repack && (p->anchor || p->apack)) {
            for (int i = p->keep_ck - 1; i + 1 < h->nck; i++) hi_link_free(&h->links[i]);
            h->nck = p->keep_ck;
            take_anchor(h, p);
        }
        h->cur--;
    } else {
        h->cur++;
        push_checkpoint(h, p);
    }
    if (p->repack && h->nck && h->anchor) { /* the same full-copy anchor, packed */
        hi_anchor_set(h, h->anchor, p->apack, p->apack_len, p->asum);
        p->apack = NULL;
    }
    memcpy(h->state, state, h->n * sizeof *state);
    if (p->bad_anchor) { /* nothing below the new state is reachable */
        h->mismatches++;
        hi_drop_below_current(h);
    }
    df_history_plan_free(p);
    h->gen++;
    hi_enforce(h);
    return DF_OK;
}

int df_history_repair(df_history *h, const df_history_plan *p)
{
    if (!h || !h->state || !p || !p->mismatch || p->gen != h->gen) return 0;
    uint64_t d0 = h->dropped;
    h->mismatches++;
    if (p->dir > 0) {
        h->dropped += (uint64_t)(h->count - h->cur);
        hi_truncate(h, h->cur);
    } else if (p->dir < 0) {
        int upto = h->cur;
        for (int c = h->nck - 1; c >= 0; c--)
            if (h->ck[c] > p->bad_step && h->ck[c] <= h->cur) upto = h->ck[c];
        if (p->bad_step < 0) hi_drop_below_current(h); /* the anchor itself */
        else hi_drop_prefix(h, upto);
    }
    h->gen++;
    hi_account(h);
    return (int)(h->dropped - d0);
}

static int commit_blob(df_history *h, const double *pos, const uint8_t *blob, size_t len,
                       df_error *err)
{
    df_history_plan p;
    int rc = df_history_plan_commit(h, pos, blob, len, &p, err);
    if (rc == DF_OK) rc = df_history_install(h, &p, pos, err);
    df_history_plan_free(&p);
    return rc;
}

int df_history_commit(df_history *h, const double *pos, df_error *err)
{
    if (!h || !h->state) return df_error_set(err, DF_EINVAL, "history: NULL");
    return commit_blob(h, pos, NULL, 0, err);
}

int df_history_commit_recipe(df_history *h, const double *pos, const uint8_t *blob, size_t len,
                             df_error *err)
{
    if (!h || !h->state) return df_error_set(err, DF_EINVAL, "history: NULL");
    return commit_blob(h, pos, blob, len, err);
}

int df_history_peek(const df_history *h, int dir, double *out, df_error *err)
{
    df_history_plan p;
    int rc = df_history_plan_move(h, dir, out, &p, err);
    df_history_plan_free(&p);
    return rc;
}

static const double *move(df_history *h, int dir, df_error *err)
{
    if (!h || !h->state) {
        df_error_set(err, DF_EINVAL, "history: NULL");
        return NULL;
    }
    double *out = malloc(h->n * sizeof *out);
    if (!out) {
        df_error_set(err, DF_ENOMEM, "history: out of memory");
        return NULL;
    }
    df_history_plan p;
    int rc = df_history_plan_move(h, dir, out, &p, err);
    if (rc == DF_OK) rc = df_history_install(h, &p, out, err);
    else df_history_repair(h, &p);
    df_history_plan_free(&p);
    free(out);
    return rc == DF_OK ? h->state : NULL;
}

const double *df_history_undo(df_history *h, df_error *err) { return move(h, -1, err); }

const double *df_history_redo(df_history *h, df_error *err) { return move(h, 1, err); }

int df_history_can_undo(const df_history *h) { return h && h->state ? h->cur : 0; }

int df_history_can_redo(const df_history *h)
{
    return h && h->state ? h->count - h->cur : 0;
}

size_t df_history_bytes(const df_history *h) { return h ? h->bytes : 0; }

size_t df_history_undo_bytes(const df_history *h)
{
    return h && h->state ? h->bytes - h->n * sizeof(double) : 0;
}

void df_history_parts(const df_history *h, size_t *anchor, size_t *links, size_t *steps)
{
    size_t a = 0, l = 0, s = 0;
    if (h && h->state) {
        a = h->anchor ? h->n * sizeof(double) : h->apack_len;
        for (int i = 0; i + 1 < h->nck; i++) l += h->links[i].len + sizeof h->links[i];
        for (int i = 0; i < h->count; i++) s += hi_step_bytes(&h->steps[i]);
    }
    if (anchor) *anchor = a;
    if (links) *links = l;
    if (steps) *steps = s;
}

int df_history_steps_of(const df_history *h, int kind)
{
    int c = 0;
    for (int i = 0; h && i < h->count; i++) c += h->steps[i].kind == kind;
    return c;
}

/* history.c — undo/redo stack of committed positions, XOR steps under a byte budget (see
 * history.h). */
#include "server/session/history.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static size_t step_bytes(const df_history_step *s)
{
    return (size_t)s->count * (3 * sizeof(uint64_t) + (s->idx ? sizeof(uint32_t) : 0)) +
           sizeof *s;
}

static void step_free(df_history_step *s)
{
    free(s->idx);
    free(s->x);
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

/* XORs step `s` into `state` (applies it forwards or backwards: the same operation). */
static void step_apply(const df_history_step *s, double *state, size_t n)
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

int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err)
{
    if (!h) return df_error_set(err, DF_EINVAL, "history: NULL");
    memset(h, 0, sizeof *h);
    if (!pos || n == 0 || n % 3 != 0 || n / 3 > UINT32_MAX || max_states < 2)
        return df_error_set(err, DF_EINVAL, "history: bad arguments (n %zu, max %d)", n,
                            max_states);
    h->steps = calloc((size_t)max_states - 1, sizeof *h->steps);
    h->state = malloc(n * sizeof *h->state);
    if (!h->steps || !h->state) {
        free(h->steps);
        free(h->state);
        memset(h, 0, sizeof *h);
        return df_error_set(err, DF_ENOMEM, "history: out of memory (%zu doubles)", n);
    }
    memcpy(h->state, pos, n * sizeof *h->state);
    h->max_states = max_states;
    h->n = n;
    h->bytes = n * sizeof(double);
    h->max_bytes = SIZE_MAX;
    return DF_OK;
}

void df_history_free(df_history *h)
{
    if (!h) return;
    for (int i = 0; i < h->count; i++) step_free(&h->steps[i]);
    free(h->steps);
    free(h->state);
    memset(h, 0, sizeof *h);
}

/* Drops the oldest step (the current state stays: cur >= 1 after a commit). */
static void drop_oldest(df_history *h)
{
    h->bytes -= step_bytes(&h->steps[0]);
    step_free(&h->steps[0]);
    memmove(h->steps, h->steps + 1, (size_t)(h->count - 1) * sizeof *h->steps);
    h->count--;
    h->cur--;
    h->dropped++;
}

/* Drops oldest steps while over a cap; never a step above the current state. */
static int enforce(df_history *h)
{
    int dropped = 0;
    while (h->cur > 0 && (h->count > h->max_states - 1 || h->bytes > h->max_bytes)) {
        drop_oldest(h);
        dropped++;
    }
    return dropped;
}

int df_history_set_max_bytes(df_history *h, size_t max_bytes)
{
    if (!h || !h->state) return 0;
    h->max_bytes = max_bytes;
    return enforce(h);
}

int df_history_commit(df_history *h, const double *pos, df_error *err)
{
    if (!h || !h->state || !pos) return df_error_set(err, DF_EINVAL, "history: NULL");
    const double *a = h->state, *b = pos;
    size_t nv = h->n / 3, changed = 0;
    for (size_t i = 0; i < h->n; i += 3)
        changed += ((bits(a + i) ^ bits(b + i)) | (bits(a + i + 1) ^ bits(b + i + 1)) |
                    (bits(a + i + 2) ^ bits(b + i + 2))) != 0;
    if (changed == 0) return DF_OK; /* no change */
    df_history_step st = {.count = (uint32_t)changed};
    int dense = changed * (3 * sizeof(uint64_t) + sizeof(uint32_t)) >= h->n * sizeof(uint64_t);
    if (dense) st.count = (uint32_t)nv;
    st.x = malloc(3 * (size_t)st.count * sizeof *st.x);
    if (!dense) st.idx = malloc((size_t)st.count * sizeof *st.idx);
    if (!st.x || (!dense && !st.idx)) {
        step_free(&st);
        return df_error_set(err, DF_ENOMEM, "history: out of memory (%zu changed vertices)",
                            changed);
    }
    if (dense) {
        for (size_t i = 0; i < h->n; i++) st.x[i] = bits(a + i) ^ bits(b + i);
    } else {
        uint32_t k = 0;
        for (size_t i = 0; i < nv; i++) {
            uint64_t x0 = bits(a + 3 * i) ^ bits(b + 3 * i),
                     x1 = bits(a + 3 * i + 1) ^ bits(b + 3 * i + 1),
                     x2 = bits(a + 3 * i + 2) ^ bits(b + 3 * i + 2);
            if (!(x0 | x1 | x2)) continue;
            st.idx[k] = (uint32_t)i;
            st.x[3 * (size_t)k] = x0;
            st.x[3 * (size_t)k + 1] = x1;
            st.x[3 * (size_t)k + 2] = x2;
            k++;
        }
    }
    for (int i = h->cur; i < h->count; i++) {
        h->bytes -= step_bytes(&h->steps[i]);
        step_free(&h->steps[i]);
    }
    h->count = h->cur;
    if (h->count == h->max_states - 1) drop_oldest(h); /* the array has max_states - 1 slots */
    h->steps[h->count++] = st;
    h->cur = h->count;
    h->bytes += step_bytes(&st);
    memcpy(h->state, pos, h->n * sizeof *pos);
    enforce(h);
    return DF_OK;
}

int df_history_peek(const df_history *h, int dir, double *out, df_error *err)
{
    if (!h || !h->state || !out || (dir != -1 && dir != 1))
        return df_error_set(err, DF_EINVAL, "history: bad arguments");
    if (dir < 0 ? h->cur == 0 : h->cur >= h->count)
        return df_error_set(err, DF_ESTATE, dir < 0 ? "nothing to undo" : "nothing to redo");
    memcpy(out, h->state, h->n * sizeof *out);
    step_apply(&h->steps[dir < 0 ? h->cur - 1 : h->cur], out, h->n);
    return DF_OK;
}

const double *df_history_undo(df_history *h, df_error *err)
{
    if (!h || !h->state) {
        df_error_set(err, DF_EINVAL, "history: NULL");
        return NULL;
    }
    if (h->cur == 0) {
        df_error_set(err, DF_ESTATE, "nothing to undo");
        return NULL;
    }
    step_apply(&h->steps[--h->cur], h->state, h->n);
    return h->state;
}

const double *df_history_redo(df_history *h, df_error *err)
{
    if (!h || !h->state) {
        df_error_set(err, DF_EINVAL, "history: NULL");
        return NULL;
    }
    if (h->cur >= h->count) {
        df_error_set(err, DF_ESTATE, "nothing to redo");
        return NULL;
    }
    step_apply(&h->steps[h->cur++], h->state, h->n);
    return h->state;
}

int df_history_can_undo(const df_history *h) { return h && h->state ? h->cur : 0; }

int df_history_can_redo(const df_history *h)
{
    return h && h->state ? h->count - h->cur : 0;
}

size_t df_history_bytes(const df_history *h) { return h ? h->bytes : 0; }

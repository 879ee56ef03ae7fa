/* history.c — undo/redo stack of committed positions (see history.h). */
#include "server/history.h"

#include <stdlib.h>
#include <string.h>

int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err)
{
    if (!h) return df_error_set(err, DF_EINVAL, "history: NULL");
    memset(h, 0, sizeof *h);
    if (!pos || n == 0 || max_states < 2)
        return df_error_set(err, DF_EINVAL, "history: bad arguments (n %zu, max %d)", n,
                            max_states);
    h->states = calloc((size_t)max_states, sizeof *h->states);
    double *s = malloc(n * sizeof *s);
    if (!h->states || !s) {
        free(h->states);
        free(s);
        h->states = NULL;
        return df_error_set(err, DF_ENOMEM, "history: out of memory (%zu doubles)", n);
    }
    memcpy(s, pos, n * sizeof *s);
    h->states[0] = s;
    h->count = 1;
    h->cur = 0;
    h->max_states = max_states;
    h->n = n;
    return DF_OK;
}

void df_history_free(df_history *h)
{
    if (!h) return;
    for (int i = 0; i < h->count; i++) free(h->states[i]);
    free(h->states);
    memset(h, 0, sizeof *h);
}

int df_history_commit(df_history *h, const double *pos, df_error *err)
{
    if (!h || !h->states || !pos) return df_error_set(err, DF_EINVAL, "history: NULL");
    if (memcmp(h->states[h->cur], pos, h->n * sizeof *pos) == 0) return DF_OK; /* no change */
    double *s = malloc(h->n * sizeof *s);
    if (!s) return df_error_set(err, DF_ENOMEM, "history: out of memory");
    memcpy(s, pos, h->n * sizeof *s);
    for (int i = h->cur + 1; i < h->count; i++) free(h->states[i]);
    h->count = h->cur + 1;
    if (h->count == h->max_states) {
        free(h->states[0]);
        memmove(h->states, h->states + 1, (size_t)(h->count - 1) * sizeof *h->states);
        h->count--;
    }
    h->states[h->count++] = s;
    h->cur = h->count - 1;
    return DF_OK;
}

const double *df_history_undo(df_history *h, df_error *err)
{
    if (!h || !h->states) {
        df_error_set(err, DF_EINVAL, "history: NULL");
        return NULL;
    }
    if (h->cur == 0) {
        df_error_set(err, DF_ESTATE, "nothing to undo");
        return NULL;
    }
    return h->states[--h->cur];
}

const double *df_history_redo(df_history *h, df_error *err)
{
    if (!h || !h->states) {
        df_error_set(err, DF_EINVAL, "history: NULL");
        return NULL;
    }
    if (h->cur + 1 >= h->count) {
        df_error_set(err, DF_ESTATE, "nothing to redo");
        return NULL;
    }
    return h->states[++h->cur];
}

int df_history_can_undo(const df_history *h) { return h && h->states ? h->cur : 0; }

int df_history_can_redo(const df_history *h)
{
    return h && h->states ? h->count - 1 - h->cur : 0;
}

size_t df_history_bytes(const df_history *h)
{
    return h ? (size_t)h->count * h->n * sizeof(double) : 0;
}

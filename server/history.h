/* history.h — a session's undo/redo stack of committed position states (pure, no I/O).
 *
 * Every committed change (stroke end, final handle move, reset, load) pushes a full copy of the
 * positions (nv x 3 doubles). `cur` indexes the state the session currently shows. Undo moves to
 * cur - 1, redo to cur + 1; a commit after undos drops the redo tail. At most `max_states` states
 * are kept (the oldest is dropped, so undo depth is max_states - 1). Version numbers are NOT kept
 * here: undo/redo are broadcast as new versions by the session. */
#ifndef DF_SERVER_HISTORY_H
#define DF_SERVER_HISTORY_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_HISTORY_DEFAULT_MAX 64

typedef struct df_history {
    double **states;   /* count copies of n doubles */
    int count, cur, max_states;
    size_t n;          /* doubles per state (3 * nv) */
} df_history;

/* Initializes with the first state (a copy of `pos`, n doubles). max_states >= 2.
 * Errors: DF_EINVAL (NULL, n == 0, max_states < 2), DF_ENOMEM; h zeroed on error. */
int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err);

/* Frees every state; h becomes empty. NULL-safe. */
void df_history_free(df_history *h);

/* Commits a copy of `pos` (h->n doubles) as the new current state, dropping the redo tail and,
 * when full, the oldest state. A `pos` bitwise equal to the current state is no change and adds
 * no step (the redo tail stays): two interleaved strokes are committed by whichever ends first,
 * and the second must not leave an empty step for undo to "revert". Errors: DF_EINVAL,
 * DF_ENOMEM (history unchanged). */
int df_history_commit(df_history *h, const double *pos, df_error *err);

/* Steps back: returns the now-current state (owned by h) or NULL with DF_ESTATE in *err when
 * nothing is left to undo. */
const double *df_history_undo(df_history *h, df_error *err);

/* Steps forward: the now-current state or NULL with DF_ESTATE when nothing is left to redo. */
const double *df_history_redo(df_history *h, df_error *err);

/* Number of undo / redo steps available. */
int df_history_can_undo(const df_history *h);
int df_history_can_redo(const df_history *h);

/* Bytes held by the stored states. */
size_t df_history_bytes(const df_history *h);

#endif

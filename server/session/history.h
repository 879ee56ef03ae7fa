/* history.h — a session's undo/redo stack of committed position states (pure, no I/O).
 *
 * Every committed change (stroke end, final handle move, load) is one step. The history keeps
 * one full copy of the current state (n doubles) and, per step, only what changed: the vertices
 * (triples of doubles) whose bits differ, each stored as the XOR of the old and new bit patterns
 * (or every vertex, without indices, when that is smaller). XOR runs both ways, so undo and redo
 * restore states bit for bit. `cur` counts the steps below the current state: undo moves to
 * cur - 1, redo to cur + 1; a commit after undos drops the redo tail. Bounds: at most
 * max_states - 1 steps, and at most `max_bytes` held in total (the current state included); a
 * commit beyond either drops the oldest steps (counted in `dropped`), down to none when one step
 * alone does not fit. Version numbers are NOT kept here: undo/redo are broadcast as new versions
 * by the session. */
#ifndef DF_SERVER_HISTORY_H
#define DF_SERVER_HISTORY_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

/* One step: state k -> state k + 1. */
typedef struct df_history_step {
    uint32_t count;    /* vertices changed */
    uint32_t *idx;     /* their indices, ascending; NULL when dense (every vertex, in order) */
    uint64_t *x;       /* 3 * count XORs of old and new double bits */
} df_history_step;

typedef struct df_history {
    double *state;           /* the current state, n doubles */
    df_history_step *steps;  /* count steps, oldest first */
    int count, cur, max_states;
    size_t n;                /* doubles per state (3 * nv) */
    size_t bytes;            /* held: state + steps */
    size_t max_bytes;        /* budget of `bytes` (SIZE_MAX: none) */
    uint64_t dropped;        /* oldest steps dropped to the caps */
} df_history;

/* Initializes with the first state (a copy of `pos`, n doubles, n a multiple of 3 and
 * <= 3 * UINT32_MAX). max_states >= 2; no byte budget until df_history_set_max_bytes.
 * Errors: DF_EINVAL (NULL, bad n, max_states < 2), DF_ENOMEM; h zeroed on error. */
int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err);

/* Frees every state; h becomes empty. NULL-safe. */
void df_history_free(df_history *h);

/* Sets the byte budget and drops the oldest steps until the history fits (the current state is
 * always kept, even alone above the budget). Returns the number of steps dropped. */
int df_history_set_max_bytes(df_history *h, size_t max_bytes);

/* Commits `pos` (h->n doubles) as the new current state, dropping the redo tail and then, over
 * max_states or max_bytes, the oldest steps. A `pos` bitwise equal to the current state is no
 * change and adds no step (the redo tail stays): two interleaved strokes are committed by
 * whichever ends first, and the second must not leave an empty step for undo to "revert".
 * Errors: DF_EINVAL, DF_ENOMEM (history unchanged). */
int df_history_commit(df_history *h, const double *pos, df_error *err);

/* Writes the state one undo (dir -1) or redo (dir +1) away into `out` (h->n doubles) without
 * moving. Errors: DF_EINVAL, DF_ESTATE when there is no such step (out untouched). */
int df_history_peek(const df_history *h, int dir, double *out, df_error *err);

/* Steps back: returns the now-current state (owned by h) or NULL with DF_ESTATE in *err when
 * nothing is left to undo. */
const double *df_history_undo(df_history *h, df_error *err);

/* Steps forward: the now-current state or NULL with DF_ESTATE when nothing is left to redo. */
const double *df_history_redo(df_history *h, df_error *err);

/* Number of undo / redo steps available. */
int df_history_can_undo(const df_history *h);
int df_history_can_redo(const df_history *h);

/* Bytes held (the current state and every step). */
size_t df_history_bytes(const df_history *h);

#endif

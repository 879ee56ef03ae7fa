/* history_int.h — internals shared by history.c (the API: plans and installs) and
 * history_ckpt.c (steps, checkpoints, drops). Not for other callers: see history.h. Every
 * function keeps h's invariants (history.h) and leaves h->bytes to hi_account. */
#ifndef DF_SERVER_HISTORY_INT_H
#define DF_SERVER_HISTORY_INT_H

#include "server/session/history.h"

/* Bytes a step holds (its arrays or blob, plus the struct). */
size_t hi_step_bytes(const df_history_step *s);

/* Frees a step's arrays / blob and zeroes it. */
void hi_step_free(df_history_step *s);

/* Builds the XOR step from a to b (n doubles each) into *st (sparse or dense, the smaller).
 * Returns DF_OK (st->count 0: bitwise equal, nothing allocated) or DF_ENOMEM. */
int hi_step_xor(const double *a, const double *b, size_t n, df_history_step *st, df_error *err);

/* Applies step k of h forwards to `a` (n doubles): XOR in place, or RECIPE replayed through
 * `tmp` (n doubles; *scratch the callback's buffer, history.h) and checked against its
 * checksum (*replays counted). Errors: DF_ESTATE (no replay callback), the replay's error,
 * DF_EINTERNAL with *mismatch = 1 when the checksum differs; `a` unspecified on error. */
int hi_forward(const df_history *h, int k, double *a, double *tmp, void **scratch,
               uint64_t *replays, int *mismatch, df_error *err);

/* Writes the anchor's state into out (n doubles): the full copy, or the reference with the
 * packed delta applied and its checksum checked. Errors: DF_EINTERNAL (a corrupt packed
 * anchor or a changed reference: *bad = 1 when bad is not NULL), DF_ENOMEM. */
int hi_anchor_read(const df_history *h, double *out, int *bad, df_error *err);

/* Packs `state` (n doubles) against h->ref into *blob / *len (malloc'd) with its checksum
 * *sum (every read checks it: hi_anchor_read). Errors: the codec's (nothing returned). */
int hi_anchor_pack(const df_history *h, const double *state, uint8_t **blob, size_t *len,
                   uint64_t *sum, df_error *err);

/* Replaces h's anchor by the full copy `a` (owned; may be h->anchor) or, when blob is not
 * NULL, by the packed anchor (blob, len, sum; owned). */
void hi_anchor_set(df_history *h, double *a, uint8_t *blob, size_t len, uint64_t sum);

/* Writes state ck[i] into out: the anchor with links nck-2 .. i applied. Errors: as
 * hi_anchor_read (*bad), the codec's (DF_EFORMAT, DF_ENOMEM). */
int hi_ck_state(const df_history *h, int i, double *out, int *bad, df_error *err);

/* Encodes the link turning `newer` into `older` (n doubles each). Errors: the codec's. */
int hi_link_make(const double *newer, const double *older, size_t n, df_history_link *l,
                 df_error *err);
void hi_link_free(df_history_link *l);

/* Frees the anchor and every link: no checkpoint (nck 0). */
void hi_ck_clear(df_history *h);

/* Recomputes h->bytes. */
void hi_account(df_history *h);

/* Drops steps [from, count) (from >= cur) and the checkpoints above `from`. */
void hi_truncate(df_history *h, int from);

/* Drops every step below `upto`, which is a checkpoint index or h->cur (then the current
 * state becomes the only checkpoint); counts them in h->dropped. */
void hi_drop_prefix(df_history *h, int upto);

/* The anchor is unusable: drops it, every link and every step below the current state, which
 * becomes the only checkpoint (a full copy); counts the steps in h->dropped. */
void hi_drop_below_current(df_history *h);

/* Drops the oldest step (or the oldest checkpoint segment), cur > 0 required. Returns the
 * number of steps dropped. */
int hi_drop_oldest(df_history *h);

/* Clears the checkpoints when no RECIPE step is held. */
void hi_tidy(df_history *h);

/* Drops oldest steps while over max_states - 1 steps or max_bytes (never the current state).
 * Returns the number dropped. */
int hi_enforce(df_history *h);

#endif

/* history.h — a session's undo/redo stack of committed position states (pure, no I/O).
 *
 * Every committed change (stroke end, final handle move, load) is one step from state k to
 * state k + 1. A step is one of:
 *   XOR    the vertices (triples of doubles) whose bits differ, each stored as the XOR of the
 *          old and new bit patterns (or every vertex, without indices, when that is smaller).
 *          XOR runs both ways, so it is undone and redone bit for bit.
 *   RECIPE an opaque blob (a brush stroke's request, stroke_recipe.h) that the replay callback
 *          turns state k into state k + 1 with, plus the 64-bit checksum of state k + 1
 *          (df_positions_checksum) and the measured replay cost. A few hundred bytes instead of
 *          24 per moved vertex, but it only runs forwards.
 * The history keeps one full copy of the current state (`state`, n doubles). So that states
 * below a RECIPE step stay reachable it keeps CHECKPOINTS (history_ckpt.c) as soon as it holds a
 * RECIPE step: state indices ck[0] < ... < ck[nck-1], the newest one (the ANCHOR) and between
 * consecutive ones a lossless packed link (delta.h delta layout, taken from the newer to the
 * older state). Every RECIPE step is at or above ck[0]. Without a REFERENCE the anchor is a
 * full copy (n doubles); with one (df_history_set_reference: a state the caller keeps alive and
 * unchanged, e.g. the session's rest shape) it is held PACKED as the delta.h delta from the
 * reference to the anchor plus the anchor's checksum (a local stroke history stays close to
 * its rest shape: a fraction of the full copy). Every read of a packed anchor decodes it (a
 * copy of the reference with the delta applied) and checks the checksum: a corrupt anchor or a
 * changed reference is DF_EINTERNAL, never a different mesh. New packed anchors are encoded
 * while planning, on the worker; an anchor the loop thread makes (a drop below the current
 * state, df_history_repair) stays a full copy until the next plan packs it.
 * State j is reached from the current state when only XOR steps lie between (or forwards, for
 * redo), else from the newest checkpoint <= j (the anchor, or the anchor with links applied
 * backwards) by applying the steps forwards (RECIPE: replay, checked against its checksum), or
 * from ck[0] backwards over XOR steps when j < ck[0]. Checkpoints are never above the current
 * state except ck[0] when nck == 1. A new checkpoint is taken at the new state of a commit or a
 * redo when the replay cost of the RECIPE steps since the newest checkpoint would exceed
 * `replay_budget_ns` (so an undo replays about that much at most); an undo below the anchor
 * moves the anchor down (the checkpoints above are dropped; redo takes them again).
 *
 * Two-phase changes, so a session's loop thread never replays nor compresses: a worker PLANS a
 * commit / undo / redo against the const history (df_history_plan_*: computes the target
 * state, the new step, replays, links and anchor), the loop thread INSTALLS the plan
 * (df_history_install: pointer moves and copies). A plan is valid for the history generation it
 * was made for only. `cur` counts the steps below the current state: undo moves to cur - 1, redo
 * to cur + 1; a commit after undos drops the redo tail. Bounds: at most max_states - 1 steps,
 * and at most `max_bytes` held in total; beyond either the oldest steps are dropped (counted in
 * `dropped`; with several checkpoints the whole oldest checkpoint segment goes at once; with one
 * checkpoint at state 0 the anchor is moved up one step, which replays a RECIPE step once and
 * packs the anchor again on the calling thread, unless no step would be left below the current
 * state). A replay whose checksum differs is never installed: the plan fails with DF_EINTERNAL and
 * df_history_repair drops the steps it made unreachable (counted). Version numbers are NOT kept
 * here: undo/redo are broadcast as new versions by the session. */
#ifndef DF_SERVER_HISTORY_H
#define DF_SERVER_HISTORY_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

enum { DF_HISTORY_XOR = 0, DF_HISTORY_RECIPE = 1 };

/* Replays `blob` (len bytes, a RECIPE step) from state `from` into `to` (n doubles each,
 * distinct). `*scratch` is the callback's own reusable buffer for one plan: NULL at the plan's
 * first replay; the callback may store a malloc'd buffer there (sized for this history's n) and
 * find it again at the plan's later replays; the history free()s it when the plan is done.
 * A call with blob NULL (len 0, from and to NULL) only prepares *scratch (allocates and touches
 * it) and returns DF_OK or DF_ENOMEM: the history makes it before a replay whose cost it
 * measures, so that the cost recorded is that of a replay, not of first-touching memory.
 * DF_OK or an error with err set. Called on whichever thread plans or installs. */
typedef int (*df_history_replay_fn)(void *ctx, const uint8_t *blob, size_t len,
                                    const double *from, double *to, void **scratch,
                                    df_error *err);

/* One step: state k -> state k + 1. */
typedef struct df_history_step {
    int kind;          /* DF_HISTORY_XOR or DF_HISTORY_RECIPE */
    uint32_t count;    /* XOR: vertices changed */
    uint32_t *idx;     /* XOR: their indices, ascending; NULL when dense (every vertex) */
    uint64_t *x;       /* XOR: 3 * count XORs of old and new double bits */
    uint8_t *blob;     /* RECIPE: the recipe (owned) */
    size_t len;        /* RECIPE: its bytes */
    uint64_t sum;      /* RECIPE: df_positions_checksum of state k + 1 */
    uint64_t cost_ns;  /* RECIPE: measured replay time */
} df_history_step;

/* A packed link between consecutive checkpoints (codec.h delta from the newer to the older). */
typedef struct df_history_link {
    uint8_t *blob;
    size_t len;
} df_history_link;

typedef struct df_history {
    double *state;           /* the current state, n doubles */
    df_history_step *steps;  /* count steps, oldest first (max_states slots) */
    int count, cur, max_states;
    size_t n;                /* doubles per state (3 * nv) */
    size_t bytes;            /* held: state + anchor + links + steps */
    size_t max_bytes;        /* budget of `bytes` (SIZE_MAX: none) */
    uint64_t dropped;        /* oldest steps dropped to the caps or as unreachable */
    double *anchor;          /* state ck[nck - 1] as a full copy (n doubles), or NULL */
    uint8_t *apack;          /* ... or packed against `ref` (delta.h delta ref -> anchor) */
    size_t apack_len;        /* its bytes */
    uint64_t asum;           /* df_positions_checksum of the packed anchor's state */
    const double *ref;       /* the reference (n doubles, the caller's) or NULL: full copies */
    int *ck;                 /* checkpoint state indices, ascending (max_states + 1 slots) */
    int nck;                 /* 0 exactly when no RECIPE step is held */
    df_history_link *links;  /* nck - 1: links[i] turns state ck[i + 1] into state ck[i] */
    df_history_replay_fn replay; /* NULL: RECIPE steps cannot be planned */
    void *replay_ctx;
    uint64_t replay_budget_ns;   /* replay cost between checkpoints (default 1 s) */
    uint64_t (*clock_ns)(void);  /* measures replay costs: NULL = CLOCK_MONOTONIC (tests set a
                                  * deterministic one) */
    uint64_t gen;            /* bumped by every change: a plan is for one generation */
    uint64_t replays, mismatches; /* replays run (planned or installed), checksum mismatches */
} df_history;

/* What a worker planned (df_history_plan_*) for the loop thread to install. */
typedef struct df_history_plan {
    int dir;                 /* 0 commit, -1 undo, +1 redo */
    int valid;               /* 1: planned, not installed yet */
    int nochange;            /* commit of the current state: nothing to install */
    int fallback;            /* commit: the recipe did not reproduce `pos`: an XOR step */
    uint64_t gen;            /* h->gen when planned */
    df_history_step step;    /* commit: the new step (owned until installed) */
    int keep_ck;             /* undo: checkpoints kept (nck when unchanged) */
    double *anchor;          /* undo: state ck[keep_ck - 1] (owned), or NULL: anchor unchanged;
                              * commit/redo: the new anchor (a copy of the target) or NULL;
                              * NULL when packed (apack) */
    uint8_t *apack;          /* the new anchor packed against h->ref (owned) or NULL */
    size_t apack_len;
    uint64_t asum;           /* its state's checksum */
    int repack;              /* 1: apack is h's full-copy anchor packed (no other anchor change) */
    int bad_anchor;          /* commit/redo: the anchor did not decode: the install drops every
                              * step below the new state (counted as a mismatch) */
    int new_ck;              /* commit/redo: 1 = a checkpoint at the target state */
    df_history_link link;    /* commit/redo: the link from the target to the old anchor */
    uint64_t replays;        /* replays run while planning */
    int mismatch;            /* 1: a replay's checksum differed (the plan failed) */
    int bad_step;            /* its step index; -1: the anchor did not decode */
} df_history_plan;

/* Initializes with the first state (a copy of `pos`, n doubles, n a multiple of 3 and
 * <= 3 * UINT32_MAX). max_states >= 2; no byte budget until df_history_set_max_bytes, no
 * replay callback until df_history_set_replay. Errors: DF_EINVAL (NULL, bad n,
 * max_states < 2), DF_ENOMEM; h zeroed on error. */
int df_history_init(df_history *h, const double *pos, size_t n, int max_states, df_error *err);

/* Sets the replay callback of RECIPE steps and the checkpoint budget (replay ns between
 * checkpoints; 0: a checkpoint after every RECIPE step). */
void df_history_set_replay(df_history *h, df_history_replay_fn fn, void *ctx,
                           uint64_t budget_ns);

/* Sets the reference the anchor is packed against (history.h): `ref` (h->n doubles) must stay
 * alive and unchanged while set; NULL: full-copy anchors. A packed anchor held is decoded
 * against the old reference (which must still be unchanged) and kept as a full copy until the
 * next plan packs it against the new one. Bumps the generation. Loop thread. Errors: DF_EINVAL,
 * DF_ENOMEM, DF_EINTERNAL (the held anchor did not decode: every step below the current state
 * is dropped, counted, and the reference set); on DF_ENOMEM nothing changed. */
int df_history_set_reference(df_history *h, const double *ref, df_error *err);

/* Forgets every step and checkpoint: `pos` (h->n doubles) becomes the only state (no undo, no
 * redo). Keeps the replay callback, budgets, reference and counters (the forgotten steps are
 * not counted as dropped); allocates nothing. Loop thread. */
void df_history_reset(df_history *h, const double *pos);

/* Frees every state; h becomes empty. NULL-safe. */
void df_history_free(df_history *h);

/* Sets the byte budget and drops the oldest steps until the history fits (the current state is
 * always kept, even alone above the budget). Returns the number of steps dropped. */
int df_history_set_max_bytes(df_history *h, size_t max_bytes);

/* Plans committing `pos` (h->n doubles) as the new current state. With `blob` (len bytes, the
 * recipe that should turn the current state into pos) the blob is replayed from h->state and,
 * when the result is bitwise pos, the step is a RECIPE (checksum and measured cost recorded;
 * a checkpoint planned when due); otherwise (no blob, no callback, the replay failed or
 * differs: plan->fallback, a difference counted in the plan's mismatch) an XOR step. A `pos`
 * bitwise equal to the current state is no change (plan->nochange): two interleaved strokes
 * are committed by whichever ends first, and the second must not leave an empty step.
 * Reads h only (a worker). Errors: DF_EINVAL, DF_ENOMEM (plan empty). */
int df_history_plan_commit(const df_history *h, const double *pos, const uint8_t *blob,
                           size_t len, df_history_plan *plan, df_error *err);

/* Plans an undo (dir -1) or redo (dir +1): writes the target state into `out` (h->n doubles).
 * Reads h only (a worker). Errors: DF_EINVAL, DF_ESTATE (nothing to undo / redo), DF_ENOMEM,
 * the replay's error, DF_EINTERNAL when a RECIPE step's replay does not reproduce its checksum
 * (plan->mismatch: pass the plan to df_history_repair); out unspecified on error. */
int df_history_plan_move(const df_history *h, int dir, double *out, df_history_plan *plan,
                         df_error *err);

/* Installs a plan made for this generation: the target state (`state`, h->n doubles: the
 * plan's `pos` or `out`) becomes current, then the caps are enforced. Consumes the plan's
 * buffers (plan emptied). Loop thread. Errors: DF_ESTATE (a stale or failed plan; nothing
 * changed). */
int df_history_install(df_history *h, df_history_plan *plan, const double *state,
                       df_error *err);

/* After a plan that failed with a mismatch: drops the steps it found unreachable (undo: every
 * step below the first checkpoint above the bad step, or below the current state; redo: the
 * redo tail from the bad step) and counts the mismatch. No-op for other plans. Loop thread.
 * Returns the number of steps dropped. */
int df_history_repair(df_history *h, const df_history_plan *plan);

/* Frees what a plan owns (NULL-safe); the plan becomes empty. */
void df_history_plan_free(df_history_plan *plan);

/* One-call forms (plan + install), for callers that may replay on their own thread (restore,
 * tests). commit: an XOR step; DF_OK also when pos is the current state. commit_recipe: as
 * df_history_plan_commit with a blob. Errors as plan + install. */
int df_history_commit(df_history *h, const double *pos, df_error *err);
int df_history_commit_recipe(df_history *h, const double *pos, const uint8_t *blob, size_t len,
                             df_error *err);

/* Writes the state one undo (dir -1) or redo (dir +1) away into `out` without moving. Errors as
 * df_history_plan_move (a mismatch is not repaired). */
int df_history_peek(const df_history *h, int dir, double *out, df_error *err);

/* Steps back / forward: returns the now-current state (owned by h) or NULL with *err set:
 * DF_ESTATE when nothing is left, or the plan's error (a mismatch is repaired). */
const double *df_history_undo(df_history *h, df_error *err);
const double *df_history_redo(df_history *h, df_error *err);

/* Number of undo / redo steps available. */
int df_history_can_undo(const df_history *h);
int df_history_can_redo(const df_history *h);

/* Bytes held (the current state, the anchor, links and every step). */
size_t df_history_bytes(const df_history *h);

/* Bytes of the undo history proper: anchor + links + steps (without the current state); a
 * packed anchor counts its packed bytes. */
size_t df_history_undo_bytes(const df_history *h);

/* The parts of df_history_undo_bytes: the anchor (packed or full), the links and the steps
 * (RECIPE blobs and XOR arrays, with their structs). Any pointer may be NULL. */
void df_history_parts(const df_history *h, size_t *anchor, size_t *links, size_t *steps);

/* Steps held of `kind` (DF_HISTORY_XOR / DF_HISTORY_RECIPE). */
int df_history_steps_of(const df_history *h, int kind);

#endif

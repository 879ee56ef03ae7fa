/* commit.h — the one place where a session changes: df_session_commit applies a change record
 * (df_change) that a job's compute filled without writing the session, on the loop thread.
 *
 * A job's work reads the session (its FIFO makes it the only job that runs) and fills its
 * change record: the new positions and published displacements (buffers the job borrowed from
 * the session's scratch, swapped in, never copied), the frames of the new version, the stroke
 * state it produced, the cache objects it built or used, its timings and the history step. The
 * commit then does, in this fixed order:
 *   0. store:    srv->store_ops->change (server/store/journal.h) writes the change durably
 *                first; when that fails the change is a failed one (below): nothing of it is
 *                applied, broadcast or acknowledged, the error is answered;
 *   1. state:    swap positions and displacements in, publish the version number, stroke and
 *                handle-set state, rest shape;
 *   2. history:  the undo step (commit / reset / undo / redo), charged to the memory budget;
 *                then the stroke the change ended (cancel, end) is dropped;
 *   3. accounting: timings, cache hit/miss, install / drop cached factorizations, LRU eviction;
 *   4. hook:     srv->commit_hook (an observer: a scale-out log entry; the durable store
 *                writes at step 0, where it can still refuse the change);
 *   5. broadcast the version's frames to the subscribers and keep them in the session's resync
 *      ring (session.h df_session_resync_record: by reference); a change to the session's strokes
 *      (begin, update, knob, end, cancel) then tells the HID subsystem (force feedback,
 *      srv->hid_ops->strokes_changed);
 *   6. answer the request (ack with the new version), unless the job answers itself.
 * A change whose compute failed (rc != DF_OK) does only step 3 (what it built is still cached
 * and counted; and a history plan that found a replay mismatch repairs the history) and
 * answers the error. Loop thread only. */
#ifndef DF_SERVER_COMMIT_H
#define DF_SERVER_COMMIT_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "server/net/req.h"
#include "server/session/session.h"
#include "server/session/stream.h"

/* History step of a change (df_change.hist). */
enum { DF_HIST_NONE = 0, DF_HIST_COMMIT, DF_HIST_RESET, DF_HIST_UNDO, DF_HIST_REDO };

typedef struct df_change {
    int rc;                      /* DF_OK, or the compute's error (err) */
    df_error *err;
    df_req *req;                 /* answered in step 6 (NULL: the job answers itself) */
    int answered_by_job;         /* 1: step 6 is skipped (moves reply with a move result) */
    /* 1. state */
    int own_buffers;             /* pos / uf were allocated for this change: the buffers they
                                  * replace are freed (else they become the session's scratch) */
    double *pos;                 /* new current positions (s->nv x 3), or NULL: unchanged */
    float *uf;                   /* new published displacements, or NULL (with version 0) */
    uint64_t version;            /* the version those frames publish; 0: no new version */
    df_frames frames;            /* the version's frames (released by df_change_clear) */
    df_stroke *stroke;           /* the stroke this change moved (applied / base / version) */
    float *applied;              /* its new contribution (swapped in), or NULL */
    double *base;                /* its rebased base (swapped in, old freed), or NULL */
    uint64_t work_ns;            /* its measured update (when set_work_ns) */
    int set_work_ns;
    double tip[3];               /* its grab tip now (when set_tip; df_stroke.tip) */
    int set_tip;
    int set_params;              /* the stroke's knobs become brush / strength (SET_BRUSH_PARAM) */
    df_kelvinlet_brush brush;
    double strength;
    int set_recipe;              /* the stroke's last_brush / last_strength / last_load /
                                  * last_replayable become the fields below (a publish) */
    df_kelvinlet_brush recipe_brush;
    double recipe_strength;
    double recipe_load[16];
    int recipe_replayable;
    df_stroke *link;             /* a new stroke to link (owned until the commit) */
    int drop_stroke;             /* drop the requester's stroke (cancel, end) */
    int rest_from_cur;           /* reset-rest: rest shape = the new current positions */
    df_handleset *hs;            /* a new handle set to install (owned until the commit) */
    double brush_ms, move_ms;    /* worker time; < 0: unchanged */
    /* 2. history */
    int hist;                    /* DF_HIST_* */
    df_history_plan hplan;       /* COMMIT / UNDO / REDO planned by the work (history.h; valid
                                  * set): installed, no replay on the loop thread. Not valid:
                                  * COMMIT is an XOR step, UNDO / REDO replay here (restore).
                                  * A failed plan with a replay mismatch is repaired (the
                                  * unreachable steps dropped) even though the change fails. */
    /* 3. caches */
    int kc_used, kc_hit;         /* Kelvinlet pin LU used / reused without refactoring */
    uint32_t kc_pins;
    df_kelvinlet_constraints *kc;/* a pin LU the compute built (installed as s->kc) */
    df_admm *solver;             /* an ADMM solver the compute rebuilt for s->hs (installed) */
    int solver_created, solver_hit; /* the handle set's ADMM solver rebuilt / reused */
    int solver_drop;             /* drop the cached solver (rest shape changed) */
} df_change;

/* An empty change (no state, no history step, timings unchanged) answering `req`. */
void df_change_init(df_change *c, df_req *req, df_error *err);

/* Releases what a change still owns (frames, an uninstalled stroke, handle set or pin LU). */
void df_change_clear(df_server *srv, df_change *c);

/* Called at step 4 of every successful commit when set (srv->commit_hook); see above. */
typedef void (*df_commit_hook_fn)(void *arg, const struct df_session *s,
                                  const struct df_change *c);

/* Applies change `c` to session `s` in the fixed order above and answers its request. Returns
 * DF_OK, or the error answered (c->rc, or the history step's DF_ENOMEM: then steps 3-5 are
 * skipped, state of step 1 stays). Loop thread. */
int df_session_commit(df_session *s, df_change *c);

#endif

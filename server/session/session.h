/* session.h — the session registry and a session's state.
 *
 * A session is one loaded mesh: its topology and BASE positions (load-time, the displacement
 * stream's reference), the REST shape (ADMM reference; reset-rest replaces it by the current
 * positions), the CURRENT positions (double), the published float32 displacements `uf`
 * (u = fl32(cur - base): what every subscriber holds after applying the stream), the version
 * counter, the undo/redo history, the subscribers, the open strokes, the handle set and the
 * cached factorizations.
 *
 * Ordering: every request that reads or changes a session is a df_job on the session's FIFO
 * (job.h). Only the head job runs; its `work` (a worker thread, or inline) reads the session and
 * writes no session field: it fills the job's change record, which df_session_commit applies
 * on the loop thread (commit.h), the only writer of positions, displacements, version, strokes,
 * handle set, history and caches. Two things a running work uses in place: the scratch
 * buffers job.c lends it (s->scratch_*, allocated on the loop thread before the work starts)
 * and the cached factorization it runs (s->kc refactorized when pins change, hs->solver
 * iterating), which only an idle session's eviction may free. Subscribers, name and the FIFO
 * are loop-thread only. */
#ifndef DF_SERVER_SESSION_H
#define DF_SERVER_SESSION_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>

#include "core/admm/admm.h"
#include "core/kelvinlet/kelvinlet.h"
#include "core/mesh/mesh.h"
#include "server/session/brush_state.h"
#include "server/session/history.h"
#include "server/session/resync.h"
#include "server/session/membership.h"
#include "server/server.h"

#define DF_SESSION_NAME_MAX 256
#define DF_SESSION_HISTORY_MAX 64   /* committed states kept for undo/redo */
/* Memory charged per vertex of a session (membudget.h): base, rest and current positions
 * (3 x 24), float32 base and published displacements (2 x 12), the running job's scratch
 * (stream.h: 12 + 4 + 12 + 24 + 12). The undo history and the ring are charged separately. */
#define DF_SESSION_BYTES_PER_VERTEX 160

/* An open brush stroke of one client (begin .. end/cancel). */
typedef struct df_stroke {
    uint64_t conn_id;
    df_kelvinlet_brush brush;    /* from begin (with the client's knob overrides) */
    double strength;
    double tip[3];               /* grab tip of its last begin/update (strength applied): the
                                    load whose Kelvinlet force HID force feedback plays */
    uint32_t n_pins;
    int pin_flags;               /* DF_KELVINLET_PIN_* bits */
    int progress;                /* its BRUSH_BEGIN asked for WORK_PROGRESS (options PROGRESS):
                                    the pin LU's FACTORIZE events, to each request that builds it */
    double *pins;                /* n_pins x 3, NULL when none */
    double *base;                /* positions without this stroke's contribution, nv x 3 */
    float *startf;               /* fl32(positions at begin): the points the field is evaluated at */
    float *applied;              /* displacement this stroke currently contributes, nv x 3 */
    uint64_t last_version;       /* session version this stroke produced last */
    uint64_t work_ns;            /* time of its last field evaluation (begin or update), ns;
                                  * 0 = none yet. Predicts the next update (job.h, inline) */
    /* What produced `applied` (stroke_recipe.h): the brush and strength its last publish used
     * (knobs may change `brush` for the next one) and that publish's cumulative load. */
    df_kelvinlet_brush last_brush;
    double last_strength;
    double last_load[16];
    int last_replayable;         /* 1: applied = the recipe's motion at startf, and base is
                                  * still the state the stroke began from (never rebased);
                                  * 0: nothing published, a cancel, or rebased */
    uint64_t base_version;       /* session version whose positions are `base` unless
                                  * rebased (the version at begin) */
    int rebased;                 /* 1: base was rebased once (another change landed) */
    double *surf_dist;           /* brush.surface: edge-graph distances over startf from
                                  * vertex surf_src (surface_cache.h), nv; else NULL */
    int32_t surf_src;
    struct df_stroke *next;
} df_stroke;

/* The session's handle set (one at a time) and its cached ADMM solver. */
typedef struct df_handleset {
    df_admm_params params;
    int32_t nh;
    int32_t *handles;
    int n_affine;
    df_admm_affine *affine;      /* verts arrays owned (malloc'd) */
    int max_iters;
    df_admm *solver;             /* cached factorization; NULL when evicted (re-created on use) */
    size_t solver_bytes;         /* estimate charged to the cache */
    uint64_t lru;                /* srv->lru_clock at last use */
} df_handleset;

/* Loop-owned copies of compute-state figures, for the stats request (h_stats.c): a worker may be
 * writing the originals (s->kc, s->hs->solver, the timings) while the loop answers. Refreshed by
 * df_session_seen_sync when no job runs. */
typedef struct df_session_seen {
    int handles;                 /* s->hs->nh, 0 without a handle set */
    int solver_cached;           /* s->hs->solver != NULL */
    int kc_cached;               /* s->kc != NULL */
    size_t cache_bytes;          /* solver_bytes + kc_bytes */
    double brush_last_ms, move_last_ms;
    df_admm_active_stats act;    /* the solver's active-set counters (zero without a solver) */
} df_session_seen;

typedef struct df_session {
    struct df_server *srv;
    uint64_t id;
    char name[DF_SESSION_NAME_MAX];
    df_mesh mesh;                /* topology; mesh.V = BASE positions */
    int32_t nv;
    double *rest, *cur;          /* nv x 3 */
    float *basef;                /* fl32(base), nv x 3 */
    float *uf;                   /* published displacements, nv x 3 */
    atomic_uint_fast64_t version;
    df_history hist;
    df_conn **subs;              /* subscribers (each holds a conn reference) */
    uint8_t *sub_shm;            /* sub_shm[i]: subs[i] reads frames from `shm` (STREAM_SHM) */
    int nsubs, capsubs, nshm;    /* nshm: subscribers with sub_shm set */
    struct df_shm_ring *shm;     /* shared-memory stream ring, made by the first STREAM_SHM */
    struct df_sublag *sub_lag;   /* sub_lag[i]: subs[i]'s coalescing state (stream_lag.h) */
    struct df_qgroup *qg;        /* quantized stream groups, one per error bound (stream_enc.h) */
    int nqg;
    struct df_job *jhead, *jtail;/* queued jobs, not started */
    struct df_job *running;      /* the head job while it runs (or NULL) */
    df_stroke *strokes;
    df_handleset *hs;
    df_kelvinlet_constraints *kc;/* cached K_pp LU of the last pinned set; NULL when none */
    struct df_surface_cache *surf;/* surface-brush adjacency and distances (running job only) */
    size_t kc_bytes;
    uint64_t kc_lru;
    /* Scratch of the running job (allocated on first use, reused: no per-version allocation). */
    float *scratch_u;            /* next published displacements, nv x 3 (swapped with uf) */
    int32_t *scratch_idx;        /* changed vertex indices, nv */
    float *scratch_rows;         /* sparse rows, nv x 3 */
    double *scratch_pos;         /* next positions, nv x 3 (brush: swapped with cur) */
    float *scratch_disp;         /* brush field, nv x 3 */
    /* Degenerate elements of the rest shape as loaded or restored (df_admm_find_degenerate; the
     * solver excludes them from its energies): written before the session is published. */
    df_admm_degenerate degen;
    double brush_last_ms;        /* worker time of the last brush begin/update/cancel */
    double move_last_ms;         /* worker time of the last handle move */
    df_session_seen seen;        /* loop thread only: the above as of the last finished job */
    uint64_t mem_bytes;          /* charged to srv->mem: DF_MEM_SESSIONS (the estimate) */
    uint64_t hist_charged;       /* ... DF_MEM_HISTORY (df_history_bytes at the last change) */
    uint64_t shm_charged;        /* ... DF_MEM_SHM (the ring file) */
    df_resync resync;            /* frames of the versions last broadcast (resync.h), loop thread */
    uint64_t resync_charged;     /* ... DF_MEM_RESYNC (resync.bytes at the last change) */
    char owner[DF_PRINCIPAL_MAX];/* principal of the creator (df_conn.principal), access.h;
                                  * "" for a session of an older store (admins own it) */
    df_membership acc;           /* access mode, observers, join key hash, members */
    uint64_t upload_bytes;       /* bytes of its uploaded file (quota_upload_mb), 0 for paths */
    int closed;                  /* close requested: no new jobs; freed when the FIFO drains */
    /* The session brush (brush_state.h), loop thread only: workers never read it. */
    df_brush_state brush;        /* current values (the one struct a durable store persists) */
    uint64_t brush_seq;          /* changes of `brush` so far (not the session version) */
    df_brush_changer brush_by;   /* who made the last change */
    struct df_cursor_limiter *cursor; /* BRUSH_CURSOR rate limiter, made on first use */
    struct df_session *next;
} df_session;

/* Bytes charged to the memory budget for a session on `mesh` (df_session.mem_bytes): per vertex
 * DF_SESSION_BYTES_PER_VERTEX, plus the elements and boundary faces. */
uint64_t df_session_estimate_bytes(const df_mesh *mesh);

/* Creates a session owning `mesh` (moved in: the caller's struct is zeroed) named `name`
 * ("" -> "session-<id>") and links it into srv. Names are unique among live sessions. The
 * estimate and the history's first state are charged to srv->mem first. Errors: DF_EEXIST (a
 * live session already has `name`), DF_ELIMIT (max_sessions, or memory_max_mb: the message
 * names it), DF_ENOMEM, or the durable store's error (srv->store_ops->session_created: DF_EIO,
 * DF_ELIMIT when full; the session is not created). On error the mesh is freed. */
int df_session_create(df_server *srv, df_mesh *mesh, const char *name, df_session **out,
                      df_error *err);

/* df_session_create for principal `owner` (may be ""; longer than DF_PRINCIPAL_MAX - 1 is
 * cut): the session's owner and its access policy (membership.h: mode session_access and
 * observers session_observers of the config; in key mode a fresh random join key that nobody
 * learns until the owner rotates it) are set before the store writes the session, so they
 * are durable with it. Errors: as df_session_create, and DF_EINTERNAL when no key could be
 * made. */
int df_session_create_as(df_server *srv, df_mesh *mesh, const char *name, const char *owner,
                         df_session **out, df_error *err);

/* Finds a live (not closed) session by id / by name; NULL when absent. */
df_session *df_session_find(df_server *srv, uint64_t id);
df_session *df_session_find_name(df_server *srv, const char *name);

/* Marks the session closed, tells subscribers (SESSION_CLOSED event) and drops them; the job
 * FIFO frees it once it is empty (df_job_pump). */
void df_session_close(df_session *s);

/* Frees a session that has no running job (unlinks it from srv). */
void df_session_destroy(df_session *s);

/* Adds / removes a subscriber. add: DF_OK (also when already subscribed), DF_ELIMIT. */
int df_session_subscribe(df_session *s, df_conn *c, df_error *err);
int df_session_unsubscribe(df_session *s, df_conn *c);

/* Switches subscriber `c` to the shared-memory stream, creating the session's ring first if
 * needed (server/net/shm.h). DF_OK (also when already switched), DF_ESTATE when c is not subscribed,
 * or df_shm_create's error. */
int df_session_attach_shm(df_session *s, df_conn *c, df_error *err);

/* Sends `frame` to every subscriber (loop thread). A slow subscriber is dropped, not waited for.
 * Subscribers on the shared-memory stream get an SHM_REF to the frame's copy in the ring
 * instead, when the frame's size qualifies (df_shm_takes). */
void df_session_broadcast(df_session *s, df_sbuf *frame);

/* Open stroke of connection `conn_id`, or NULL. */
df_stroke *df_session_stroke(df_session *s, uint64_t conn_id);

/* Frees a stroke that is not linked into a session (NULL-safe). */
void df_stroke_free(df_stroke *st);

/* Unlinks and frees the stroke of `conn_id` (no-op when none). */
void df_session_drop_stroke(df_session *s, uint64_t conn_id);

/* Commits s->cur as a new (XOR) undo step (loop thread) within the history budget: the smaller of
 * history_max_mb and what the memory budget has left; the oldest steps are dropped to fit
 * (srv->history_dropped counts them) instead of failing. Errors: df_history_commit's. */
int df_session_history_commit(df_session *s, df_error *err);

/* Recomputes stroke recipe `r` (stroke_recipe.h) from `from` into `to` (3 nv doubles each) on
 * this session's mesh: a surface-aware recipe with the session's vertex adjacency (its surface
 * cache, built on first use) and the mesh as loaded. `scratch`: 6 nv floats reused across
 * calls, or NULL (allocated per call). Call from the session's running job (or at restore,
 * before the loop runs). Errors: those of df_stroke_recipe_replay_mesh. */
struct df_stroke_recipe;
int df_session_replay_recipe(df_session *s, const struct df_stroke_recipe *r, const double *from,
                             int threads, float *scratch, double *to, df_error *err);

/* As df_session_history_commit, with the recipe `blob` (len bytes, stroke_recipe.h) that
 * should turn the history's current state into s->cur: replayed on the calling thread, a
 * RECIPE step when it reproduces s->cur bitwise, else an XOR step (history.h). For restore. */
int df_session_history_commit_recipe(df_session *s, const uint8_t *blob, size_t len,
                                     df_error *err);

/* Installs a history plan a job's work made (df_history_plan_commit / _move, target s->cur,
 * already swapped in), then bounds the history to its budget as df_session_history_commit.
 * Loop thread. Errors: df_history_install's DF_ESTATE (a stale plan: history unchanged). */
int df_session_history_install(df_session *s, df_history_plan *plan, df_error *err);

/* After a plan that failed with a replay mismatch: drops the unreachable steps
 * (df_history_repair), logs it and recharges. No-op for other plans. Loop thread. */
void df_session_history_repair(df_session *s, const df_history_plan *plan);

/* Charges `bytes` of `kind` to the memory budget (df_mem_charge). When only the total
 * (memory_max_mb) is short, the undo history of idle sessions (no running job) gives way first:
 * their oldest undo steps are dropped, largest history first, until the charge fits or no such
 * step is left. Errors: df_mem_charge's DF_ELIMIT (nothing charged). Loop thread. */
int df_session_mem_charge(df_server *srv, df_mem_kind kind, uint64_t bytes, const char *what,
                          df_error *err);

/* Records the frames of version `version` (just broadcast) in the session's resync ring
 * (resync.h) within its budget: the smaller of resync_ring_mb and what the memory budget has
 * left (counting what the ring holds); the oldest versions are dropped to fit, and
 * resync_ring_mb 0 keeps nothing. The ring's bytes are charged as DF_MEM_RESYNC. Never fails:
 * out of memory empties the ring (a later resync from before gets a snapshot). Loop thread. */
struct df_frames;
void df_session_resync_record(df_session *s, uint64_t version, const struct df_frames *frames);

/* Empties the history in place: s->cur its only state (reset-rest clears undo/redo), the rest
 * shape s->rest its reference again (history.h: the anchor is packed against it; call this
 * right after s->rest changes, before anything reads the history). Allocates nothing: always
 * DF_OK (err unused, kept for the callers' error paths). Loop thread. */
int df_session_history_reset(df_session *s, df_error *err);

/* Copies the compute-state figures into s->seen. Loop thread, only while no job of s runs
 * (job.c calls it after each job's done; the stats request when the session is idle). */
void df_session_seen_sync(df_session *s);

/* Frees the handle set (and its solver, uncharging the cache). NULL-safe. */
void df_handleset_free(df_server *srv, df_handleset *hs);

#endif

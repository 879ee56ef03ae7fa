/* h_handles.c — handle sets (ADMM solver creation, cached) and handle moves (warm-started,
 * streaming progress, superseded by newer moves), reset-rest (see handlers.h).
 *
 * The solver's rest shape is the session's REST positions; a move's iterates replace the current
 * positions. reset-rest makes the current positions the rest shape, clears the undo/redo history
 * and drops the cached solver (the next move rebuilds it against the new rest: one analysis +
 * factorization). handles_get answers the stored set (params, indices, affine sets). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_seed.h"
#include "core/kelvinlet/kelvinlet_guess.h"
#include "proto/wire_core_map.h"
#include "server/session/cache.h"
#include "server/net/conn.h"
#include "server/handlers/handlers.h"
#include "server/exec/job.h"
#include "server/exec/work_progress.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/stream.h"

#define DF_MOVE_SLICE_MS 100 /* a move yields its worker after this long when others wait */

typedef struct hs_req {
    df_msg_handles m;          /* handles_set: the message */
    df_handleset *hs;          /* handles_set: the new set (installed in done) */
    df_msg_handle_move mv;     /* move: the message */
    int superseded;            /* move dropped from the queue by a newer move */
    int created, hit;          /* move: solver rebuilt / reused */
    df_admm_result res;
    uint8_t status;
    uint64_t progress_every;
    uint64_t t0;
    int publish_failed;        /* move: an iterate was refused (j->err says why): stop, fail */
    int published;             /* move: an iterate of it was published (posted): one undo step */
    int resumed;               /* move: it yielded its worker and runs again (time slices) */
    const float *uf_prev;      /* move: displacements of its last iterate (or the session's) */
    df_admm *solver;           /* move: the solver it runs (the set's, or one it rebuilt) */
    uint64_t version;          /* move: version of its last iterate (or the session's) */
    int yield;                 /* move: on_progress asked to yield */
    uint64_t budget;           /* move: its iteration budget (SOLVE progress total) */
    int iters_done;            /* move: iterations of the earlier slices */
    uint64_t slice_t0;         /* move: start of the current slice (uv_hrtime) */
    /* Loop thread only: an iterate the durable store refused (commit.h step 0). That iterate
     * and every later one are not applied (they were encoded from it); the move fails with
     * store_err. store_uf: the last skipped iterate's displacements, which the worker may still
     * encode the next iterate from (freed at the next skip or when the move is done). */
    int store_failed;
    df_error store_err;
    float *store_uf;
    df_work work;              /* WORK_PROGRESS of the request (options PROGRESS), else off */
} hs_req;

static void req_free(df_server *srv, void *body)
{
    hs_req *r = body;
    df_msg_handles_free(&r->m);
    df_msg_handle_move_free(&r->mv);
    if (r->hs) df_handleset_free(srv, r->hs);
    free(r->store_uf);
}

/* Builds a solver for handle set `hs` against the session's rest shape into *out (the
 * FACTORIZE stage of `w`: its start, and its end when the build succeeds). Worker thread. */
static int build_solver(const df_session *s, const df_handleset *hs, df_admm **out,
                        df_work *w, df_error *err)
{
    df_mesh m = s->mesh;
    m.V = s->rest;
    df_work_report(w, DF_STAGE_FACTORIZE, 0, 1, 0, 1);
    df_admm_params p = hs->params;
    /* config admm_active: 1 the active-set mode, 2 the same with the recommended tail test */
    p.active = s->srv->cfg.admm_active != 0;
    p.active_tail = s->srv->cfg.admm_active == 2 ? DF_ADMM_ACTIVE_TAIL : 0.0;
    int rc = df_admm_create(&m, &p, hs->handles, hs->nh, hs->affine, hs->n_affine, out, err);
    if (rc == DF_OK) df_work_report(w, DF_STAGE_FACTORIZE, 1, 1, 1, 1);
    return rc;
}

/* Starts the request's progress reporting (worker thread, first slice). */
static void work_start(df_job *j, uint32_t options)
{
    hs_req *r = j->body;
    df_work_init(&r->work, j->srv, j->req.c, j->req.id, j->s->id,
                 (options & DF_WORK_OPT_PROGRESS) != 0);
}

static void set_work(df_job *j)
{
    hs_req *r = j->body;
    df_session *s = j->s;
    const df_msg_handles *m = &r->m;
    work_start(j, m->options);
    for (uint32_t i = 0; i < m->n_handles; i++)
        if (m->handles[i] < 0 || m->handles[i] >= s->nv) {
            j->rc = df_error_set(&j->err, DF_EINVAL, "handles_set: handle %u is vertex %d, "
                                 "out of range (%d vertices)", i, m->handles[i], s->nv);
            return;
        }
    df_admm_energy energy;
    if (df_wire_energy_to_core(m->energy, &energy) != DF_OK) {
        j->rc = df_error_set(&j->err, DF_EINVAL, "handles: energy %u not in 1..%d", m->energy,
                             DF_ENERGY_MAX);
        return;
    }
    df_handleset *hs = calloc(1, sizeof *hs);
    if (!hs) {
        j->rc = df_error_set(&j->err, DF_ENOMEM, "out of memory");
        return;
    }
    r->hs = hs;
    df_admm_params_default(&hs->params, energy);
    hs->params.w = m->w;
    hs->params.s = m->s;
    hs->params.rho = m->rho;
    hs->params.tol = m->tol;
    hs->params.max_iters = (int)m->max_iters;
    hs->params.youngs = m->youngs;
    hs->params.poisson = m->poisson;
    hs->params.area_weighting = m->area_weighting;
    hs->params.accelerate = m->accelerate;
    hs->params.anderson_m = m->anderson_m;
    hs->params.strain_min = m->strain_min;
    hs->params.strain_max = m->strain_max;
    hs->params.bending = m->bending;
    hs->max_iters = (int)m->max_iters;
    hs->nh = (int32_t)m->n_handles;
    hs->handles = malloc((size_t)hs->nh * sizeof *hs->handles);
    hs->affine = m->n_affine ? calloc(m->n_affine, sizeof *hs->affine) : NULL;
    if (!hs->handles || (m->n_affine && !hs->affine)) {
        j->rc = df_error_set(&j->err, DF_ENOMEM, "out of memory");
        return;
    }
    memcpy(hs->handles, m->handles, (size_t)hs->nh * sizeof *hs->handles);
    for (uint32_t k = 0; k < m->n_affine; k++) {
        const df_msg_affine_set *a = &m->affine[k];
        int32_t *v = malloc(a->n_indices * sizeof *v);
        if (!v) {
            j->rc = df_error_set(&j->err, DF_ENOMEM, "out of memory");
            return;
        }
        memcpy(v, a->indices, a->n_indices * sizeof *v);
        hs->affine[k].verts = v;
        hs->affine[k].n = (int32_t)a->n_indices;
        hs->affine[k].m = a->rows;
        memcpy(hs->affine[k].A, a->A, sizeof a->A);
        memcpy(hs->affine[k].b, a->b, sizeof a->b);
        hs->n_affine++;
    }
    /* hs is the job's own until committed */
    j->rc = build_solver(s, hs, &hs->solver, &r->work, &j->err);
    if (j->rc != DF_OK) return;
    j->change.hs = hs; /* installed, its solver cached, by the commit */
    j->change.solver_created = 1;
    r->hs = NULL;
}

static int set_decode(const df_req *rq, const uint8_t *p, void *body, uint64_t *sid,
                      df_error *err)
{
    hs_req *r = body;
    int rc = df_msg_handles_decode(p, rq->len, &r->m, err); /* owned by the body */
    *sid = r->m.session_id;
    return rc;
}

const df_job_kind df_k_handles_set = {.body_size = sizeof(hs_req), .decode = set_decode,
                                      .release = req_free, .work = set_work,
                                      .done = df_job_commit};

/* Handles_get: the session's current set as a handles body (loop thread, in FIFO order so it sees
 * every earlier handles_set). The affine index arrays point into `hs` (valid during the call). */
static void get_done(df_job *j)
{
    df_session *s = j->s;
    const df_handleset *hs = s->hs;
    if (df_job_failed(j)) return;
    if (!hs) {
        df_error e;
        df_error_set(&e, DF_ENOTFOUND, "handles_get: session %llu has no handle set",
                     (unsigned long long)s->id);
        df_req_fail(&j->req, &e);
        return;
    }
    df_msg_affine_set aff[DF_MAX_AFFINE_SETS];
    df_msg_handles m;
    memset(&m, 0, sizeof m);
    m.session_id = s->id;
    if (df_core_energy_to_wire(hs->params.energy, &m.energy) != DF_OK) {
        df_error e;
        df_error_set(&e, DF_EINTERNAL, "handles_get: energy %d has no wire value",
                     (int)hs->params.energy);
        df_req_fail(&j->req, &e);
        return;
    }
    m.area_weighting = (uint8_t)hs->params.area_weighting;
    m.accelerate = (uint8_t)hs->params.accelerate;
    m.anderson_m = (uint8_t)hs->params.anderson_m;
    m.w = hs->params.w;
    m.s = hs->params.s;
    m.rho = hs->params.rho;
    m.tol = hs->params.tol;
    m.youngs = hs->params.youngs;
    m.poisson = hs->params.poisson;
    m.strain_min = hs->params.strain_min;
    m.strain_max = hs->params.strain_max;
    m.bending = hs->params.bending;
    m.max_iters = (uint32_t)hs->max_iters;
    m.n_handles = (uint32_t)hs->nh;
    m.handles = hs->handles;
    m.n_affine = (uint32_t)(hs->n_affine < (int)DF_MAX_AFFINE_SETS ? hs->n_affine
                                                                     : (int)DF_MAX_AFFINE_SETS);
    for (uint32_t k = 0; k < m.n_affine; k++) {
        const df_admm_affine *a = &hs->affine[k];
        memset(&aff[k], 0, sizeof aff[k]);
        aff[k].rows = (uint8_t)a->m;
        memcpy(aff[k].A, a->A, sizeof aff[k].A);
        memcpy(aff[k].b, a->b, sizeof aff[k].b);
        aff[k].n_indices = (uint32_t)a->n;
        aff[k].indices = (int32_t *)a->verts;
    }
    m.affine = aff;
    df_error err;
    df_buf b;
    size_t start;
    df_buf_init(&b);
    int rc = df_frame_begin(&b, j->req.type, DF_FLAG_REPLY, j->req.id, &start, &err);
    if (rc == DF_OK) rc = df_msg_handles_encode(&m, &b, &err);
    if (rc == DF_OK) rc = df_frame_end(&b, start, &err);
    df_sbuf *f = rc == DF_OK ? df_sbuf_from_buf(&b) : NULL;
    if (!f) {
        df_buf_free(&b);
        if (rc == DF_OK) df_error_set(&err, DF_ENOMEM, "out of memory building a frame");
        df_log(DF_LOG_ERROR, "encoding a handles_get reply failed: %s", err.msg);
        df_error_set(&err, DF_EINTERNAL, "handles_get: server could not encode the set");
        df_req_fail(&j->req, &err);
        return;
    }
    df_req_reply(&j->req, f);
    df_sbuf_unref(f);
}

const df_job_kind df_k_handles_get = {.decode = df_job_decode_ref, .done = get_done,
                                      .beside = DF_JOB_BESIDE_READ}; /* fixed during a move */

static double finite_or(double v, double dflt) { return isfinite(v) ? v : dflt; }

/* A move's iterate on its way to the loop: a change record committed as it arrives. */
typedef struct move_iter {
    df_task t;                 /* posted through the pool's completion channel */
    df_session *s;
    df_change ch;
    hs_req *r;                 /* its move (alive until the move's done, which runs after) */
} move_iter;

static void iter_commit(df_task *t)
{
    move_iter *m = (move_iter *)t; /* t is the first member */
    hs_req *r = m->r;
    if (!r->store_failed) { /* no request: the move answers once it ends */
        m->ch.err = &r->store_err;
        if (df_session_commit(m->s, &m->ch) != DF_OK) r->store_failed = 1;
        else m->ch.err = NULL;
    } else {
        m->ch.rc = DF_ESTATE; /* after a refused iterate: skipped, not applied */
    }
    if (r->store_failed && m->ch.uf) { /* the worker may encode from it: keep it for now */
        free(r->store_uf);
        r->store_uf = m->ch.uf;
        m->ch.uf = NULL;
    }
    df_change_clear(m->s->srv, &m->ch);
    free(m);
}

/* Encodes the iterate V as the move's next version (pure: from the move's previous iterate, in
 * buffers of its own) and posts it to the loop, which commits it (commit.h) before the move's
 * completion: requests answered beside the move (job.h) see exactly the versions subscribers
 * have been sent. Worker thread. */
static int publish_iterate(df_job *j, const double *V, int iteration, double objective,
                           double residual, uint8_t status, int final)
{
    hs_req *r = j->body;
    const df_session *s = j->s;
    df_msg_progress pr;
    memset(&pr, 0, sizeof pr);
    pr.status = status;
    pr.final = (uint8_t)final;
    pr.iteration = (uint32_t)(iteration > 0 ? iteration : 0);
    pr.objective = finite_or(objective, DBL_MAX);
    pr.residual = finite_or(residual, DBL_MAX);
    if (pr.residual < 0) pr.residual = 0;
    pr.elapsed_ms = (double)(uv_hrtime() - r->t0) / 1e6;
    size_t n = 3 * (size_t)s->nv;
    move_iter *m = calloc(1, sizeof *m);
    float *uf = malloc(n * sizeof *uf);
    double *pos = malloc(n * sizeof *pos);
    if (!m || !uf || !pos) {
        free(m);
        free(uf);
        free(pos);
        return df_error_set(&j->err, DF_ENOMEM, "out of memory for a move iterate");
    }
    df_change_init(&m->ch, NULL, NULL);
    int rc = df_stream_encode(s, r->uf_prev, r->version + 1, V, DF_CHANGE_HANDLE_MOVE, &pr,
                              j->req.id, uf, &m->ch.frames, NULL, &j->err);
    if (rc != DF_OK) {
        df_change_clear(j->srv, &m->ch);
        free(m);
        free(uf);
        free(pos);
        return rc;
    }
    memcpy(pos, V, n * sizeof *pos);
    m->ch.pos = pos;
    m->ch.uf = uf;
    m->ch.own_buffers = 1;
    m->ch.version = ++r->version;
    m->s = j->s;
    m->r = r;
    m->t.after = iter_commit;
    r->uf_prev = uf;
    r->published = 1;
    df_pool_post(j->srv->pool, &m->t);
    return DF_OK;
}

static int on_progress(void *user, const df_admm_progress *p)
{
    df_job *j = user;
    hs_req *r = j->body;
    if (atomic_load(&j->cancel)) return 1;
    int it = r->iters_done + p->iteration;
    df_work_report(&r->work, DF_STAGE_SOLVE, (uint64_t)(it > 0 ? it : 0), r->budget, 0, 1);
    if (r->progress_every && it % (int)r->progress_every == 0) {
        int prc = publish_iterate(j, p->V, it, p->objective, p->residual, DF_MOVE_RUNNING, 0);
        if (prc != DF_OK) { /* e.g. an iterate not finite in float32: the move fails */
            r->publish_failed = prc;
            return 1;
        }
    }
    /* Time slices: another move waits for the long lane (pool.h) and this one had its turn. */
    if (j->srv->pool && df_pool_heavy_waiting(j->srv->pool) > 0 &&
        uv_hrtime() - r->slice_t0 >= DF_MOVE_SLICE_MS * 1000000ull) {
        r->yield = 1;
        return 1;
    }
    return 0;
}

/* Refuses targets whose handle would leave float32 range: the position a client holds is the
 * load-time float32 position plus a float32 displacement, and both must stay finite. */
static int targets_check(const df_session *s, const df_handleset *hs, const double *t,
                         df_error *err)
{
    for (int32_t k = 0; k < hs->nh; k++)
        for (int c = 0; c < 3; c++) {
            size_t i = 3 * (size_t)hs->handles[k] + (size_t)c;
            float u = (float)(t[3 * (size_t)k + c] - s->mesh.V[i]);
            if (!isfinite(u) || !isfinite(s->basef[i] + u))
                return df_error_set(err, DF_EINVAL, "handles_move: target %d (vertex %d) "
                                    "component %d = %g is not finite in float32 (|x| <= "
                                    "3.4e38); nothing changed", k, hs->handles[k], c,
                                    t[3 * (size_t)k + c]);
        }
    return DF_OK;
}

/* Option KELVINLET_GUESS: the solver starts from the Kelvinlet field of the handles' move
 * (core/kelvinlet/kelvinlet_guess.h: default radius, the solver's Poisson ratio for Neo-Hookean,
 * 0.5 otherwise) applied to the session's current positions, restricted to the vertices it moves
 * most and scaled, both chosen by the objective (core/admm/admm_seed.h); the plain start (the
 * current positions) when that does not lower the objective. Needs the targets set first. */
static int guess_positions(df_admm *solver, const df_session *s, const df_handleset *hs,
                           const double *targets, df_error *err)
{
    size_t n = 3 * (size_t)s->mesh.nv;
    double *G = malloc(n * sizeof *G);
    if (!G)
        return df_error_set(err, DF_ENOMEM, "handles_move: out of memory for the Kelvinlet guess");
    double nu = hs->params.energy == DF_ADMM_NEOHOOKEAN ? hs->params.poisson : 0.5;
    int rc = df_kelvinlet_guess(s->cur, s->mesh.nv, hs->handles, hs->nh, targets, 0.0, nu, G,
                                NULL, NULL, err);
    df_admm_seed_report rep;
    if (rc == DF_OK)
        rc = df_admm_seed(solver, s->cur, G, DF_ADMM_SEED_SHRINK_AUTO, &rep, err);
    if (rc == DF_OK)
        df_log(DF_LOG_DEBUG, "session %llu: Kelvinlet guess: shrink %.2f alpha %.3f (objective "
               "%.6g, plain start %.6g)", (unsigned long long)s->id, rep.shrink, rep.alpha,
               rep.e_seed, rep.e_plain);
    free(G);
    return rc;
}

/* Checks the request and prepares the solver for the first slice of a move: the handle set's
 * solver (rebuilt when evicted), the session's current positions, the targets. */
static int move_setup(df_job *j)
{
    hs_req *r = j->body;
    const df_session *s = j->s;
    const df_handleset *hs = s->hs;
    if (!hs)
        return df_error_set(&j->err, DF_ESTATE, "handles_move: session %llu has no handle set "
                            "(send handles_set first)", (unsigned long long)s->id);
    if ((int32_t)r->mv.n_targets != hs->nh)
        return df_error_set(&j->err, DF_EINVAL, "handles_move: %u targets for %d handles",
                            r->mv.n_targets, hs->nh);
    int rc = targets_check(s, hs, r->mv.targets, &j->err);
    if (rc != DF_OK) return rc;
    if ((r->mv.options & DF_WORK_OPT_POLISH) &&
        (s->mesh.kind != DF_MESH_TET || hs->params.energy == DF_ADMM_CLOTH ||
         hs->params.energy == DF_ADMM_POLYLINE))
        return df_error_set(&j->err, DF_EUNSUPPORTED, "handles_move: option POLISH needs a tet "
                            "mesh with the arap, acap or neohookean energy; nothing changed");
    if (!hs->solver) { /* evicted: rebuilt into the change, cached by the commit */
        rc = build_solver(s, hs, &j->change.solver, &r->work, &j->err);
        if (rc != DF_OK) return rc;
        r->created = 1;
    } else {
        r->hit = 1;
    }
    r->solver = hs->solver ? hs->solver : j->change.solver;
    /* Start from the session's current positions (PROTOCOL.md 6): an undo, a brush or another
     * client's edit since the solver's last run invalidates its warm start there. A target
     * with z != 0 on a 2D session is refused here (df_admm_set_targets, EINVAL). */
    if (r->mv.options & DF_WORK_OPT_KELVINLET_GUESS) {
        rc = df_admm_set_targets(r->solver, r->mv.targets, &j->err);
        if (rc == DF_OK) rc = guess_positions(r->solver, s, hs, r->mv.targets, &j->err);
    } else {
        rc = df_admm_set_positions(r->solver, s->cur, NULL, &j->err);
        if (rc == DF_OK) rc = df_admm_set_targets(r->solver, r->mv.targets, &j->err);
    }
    r->progress_every = r->mv.progress_every;
    r->uf_prev = s->uf; /* its iterates are encoded one from the other (publish_iterate) */
    r->version = atomic_load(&s->version);
    return rc;
}

/* Option POLISH (PROTOCOL.md 4.16): projected Newton on the moved set after the ADMM iterations
 * (df_admm_polish with its defaults: relative KKT residual 1e-9, at most 50 steps), in the move's
 * last slice. Skipped, the move ending as ADMM left it, when the polish's start is not valid
 * (DF_ESTATE: handles not on their targets yet, damped Neo-Hookean steps pending). The result then
 * reports the polish: iterations + its Newton steps, its objective, its KKT residual; converged
 * when that is below its tolerance, else budget. */
static int polish_move(df_job *j)
{
    hs_req *r = j->body;
    df_admm_polish_result pr;
    df_error perr;
    int rc = df_admm_polish(r->solver, NULL, &pr, &perr);
    if (rc == DF_ESTATE) {
        df_log(DF_LOG_INFO, "session %llu: move polish skipped: %s",
               (unsigned long long)j->s->id, perr.msg);
        return DF_OK;
    }
    if (rc != DF_OK) {
        j->err = perr;
        return rc;
    }
    r->res.iterations += pr.iterations;
    r->res.objective = pr.objective;
    r->res.residual = pr.kkt;
    r->res.converged = pr.converged;
    r->status = pr.converged ? DF_MOVE_CONVERGED : DF_MOVE_BUDGET;
    return DF_OK;
}

/* Work of HANDLES_MOVE (one time slice): reads the session, runs the solver (the handle set's
 * cached one, used in place: the running job's), posts its iterates (publish_iterate). */
static void move_work(df_job *j)
{
    hs_req *r = j->body;
    const df_handleset *hs = j->s->hs;
    /* no handle set: move_setup refuses the move (ESTATE) */
    int max_iters = r->mv.max_iters ? (int)r->mv.max_iters : hs ? hs->max_iters : 0;
    if (!r->resumed) {
        r->t0 = uv_hrtime();
        work_start(j, r->mv.options);
        r->budget = (uint64_t)max_iters;
        if ((j->rc = move_setup(j)) != DF_OK) return;
    }
    r->slice_t0 = uv_hrtime();
    r->yield = 0;
    double max_ms = 0;
    if (r->mv.max_ms) { /* the budget counts from the move's start, waits included */
        max_ms = (double)r->mv.max_ms - (double)(r->slice_t0 - r->t0) / 1e6;
        if (max_ms <= 0) max_ms = 1e-3; /* one more iteration, then the budget stops it */
    }
    df_admm_budget b = {.max_iters = max_iters - r->iters_done,
                        .max_ms = max_ms,
                        .progress_every = 1, /* every iteration: prompt supersede checks */
                        .progress = on_progress,
                        .user = j};
    int rc = df_admm_run(r->solver, &b, &r->res, &j->err);
    if (r->publish_failed) { /* j->err holds the refusal; the iterates before it stay */
        r->status = DF_MOVE_FAILED;
        j->change.move_ms = (double)(uv_hrtime() - r->t0) / 1e6;
        j->rc = r->publish_failed;
        return;
    }
    r->iters_done += r->res.iterations;
    r->res.iterations = r->iters_done;
    if (rc == DF_OK && r->yield) {
        if (!(r->res.residual < hs->params.tol) && r->iters_done < max_iters) {
            r->resumed = 1; /* back to the tail of the long lane; continues from here */
            j->task.requeue = 1;
            j->change.move_ms = (double)(uv_hrtime() - r->t0) / 1e6;
            return;
        }
        if (r->res.residual < hs->params.tol) { /* it converged at the yielding iteration */
            r->res.converged = 1;
            r->res.stop = DF_ADMM_STOP_CONVERGED;
        } else {
            r->res.stop = DF_ADMM_STOP_ITERS; /* its last slice ended the budget */
        }
    }
    if (rc != DF_OK) r->status = DF_MOVE_FAILED;
    else if (r->res.converged) r->status = DF_MOVE_CONVERGED;
    else if (r->res.stop == DF_ADMM_STOP_CALLBACK) r->status = DF_MOVE_SUPERSEDED;
    else r->status = DF_MOVE_BUDGET;
    if (rc == DF_OK && (r->mv.options & DF_WORK_OPT_POLISH) && r->status != DF_MOVE_SUPERSEDED) {
        rc = polish_move(j);
        if (rc != DF_OK) r->status = DF_MOVE_FAILED;
    }
    j->change.move_ms = (double)(uv_hrtime() - r->t0) / 1e6;
    int prc = publish_iterate(j, df_admm_positions(r->solver), r->res.iterations,
                              r->res.objective, r->res.residual, r->status, 1);
    j->rc = rc != DF_OK ? rc : prc;
    if (j->rc == DF_OK) /* the last SOLVE event: the iterations run, of the budget */
        df_work_report(&r->work, DF_STAGE_SOLVE, (uint64_t)r->res.iterations, r->budget, 1, 1);
}

/* A move's commit: the solver's cache accounting and, when it published iterates (each already
 * a version: see publish_iterate), one undo step; then the move result (or its error). */
static void move_done(df_job *j)
{
    hs_req *r = j->body;
    df_session *s = j->s;
    df_change *ch = &j->change;
    df_error herr;
    ch->solver_created = r->created;
    ch->solver_hit = r->hit;
    ch->hist = r->published && !r->superseded ? DF_HIST_COMMIT : DF_HIST_NONE;
    ch->answered_by_job = 1;
    ch->err = &herr;
    ch->rc = DF_OK; /* its published iterates stay, even when the move then failed */
    if (df_session_commit(s, ch) != DF_OK)
        df_log(DF_LOG_WARN, "session %llu: could not record the move for undo",
               (unsigned long long)s->id);
    free(r->store_uf); /* the worker is done */
    r->store_uf = NULL;
    if (r->store_failed) { /* an iterate was not stored: the move fails with the store's error */
        j->rc = r->store_err.code;
        j->err = r->store_err;
        r->superseded = 0;
    }
    /* the final frames were posted by the worker and broadcast before this `done` (job.c) */
    df_msg_move_result res;
    memset(&res, 0, sizeof res);
    res.session_id = s->id;
    res.version = atomic_load(&s->version);
    if (r->superseded) {
        res.status = DF_MOVE_SUPERSEDED;
        df_req_reply_move_result(&j->req, &res);
        return;
    }
    if (df_job_failed(j)) return;
    res.status = r->status;
    res.iterations = (uint32_t)r->res.iterations;
    res.objective = finite_or(r->res.objective, DBL_MAX);
    res.residual = finite_or(r->res.residual, DBL_MAX);
    res.elapsed_ms = (double)(uv_hrtime() - r->t0) / 1e6;
    df_req_reply_move_result(&j->req, &res);
}

static int pred_move(const df_job *j, void *arg)
{
    (void)arg;
    if (j->req.type != DF_MSG_HANDLES_MOVE) return 0;
    ((hs_req *)j->body)->superseded = 1;
    return 1;
}

static int move_decode(const df_req *rq, const uint8_t *p, void *body, uint64_t *sid,
                       df_error *err)
{
    hs_req *r = body;
    int rc = df_msg_handle_move_decode(p, rq->len, &r->mv, err); /* owned by the body */
    *sid = r->mv.session_id;
    return rc;
}

/* A newer move supersedes the running one and any queued ones. */
static void move_queued(df_job *j)
{
    df_session *s = j->s;
    if (s->running && s->running->req.type == DF_MSG_HANDLES_MOVE) {
        atomic_store(&s->running->cancel, 1);
        j->srv->stats.jobs_superseded++;
    }
    j->srv->stats.jobs_superseded +=
        (uint64_t)df_job_drop_queued(s, pred_move, NULL, "superseded by a newer move");
}

const df_job_kind df_k_handles_move = {.body_size = sizeof(hs_req), .decode = move_decode,
                                       .release = req_free, .queued = move_queued,
                                       .work = move_work, .done = move_done, .heavy = 1,
                                       .preemptible = 1};

/* Work of RESET_REST (pure): the current positions as a new version (kind RESET_REST); the
 * commit makes them the rest shape, clears undo/redo and drops the solver (rebuilt against the
 * new rest by the next move). */
static void reset_work(df_job *j)
{
    const df_session *s = j->s;
    df_change *ch = &j->change;
    j->rc = df_stream_encode(s, NULL, 0, s->cur, DF_CHANGE_RESET_REST, NULL, 0,
                             s->scratch_u, &ch->frames, NULL, &j->err);
    if (j->rc != DF_OK) return;
    ch->uf = s->scratch_u;
    ch->version = atomic_load(&s->version) + 1;
    ch->rest_from_cur = 1;
    ch->hist = DF_HIST_RESET;
    ch->solver_drop = 1;
}

const df_job_kind df_k_reset_rest = {.body_size = sizeof(hs_req), .decode = df_job_decode_ref,
                                     .release = req_free, .work = reset_work,
                                     .done = df_job_commit};

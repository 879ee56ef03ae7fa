/* h_brush.c — Kelvinlet brush strokes: begin / update / end / cancel (see handlers.h).
 *
 * Stroke semantics. A stroke belongs to one client on one session. begin fixes every brush
 * parameter and the material points: the field is always evaluated at the positions the mesh
 * had when the stroke began (fl32). begin and each update carry the CUMULATIVE load since begin
 * (grab tip, twist vector, scale, centre gradient; multiplied by strength); the server computes
 * the displacement d_k of that load and sets positions = base + d_k, where base is the shape
 * without this stroke's contribution. So an update replaces the previous one (dropped updates
 * lose nothing) and the result of a stroke does not depend on how many updates were sent. With
 * `moving` the brush centre is advected along the load over `steps` substeps (paper sec. 9,
 * df_kelvinlet_brush.moving): still relative to the stroke start. When another change (another
 * client's stroke, a move) lands between two updates of a stroke, base is rebased to
 * current - d_(k-1) first, so concurrent strokes add up instead of overwriting each other.
 * end commits the stroke as one undo step (no new version); cancel sets positions = base (one
 * version of kind BRUSH_CANCEL, or none when the stroke has applied nothing: then it changes
 * nothing, e.g. after an update the engine rejected). Each begin/update is one version (kind BRUSH).
 * A begin whose loads are all zero publishes nothing (ack with the current version).
 * Knobs (set brush parameter: radius / nu / strength / falloff / ratio) change the client's open
 * stroke from its next update on (ESTATE without one). A begin whose `use_session` bits name
 * brush fields takes those from the session brush (brush_state.h) as it is when the begin
 * arrives; the stroke keeps them (a later brush state change does not alter an open stroke). A client that disconnects with an open
 * stroke has it ended (committed as an undo step). Pinned points use the
 * session's cached K_pp LU (df_kelvinlet_constraints), refactorized only when pins or kernel
 * change. A surface-aware begin (wire `surface` 1) takes, once, the edge-graph distances over the
 * rest mesh from the vertex nearest its centre (server/session/surface_cache.h: cached per session
 * and vertex) and every publish multiplies the field by their weights (stroke_recipe.h
 * df_stroke_surface_mask, what a replay runs): vertices not connected to it never move. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/wire_core_map.h"
#include "server/session/cache.h"
#include "server/handlers/handlers.h"
#include "server/exec/job.h"
#include "server/exec/work_progress.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/stream.h"
#include "server/session/stroke_end.h"
#include "server/session/stroke_recipe.h"
#include "server/session/surface_cache.h"

/* Below this many vertices a brush field is evaluated by the worker thread alone: waking an
 * OpenMP team costs more than it saves. Above it, on the `threads` setting (config.h) at most:
 * passed in the prepared field, never through omp_set_num_threads. */
#define DF_BRUSH_PARALLEL_MIN_VERTICES 32768

typedef struct brush_req {
    df_msg_brush begin;          /* begin: the message (owns `pinned`) */
    double load[16];             /* move[3] twist[3] scale matrix[9] */
    df_stroke *created;          /* begin: the new stroke (moved to the change on success) */
} brush_req;

static void req_free(df_server *srv, void *body)
{
    (void)srv;
    brush_req *r = body;
    df_msg_brush_free(&r->begin);
    df_stroke_free(r->created);
}

/* Computes the displacement of the stroke's brush under `load` at st->startf into disp. A pin
 * LU built here goes to the change (ch->kc); an existing one (s->kc, the running job's cache
 * object: only evicted while its session is idle) is refactorized in place when pins changed.
 * `w` gets the FACTORIZE stage of an LU built (start and end) or refactorized (end only: known
 * after the fact). Worker thread (pinned strokes never run inline). */
static int stroke_field(const df_session *s, const df_stroke *st, const double *load,
                        float *disp, df_change *ch, df_work *w, df_error *err)
{
    df_kelvinlet_brush b;
    df_stroke_loaded_brush(&st->brush, st->strength, load, &b);
    df_kelvinlet_prepared prep;
    int rc, threads = s->nv < DF_BRUSH_PARALLEL_MIN_VERTICES ? 1 : s->srv->cfg.threads;
    if (st->n_pins) {
        df_kelvinlet_pins pins = {.n = st->n_pins, .points = st->pins,
                                  .flags = st->pin_flags, .radius = b.radius,
                                  .ratio = b.ratio, .nu = b.nu, .order = b.order,
                                  .threads = threads};
        df_kelvinlet_constraints *kc = s->kc;
        if (!kc) {
            df_work_report(w, DF_STAGE_FACTORIZE, 0, 1, 0, 1);
            rc = df_kelvinlet_constraints_create(&pins, &ch->kc, err);
            kc = ch->kc;
            ch->kc_hit = 0;
        } else {
            unsigned long before = df_kelvinlet_constraints_factorizations(kc);
            rc = df_kelvinlet_constraints_update(kc, &pins, err);
            ch->kc_hit = df_kelvinlet_constraints_factorizations(kc) == before;
        }
        if (rc != DF_OK) return rc;
        if (!ch->kc_hit) df_work_report(w, DF_STAGE_FACTORIZE, 1, 1, 1, 1);
        ch->kc_used = 1;
        ch->kc_pins = st->n_pins;
        rc = df_kelvinlet_constraints_solve(kc, &b, &prep, err);
    } else {
        rc = df_kelvinlet_prepare(&b, &prep, err);
    }
    if (rc != DF_OK) return rc;
    memcpy(ch->tip, b.tip, sizeof ch->tip); /* the stroke's grab tip (force feedback) */
    ch->set_tip = 1;
    prep.threads = threads;
    rc = df_kelvinlet_displacements(&prep, st->startf, (size_t)s->nv, disp, err);
    df_kelvinlet_prepared_free(&prep);
    if (rc == DF_OK && st->surf_dist) /* surface-aware: the replay's very mask (stroke_recipe.h) */
        rc = df_stroke_surface_mask(&b, st->startf, s->nv, st->surf_dist, st->surf_src, disp,
                                    err);
    if (rc == DF_OK && s->mesh.planar) /* 2D session: z stays 0 (planar_check), verified */
        for (int32_t i = 0; i < s->nv; i++)
            if (disp[3 * (size_t)i + 2] != 0.0f)
                return df_error_set(err, DF_EINVAL, "brush: the field would move vertex %d "
                                    "off the plane of this 2D session (z %g)", i,
                                    (double)disp[3 * (size_t)i + 2]);
    return rc;
}

/* Encodes base + m as the next version into change `ch`, m = fl32(x0 + disp) - x0 the float32
 * motion of each stroke-start point x0 = st->startf (0 where disp is below x0's resolution;
 * disp = s->scratch_disp, replaced by m). The commit makes the stroke contribute m. The job's
 * borrowed scratch buffers are swapped in by the commit, not copied. */
static int stroke_publish(const df_session *s, const df_stroke *st, uint8_t kind,
                          const double *load, df_change *ch, df_error *err)
{
    size_t n = 3 * (size_t)s->nv;
    float *disp = s->scratch_disp;
    const double *base = st->base;
    double *rebased = NULL;
    if (atomic_load(&s->version) != st->last_version) { /* someone else changed the mesh */
        rebased = malloc(n * sizeof *rebased);
        if (!rebased) return df_error_set(err, DF_ENOMEM, "out of memory");
        for (size_t i = 0; i < n; i++) rebased[i] = s->cur[i] - (double)st->applied[i];
        base = rebased;
    }
    double *pos = s->scratch_pos;
    df_stroke_motion(st->startf, disp, base, pos, n); /* the arithmetic replays redo */
    int rc = df_stream_encode(s, NULL, 0, pos, kind, NULL, 0, s->scratch_u, &ch->frames, NULL,
                              err);
    if (rc != DF_OK) {
        free(rebased);
        return rc;
    }
    ch->pos = pos;
    ch->uf = s->scratch_u;
    ch->version = atomic_load(&s->version) + 1;
    ch->applied = disp;
    ch->base = rebased;
    ch->set_recipe = 1; /* what replays this publish (stroke_recipe.h), when anything can */
    ch->recipe_brush = st->brush;
    ch->recipe_strength = st->strength;
    if (load) memcpy(ch->recipe_load, load, sizeof ch->recipe_load);
    ch->recipe_replayable = load && !rebased && !st->rebased;
    return DF_OK;
}

/* True when stroke `st` contributes no displacement (n floats of st->applied are all zero):
 * it never published, or its loads were zero, so cancelling it changes nothing. */
static int stroke_applied_nothing(const df_stroke *st, size_t n)
{
    if (!st->applied) return 1;
    for (size_t i = 0; i < n; i++)
        if (st->applied[i] != 0.0f) return 0;
    return 1;
}

/* The checks a stroke's fixed parameters must pass whatever its loads: strength within
 * +-DF_BRUSH_MAX_STRENGTH, pins only on a 3D, unmirrored, stationary brush (what the pinned
 * solver supports), and the Kelvinlet engine's own rules (nu, radii, ratio, order; a scale brush
 * at nu 0.5 is singular). `what` names the request in messages. */
static int stroke_params_check(const df_stroke *st, const char *what, df_error *err)
{
    const df_kelvinlet_brush *b = &st->brush;
    if (!isfinite(st->strength) || fabs(st->strength) > DF_BRUSH_MAX_STRENGTH)
        return df_error_set(err, DF_EINVAL, "%s: strength %g outside [-%g, %g]", what,
                            st->strength, DF_BRUSH_MAX_STRENGTH, DF_BRUSH_MAX_STRENGTH);
    if (st->n_pins && (b->dim != 3 || b->mirror || b->moving))
        return df_error_set(err, DF_EUNSUPPORTED, "%s: pinned points need a 3D, unmirrored, "
                            "stationary brush (dim %d, mirror %d, moving %d)", what, b->dim,
                            b->mirror, b->moving);
    df_kelvinlet_prepared prep;
    df_error e;
    int rc = df_kelvinlet_prepare(b, &prep, &e);
    if (rc != DF_OK)
        return df_error_set(err, rc, "%s: %s", what, e.msg);
    df_kelvinlet_prepared_free(&prep);
    return DF_OK;
}

int df_h_brush_knob_check(const df_stroke *st, uint8_t param, double value, df_error *err)
{
    df_stroke t = *st;  /* shallow: only the scalar parameters change */
    const char *name = "?";
    switch (param) {
    case DF_BP_RADIUS: t.brush.radius = value; name = "radius"; break;
    case DF_BP_NU: t.brush.nu = value; name = "nu"; break;
    case DF_BP_STRENGTH: t.strength = value; name = "strength"; break;
    case DF_BP_FALLOFF: t.brush.order = (int)value; name = "falloff"; break;
    case DF_BP_RATIO: t.brush.ratio = value; name = "ratio"; break;
    default:
        return df_error_set(err, DF_EINVAL, "set_brush_param: param %u not in 1..%u", param,
                            DF_BP_MAX);
    }
    df_error e;
    int rc = stroke_params_check(&t, "set_brush_param", &e);
    if (rc != DF_OK)
        return df_error_set(err, rc, "set_brush_param: %s %g refused, stroke unchanged (%s)",
                            name, value, e.msg + strlen("set_brush_param: "));
    return DF_OK;
}

/* A 2D session (mesh declared 2D) keeps every z at 0: a load that would move z is refused
 * rather than having its z part dropped. Loads: move z, twist about x or y, a gradient with a
 * z row or column; with a 3D brush also a centre, mirror normal or pin off the z = 0 plane
 * (those make the 3D field move z). `b` may be NULL (updates: the loads only). */
static int planar_check(const df_session *s, const df_kelvinlet_brush *b, const df_stroke *st,
                        const double *load, const char *what, df_error *err)
{
    if (!s->mesh.planar) return DF_OK;
    static const char *const hint = "the session is 2D (load the mesh as 3D to move z)";
    if (load[2] != 0.0)
        return df_error_set(err, DF_EINVAL, "%s: move z = %g would leave the plane: %s", what,
                            load[2], hint);
    if (load[3] != 0.0 || load[4] != 0.0)
        return df_error_set(err, DF_EINVAL, "%s: twist (%g, %g, _) about x/y would leave the "
                            "plane: %s", what, load[3], load[4], hint);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            if ((i == 2 || k == 2) && load[7 + 3 * i + k] != 0.0)
                return df_error_set(err, DF_EINVAL, "%s: matrix[%d][%d] = %g would move z: %s",
                                    what, i, k, load[7 + 3 * i + k], hint);
    if (!b || b->dim != 3) return DF_OK;
    if (b->centre[2] != 0.0)
        return df_error_set(err, DF_EINVAL, "%s: a 3D brush centred at z = %g would move z: %s "
                            "(or use dim 2)", what, b->centre[2], hint);
    if (b->mirror && b->mirror_normal[2] != 0.0)
        return df_error_set(err, DF_EINVAL, "%s: mirror normal z = %g would move z: %s", what,
                            b->mirror_normal[2], hint);
    for (uint32_t k = 0; k < st->n_pins; k++)
        if (st->pins[3 * (size_t)k + 2] != 0.0)
            return df_error_set(err, DF_EINVAL, "%s: pinned point %u at z = %g would move z: %s",
                                what, k, st->pins[3 * (size_t)k + 2], hint);
    return DF_OK;
}

/* 1 when all 16 load components of a request (move, twist, scale, matrix) are zero. */
static int load_is_zero(const double *load)
{
    int zero = 1;
    for (int i = 0; i < 16; i++) zero &= load[i] == 0.0;
    return zero;
}

static void begin_work_inner(df_job *j);

/* Work of BRUSH_BEGIN (pure: reads the session, fills j->change; the scratch buffers were lent
 * by job.c). */
static void begin_work(df_job *j)
{
    uint64_t t0 = uv_hrtime();
    begin_work_inner(j);
    uint64_t dt = uv_hrtime() - t0;
    j->change.brush_ms = (double)dt / 1e6;
    brush_req *r = j->body; /* a zero-load begin evaluates no field: nothing measured */
    if (r->created && !load_is_zero(r->load) && j->rc == DF_OK) r->created->work_ns = dt;
    if (j->rc == DF_OK) { /* the new stroke goes to the session with the commit */
        j->change.link = r->created;
        r->created = NULL;
    }
}

static void begin_work_inner(df_job *j)
{
    brush_req *r = j->body;
    const df_session *s = j->s;
    if (df_session_stroke(j->s, j->conn_id)) {
        j->rc = df_error_set(&j->err, DF_ESTATE,
                             "brush_begin: this client already has an open stroke on session "
                             "%llu (end or cancel it first)", (unsigned long long)s->id);
        return;
    }
    size_t n = 3 * (size_t)s->nv;
    df_stroke *st = calloc(1, sizeof *st);
    float *disp = s->scratch_disp;
    if (st) {
        st->base = malloc(n * sizeof *st->base);
        st->startf = malloc(n * sizeof *st->startf);
        st->applied = calloc(n, sizeof *st->applied);
        if (r->begin.n_pinned) st->pins = malloc(3 * (size_t)r->begin.n_pinned * sizeof(double));
    }
    r->created = st;
    if (!st || !st->base || !st->startf || !st->applied ||
        (r->begin.n_pinned && !st->pins)) {
        j->rc = df_error_set(&j->err, DF_ENOMEM, "out of memory");
        return;
    }
    const df_msg_brush *m = &r->begin;
    df_kelvinlet_brush *b = &st->brush;
    int pin_flags = 0;
    if ((j->rc = df_wire_brush_to_core(m, b, &j->err)) != DF_OK) return;
    if (df_wire_pin_flags_to_core(m->pin_flags, &pin_flags) != DF_OK) {
        j->rc = df_error_set(&j->err, DF_EINVAL, "brush: pin_flags 0x%x", m->pin_flags);
        return;
    }
    st->strength = m->strength;
    st->conn_id = j->conn_id;
    st->n_pins = m->n_pinned;
    st->pin_flags = pin_flags;
    st->progress = (m->options & DF_WORK_OPT_PROGRESS) != 0;
    if (m->n_pinned) memcpy(st->pins, m->pinned, 3 * (size_t)m->n_pinned * sizeof(double));
    memcpy(st->base, s->cur, n * sizeof *st->base);
    for (size_t i = 0; i < n; i++) st->startf[i] = (float)s->cur[i];
    st->last_version = atomic_load(&s->version);
    st->base_version = st->last_version;
    /* validate the brush (a zero-load begin publishes nothing; the pin LU is built and
     * checked by the first update) */
    if ((j->rc = stroke_params_check(st, "brush_begin", &j->err)) != DF_OK) return;
    if ((j->rc = planar_check(s, &st->brush, st, r->load, "brush_begin", &j->err)) != DF_OK)
        return;
    if (b->surface && /* distances from the centre's vertex over startf, cached per session */
        (j->rc = df_surface_cache_dist(&((df_session *)s)->surf, &s->mesh, st->startf, s->nv,
                                       b->centre, &st->surf_src, &st->surf_dist, &j->err))
            != DF_OK)
        return;
    if (load_is_zero(r->load)) return;
    df_work w;
    df_work_init(&w, j->srv, j->req.c, j->req.id, s->id, st->progress);
    j->rc = stroke_field(s, st, r->load, disp, &j->change, &w, &j->err);
    if (j->rc == DF_OK) j->rc = stroke_publish(s, st, DF_CHANGE_BRUSH, r->load, &j->change, &j->err);
}

static void update_work_inner(df_job *j);

/* Work of BRUSH_UPDATE and BRUSH_CANCEL (pure, as begin_work). */
static void update_work(df_job *j)
{
    uint64_t t0 = uv_hrtime();
    update_work_inner(j);
    uint64_t dt = uv_hrtime() - t0;
    df_change *ch = &j->change;
    ch->brush_ms = (double)dt / 1e6;
    ch->stroke = df_session_stroke(j->s, j->conn_id);
    if (ch->stroke && j->req.type == DF_MSG_BRUSH_UPDATE) {
        ch->set_work_ns = 1;
        ch->work_ns = j->rc == DF_OK ? dt : 0;
    }
    if (j->req.type == DF_MSG_BRUSH_CANCEL) ch->drop_stroke = 1;
}

/* Predicted cost of a brush update at the head of its FIFO: the same stroke's last field
 * evaluation. Pinned strokes never run inline (an evicted K_pp factorization would be rebuilt
 * in the update), nor strokes not measured yet. */
static uint64_t update_cost(const df_job *j)
{
    const df_stroke *st = df_session_stroke(j->s, j->conn_id);
    return st && st->n_pins == 0 ? st->work_ns : 0;
}

static void update_work_inner(df_job *j)
{
    brush_req *r = j->body;
    const df_session *s = j->s;
    const df_stroke *st = df_session_stroke(j->s, j->conn_id);
    if (!st) {
        j->rc = df_error_set(&j->err, DF_ESTATE, "%s: no open stroke on session %llu",
                             df_msg_type_name(j->req.type), (unsigned long long)s->id);
        return;
    }
    size_t n = 3 * (size_t)s->nv;
    float *disp = s->scratch_disp;
    df_change *ch = &j->change;
    if (j->req.type == DF_MSG_BRUSH_CANCEL) {
        if (stroke_applied_nothing(st, n)) return; /* nothing to undo: no version */
        memset(disp, 0, n * sizeof *disp);
        j->rc = stroke_publish(s, st, DF_CHANGE_BRUSH_CANCEL, NULL, ch, &j->err);
    } else {
        j->rc = planar_check(s, NULL, st, r->load, "brush_update", &j->err);
        df_work w;
        df_work_init(&w, j->srv, j->req.c, j->req.id, s->id, st->progress);
        if (j->rc == DF_OK) j->rc = stroke_field(s, st, r->load, disp, ch, &w, &j->err);
        if (j->rc == DF_OK) j->rc = stroke_publish(s, st, DF_CHANGE_BRUSH, r->load, ch, &j->err);
    }
}

/* The cumulative load of a begin or update message (move, twist, scale, matrix) into r->load. */
static void load_from(brush_req *r, const double *move, const double *twist, double scale,
                      const double *matrix)
{
    memcpy(r->load, move, 3 * sizeof(double));
    memcpy(r->load + 3, twist, 3 * sizeof(double));
    r->load[6] = scale;
    memcpy(r->load + 7, matrix, 9 * sizeof(double));
}

/* The fields a begin's `use_session` bits name, copied from the session brush into the message
 * (loop thread, when the request arrives: the stroke uses the brush as of its arrival, and the
 * worker never reads the session brush). An unknown session is left to df_job_request. */
static void take_session_brush(df_server *srv, df_msg_brush *m)
{
    const df_session *s = m->use_session ? df_session_find(srv, m->session_id) : NULL;
    if (!s) return;
    const df_brush_state *b = df_brush_state_get(s);
    unsigned u = m->use_session;
    if (u & DF_BS_TYPE) m->type = b->type;
    if (u & DF_BS_RADIUS) m->radius = b->radius;
    if (u & DF_BS_NU) m->nu = b->nu;
    if (u & DF_BS_STRENGTH) m->strength = b->strength;
    if (u & DF_BS_FALLOFF) m->falloff = b->falloff;
    if (u & DF_BS_RATIO) m->ratio = b->ratio;
    if (u & DF_BS_INTEGRATOR) {
        m->integrator = b->integrator;
        m->steps = b->steps;
    }
    if (u & DF_BS_MIRROR) {
        m->has_mirror = b->has_mirror;
        memcpy(m->mirror_point, b->mirror_point, sizeof m->mirror_point);
        memcpy(m->mirror_normal, b->mirror_normal, sizeof m->mirror_normal);
    }
}

static int begin_decode(const df_req *rq, const uint8_t *p, void *body, uint64_t *sid,
                        df_error *err)
{
    brush_req *r = body;
    int rc = df_msg_brush_decode(p, rq->len, &r->begin, err); /* owned by the body from here */
    if (rc != DF_OK) return rc;
    *sid = r->begin.session_id;
    take_session_brush(rq->srv, &r->begin);
    load_from(r, r->begin.move, r->begin.twist, r->begin.scale, r->begin.matrix);
    return DF_OK;
}

static int update_decode(const df_req *rq, const uint8_t *p, void *body, uint64_t *sid,
                         df_error *err)
{
    df_msg_brush_update m;
    int rc = df_msg_brush_update_decode(p, rq->len, &m, err);
    if (rc != DF_OK) return rc;
    *sid = m.session_id;
    load_from(body, m.move, m.twist, m.scale, m.matrix);
    return DF_OK;
}

const df_job_kind df_k_brush_begin = {.body_size = sizeof(brush_req), .decode = begin_decode,
                                      .release = req_free, .work = begin_work,
                                      .done = df_job_commit};
const df_job_kind df_k_brush_update = {.body_size = sizeof(brush_req), .decode = update_decode,
                                       .release = req_free, .work = update_work,
                                       .done = df_job_commit, .inline_cost = update_cost};
const df_job_kind df_k_brush_cancel = {.body_size = sizeof(brush_req),
                                       .decode = df_job_decode_ref, .release = req_free,
                                       .work = update_work, .done = df_job_commit};

/* BRUSH_END work (a worker): plans the stroke's undo step. A RECIPE step (the stroke's
 * request, stroke_recipe.h) when its last publish is replayable and began from the history's
 * current state: the plan replays it from that state and keeps it only when the replay is
 * bitwise s->cur (history.h); else (another uncommitted change in between, a rebase, a cancel)
 * an XOR step. The loop thread only installs the plan. */
static void end_work(df_job *j)
{
    const df_session *s = j->s;
    const df_stroke *st = df_session_stroke(j->s, j->conn_id);
    if (!st) {
        j->rc = df_error_set(&j->err, DF_ESTATE, "brush_end: no open stroke on session %llu",
                             (unsigned long long)s->id);
        return;
    }
    j->rc = df_stroke_end_plan(s, st, &j->change.hplan, &j->err);
}

/* BRUSH_END done: the stroke becomes one undo step and is dropped (loop thread, FIFO order). */
static void end_done(df_job *j)
{
    j->change.hist = DF_HIST_COMMIT;
    j->change.drop_stroke = 1;
    df_job_commit(j);
}

const df_job_kind df_k_brush_end = {.decode = df_job_decode_ref, .work = end_work,
                                    .done = end_done};

/* commit.c — df_session_commit: a change record applied to its session in one fixed order
 * (see commit.h). */
#include "server/session/commit.h"

#include <stdlib.h>
#include <string.h>

#include "server/session/cache.h"
#include "server/net/conn.h"
#include "server/log.h"

void df_change_init(df_change *c, df_req *req, df_error *err)
{
    memset(c, 0, sizeof *c);
    c->req = req;
    c->err = err;
    c->brush_ms = c->move_ms = -1;
}

void df_change_clear(df_server *srv, df_change *c)
{
    df_frames_clear(&c->frames);
    if (c->own_buffers) { /* not committed */
        free(c->pos);
        free(c->uf);
    }
    c->pos = NULL;
    c->uf = NULL;
    df_stroke_free(c->link);
    c->link = NULL;
    free(c->base);
    c->base = NULL;
    if (c->hs) df_handleset_free(srv, c->hs);
    c->hs = NULL;
    df_kelvinlet_constraints_free(c->kc);
    c->kc = NULL;
    df_admm_free(c->solver);
    c->solver = NULL;
    df_history_plan_free(&c->hplan);
}

/* Step 1: the new state, swapped in (the old buffers become the session's scratch). */
static void apply_state(df_session *s, df_change *c)
{
    if (c->pos) {
        double *old = s->cur;
        s->cur = c->pos;
        if (c->own_buffers) free(old);
        else s->scratch_pos = old;
        c->pos = NULL;
    }
    if (c->version) {
        float *old = s->uf;
        s->uf = c->uf;
        if (c->own_buffers) free(old);
        else s->scratch_u = old;
        c->uf = NULL;
        atomic_store(&s->version, c->version);
    }
    if (c->rest_from_cur) memcpy(s->rest, s->cur, 3 * (size_t)s->nv * sizeof(double));
    df_stroke *st = c->link ? c->link : c->stroke;
    if (st && c->applied) {
        float *old = st->applied;
        st->applied = c->applied;
        s->scratch_disp = old;
        c->applied = NULL;
    }
    if (st && c->base) {
        st->rebased = 1;
        free(st->base);
        st->base = c->base;
        c->base = NULL;
    }
    if (st && c->version) st->last_version = c->version;
    if (st && c->set_tip) memcpy(st->tip, c->tip, sizeof st->tip);
    if (st && c->set_recipe) {
        st->last_brush = c->recipe_brush;
        st->last_strength = c->recipe_strength;
        memcpy(st->last_load, c->recipe_load, sizeof st->last_load);
        st->last_replayable = c->recipe_replayable;
    }
    if (st && c->set_params) {
        st->brush = c->brush;
        st->strength = c->strength;
    }
    if (c->link) {
        c->link->next = s->strokes;
        s->strokes = c->link;
        c->link = NULL;
    }
    if (c->hs) {
        df_handleset_free(s->srv, s->hs);
        s->hs = c->hs;
        c->hs = NULL;
    }
}

/* Step 2: the undo step, then the stroke it ended. */
static int apply_history(df_session *s, df_change *c)
{
    int rc = DF_OK;
    switch (c->hist) {
    case DF_HIST_COMMIT:
        rc = c->hplan.valid ? df_session_history_install(s, &c->hplan, c->err)
                            : df_session_history_commit(s, c->err);
        break;
    case DF_HIST_RESET: df_session_history_reset(s, NULL); break; /* cannot fail */
    case DF_HIST_UNDO:
    case DF_HIST_REDO:
        if (c->hplan.valid) rc = df_session_history_install(s, &c->hplan, c->err);
        else if (c->hist == DF_HIST_UNDO) df_history_undo(&s->hist, NULL);
        else df_history_redo(&s->hist, NULL);
        break;
    default: break;
    }
    if (rc == DF_OK && c->drop_stroke && c->req)
        df_session_drop_stroke(s, df_req_origin(c->req));
    return rc;
}

/* Step 3: timings, cache accounting and the memory cap (also after a failed compute). */
static void apply_caches(df_session *s, df_change *c)
{
    df_server *srv = s->srv;
    df_stroke *st = c->link ? c->link : c->stroke;
    if (st && c->set_work_ns) st->work_ns = c->work_ns;
    if (c->brush_ms >= 0) s->brush_last_ms = c->brush_ms;
    if (c->move_ms >= 0) s->move_last_ms = c->move_ms;
    if (c->kc) { /* built by the compute: the session's pin LU from now on */
        df_kelvinlet_constraints_free(s->kc);
        s->kc = c->kc;
        c->kc = NULL;
    }
    if (c->kc_used) {
        if (c->kc_hit) srv->stats.kelvin_lu_hits++;
        else srv->stats.kelvin_lu_misses++;
        if (s->kc) {
            srv->cache_bytes -= s->kc_bytes <= srv->cache_bytes ? s->kc_bytes : srv->cache_bytes;
            df_cache_install_kelvinlet(srv, s, df_cache_estimate_kelvinlet(c->kc_pins));
        }
    }
    if (c->solver) { /* rebuilt by the compute (an evicted one): the set's from now on */
        if (s->hs && !s->hs->solver) s->hs->solver = c->solver;
        else df_admm_free(c->solver);
        c->solver = NULL;
    }
    if (c->solver_created && s->hs) {
        srv->stats.admm_misses++;
        df_cache_install_solver(srv, s->hs, df_cache_estimate_admm(s->nv, s->mesh.ne));
    } else if (c->solver_hit && s->hs) {
        srv->stats.admm_hits++;
        df_cache_touch_solver(srv, s->hs);
    }
    if (c->solver_drop && s->hs) df_cache_drop_solver(srv, s->hs);
    df_cache_enforce(srv);
}

int df_session_commit(df_session *s, df_change *c)
{
    df_server *srv = s->srv;
    int strokes = c->link || c->stroke || c->drop_stroke || c->set_params;
    if (c->rc == DF_OK && srv->store_ops) { /* step 0: durable first (server/store/journal.h) */
        df_error e;
        if ((c->rc = srv->store_ops->change(srv, s, c, &e)) != DF_OK) {
            df_log(DF_LOG_ERROR, "session %llu: change not applied: %s", (unsigned long long)s->id,
                   e.msg);
            if (c->err) *c->err = e;
        }
    }
    if (c->rc == DF_OK) {
        apply_state(s, c);
        c->rc = apply_history(s, c);
    }
    if (c->rc != DF_OK && c->hplan.mismatch) df_session_history_repair(s, &c->hplan);
    apply_caches(s, c);
    if (c->rc != DF_OK) {
        if (c->req && !c->answered_by_job) df_req_fail(c->req, c->err);
        return c->rc;
    }
    if (srv->commit_hook) srv->commit_hook(srv->commit_hook_arg, s, c);
    for (size_t i = 0; i < c->frames.n; i++) df_session_broadcast(s, c->frames.v[i]);
    if (c->frames.n) srv->stats.versions++;
    if (c->version) df_session_resync_record(s, c->version, &c->frames); /* resync.h */
    if (strokes && srv->hid_ops && srv->hid_ops->strokes_changed)
        srv->hid_ops->strokes_changed(srv, s);
    if (c->req && !c->answered_by_job) df_req_ack(c->req, s->id, atomic_load(&s->version));
    return DF_OK;
}

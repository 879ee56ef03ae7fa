/* session.c — session registry, subscribers, strokes (see session.h). */
#include "server/session/session.h"
#include "server/session/stream_enc.h"
#include "server/session/stream_lag.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/session/cache.h"
#include "server/net/conn.h"
#include "server/log.h"
#include "server/session/meshload.h"
#include "server/session/stroke_recipe.h"
#include "server/session/surface_cache.h"
#include "server/net/reply.h"
#include "server/net/shm.h"
#include "server/session/stream.h"

uint64_t df_session_estimate_bytes(const df_mesh *mesh)
{
    int es = df_mesh_elem_size(mesh->kind);
    return (uint64_t)(mesh->nv > 0 ? mesh->nv : 0) * DF_SESSION_BYTES_PER_VERTEX +
           (uint64_t)(mesh->ne > 0 ? mesh->ne : 0) * (uint64_t)es * sizeof(int32_t) +
           (uint64_t)(mesh->nf > 0 ? mesh->nf : 0) * 3 * sizeof(int32_t) + sizeof(df_session);
}

int df_session_replay_recipe(df_session *s, const df_stroke_recipe *r, const double *from,
                             int threads, float *scratch, double *to, df_error *err)
{
    const df_mesh_sparse *adj = NULL;
    if (r->brush.surface) {
        int rc = df_surface_cache_adjacency(&s->surf, &s->mesh, &adj, err);
        if (rc != DF_OK) return rc;
    }
    const double *rest = adj ? s->mesh.V : NULL;
    if (scratch)
        return df_stroke_recipe_replay_with(r, from, s->nv, adj, rest, s->mesh.planar, threads,
                                            scratch, to, err);
    return df_stroke_recipe_replay_mesh(r, from, s->nv, adj, rest, s->mesh.planar, threads, to,
                                        err);
}

/* The history's replay of a RECIPE step (history.h): a stroke recipe (stroke_recipe.h)
 * recomputed on this session's mesh, with the server's thread count, through the plan's
 * scratch (6 * nv floats, allocated at its first replay and reused by the others). Runs as
 * the session's job (its surface cache is the running job's). */
static int replay_recipe(void *ctx, const uint8_t *blob, size_t len, const double *from,
                         double *to, void **scratch, df_error *err)
{
    df_session *s = ctx;
    size_t bytes = 6 * (size_t)s->nv * sizeof(float);
    if (!*scratch && !(*scratch = malloc(bytes)))
        return df_error_set(err, DF_ENOMEM, "undo history: out of memory replaying a stroke "
                            "(%d vertices)", s->nv);
    if (!blob) { /* prepare only (history.h): touched now, not during a timed replay */
        memset(*scratch, 0, bytes);
        return DF_OK;
    }
    df_stroke_recipe r;
    int rc = df_stroke_recipe_decode(blob, len, &r, err);
    if (rc != DF_OK) return rc;
    rc = df_session_replay_recipe(s, &r, from, s->srv->cfg.threads, *scratch, to, err);
    df_stroke_recipe_free(&r);
    return rc;
}

/* The replay callback and budget, and the reference the history packs its anchor against:
 * the rest shape, which changes only at reset-rest (whose commit resets the history right
 * after the copy, df_session_history_reset) and at a store restore (before the history is
 * reset to the snapshot). */
static void history_set_replay(df_session *s)
{
    df_history_set_replay(&s->hist, replay_recipe, s,
                          (uint64_t)s->srv->cfg.history_replay_ms * 1000000u);
    df_history_set_reference(&s->hist, s->rest, NULL); /* an empty history: cannot fail */
}

/* Recharges the history's bytes after a change (it bounded itself against df_mem_room). */
static void history_recharge(df_session *s)
{
    uint64_t now = df_history_bytes(&s->hist);
    df_mem_adjust(df_server_mem(s->srv), DF_MEM_HISTORY, s->hist_charged, now);
    s->hist_charged = now;
}

/* The budget of this session's history: history_max_mb, or less when the memory budget has less
 * room (counting what the history already holds). */
static size_t history_budget(const df_session *s)
{
    uint64_t per = (uint64_t)s->srv->cfg.history_max_mb << 20;
    uint64_t room = df_mem_room(df_server_mem(s->srv), DF_MEM_HISTORY) + s->hist_charged;
    uint64_t b = per < room ? per : room;
    return b < SIZE_MAX ? (size_t)b : SIZE_MAX;
}

/* Drops oldest undo steps of idle sessions, largest history first, until `want` bytes are
 * freed or none is left; returns the bytes freed. */
static uint64_t reclaim_history(df_server *srv, uint64_t want)
{
    uint64_t freed = 0;
    while (freed < want) {
        df_session *best = NULL;
        for (df_session *s = srv->sessions; s; s = s->next)
            if (!s->running && df_history_can_undo(&s->hist) > 0 &&
                (!best || df_history_bytes(&s->hist) > df_history_bytes(&best->hist)))
                best = s;
        if (!best) break;
        uint64_t before = best->hist_charged, d0 = best->hist.dropped;
        df_history_set_max_bytes(&best->hist, df_history_bytes(&best->hist) - 1); /* one step */
        srv->history_dropped += best->hist.dropped - d0;
        history_recharge(best);
        freed += before - best->hist_charged;
    }
    if (freed)
        df_log(DF_LOG_INFO, "memory budget: dropped %llu bytes of old undo steps",
               (unsigned long long)freed);
    return freed;
}

/* Drops the oldest versions of resync rings, largest ring first, until `want` bytes are freed
 * or no ring is left; returns the bytes freed. Rings give way before undo steps: a version
 * dropped from a ring costs a resyncing client a snapshot at worst, a dropped step is lost. */
static uint64_t reclaim_resync(df_server *srv, uint64_t want)
{
    uint64_t freed = 0;
    while (freed < want) {
        df_session *best = NULL;
        for (df_session *s = srv->sessions; s; s = s->next)
            if (s->resync.count && (!best || s->resync.bytes > best->resync.bytes)) best = s;
        if (!best) break;
        uint64_t left = want - freed, have = best->resync.bytes;
        freed += df_resync_trim(&best->resync, have > left ? have - left : 0);
        df_mem_adjust(df_server_mem(srv), DF_MEM_RESYNC, best->resync_charged, best->resync.bytes);
        best->resync_charged = best->resync.bytes;
    }
    return freed;
}

int df_session_mem_charge(df_server *srv, df_mem_kind kind, uint64_t bytes, const char *what,
                          df_error *err)
{
    df_membudget *mb = df_server_mem(srv);
    if ((unsigned)kind < DF_MEM_KINDS && mb->used[kind] <= mb->kind_max[kind] &&
        bytes <= mb->kind_max[kind] - mb->used[kind]) {
        uint64_t used = df_mem_used(mb), room = used < mb->max ? mb->max - used : 0;
        if (bytes > room) room += reclaim_resync(srv, bytes - room);
        if (bytes > room) reclaim_history(srv, bytes - room);
    }
    return df_mem_charge(mb, kind, bytes, what, err);
}

int df_session_create(df_server *srv, df_mesh *mesh, const char *name, df_session **out,
                      df_error *err)
{
    return df_session_create_as(srv, mesh, name, "", out, err);
}

_Static_assert((int)DF_SESSION_ACCESS_OPEN == (int)DF_ACCESS_MODE_OPEN &&
               (int)DF_SESSION_ACCESS_KEY == (int)DF_ACCESS_MODE_KEY &&
               (int)DF_SESSION_ACCESS_OWNER == (int)DF_ACCESS_MODE_OWNER, "config modes are access modes");

int df_session_create_as(df_server *srv, df_mesh *mesh, const char *name, const char *owner,
                         df_session **out, df_error *err)
{
    int max = srv->cfg.max_sessions < (int)DF_MAX_SESSIONS ? srv->cfg.max_sessions
                                                           : (int)DF_MAX_SESSIONS;
    if (srv->n_sessions >= max) {
        df_meshload_free(mesh);
        return df_error_set(err, DF_ELIMIT, "too many sessions (max_sessions = %d)", max);
    }
    if (name && name[0] && df_session_find_name(srv, name)) {
        df_meshload_free(mesh);
        return df_error_set(err, DF_EEXIST,
                            "session name '%s' is already in use (close that session or pick "
                            "another name)", name);
    }
    size_t n = (size_t)mesh->nv * 3;
    uint64_t est = df_session_estimate_bytes(mesh);
    char what[64];
    snprintf(what, sizeof what, "session of %d vertices", mesh->nv);
    uint64_t state = n * sizeof(double); /* the history's first state */
    if (df_session_mem_charge(srv, DF_MEM_SESSIONS, est + state, what, err) != DF_OK) {
        df_meshload_free(mesh);
        return err ? err->code : DF_ELIMIT;
    }
    df_membudget *mb = df_server_mem(srv);
    df_mem_release(mb, DF_MEM_SESSIONS, state); /* charged as history: same total */
    df_mem_adjust(mb, DF_MEM_HISTORY, 0, state);
    df_session *s = calloc(1, sizeof *s);
    if (s) {
        s->rest = malloc(n * sizeof *s->rest);
        s->cur = malloc(n * sizeof *s->cur);
        s->basef = malloc(n * sizeof *s->basef);
        s->uf = calloc(n, sizeof *s->uf);
    }
    if (!s || !s->rest || !s->cur || !s->basef || !s->uf ||
        df_history_init(&s->hist, mesh->V, n, DF_SESSION_HISTORY_MAX, err) != DF_OK) {
        if (s) {
            free(s->rest);
            free(s->cur);
            free(s->basef);
            free(s->uf);
            free(s);
        }
        df_mem_release(mb, DF_MEM_SESSIONS, est);
        df_mem_release(mb, DF_MEM_HISTORY, state);
        df_meshload_free(mesh);
        return df_error_set(err, DF_ENOMEM, "out of memory creating a session (%d vertices)",
                            mesh->nv);
    }
    s->srv = srv;
    s->mem_bytes = est;
    s->hist_charged = state;
    history_recharge(s);
    s->mesh = *mesh;
    memset(mesh, 0, sizeof *mesh);
    s->nv = s->mesh.nv;
    memcpy(s->rest, s->mesh.V, n * sizeof(double));
    history_set_replay(s);
    memcpy(s->cur, s->mesh.V, n * sizeof(double));
    for (size_t i = 0; i < n; i++) s->basef[i] = (float)s->mesh.V[i];
    atomic_init(&s->version, 0);
    df_brush_state_defaults(&s->brush);
    s->id = ++srv->next_session_id;
    if (name && name[0]) snprintf(s->name, sizeof s->name, "%s", name);
    else snprintf(s->name, sizeof s->name, "session-%llu", (unsigned long long)s->id);
    snprintf(s->owner, sizeof s->owner, "%s", owner ? owner : "");
    df_membership_init(&s->acc, srv->cfg.access.session_access, srv->cfg.access.session_observers);
    s->next = srv->sessions;
    srv->sessions = s;
    srv->n_sessions++;
    if (s->acc.mode == DF_ACCESS_MODE_KEY && df_membership_new_key(&s->acc, NULL, err) != DF_OK) {
        int rc = err ? err->code : DF_EINTERNAL;
        df_session_destroy(s);
        return rc;
    }
    if (srv->store_ops && srv->store_ops->session_created(srv, s, err) != DF_OK) {
        int rc = err ? err->code : DF_EIO;
        df_session_destroy(s); /* not durable: not created */
        return rc;
    }
    *out = s;
    return DF_OK;
}

df_session *df_session_find(df_server *srv, uint64_t id)
{
    for (df_session *s = srv->sessions; s; s = s->next)
        if (s->id == id && !s->closed) return s;
    return NULL;
}

df_session *df_session_find_name(df_server *srv, const char *name)
{
    for (df_session *s = srv->sessions; s; s = s->next)
        if (!s->closed && strcmp(s->name, name) == 0) return s;
    return NULL;
}

void df_stroke_free(df_stroke *st)
{
    if (!st) return;
    free(st->pins);
    free(st->base);
    free(st->startf);
    free(st->applied);
    free(st->surf_dist);
    free(st);
}

void df_handleset_free(df_server *srv, df_handleset *hs)
{
    if (!hs) return;
    df_cache_drop_solver(srv, hs);
    free(hs->handles);
    for (int i = 0; i < hs->n_affine; i++) free((void *)hs->affine[i].verts);
    free(hs->affine);
    free(hs);
}

void df_session_destroy(df_session *s)
{
    df_server *srv = s->srv;
    for (df_session **pp = &srv->sessions; *pp; pp = &(*pp)->next)
        if (*pp == s) {
            *pp = s->next;
            break;
        }
    srv->n_sessions--;
    for (int i = 0; i < s->nsubs; i++) df_stream_lag_release(s, i);
    for (int i = 0; i < s->nsubs; i++) df_conn_unref(s->subs[i]);
    free(s->subs);
    free(s->sub_shm);
    free(s->sub_lag);
    df_shm_destroy(s->shm);
    df_stream_enc_free(s);
    df_brush_state_release(s);
    while (s->strokes) {
        df_stroke *st = s->strokes;
        s->strokes = st->next;
        df_stroke_free(st);
    }
    df_handleset_free(srv, s->hs);
    df_cache_drop_kelvinlet(srv, s);
    df_surface_cache_free(s->surf);
    df_history_free(&s->hist);
    df_resync_free(&s->resync);
    df_membership_free(&s->acc);
    df_membudget *mb = df_server_mem(srv);
    df_mem_release(mb, DF_MEM_HISTORY, s->hist_charged);
    df_mem_release(mb, DF_MEM_RESYNC, s->resync_charged);
    df_mem_release(mb, DF_MEM_SESSIONS, s->mem_bytes);
    df_mem_release(mb, DF_MEM_SHM, s->shm_charged);
    df_meshload_free(&s->mesh);
    free(s->rest);
    free(s->cur);
    free(s->basef);
    free(s->uf);
    free(s->scratch_u);
    free(s->scratch_idx);
    free(s->scratch_rows);
    free(s->scratch_pos);
    free(s->scratch_disp);
    df_log(DF_LOG_INFO, "session %llu closed", (unsigned long long)s->id);
    free(s);
}

void df_session_close(df_session *s)
{
    if (s->closed) return;
    s->closed = 1;
    if (s->srv->hid_ops) /* devices bound to it follow the most recent session (hid_manager.h) */
        s->srv->hid_ops->session_gone(s->srv, s);
    df_msg_session_ref m = {.session_id = s->id};
    df_error err;
    df_sbuf *f = df_out_session_ref(DF_MSG_SESSION_CLOSED, DF_FLAG_EVENT, 0, &m, &err);
    if (f) {
        df_session_broadcast(s, f);
        df_sbuf_unref(f);
    }
    for (int i = 0; i < s->nsubs; i++) df_stream_lag_release(s, i);
    for (int i = 0; i < s->nsubs; i++) df_conn_unref(s->subs[i]);
    s->nsubs = s->nshm = 0;
}

int df_session_subscribe(df_session *s, df_conn *c, df_error *err)
{
    for (int i = 0; i < s->nsubs; i++)
        if (s->subs[i] == c) return DF_OK;
    if (s->nsubs >= s->srv->cfg.max_clients)
        return df_error_set(err, DF_ELIMIT, "session %llu has too many subscribers",
                            (unsigned long long)s->id);
    if (s->nsubs == s->capsubs) {
        int nc = s->capsubs ? 2 * s->capsubs : 8;
        df_conn **n = realloc(s->subs, (size_t)nc * sizeof *n);
        if (!n) return df_error_set(err, DF_ENOMEM, "out of memory");
        s->subs = n;
        uint8_t *f = realloc(s->sub_shm, (size_t)nc);
        if (!f) return df_error_set(err, DF_ENOMEM, "out of memory");
        s->sub_shm = f;
        df_sublag *l = realloc(s->sub_lag, (size_t)nc * sizeof *l);
        if (!l) return df_error_set(err, DF_ENOMEM, "out of memory");
        s->sub_lag = l;
        s->capsubs = nc;
    }
    df_conn_ref(c);
    s->sub_shm[s->nsubs] = 0;
    memset(&s->sub_lag[s->nsubs], 0, sizeof s->sub_lag[0]);
    s->subs[s->nsubs++] = c;
    return DF_OK;
}

int df_session_unsubscribe(df_session *s, df_conn *c)
{
    for (int i = 0; i < s->nsubs; i++)
        if (s->subs[i] == c) {
            s->nshm -= s->sub_shm[i];
            df_stream_lag_release(s, i);
            memmove(s->subs + i, s->subs + i + 1, (size_t)(s->nsubs - i - 1) * sizeof *s->subs);
            memmove(s->sub_shm + i, s->sub_shm + i + 1, (size_t)(s->nsubs - i - 1));
            memmove(s->sub_lag + i, s->sub_lag + i + 1,
                    (size_t)(s->nsubs - i - 1) * sizeof *s->sub_lag);
            s->nsubs--;
            df_stream_enc_prune(s);
            df_conn_unref(c);
            return 1;
        }
    return 0;
}

int df_session_attach_shm(df_session *s, df_conn *c, df_error *err)
{
    int i = 0;
    while (i < s->nsubs && s->subs[i] != c) i++;
    if (i == s->nsubs)
        return df_error_set(err, DF_ESTATE, "stream_shm: not subscribed to session %llu; "
                            "subscribe first", (unsigned long long)s->id);
    if (!s->shm) {
        uint64_t cap = df_shm_ring_size(s->nv, s->srv->cfg.shm_ring_bytes);
        uint64_t bytes = cap + DF_SHM_HEADER_BYTES;
        int rc = df_session_mem_charge(s->srv, DF_MEM_SHM, bytes, "stream_shm", err);
        if (rc) return rc;
        rc = df_shm_create(s->id, cap, &s->shm, err);
        if (rc) {
            df_mem_release(df_server_mem(s->srv), DF_MEM_SHM, bytes);
            return rc;
        }
        s->shm_charged = bytes;
    }
    if (!s->sub_shm[i]) s->nshm++;
    s->sub_shm[i] = 1;
    return DF_OK;
}

/* The SHM_REF frame standing for `frame` once it is copied into the session's ring; NULL when the
 * frame stays on the socket (no ring subscriber, size outside the ring's bounds, out of memory). */
static df_sbuf *shm_ref_for(df_session *s, df_sbuf *frame)
{
    if (s->nshm == 0 || !df_shm_takes(s->shm, frame->len)) return NULL;
    df_msg_shm_ref m = {.session_id = s->id, .length = (uint32_t)frame->len};
    m.position = df_shm_put(s->shm, frame->data, m.length);
    df_error err;
    df_sbuf *ref = df_out_shm_ref(DF_MSG_SHM_REF, DF_FLAG_EVENT, 0, &m, &err);
    if (ref) s->srv->stats.shm_frames++;
    return ref;
}

/* 1 when a subscriber negotiated a stream encoding (stream_enc.h). */
static int any_encoded(df_conn *const *subs, int n)
{
    for (int i = 0; i < n; i++)
        if (subs[i]->stream_enc || subs[i]->stream_neg) return 1;
    return 0;
}

void df_session_broadcast(df_session *s, df_sbuf *frame)
{
    /* df_conn_send may drop a subscriber (closing it unsubscribes it): iterate over a copy. */
    df_conn *local[64];
    uint8_t local_shm[64];
    int n = s->nsubs;
    df_conn **subs = n <= 64 ? local : malloc((size_t)n * sizeof *subs);
    uint8_t *shm = n <= 64 ? local_shm : malloc((size_t)n);
    if (!subs || !shm) {
        if (subs != local) free(subs);
        if (shm != local_shm) free(shm);
        return;
    }
    for (int i = 0; i < n; i++) {
        subs[i] = s->subs[i];
        shm[i] = s->sub_shm[i];
        df_conn_ref(subs[i]);
    }
    df_sbuf *ref = shm_ref_for(s, frame);
    /* negotiated encodings (stream_enc.h): every quantized group follows every stream frame,
     * whoever of its subscribers is still open */
    df_enc_variants vs = {.n = 0};
    int encoded = s->nqg > 0 || any_encoded(subs, n);
    if (encoded && df_stream_enc_applies(frame)) {
        df_stream_enc_follow(s, frame, &vs);
    } else {
        encoded = 0;
    }
    for (int i = 0; i < n; i++) {
        int by_ref = ref && shm[i];
        if (encoded && (subs[i]->stream_enc || subs[i]->stream_neg) && !by_ref &&
            !subs[i]->closing) {
            /* its variant, or coalesced when it cannot keep up (stream_lag.h) */
            int j = 0;
            while (j < s->nsubs && s->subs[j] != subs[i]) j++;
            if (j < s->nsubs) df_stream_lag_send(s, j, frame, &vs);
            df_conn_unref(subs[i]);
            continue;
        }
        df_sbuf *f = by_ref ? df_sbuf_ref(ref) : df_sbuf_ref(frame);
        if (!subs[i]->closing && df_conn_send(subs[i], f) == DF_OK && by_ref)
            s->srv->stats.shm_refs++;
        df_sbuf_unref(f);
        df_conn_unref(subs[i]);
    }
    df_stream_enc_variants_clear(&vs);
    df_sbuf_unref(ref);
    if (subs != local) free(subs);
    if (shm != local_shm) free(shm);
}

int df_session_history_commit(df_session *s, df_error *err)
{
    return df_session_history_commit_recipe(s, NULL, 0, err);
}

/* Undo steps come before resync rings when the memory budget is short: makes room for a step
 * (at most one full state) out of the rings first. */
static void history_room(df_session *s)
{
    uint64_t per = (uint64_t)s->srv->cfg.history_max_mb << 20;
    uint64_t room = df_mem_room(df_server_mem(s->srv), DF_MEM_HISTORY) + s->hist_charged;
    uint64_t step = 3 * (uint64_t)s->nv * sizeof(double);
    uint64_t free_room = room - s->hist_charged; /* room counts what the history holds */
    if (room < per && free_room < step) {
        uint64_t want = step - free_room;
        reclaim_resync(s->srv, per - room < want ? per - room : want);
    }
}

int df_session_history_commit_recipe(df_session *s, const uint8_t *blob, size_t len,
                                     df_error *err)
{
    history_room(s);
    uint64_t d0 = s->hist.dropped;
    df_history_set_max_bytes(&s->hist, history_budget(s));
    int rc = df_history_commit_recipe(&s->hist, s->cur, blob, len, err);
    s->srv->history_dropped += s->hist.dropped - d0;
    history_recharge(s);
    return rc;
}

int df_session_history_install(df_session *s, df_history_plan *plan, df_error *err)
{
    history_room(s);
    uint64_t d0 = s->hist.dropped;
    int rc = df_history_install(&s->hist, plan, s->cur, err);
    if (rc == DF_OK) df_history_set_max_bytes(&s->hist, history_budget(s));
    s->srv->history_dropped += s->hist.dropped - d0;
    history_recharge(s);
    return rc;
}

void df_session_history_repair(df_session *s, const df_history_plan *plan)
{
    uint64_t d0 = s->hist.dropped;
    int n = df_history_repair(&s->hist, plan);
    if (!n && !plan->mismatch) return;
    df_log(DF_LOG_ERROR, "session %llu: undo history: a recorded stroke no longer replays to "
           "the state it recorded; %d unreachable step(s) dropped",
           (unsigned long long)s->id, n);
    s->srv->history_dropped += s->hist.dropped - d0;
    history_recharge(s);
}

void df_session_resync_record(df_session *s, uint64_t version, const df_frames *frames)
{
    df_membudget *mb = df_server_mem(s->srv);
    uint64_t per = (uint64_t)s->srv->cfg.resync_ring_mb << 20;
    uint64_t room = df_mem_room(mb, DF_MEM_RESYNC) + s->resync_charged;
    df_error err;
    if (df_resync_push(&s->resync, version, frames->v, frames->n, per < room ? per : room,
                       &err) != DF_OK)
        df_log(DF_LOG_WARN, "session %llu: %s (a resync from before gets a snapshot)",
               (unsigned long long)s->id, err.msg);
    df_mem_adjust(mb, DF_MEM_RESYNC, s->resync_charged, s->resync.bytes);
    s->resync_charged = s->resync.bytes;
}

int df_session_history_reset(df_session *s, df_error *err)
{
    (void)err;
    /* in place (allocates nothing, so it cannot fail): the rest shape may just have changed
     * under the anchor packed against it (reset-rest, restore) and must not be read again */
    df_history_reset(&s->hist, s->cur); /* counters survive */
    history_set_replay(s);
    df_history_set_max_bytes(&s->hist, history_budget(s));
    history_recharge(s);
    return DF_OK;
}

df_stroke *df_session_stroke(df_session *s, uint64_t conn_id)
{
    for (df_stroke *st = s->strokes; st; st = st->next)
        if (st->conn_id == conn_id) return st;
    return NULL;
}

void df_session_drop_stroke(df_session *s, uint64_t conn_id)
{
    for (df_stroke **pp = &s->strokes; *pp; pp = &(*pp)->next)
        if ((*pp)->conn_id == conn_id) {
            df_stroke *st = *pp;
            *pp = st->next;
            df_stroke_free(st);
            return;
        }
}

void df_session_seen_sync(df_session *s)
{
    df_session_seen *v = &s->seen;
    v->handles = s->hs ? s->hs->nh : 0;
    v->solver_cached = s->hs && s->hs->solver;
    v->kc_cached = s->kc != NULL;
    v->cache_bytes = (s->hs ? s->hs->solver_bytes : 0) + s->kc_bytes;
    v->brush_last_ms = s->brush_last_ms;
    v->move_last_ms = s->move_last_ms;
    df_admm_get_active_stats(s->hs ? s->hs->solver : NULL, &v->act);
}

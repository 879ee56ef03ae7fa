/* h_stats.c — the stats request: daemon-wide or per-session counters (see handlers.h).
 * Keys are PROTOCOL.md's names (frames_in, cache.admm_chol.hits, version, nv, ...), one per value. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/handlers/handlers.h"
#include "server/exec/pool.h"
#include "server/net/reply.h"
#include "server/net/shm.h"
#include "server/session/access.h"

#define DF_STATS_MAX 128 /* entries this server reports (a device's: h_devices.c) */

static void put(df_msg_stats *st, const char *key, double v)
{
    if (st->count >= DF_STATS_MAX) return;
    snprintf(st->items[st->count].key, sizeof st->items[st->count].key, "%s", key);
    st->items[st->count].value = v;
    st->count++;
}

int df_h_stats(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_stats_req m;
    int rc = df_msg_stats_req_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_server *srv = r->srv;
    if (m.session_id & DF_DEVICE_ID_BIT) return df_h_device_stats(r, m.session_id, err);
    df_session *s = NULL;
    if (m.session_id && !(s = df_session_find(srv, m.session_id)))
        return df_error_set(err, DF_ENOTFOUND, "stats: no session %llu",
                            (unsigned long long)m.session_id);
    if (s && (rc = df_access_require(r, s, DF_RIGHT_OBSERVE, err)) != DF_OK)
        return rc; /* a session that admits no observers shows its counters to members only */
    df_msg_stat items[DF_STATS_MAX];
    df_msg_stats st = {0, items};
    const df_stats *x = &srv->stats;
    if (!s) {
        put(&st, "uptime_s", (double)(uv_hrtime() - x->start_ns) / 1e9);
        put(&st, "sessions", srv->n_sessions);
        put(&st, "clients", srv->n_conns);
        put(&st, "clients_total", (double)x->clients_total);
        put(&st, "clients_dropped", (double)x->clients_dropped);
        put(&st, "clients_refused", (double)x->clients_refused);
        put(&st, "clients_refused_fds", (double)x->clients_refused_fds);
        put(&st, "clients_handshake_timeout", (double)x->clients_handshake_timeout);
        put(&st, "clients_idle_timeout", (double)x->clients_idle_timeout);
        put(&st, "clients_refused_peer", (double)x->clients_refused_peer);
        put(&st, "auth_ok", (double)x->auth_ok);
        put(&st, "auth_failed", (double)x->auth_failed);
        put(&st, "auth_limited", (double)x->auth_limited);
        put(&st, "join_ok", (double)x->join_ok);
        put(&st, "join_failed", (double)x->join_failed);
        put(&st, "join_limited", (double)x->join_limited);
        put(&st, "frames_in", (double)x->frames_in);
        put(&st, "frames_out", (double)x->frames_out);
        put(&st, "bytes_in", (double)x->bytes_in);
        put(&st, "bytes_out", (double)x->bytes_out);
        put(&st, "writes_blocked", (double)x->writes_blocked);
        put(&st, "fanout_resumed", (double)x->fanout_resumed);
        put(&st, "shm_frames", (double)x->shm_frames);
        put(&st, "shm_refs", (double)x->shm_refs);
        put(&st, "requests_ok", (double)x->requests_ok);
        put(&st, "requests_failed", (double)x->requests_failed);
        put(&st, "requests_double_answer", (double)x->requests_double_answer);
        put(&st, "jobs_submitted", (double)x->jobs_submitted);
        put(&st, "jobs_completed", (double)x->jobs_completed);
        put(&st, "jobs_running", srv->jobs_running);
        put(&st, "jobs_superseded", (double)x->jobs_superseded);
        put(&st, "jobs_inline", (double)x->jobs_inline);
        put(&st, "jobs_inline_deferred", (double)x->jobs_inline_deferred);
        put(&st, "jobs_beside_move", (double)x->jobs_beside_move);
        put(&st, "moves_preempted", (double)x->moves_preempted);
        put(&st, "moves_orphaned", (double)x->moves_orphaned);
        put(&st, "inline_us", srv->cfg.inline_us);
        put(&st, "versions", (double)x->versions);
        put(&st, "resync_replays", (double)x->resync_replays);
        put(&st, "resync_snapshots", (double)x->resync_snapshots);
        put(&st, "resync_ring_bytes", (double)df_server_mem(srv)->used[DF_MEM_RESYNC]);
        put(&st, "resync.limit_bytes", (double)((uint64_t)srv->cfg.resync_ring_mb << 20));
        put(&st, "brush_state_changes", (double)x->brush_state_changes);
        put(&st, "store_changes", (double)x->store_changes);
        put(&st, "store_log_bytes", (double)x->store_log_bytes);
        put(&st, "store_errors", (double)x->store_errors);
        put(&st, "store_recipe_records", (double)x->store_recipe_records);
        put(&st, "store_recipes_replayed", (double)x->store_recipes_replayed);
        put(&st, "store_recipes_skipped", (double)x->store_recipes_skipped);
        put(&st, "store_replay_mismatches", (double)x->store_replay_mismatches);
        put(&st, "brush_cursor_events", (double)x->brush_cursor_events);
        put(&st, "cursor_hz", srv->cfg.cursor_hz);
        put(&st, "shm_ring_bytes", (double)srv->cfg.shm_ring_bytes);
        put(&st, "cache.bytes", (double)srv->cache_bytes);
        put(&st, "cache.limit_bytes", (double)(srv->cfg.cache_memory_mb << 20));
        put(&st, "cache.kelvinlet_lu.hits", (double)x->kelvin_lu_hits);
        put(&st, "cache.kelvinlet_lu.misses", (double)x->kelvin_lu_misses);
        put(&st, "cache.admm_chol.hits", (double)x->admm_hits);
        put(&st, "cache.admm_chol.misses", (double)x->admm_misses);
        put(&st, "cache.lru_evictions", (double)x->lru_evictions);
        const df_membudget *mb = df_server_mem(srv); /* membudget.h */
        int uploads = 0;
        for (df_conn *k = srv->conns; k; k = k->next) uploads += k->upload != NULL;
        put(&st, "memory_used_bytes", (double)df_mem_used(mb));
        put(&st, "memory_max_bytes", (double)mb->max);
        put(&st, "memory_refused", (double)mb->refused);
        put(&st, "memory.uploads_bytes", (double)mb->used[DF_MEM_UPLOADS]);
        put(&st, "memory.sessions_bytes", (double)mb->used[DF_MEM_SESSIONS]);
        put(&st, "memory.shm_bytes", (double)mb->used[DF_MEM_SHM]);
        put(&st, "memory.history_bytes", (double)mb->used[DF_MEM_HISTORY]);
        put(&st, "memory.resync_bytes", (double)mb->used[DF_MEM_RESYNC]);
        put(&st, "memory.stream_bytes", (double)mb->used[DF_MEM_STREAM]);
        put(&st, "uploads_in_flight", uploads);
        put(&st, "uploads_max_bytes", (double)((uint64_t)srv->cfg.uploads_max_mb << 20));
        put(&st, "max_upload_bytes", (double)((uint64_t)srv->cfg.max_upload_mb << 20));
        put(&st, "shm_total_bytes", (double)srv->cfg.shm_total_bytes);
        put(&st, "history.limit_bytes", (double)((uint64_t)srv->cfg.history_max_mb << 20));
        put(&st, "history.steps_dropped", (double)srv->history_dropped);
        uint32_t ndev = 0, nopen = 0;
        uint64_t hid_events = 0;
        if (srv->hid_ops) srv->hid_ops->counts(srv, &ndev, &nopen, &hid_events);
        put(&st, "hid.devices", ndev);
        put(&st, "hid.devices_open", nopen);
        put(&st, "hid.events", (double)hid_events);
        if (srv->pool) { /* compute pool hand-offs (pool.h) */
            df_pool_counters pc;
            df_pool_counters_get(srv->pool, &pc);
            put(&st, "pool.threads", srv->cfg.threads);
            put(&st, "pool.spin_us", srv->cfg.spin_us);
            put(&st, "pool.tasks", (double)pc.tasks);
            put(&st, "pool.spin_hits", (double)pc.spin_hits);
            put(&st, "pool.wakeups", (double)pc.wakeups);
            put(&st, "pool.long_lane", pc.heavy_max);
            put(&st, "pool.long_waits", (double)pc.heavy_waits);
        }
        /* per client: output rate over the last second, versions coalesced (stream_lag.h) */
        put(&st, "stream_coalesced_versions", (double)x->stream_coalesced);
        for (df_conn *k = srv->conns; k; k = k->next) {
            if (!k->hello_done || k->closing) continue;
            char key[DF_MAX_STATS_KEY_LEN + 1];
            snprintf(key, sizeof key, "client.%llu.bytes_per_s", (unsigned long long)k->id);
            put(&st, key, k->bytes_per_s);
            snprintf(key, sizeof key, "client.%llu.coalesced", (unsigned long long)k->id);
            put(&st, key, (double)k->coalesced);
        }
    } else {
        int strokes = 0;
        for (df_stroke *k = s->strokes; k; k = k->next) strokes++;
        put(&st, "version", (double)atomic_load(&s->version));
        put(&st, "nv", s->nv);
        put(&st, "ne", s->mesh.ne);
        put(&st, "subscribers", s->nsubs);
        put(&st, "shm_subscribers", s->nshm);
        put(&st, "shm.ring_bytes", s->shm ? (double)s->shm->capacity : 0);
        put(&st, "undo_depth", df_history_can_undo(&s->hist));
        put(&st, "redo_depth", df_history_can_redo(&s->hist));
        put(&st, "history_bytes", (double)df_history_bytes(&s->hist));
        put(&st, "history_steps_dropped", (double)s->hist.dropped);
        put(&st, "history_undo_bytes", (double)df_history_undo_bytes(&s->hist));
        put(&st, "history_recipe_steps", df_history_steps_of(&s->hist, DF_HISTORY_RECIPE));
        put(&st, "history_xor_steps", df_history_steps_of(&s->hist, DF_HISTORY_XOR));
        put(&st, "history_checkpoints", s->hist.nck);
        size_t anchor_bytes;
        df_history_parts(&s->hist, &anchor_bytes, NULL, NULL);
        put(&st, "history_anchor_bytes", (double)anchor_bytes);
        put(&st, "history_replays", (double)s->hist.replays);
        put(&st, "history_replay_mismatches", (double)s->hist.mismatches);
        put(&st, "memory_bytes", (double)(s->mem_bytes + s->hist_charged + s->shm_charged +
                                          s->resync_charged));
        put(&st, "resync_ring_bytes", (double)s->resync.bytes);
        put(&st, "resync_versions", (double)s->resync.count);
        /* the oldest from_version a resync replays (current version when nothing is kept) */
        put(&st, "resync_from", (double)(s->resync.count ? df_resync_first(&s->resync) - 1
                                                          : atomic_load(&s->version)));
        /* degenerate elements: 1 = excluded from the solver's energies (admm.h) */
        put(&st, "degenerate_elements", s->degen.elements);
        put(&st, "degenerate_action", s->degen.elements > 0);
        put(&st, "degenerate_followers", s->degen.followers);
        put(&st, "degenerate_at_rest", s->degen.at_rest);
        put(&st, "open_strokes", strokes);
        put(&st, "brush.seq", (double)s->brush_seq);
        put(&st, "job_running", s->running != NULL);
        /* A worker may be writing the compute state: read the loop-owned copies (session.h). */
        if (!s->running) df_session_seen_sync(s);
        const df_session_seen *v = &s->seen;
        put(&st, "handles", v->handles);
        put(&st, "cache.admm_chol.cached", v->solver_cached);
        put(&st, "cache.kelvinlet_lu.cached", v->kc_cached);
        put(&st, "cache.bytes", (double)v->cache_bytes);
        put(&st, "brush.last_ms", v->brush_last_ms);
        put(&st, "move.last_ms", v->move_last_ms);
        /* active-set mode (config admm_active, admm.h DF_ADMM_ACTIVE) of the cached solver */
        put(&st, "admm.active", srv->cfg.admm_active);
        put(&st, "admm.active_runs", (double)v->act.runs);
        put(&st, "admm.active_fallbacks", (double)v->act.fallbacks);
        put(&st, "admm.active_region_vertices", v->act.region_vertices);
        put(&st, "admm.active_region_elements", v->act.region_elements);
        put(&st, "admm.active_support", v->act.support);
        put(&st, "admm.active_region_grows", (double)v->act.grows);
        put(&st, "admm.active_check_grows", (double)v->act.check_grows);
        put(&st, "admm.active_tail_grows", (double)v->act.tail_grows);
    }
    df_req_reply_stats(r, &st);
    return DF_OK;
}

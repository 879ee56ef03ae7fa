/* cache.c — LRU memory cap on cached factorizations (see cache.h). */
#include "server/session/cache.h"

#include "server/log.h"

size_t df_cache_estimate_admm(int32_t nv, int32_t ne)
{
    return (size_t)(nv > 0 ? nv : 0) * DF_CACHE_ADMM_BYTES_PER_VERTEX +
           (size_t)(ne > 0 ? ne : 0) * DF_CACHE_ADMM_BYTES_PER_ELEMENT;
}

size_t df_cache_estimate_kelvinlet(uint32_t n_pins)
{
    size_t k = 12 * (size_t)n_pins;
    return 2 * k * k * sizeof(double) + 4096;
}

void df_cache_install_solver(df_server *srv, df_handleset *hs, size_t bytes)
{
    srv->cache_bytes += bytes;
    hs->solver_bytes = bytes;
    hs->lru = ++srv->lru_clock;
}

void df_cache_install_kelvinlet(df_server *srv, df_session *s, size_t bytes)
{
    srv->cache_bytes += bytes;
    s->kc_bytes = bytes;
    s->kc_lru = ++srv->lru_clock;
}

void df_cache_touch_solver(df_server *srv, df_handleset *hs) { hs->lru = ++srv->lru_clock; }

void df_cache_touch_kelvinlet(df_server *srv, df_session *s) { s->kc_lru = ++srv->lru_clock; }

void df_cache_drop_solver(df_server *srv, df_handleset *hs)
{
    if (!hs || !hs->solver) return;
    df_admm_free(hs->solver);
    hs->solver = NULL;
    srv->cache_bytes -= hs->solver_bytes <= srv->cache_bytes ? hs->solver_bytes : srv->cache_bytes;
    hs->solver_bytes = 0;
}

void df_cache_drop_kelvinlet(df_server *srv, df_session *s)
{
    if (!s->kc) return;
    df_kelvinlet_constraints_free(s->kc);
    s->kc = NULL;
    srv->cache_bytes -= s->kc_bytes <= srv->cache_bytes ? s->kc_bytes : srv->cache_bytes;
    s->kc_bytes = 0;
}

int df_cache_enforce(df_server *srv)
{
    size_t cap = srv->cfg.cache_memory_mb << 20;
    int evicted = 0;
    while (srv->cache_bytes > cap) {
        df_session *best = NULL;
        int best_is_solver = 0;
        uint64_t best_lru = UINT64_MAX;
        for (df_session *s = srv->sessions; s; s = s->next) {
            if (s->running) continue;
            if (s->hs && s->hs->solver && s->hs->lru < best_lru) {
                best = s;
                best_is_solver = 1;
                best_lru = s->hs->lru;
            }
            if (s->kc && s->kc_lru < best_lru) {
                best = s;
                best_is_solver = 0;
                best_lru = s->kc_lru;
            }
        }
        if (!best) break;
        df_log(DF_LOG_INFO, "cache over %zu MiB: evicting session %llu's %s", srv->cfg.cache_memory_mb,
               (unsigned long long)best->id, best_is_solver ? "ADMM factorization" : "Kelvinlet LU");
        if (best_is_solver) df_cache_drop_solver(srv, best->hs);
        else df_cache_drop_kelvinlet(srv, best);
        srv->stats.lru_evictions++;
        evicted++;
    }
    return evicted;
}

/* cache.h — the memory cap on cached factorizations (loop thread).
 *
 * Cached objects: each session's ADMM solver (its CHOLMOD factorization, df_handleset.solver) and
 * its Kelvinlet pinned-point solver (the LU of K_pp, df_session.kc). Their sizes are estimates
 * (df_cache_estimate_*), charged to srv->cache_bytes when installed. When the total exceeds
 * cfg.cache_memory_mb, the least recently used objects of idle sessions (no running job) are freed
 * (stats: lru_evictions); the next request that needs one rebuilds it (a cache miss). */
#ifndef DF_SERVER_CACHE_H
#define DF_SERVER_CACHE_H

#include <stddef.h>
#include <stdint.h>

#include "server/session/session.h"

#define DF_CACHE_ADMM_BYTES_PER_VERTEX 2048  /* factor + operators + ADMM state, per vertex */
#define DF_CACHE_ADMM_BYTES_PER_ELEMENT 512  /* per-element operators, rotations, duals */

/* Estimated bytes of an ADMM solver on nv vertices and ne elements. */
size_t df_cache_estimate_admm(int32_t nv, int32_t ne);

/* Estimated bytes of a Kelvinlet constraint solver with n pins (K_pp and its LU, up to 12n
 * unknowns). */
size_t df_cache_estimate_kelvinlet(uint32_t n_pins);

/* Charges `bytes` for the object just installed / used and stamps its LRU clock. */
void df_cache_install_solver(df_server *srv, df_handleset *hs, size_t bytes);
void df_cache_install_kelvinlet(df_server *srv, df_session *s, size_t bytes);

/* Marks an object used now (LRU). */
void df_cache_touch_solver(df_server *srv, df_handleset *hs);
void df_cache_touch_kelvinlet(df_server *srv, df_session *s);

/* Frees a cached object and uncharges it (no-op when absent). */
void df_cache_drop_solver(df_server *srv, df_handleset *hs);
void df_cache_drop_kelvinlet(df_server *srv, df_session *s);

/* Evicts least recently used objects of idle sessions until the total is within the cap (or
 * nothing evictable remains). Returns the number evicted. */
int df_cache_enforce(df_server *srv);

#endif

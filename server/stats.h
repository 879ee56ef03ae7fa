/* stats.h — counters reported by the stats request (loop thread only). */
#ifndef DF_SERVER_STATS_H
#define DF_SERVER_STATS_H

#include <stdint.h>

typedef struct df_stats {
    uint64_t start_ns;            /* uv_hrtime() at start */
    uint64_t clients_total;       /* connections accepted */
    uint64_t clients_dropped;     /* dropped for backpressure or framing errors */
    uint64_t clients_refused;     /* refused at max_clients */
    uint64_t clients_refused_fds; /* refused: out of file descriptors (guard.h) */
    uint64_t clients_handshake_timeout; /* closed: no HELLO within handshake_timeout_s */
    uint64_t clients_idle_timeout;/* closed: silent for idle_timeout_s (guard.h) */
    uint64_t clients_refused_peer;/* Unix peers refused by allow_uids / allow_gids (peer.h) */
    uint64_t auth_ok, auth_failed;/* TCP key authentications that succeeded / failed (auth.h) */
    uint64_t auth_limited;        /* AUTH requests refused by the failure rate limit */
    uint64_t join_ok, join_failed;/* JOINs that made a member / had a wrong key (h_access.c) */
    uint64_t join_limited;        /* JOINs refused by the wrong-key rate limit */
    uint64_t frames_in, bytes_in;
    uint64_t frames_out, bytes_out;
    uint64_t writes_blocked;      /* writes a full socket left to uv_write (a slow reader) */
    uint64_t fanout_resumed;      /* subscriber-write passes continued after a slice (conn.h) */
    uint64_t requests_ok, requests_failed;
    uint64_t requests_double_answer; /* answers to an already answered request (req.h; a bug) */
    uint64_t jobs_submitted, jobs_completed, jobs_superseded;
    uint64_t jobs_inline;         /* jobs whose work ran on the loop thread (job.h) */
    uint64_t jobs_inline_deferred;/* cheap enough, sent to the pool: iteration budget spent */
    uint64_t jobs_beside_move;    /* reads answered (undo/redo refused) while a move ran (job.h) */
    uint64_t moves_preempted;     /* moves ended early for a request queued behind them */
    uint64_t moves_orphaned;      /* moves ended because their requester disconnected */
    uint64_t versions;            /* versions broadcast, all sessions */
    uint64_t stream_coalesced;    /* versions folded into coalesced ones (stream_lag.h) */
    uint64_t resync_replays;      /* FROM_VERSION subscribes answered from the resync ring */
    uint64_t resync_snapshots;    /* ... answered with a snapshot (too old, ahead, not kept) */
    uint64_t shm_frames;          /* broadcast frames copied into a shared-memory ring */
    uint64_t shm_refs;            /* SHM_REF events queued in their place */
    uint64_t kelvin_lu_hits, kelvin_lu_misses;
    uint64_t admm_hits, admm_misses;
    uint64_t lru_evictions;
    uint64_t brush_state_changes; /* session brush changes, all sessions (brush_state.h) */
    uint64_t store_changes;      /* change-log rows written to the durable store (journal.h) */
    uint64_t store_log_bytes;    /* their blob bytes (position deltas, handle sets, brushes) */
    uint64_t store_errors;       /* store writes that failed (the request failed with them) */
    uint64_t store_recipe_records; /* of store_changes: rows with a stroke recipe (journal.h) */
    uint64_t store_recipes_replayed; /* restore: recipe records replayed and verified ... */
    uint64_t store_recipes_skipped;  /* ... and not replayed (superseded, restore.h) */
    uint64_t store_replay_mismatches; /* restore: sessions stopped at a recipe whose replay did
                                       * not reproduce its checksum (restore.h) */
    uint64_t brush_cursor_events; /* BRUSH_CURSOR events broadcast (after rate limiting) */
} df_stats;

#endif

/* membudget.h — deformd's memory accounting (pure bookkeeping, no I/O; loop thread only).
 *
 * Everything the daemon allocates on a client's behalf is charged here before it is allocated,
 * by kind: in-flight upload buffers, sessions (mesh, positions and scratch, estimated by
 * df_session_estimate_bytes), shared-memory rings, undo history, resync rings, and the stream
 * encodings' per-group quantized arrays and lagging subscribers' accumulators. A charge that would take
 * the total above `max` (config memory_max_mb), or its kind above the kind's own cap (uploads:
 * uploads_max_mb, rings: shm_total_bytes), is refused with DF_ELIMIT and a message naming the
 * limit and its config key; nothing is charged then (session.h df_session_mem_charge first lets
 * idle sessions' old undo steps give way). Cached factorizations are not charged here:
 * they have their own evicting cap (cache_memory_mb, cache.h). */
#ifndef DF_SERVER_MEMBUDGET_H
#define DF_SERVER_MEMBUDGET_H

#include <stdint.h>

#include "core/common/df_error.h"

typedef enum df_mem_kind {
    DF_MEM_UPLOADS = 0, /* buffers of chunked LOAD_MESH uploads in progress */
    DF_MEM_SESSIONS,    /* sessions: mesh, positions, scratch (estimate) */
    DF_MEM_SHM,         /* shared-memory stream rings (/dev/shm is RAM) */
    DF_MEM_HISTORY,     /* undo/redo history */
    DF_MEM_RESYNC,      /* resync rings of recently broadcast frames (resync.h) */
    DF_MEM_STREAM,      /* quantized stream groups and coalescing state (stream_enc.h,
                         * stream_lag.h) */
    DF_MEM_KINDS
} df_mem_kind;

typedef struct df_membudget {
    uint64_t max;                     /* total cap, bytes (0 = nothing may be charged) */
    uint64_t kind_max[DF_MEM_KINDS];  /* per-kind cap, bytes; UINT64_MAX = none */
    uint64_t used[DF_MEM_KINDS];      /* bytes charged now */
    uint64_t refused;                 /* charges refused (DF_ELIMIT) */
} df_membudget;

/* Sets the caps and zeroes the counters. `uploads_max` / `shm_max` are the per-kind caps of
 * DF_MEM_UPLOADS / DF_MEM_SHM (UINT64_MAX = none). Never fails. */
void df_mem_init(df_membudget *b, uint64_t max, uint64_t uploads_max, uint64_t shm_max);

/* Sets the caps like df_mem_init, keeping the counters. */
void df_mem_set_limits(df_membudget *b, uint64_t max, uint64_t uploads_max, uint64_t shm_max);

/* Bytes charged in total. */
uint64_t df_mem_used(const df_membudget *b);

/* Bytes that may still be charged to `kind` (the smaller of the total's and the kind's room). */
uint64_t df_mem_room(const df_membudget *b, df_mem_kind kind);

/* Charges `bytes` to `kind` when both the kind's cap and the total allow it. `what` prefixes the
 * message ("load_mesh", "stream_shm", ...). Errors: DF_ELIMIT (message names the limit, its
 * config key and the bytes in use; b->refused counts it), DF_EINVAL (bad kind); nothing charged. */
int df_mem_charge(df_membudget *b, df_mem_kind kind, uint64_t bytes, const char *what,
                  df_error *err);

/* Returns `bytes` of `kind` (clamped at what is charged). */
void df_mem_release(df_membudget *b, df_mem_kind kind, uint64_t bytes);

/* Replaces a holder's charge of `old_bytes` by `new_bytes` without checking the caps: for a
 * holder that bounds itself against df_mem_room (the undo history drops its oldest steps). */
void df_mem_adjust(df_membudget *b, df_mem_kind kind, uint64_t old_bytes, uint64_t new_bytes);

/* Physical memory of the machine in bytes (sysconf), or 0 when unknown. */
uint64_t df_mem_physical_bytes(void);

#endif

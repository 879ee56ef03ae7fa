/* work_progress.h — WORK_PROGRESS events (PROTOCOL.md 4.37) of one request that asked for them:
 * the stage, done/total and time since the stage began, sent to the requester only, rate-limited
 * to one event per DF_WORK_PROGRESS_GAP_MS per request (the last event of each stage, `final`,
 * is always sent), and never after the request's reply:
 *  - reports made on a worker thread (parse, factorize, solve: the job's work) are posted through
 *    the pool's completion channel (df_pool_post), which delivers them on the loop thread before
 *    the job's own completion, so before its reply;
 *  - reports made on the loop thread (upload chunks, before the job exists) are sent at once.
 * The requester's connection must stay referenced while reports may be made (the job's
 * reference, or the upload's, does). A reporter that was not asked for (df_work_init with on 0)
 * does nothing. One reporter is used by one thread at a time. */
#ifndef DF_SERVER_WORK_PROGRESS_H
#define DF_SERVER_WORK_PROGRESS_H

#include <stdint.h>

#include "server/server.h"

#define DF_WORK_PROGRESS_GAP_MS 50 /* at most 20 events per second per request */

typedef struct df_work {
    df_server *srv;
    df_conn *c;            /* the requester; NULL: reporting is off */
    uint64_t req_id;       /* the request reported on (the events' request id) */
    uint64_t session_id;   /* carried by the events; 0 while a load has no session */
    uint8_t stage;         /* stage of the last report, 0 before the first */
    int stage_final_sent;  /* the current stage's final event went out */
    uint64_t stage_t0;     /* uv_hrtime() when the current stage began */
    uint64_t last_sent;    /* uv_hrtime() of the last event sent, 0 none */
} df_work;

/* Sets up `w` for request `req_id` of connection `c` about session `session_id` (0: none yet).
 * on 0 (the client did not ask) or c NULL: every report is ignored. Any thread. */
void df_work_init(df_work *w, df_server *srv, df_conn *c, uint64_t req_id, uint64_t session_id,
                  int on);

/* Reports that stage `stage` (DF_STAGE_*) has `done` of `total` units done (total 0: unknown;
 * done is clamped to total). A new stage starts its clock. The event is sent when `final` is 1
 * (once per stage: later reports of a finished stage are ignored) or when at least
 * DF_WORK_PROGRESS_GAP_MS passed since the last event of this request; otherwise it is dropped.
 * `on_worker` 1: called from the job's work on a pool worker (posted, see above); 0: on the
 * loop thread (sent now). Out of memory drops the event (logged at debug level). */
void df_work_report(df_work *w, uint8_t stage, uint64_t done, uint64_t total, int final,
                    int on_worker);

#endif

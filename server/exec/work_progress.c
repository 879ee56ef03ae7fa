/* work_progress.c — rate-limited WORK_PROGRESS events of one request (see work_progress.h). */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <uv.h>

#include "server/exec/pool.h"
#include "server/exec/work_progress.h"
#include "server/log.h"
#include "server/net/conn.h"
#include "server/net/reply.h"

typedef struct wp_msg {
    df_task t;               /* first: the pool hands back &t */
    df_conn *c;
    uint64_t req_id;
    df_msg_work_progress m;
} wp_msg;

void df_work_init(df_work *w, df_server *srv, df_conn *c, uint64_t req_id, uint64_t session_id,
                  int on)
{
    memset(w, 0, sizeof *w);
    w->srv = srv;
    w->c = on ? c : NULL;
    w->req_id = req_id;
    w->session_id = session_id;
}

static void send_now(df_conn *c, uint64_t req_id, const df_msg_work_progress *m)
{
    df_error err;
    df_sbuf *f = df_out_work_progress(DF_MSG_WORK_PROGRESS, DF_FLAG_EVENT, req_id, m, &err);
    if (!f) {
        df_log(DF_LOG_DEBUG, "work_progress: event dropped: %s", err.msg);
        return;
    }
    df_conn_send(c, f); /* a closing connection ignores it */
    df_sbuf_unref(f);
}

static void posted(df_task *t)
{
    wp_msg *x = (wp_msg *)t;
    send_now(x->c, x->req_id, &x->m);
    free(x);
}

void df_work_report(df_work *w, uint8_t stage, uint64_t done, uint64_t total, int final,
                    int on_worker)
{
    if (!w->c || stage == 0) return;
    uint64_t now = uv_hrtime();
    if (stage != w->stage) {
        w->stage = stage;
        w->stage_t0 = now;
        w->stage_final_sent = 0;
    } else if (w->stage_final_sent) {
        return;
    }
    if (!final && w->last_sent && now - w->last_sent < DF_WORK_PROGRESS_GAP_MS * 1000000ull)
        return;
    df_msg_work_progress m;
    memset(&m, 0, sizeof m);
    m.session_id = w->session_id;
    m.stage = stage;
    m.final = final ? 1 : 0;
    m.total = total;
    m.done = total && done > total ? total : done;
    m.elapsed_ms = (double)(now - w->stage_t0) / 1e6;
    w->last_sent = now;
    if (final) w->stage_final_sent = 1;
    if (!on_worker || !w->srv->pool) {
        send_now(w->c, w->req_id, &m);
        return;
    }
    wp_msg *x = calloc(1, sizeof *x);
    if (!x) {
        df_log(DF_LOG_DEBUG, "work_progress: out of memory, event dropped");
        return;
    }
    x->t.after = posted;
    x->c = w->c;
    x->req_id = w->req_id;
    x->m = m;
    df_pool_post(w->srv->pool, &x->t);
}

/* h_peers.c — SESSION_PEERS: who is connected to a session (PROTOCOL.md 4.38; handlers.h).
 *
 * A session job without work (observe right, checked by df_job_request): it runs on the loop
 * thread when it reaches the head of the session's FIFO, so a SESSION_PEERS sent after a
 * SUBSCRIBE on the same connection lists that subscription; while a handle move runs it is
 * answered beside it (DF_JOB_BESIDE_READ: the subscriber list is no mesh state). Rows: the
 * session's subscribers in subscription order, at most DF_MAX_PEERS (the asking connection's
 * row always among them when it is subscribed). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/handlers/handlers.h"
#include "server/net/conn.h"
#include "server/session/access.h"

/* Fills row `out` for subscriber i of s, seen by connection `asker` (may be NULL). */
static void peer_row(const df_session *s, int i, const df_conn *asker, df_msg_peer_info *out)
{
    const df_conn *c = s->subs[i];
    memset(out, 0, sizeof *out);
    out->client_id = c->id;
    out->transport = c->is_tcp ? DF_TRANSPORT_TCP : DF_TRANSPORT_UNIX;
    if (c == asker) out->flags |= DF_PEER_SELF;
    if (df_access_rights(c, s) & DF_RIGHT_EDIT) out->flags |= DF_PEER_EDIT;
    if (s->sub_shm[i]) out->flags |= DF_PEER_SHM;
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->principal, sizeof out->principal, "%s", c->principal);
}

int df_session_peers_fill(const df_session *s, const df_conn *asker, uint32_t cap,
                          df_msg_peer_list *out, df_error *err)
{
    uint32_t n = (uint32_t)s->nsubs > cap ? cap : (uint32_t)s->nsubs;
    df_msg_peer_info *items = n ? calloc(n, sizeof *items) : NULL;
    if (n && !items)
        return df_error_set(err, DF_ENOMEM, "session_peers: out of memory listing %u peers",
                            (unsigned)n);
    uint32_t k = 0;
    int self = -1; /* the asker's index when it falls beyond the cap */
    for (int i = 0; i < s->nsubs; i++) {
        if (k < n) peer_row(s, i, asker, &items[k++]);
        else if (s->subs[i] == asker) self = i;
    }
    if (self >= 0 && n) peer_row(s, self, asker, &items[n - 1]); /* keep the asker's own row */
    out->count = n;
    out->items = items;
    return DF_OK;
}

static void peers_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_msg_peer_list out;
    df_error err;
    if (df_session_peers_fill(j->s, j->req.c, DF_MAX_PEERS, &out, &err) != DF_OK) {
        df_req_fail(&j->req, &err);
        return;
    }
    df_req_reply_peer_list(&j->req, &out);
    df_msg_peer_list_free(&out);
}

const df_job_kind df_k_session_peers = {.decode = df_job_decode_ref, .done = peers_done,
                                        .beside = DF_JOB_BESIDE_READ};

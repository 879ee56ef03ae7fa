/* msg_peers.c — session peer bodies (SESSION_PEERS reply, PROTOCOL.md 4.38; messages.h).
 * peer_info: u64 client_id, u8 flags, u8 transport, u16 reserved, str name, str principal
 *            (16 + name + principal bytes)
 * peer_list: u32 count, count x peer_info */
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define PEER_MIN_SIZE 16u /* 12 fixed bytes + two empty strings */

static int peer_check(const df_msg_peer_info *m, df_error *err)
{
    if (m->client_id == 0)
        return df_error_set(err, DF_EINVAL, "peer_info: client_id 0 is not a connection");
    if (m->flags & ~DF_PEER_FLAGS_ALL)
        return df_error_set(err, DF_EINVAL, "peer_info: unknown flag bits 0x%x",
                            m->flags & ~DF_PEER_FLAGS_ALL);
    if (m->transport < 1 || m->transport > DF_TRANSPORT_MAX)
        return df_error_set(err, DF_EINVAL, "peer_info: transport %u (1 unix, 2 tcp)",
                            m->transport);
    int rc = df_check_str(m->name, DF_MAX_NAME_LEN, "peer_info", "name", err);
    return rc ? rc : df_check_str(m->principal, DF_MAX_NAME_LEN, "peer_info", "principal", err);
}

static size_t peer_size(const df_msg_peer_info *m)
{
    return 12 + df_str_size(m->name) + df_str_size(m->principal);
}

static void peer_put(df_buf *out, const df_msg_peer_info *m)
{
    df_buf_put_u64(out, m->client_id);
    df_buf_put_u8(out, m->flags);
    df_buf_put_u8(out, m->transport);
    df_buf_put_u16(out, 0);
    df_put_str(out, m->name);
    df_put_str(out, m->principal);
}

static void peer_get(df_rd *r, df_msg_peer_info *t)
{
    t->client_id = df_rd_u64(r, "client_id");
    t->flags = df_rd_u8(r, "flags");
    t->transport = df_rd_u8(r, "transport");
    df_rd_reserved16(r, "reserved");
    df_rd_str(r, t->name, DF_MAX_NAME_LEN, "name");
    df_rd_str(r, t->principal, DF_MAX_NAME_LEN, "principal");
}

int df_msg_peer_info_encode(const df_msg_peer_info *m, df_buf *out, df_error *err)
{
    int rc = peer_check(m, err);
    if (rc || (rc = df_enc_reserve(out, peer_size(m), "peer_info", err)))
        return rc;
    peer_put(out, m);
    return DF_OK;
}

int df_msg_peer_info_decode(const uint8_t *p, size_t n, df_msg_peer_info *m, df_error *err)
{
    df_rd r;
    df_msg_peer_info t;
    df_rd_init(&r, p, n, "peer_info", err);
    peer_get(&r, &t);
    int rc = df_rd_end(&r);
    if (rc || (rc = peer_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* A peer_info in a list (the index is not part of its error text). */
static int item_check(const df_msg_peer_info *m, uint32_t i, df_error *err)
{
    (void)i;
    return peer_check(m, err);
}

DF_LIST_CODEC_DEFINE(peer_list, df_msg_peer_list, df_msg_peer_info, PEER_LIST, "peer_list",
                     "peers", DF_MAX_PEERS, PEER_MIN_SIZE, item_check, peer_size, peer_put,
                     peer_get)

void df_msg_peer_list_free(df_msg_peer_list *m)
{
    if (!m)
        return;
    free(m->items);
    m->items = NULL;
    m->count = 0;
}

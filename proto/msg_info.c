/* msg_info.c — session info and session list bodies (messages.h).
 * session_info: u64 session_id, u64 version, u8 kind, u8 planar, u16 subscribers, u32 nv,
 *               u32 ne, u32 undo_depth, u32 redo_depth, str name   (38 + name bytes)
 * session_list: u32 count, count x session_info */
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define INFO_MIN_SIZE 38u

static int info_check(const df_msg_session_info *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "session_info: session_id 0 is not a session");
    if (m->kind < 1 || m->kind > 3)
        return df_error_set(err, DF_EINVAL, "session_info: mesh kind %u not in 1..3", m->kind);
    if (m->planar > 1)
        return df_error_set(err, DF_EINVAL, "session_info: planar %u not 0/1", m->planar);
    if (m->nv < 1 || m->nv > DF_MAX_MESH_VERTICES)
        return df_error_set(err, DF_ELIMIT, "session_info: nv %u not in 1..%u", m->nv,
                            DF_MAX_MESH_VERTICES);
    if (m->ne > DF_MAX_MESH_ELEMENTS)
        return df_error_set(err, DF_ELIMIT, "session_info: ne %u exceeds %u", m->ne,
                            DF_MAX_MESH_ELEMENTS);
    return df_check_str(m->name, DF_MAX_NAME_LEN, "session_info", "name", err);
}

static size_t info_size(const df_msg_session_info *m)
{
    return 36 + df_str_size(m->name);
}

static void info_put(df_buf *out, const df_msg_session_info *m)
{
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    df_buf_put_u8(out, m->kind);
    df_buf_put_u8(out, m->planar);
    df_buf_put_u16(out, m->subscribers);
    df_buf_put_u32(out, m->nv);
    df_buf_put_u32(out, m->ne);
    df_buf_put_u32(out, m->undo_depth);
    df_buf_put_u32(out, m->redo_depth);
    df_put_str(out, m->name);
}

static void info_get(df_rd *r, df_msg_session_info *t)
{
    t->session_id = df_rd_u64(r, "session_id");
    t->version = df_rd_u64(r, "version");
    t->kind = df_rd_u8(r, "kind");
    t->planar = df_rd_u8(r, "planar");
    t->subscribers = df_rd_u16(r, "subscribers");
    t->nv = df_rd_u32(r, "nv");
    t->ne = df_rd_u32(r, "ne");
    t->undo_depth = df_rd_u32(r, "undo_depth");
    t->redo_depth = df_rd_u32(r, "redo_depth");
    df_rd_str(r, t->name, DF_MAX_NAME_LEN, "name");
}

int df_msg_session_info_encode(const df_msg_session_info *m, df_buf *out, df_error *err)
{
    int rc = info_check(m, err);
    if (rc || (rc = df_enc_reserve(out, info_size(m), "session_info", err)))
        return rc;
    info_put(out, m);
    return DF_OK;
}

int df_msg_session_info_decode(const uint8_t *p, size_t n, df_msg_session_info *m, df_error *err)
{
    df_rd r;
    df_msg_session_info t;
    df_rd_init(&r, p, n, "session_info", err);
    info_get(&r, &t);
    int rc = df_rd_end(&r);
    if (rc || (rc = info_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* A session_info in a list (the index is not part of its error text). */
static int item_check(const df_msg_session_info *m, uint32_t i, df_error *err)
{
    (void)i;
    return info_check(m, err);
}

DF_LIST_CODEC_DEFINE(session_list, df_msg_session_list, df_msg_session_info, SESSION_LIST,
                     "session_list", "sessions", DF_MAX_SESSIONS, INFO_MIN_SIZE, item_check,
                     info_size, info_put, info_get)

void df_msg_session_list_free(df_msg_session_list *m)
{
    if (!m)
        return;
    free(m->items);
    m->items = NULL;
    m->count = 0;
}

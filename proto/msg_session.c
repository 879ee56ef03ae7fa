/* msg_session.c — small session request/reply bodies (messages.h): session_ref, open_session,
 * subscribe, ack, get_mesh, snapshot_req, stats_req. */
#include "proto/codec_util.h"
#include "proto/messages.h"

static int need_session(uint64_t id, const char *msg, df_error *err)
{
    if (id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", msg);
    return DF_OK;
}

/* ---- session_ref: u64 session_id */
int df_msg_session_ref_encode(const df_msg_session_ref *m, df_buf *out, df_error *err)
{
    int rc = need_session(m->session_id, "session_ref", err);
    if (rc || (rc = df_enc_reserve(out, 8, "session_ref", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    return DF_OK;
}

int df_msg_session_ref_decode(const uint8_t *p, size_t n, df_msg_session_ref *m, df_error *err)
{
    df_rd r;
    df_rd_init(&r, p, n, "session_ref", err);
    uint64_t id = df_rd_u64(&r, "session_id");
    int rc = df_rd_end(&r);
    if (rc || (rc = need_session(id, "session_ref", err)))
        return rc;
    m->session_id = id;
    return DF_OK;
}

/* ---- open_session: u64 session_id, str name (non-empty iff session_id == 0) */
static int open_check(const df_msg_open_session *m, df_error *err)
{
    int rc = df_check_str(m->name, DF_MAX_NAME_LEN, "open_session", "name", err);
    if (rc)
        return rc;
    if (m->session_id == 0 && m->name[0] == '\0')
        return df_error_set(err, DF_EINVAL, "open_session: neither session_id nor name given");
    if (m->session_id != 0 && m->name[0] != '\0')
        return df_error_set(err, DF_EINVAL, "open_session: give session_id or name, not both");
    return DF_OK;
}

int df_msg_open_session_encode(const df_msg_open_session *m, df_buf *out, df_error *err)
{
    int rc = open_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 8 + df_str_size(m->name), "open_session", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_put_str(out, m->name);
    return DF_OK;
}

int df_msg_open_session_decode(const uint8_t *p, size_t n, df_msg_open_session *m, df_error *err)
{
    df_rd r;
    df_msg_open_session t;
    df_rd_init(&r, p, n, "open_session", err);
    t.session_id = df_rd_u64(&r, "session_id");
    df_rd_str(&r, t.name, DF_MAX_NAME_LEN, "name");
    int rc = df_rd_end(&r);
    if (rc || (rc = open_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- subscribe: u64 session_id, u32 flags [, u64 from_version iff flags has FROM_VERSION] */
#define SUBSCRIBE_FLAGS ((uint32_t)(DF_SUBSCRIBE_SNAPSHOT | DF_SUBSCRIBE_FROM_VERSION))

static int subscribe_check(const df_msg_subscribe *m, df_error *err)
{
    int rc = need_session(m->session_id, "subscribe", err);
    if (!rc && (m->flags & ~SUBSCRIBE_FLAGS))
        rc = df_error_set(err, DF_EINVAL, "subscribe: unknown flag bits 0x%x",
                          m->flags & ~SUBSCRIBE_FLAGS);
    if (!rc && (m->flags & SUBSCRIBE_FLAGS) == SUBSCRIBE_FLAGS)
        rc = df_error_set(err, DF_EINVAL, "subscribe: flags SNAPSHOT and FROM_VERSION are "
                          "exclusive (FROM_VERSION already sends a snapshot when needed)");
    if (!rc && !(m->flags & DF_SUBSCRIBE_FROM_VERSION) && m->from_version)
        rc = df_error_set(err, DF_EINVAL, "subscribe: from_version %llu without flag "
                          "FROM_VERSION", (unsigned long long)m->from_version);
    return rc;
}

int df_msg_subscribe_encode(const df_msg_subscribe *m, df_buf *out, df_error *err)
{
    int rc = subscribe_check(m, err);
    int from = (m->flags & DF_SUBSCRIBE_FROM_VERSION) != 0;
    if (rc || (rc = df_enc_reserve(out, from ? 20 : 12, "subscribe", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u32(out, m->flags);
    if (from) df_buf_put_u64(out, m->from_version);
    return DF_OK;
}

int df_msg_subscribe_decode(const uint8_t *p, size_t n, df_msg_subscribe *m, df_error *err)
{
    df_rd r;
    df_msg_subscribe t;
    df_rd_init(&r, p, n, "subscribe", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.flags = df_rd_u32(&r, "flags");
    t.from_version = r.rc == DF_OK && (t.flags & DF_SUBSCRIBE_FROM_VERSION)
                         ? df_rd_u64(&r, "from_version")
                         : 0;
    int rc = df_rd_end(&r);
    if (rc || (rc = subscribe_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- ack: u64 session_id, u64 version */
int df_msg_ack_encode(const df_msg_ack *m, df_buf *out, df_error *err)
{
    int rc = need_session(m->session_id, "ack", err);
    if (rc || (rc = df_enc_reserve(out, 16, "ack", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    return DF_OK;
}

int df_msg_ack_decode(const uint8_t *p, size_t n, df_msg_ack *m, df_error *err)
{
    df_rd r;
    df_msg_ack t;
    df_rd_init(&r, p, n, "ack", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.version = df_rd_u64(&r, "version");
    int rc = df_rd_end(&r);
    if (rc || (rc = need_session(t.session_id, "ack", err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- get_mesh: u64 session_id, u32 flags */
static int get_mesh_check(const df_msg_get_mesh *m, df_error *err)
{
    const uint32_t known = DF_GET_MESH_REST | DF_GET_MESH_BASE;
    int rc = need_session(m->session_id, "get_mesh", err);
    if (!rc && (m->flags & ~known))
        rc = df_error_set(err, DF_EINVAL, "get_mesh: unknown flag bits 0x%x", m->flags & ~known);
    return rc;
}

int df_msg_get_mesh_encode(const df_msg_get_mesh *m, df_buf *out, df_error *err)
{
    int rc = get_mesh_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 12, "get_mesh", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u32(out, m->flags);
    return DF_OK;
}

int df_msg_get_mesh_decode(const uint8_t *p, size_t n, df_msg_get_mesh *m, df_error *err)
{
    df_rd r;
    df_msg_get_mesh t;
    df_rd_init(&r, p, n, "get_mesh", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.flags = df_rd_u32(&r, "flags");
    int rc = df_rd_end(&r);
    if (rc || (rc = get_mesh_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- snapshot_req: u64 session_id, u64 version */
int df_msg_snapshot_req_encode(const df_msg_snapshot_req *m, df_buf *out, df_error *err)
{
    int rc = need_session(m->session_id, "snapshot_req", err);
    if (rc || (rc = df_enc_reserve(out, 16, "snapshot_req", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    return DF_OK;
}

int df_msg_snapshot_req_decode(const uint8_t *p, size_t n, df_msg_snapshot_req *m, df_error *err)
{
    df_rd r;
    df_msg_snapshot_req t;
    df_rd_init(&r, p, n, "snapshot_req", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.version = df_rd_u64(&r, "version");
    int rc = df_rd_end(&r);
    if (rc || (rc = need_session(t.session_id, "snapshot_req", err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- stats_req: u64 session_id (0 = daemon-wide) */
int df_msg_stats_req_encode(const df_msg_stats_req *m, df_buf *out, df_error *err)
{
    int rc = df_enc_reserve(out, 8, "stats_req", err);
    if (rc)
        return rc;
    df_buf_put_u64(out, m->session_id);
    return DF_OK;
}

int df_msg_stats_req_decode(const uint8_t *p, size_t n, df_msg_stats_req *m, df_error *err)
{
    df_rd r;
    df_rd_init(&r, p, n, "stats_req", err);
    uint64_t id = df_rd_u64(&r, "session_id");
    int rc = df_rd_end(&r);
    if (rc)
        return rc;
    m->session_id = id;
    return DF_OK;
}

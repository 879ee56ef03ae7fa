/* msg_access.c — per-session access bodies (messages.h; PROTOCOL.md 4.35, 4.36):
 * session_access (SESSION_ACCESS request), join (JOIN request), access_info (their reply). */
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

/* ---- session_access: u64 session_id, u8 mode, u8 observers, u8 flags, u8 reserved */
static int session_access_check(const df_msg_session_access *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "session_access: session_id 0 is not a session");
    if (m->mode > DF_ACCESS_MODE_MAX)
        return df_error_set(err, DF_EINVAL, "session_access: mode %u (0 keep, 1 open, 2 key, "
                            "3 owner)", m->mode);
    if (m->observers > 2)
        return df_error_set(err, DF_EINVAL, "session_access: observers %u (0 keep, 1 off, "
                            "2 on)", m->observers);
    if (m->flags & ~DF_ACCESS_FLAGS_ALL)
        return df_error_set(err, DF_EINVAL, "session_access: unknown flag bits 0x%x",
                            m->flags & ~DF_ACCESS_FLAGS_ALL);
    return DF_OK;
}

int df_msg_session_access_encode(const df_msg_session_access *m, df_buf *out, df_error *err)
{
    int rc = session_access_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 12, "session_access", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->mode);
    df_buf_put_u8(out, m->observers);
    df_buf_put_u8(out, m->flags);
    df_buf_put_u8(out, 0);
    return DF_OK;
}

int df_msg_session_access_decode(const uint8_t *p, size_t n, df_msg_session_access *m,
                                 df_error *err)
{
    df_rd r;
    df_msg_session_access t;
    df_rd_init(&r, p, n, "session_access", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.mode = df_rd_u8(&r, "mode");
    t.observers = df_rd_u8(&r, "observers");
    t.flags = df_rd_u8(&r, "flags");
    df_rd_reserved8(&r, "reserved");
    int rc = df_rd_end(&r);
    if (rc || (rc = session_access_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- join: u64 session_id, 32 bytes key */
int df_msg_join_encode(const df_msg_join *m, df_buf *out, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "join: session_id 0 is not a session");
    int rc = df_enc_reserve(out, 8 + DF_JOIN_KEY_BYTES, "join", err);
    if (rc)
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_bytes(out, m->key, DF_JOIN_KEY_BYTES);
    return DF_OK;
}

int df_msg_join_decode(const uint8_t *p, size_t n, df_msg_join *m, df_error *err)
{
    df_rd r;
    df_msg_join t;
    df_rd_init(&r, p, n, "join", err);
    t.session_id = df_rd_u64(&r, "session_id");
    const uint8_t *k = df_rd_bytes(&r, DF_JOIN_KEY_BYTES, "key");
    int rc = df_rd_end(&r);
    if (rc)
        return rc;
    if (t.session_id == 0)
        return df_error_set(err, DF_EINVAL, "join: session_id 0 is not a session");
    memcpy(t.key, k, DF_JOIN_KEY_BYTES);
    *m = t;
    return DF_OK;
}

/* ---- access_info: u64 session_id, u8 mode, u8 observers, u16 reserved, u32 members,
 * str owner, u16 key_len (0 or 32), key bytes */
static int access_info_check(const df_msg_access_info *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "access_info: session_id 0 is not a session");
    if (m->mode < 1 || m->mode > DF_ACCESS_MODE_MAX)
        return df_error_set(err, DF_EINVAL, "access_info: mode %u (1 open, 2 key, 3 owner)",
                            m->mode);
    if (m->observers > 1 || m->has_key > 1)
        return df_error_set(err, DF_EINVAL, "access_info: observers / has_key not 0 or 1");
    return df_check_str(m->owner, DF_MAX_NAME_LEN, "access_info", "owner", err);
}

int df_msg_access_info_encode(const df_msg_access_info *m, df_buf *out, df_error *err)
{
    int rc = access_info_check(m, err);
    size_t key_len = m->has_key ? DF_JOIN_KEY_BYTES : 0;
    if (rc || (rc = df_enc_reserve(out, 16 + df_str_size(m->owner) + 2 + key_len,
                                   "access_info", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->mode);
    df_buf_put_u8(out, m->observers);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->members);
    df_put_str(out, m->owner);
    df_buf_put_u16(out, (uint16_t)key_len);
    if (key_len) df_buf_put_bytes(out, m->key, key_len);
    return DF_OK;
}

int df_msg_access_info_decode(const uint8_t *p, size_t n, df_msg_access_info *m, df_error *err)
{
    df_rd r;
    df_msg_access_info t;
    memset(&t, 0, sizeof t);
    df_rd_init(&r, p, n, "access_info", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.mode = df_rd_u8(&r, "mode");
    t.observers = df_rd_u8(&r, "observers");
    df_rd_reserved16(&r, "reserved");
    t.members = df_rd_u32(&r, "members");
    df_rd_str(&r, t.owner, DF_MAX_NAME_LEN, "owner");
    uint16_t key_len = df_rd_u16(&r, "key_len");
    if (key_len != 0 && key_len != DF_JOIN_KEY_BYTES)
        return df_rd_fail(&r, DF_EINVAL, "key_len", "%u (0 or %u)", key_len, DF_JOIN_KEY_BYTES);
    const uint8_t *k = key_len ? df_rd_bytes(&r, key_len, "key") : NULL;
    int rc = df_rd_end(&r);
    if (rc)
        return rc;
    t.has_key = k != NULL;
    if (k) memcpy(t.key, k, DF_JOIN_KEY_BYTES);
    if ((rc = access_info_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

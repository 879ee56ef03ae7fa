/* msg_shm.c — shared-memory stream bodies (messages.h, PROTOCOL.md 4.24-4.25):
 * shm_info (STREAM_SHM reply) and shm_ref (SHM_REF event). */
#include "proto/codec_util.h"
#include "proto/messages.h"
#include "proto/shm_ring.h"

/* ---- shm_info: u64 session_id, u64 capacity, u32 min_frame, u32 max_frame, str path */
static int shm_info_check(const df_msg_shm_info *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "shm_info: session_id 0 is not a session");
    if (m->capacity < DF_SHM_MIN_CAPACITY || m->capacity > DF_SHM_MAX_CAPACITY)
        return df_error_set(err, DF_EINVAL, "shm_info: capacity %llu not in %u..%llu",
                            (unsigned long long)m->capacity, DF_SHM_MIN_CAPACITY,
                            (unsigned long long)DF_SHM_MAX_CAPACITY);
    if (m->min_frame < DF_FRAME_HEADER_SIZE || m->min_frame > m->max_frame ||
        m->max_frame > m->capacity)
        return df_error_set(err, DF_EINVAL,
                            "shm_info: frame bounds %u..%u not within %u..capacity",
                            m->min_frame, m->max_frame, DF_FRAME_HEADER_SIZE);
    int rc = df_check_str(m->path, DF_MAX_PATH_LEN, "shm_info", "path", err);
    if (!rc && m->path[0] != '/')
        rc = df_error_set(err, DF_EINVAL, "shm_info: path is not absolute");
    return rc;
}

int df_msg_shm_info_encode(const df_msg_shm_info *m, df_buf *out, df_error *err)
{
    int rc = shm_info_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 24 + df_str_size(m->path), "shm_info", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->capacity);
    df_buf_put_u32(out, m->min_frame);
    df_buf_put_u32(out, m->max_frame);
    df_put_str(out, m->path);
    return DF_OK;
}

int df_msg_shm_info_decode(const uint8_t *p, size_t n, df_msg_shm_info *m, df_error *err)
{
    df_rd r;
    df_msg_shm_info t;
    df_rd_init(&r, p, n, "shm_info", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.capacity = df_rd_u64(&r, "capacity");
    t.min_frame = df_rd_u32(&r, "min_frame");
    t.max_frame = df_rd_u32(&r, "max_frame");
    df_rd_str(&r, t.path, DF_MAX_PATH_LEN, "path");
    int rc = df_rd_end(&r);
    if (rc || (rc = shm_info_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- shm_ref: u64 session_id, u64 position, u32 length, u32 reserved */
static int shm_ref_check(const df_msg_shm_ref *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "shm_ref: session_id 0 is not a session");
    if (m->length < DF_FRAME_HEADER_SIZE)
        return df_error_set(err, DF_EINVAL, "shm_ref: length %u is shorter than a frame header",
                            m->length);
    return DF_OK;
}

int df_msg_shm_ref_encode(const df_msg_shm_ref *m, df_buf *out, df_error *err)
{
    int rc = shm_ref_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 24, "shm_ref", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->position);
    df_buf_put_u32(out, m->length);
    df_buf_put_u32(out, 0);
    return DF_OK;
}

int df_msg_shm_ref_decode(const uint8_t *p, size_t n, df_msg_shm_ref *m, df_error *err)
{
    df_rd r;
    df_msg_shm_ref t;
    df_rd_init(&r, p, n, "shm_ref", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.position = df_rd_u64(&r, "position");
    t.length = df_rd_u32(&r, "length");
    uint32_t reserved = df_rd_u32(&r, "reserved");
    if (reserved)
        df_rd_fail(&r, DF_EPROTO_RESERVED, "reserved", "reserved field is %u, must be 0",
                   reserved);
    int rc = df_rd_end(&r);
    if (rc || (rc = shm_ref_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* dc_calls_session.c — libdeformclient calls for connection-level and session messages: ping,
 * auth, load mesh (chunked inline upload or server path), list/open/close, subscribe, session
 * peers. */
#include "client/dc_client.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "client/dc_files.h"
#include "core/mesh/mesh_io.h"

/* Bytes of a load-mesh chunk body besides the data (fixed fields + name + empty path). */
#define DC_LOAD_OVERHEAD (64u + DF_MAX_NAME_LEN)

int dc_reply_ack(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_ack a;
    int rc = df_msg_ack_decode(p, h->payload_len, &a, err);
    if (rc == DF_OK && user)
        *(df_msg_ack *)user = a;
    return rc;
}

int dc_reply_session_info(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_session_info s;
    int rc = df_msg_session_info_decode(p, h->payload_len, &s, err);
    if (rc == DF_OK && user)
        *(df_msg_session_info *)user = s;
    return rc;
}

int dc_enc_session_ref(const void *m, df_buf *out, df_error *err)
{
    return df_msg_session_ref_encode(m, out, err);
}

int dc_session_ref_call(df_client *c, uint16_t type, uint64_t session_id, df_msg_ack *ack,
                        df_error *err)
{
    df_msg_session_ref r = {session_id};
    return dc_request(c, type, dc_enc_session_ref, &r, dc_reply_ack, ack, err);
}

typedef struct ping_ctx {
    const void *data;
    uint32_t len;
} ping_ctx;

static int reply_ping(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    ping_ctx *x = user;
    df_msg_ping m;
    int rc = df_msg_ping_decode(p, h->payload_len, &m, err);
    if (rc)
        return rc;
    if (m.len != x->len || (m.len && memcmp(m.data, x->data, m.len) != 0))
        return df_error_set(err, DF_EFORMAT, "ping echo differs from the %u bytes sent", x->len);
    return DF_OK;
}

static int enc_ping(const void *m, df_buf *out, df_error *err)
{
    return df_msg_ping_encode(m, out, err);
}

int df_client_ping(df_client *c, const void *data, uint32_t len, double *rtt_us, df_error *err)
{
    df_msg_ping m = {len, data};
    ping_ctx x = {data, len};
    double t0 = dc_now_us();
    int rc = dc_request(c, DF_MSG_PING, enc_ping, &m, reply_ping, &x, err);
    if (rc == DF_OK && rtt_us)
        *rtt_us = dc_now_us() - t0;
    return rc;
}

static int enc_auth(const void *m, df_buf *out, df_error *err)
{
    return df_msg_auth_encode(m, out, err);
}

int df_client_auth(df_client *c, uint16_t method, const void *token, uint32_t len, df_error *err)
{
    df_msg_auth m = {method, len, token};
    return dc_request(c, DF_MSG_AUTH, enc_auth, &m, NULL, NULL, err);
}

static int reply_load(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_load_reply r;
    int rc = df_msg_load_reply_decode(p, h->payload_len, &r, err);
    if (rc == DF_OK && user)
        *(df_msg_load_reply *)user = r;
    return rc;
}

/* Copies `s` (may be NULL) into dst (DF_MAX_NAME_LEN + 1 bytes); DF_EINVAL when too long. */
static int put_name(char *dst, const char *s, const char *what, df_error *err)
{
    size_t nl = s ? strlen(s) : 0;
    if (nl > DF_MAX_NAME_LEN)
        return df_error_set(err, DF_EINVAL, "load mesh: %s longer than %u bytes", what,
                            DF_MAX_NAME_LEN);
    memcpy(dst, s ? s : "", nl + 1);
    return DF_OK;
}

int df_client_load_mesh_bytes_ex(df_client *c, const char *name, const char *file_name,
                                 uint8_t format, const void *bytes, uint64_t len,
                                 uint64_t part2_offset, df_msg_load_reply *reply, df_error *err)
{
    c->remote_err = 0;
    if (!bytes || len == 0)
        return df_error_set(err, DF_EINVAL, "load mesh: no bytes");
    if (len > DF_MAX_MESH_BYTES)
        return df_error_set(err, DF_ELIMIT, "load mesh: %llu bytes exceeds %llu",
                            (unsigned long long)len, (unsigned long long)DF_MAX_MESH_BYTES);
    df_msg_load_mesh m;
    memset(&m, 0, sizeof m);
    m.source = DF_LOAD_INLINE;
    m.format = format;
    m.options = (uint16_t)(DF_LOAD_OPT_EXT | c->load_flags);
    int rc = put_name(m.name, name, "name", err);
    if (!rc)
        rc = put_name(m.file_name, file_name, "file name", err);
    if (rc)
        return rc;
    m.total_size = len;
    m.part2_offset = part2_offset;
    uint32_t maxp = c->server.max_frame_payload ? c->server.max_frame_payload : DF_MAX_FRAME_PAYLOAD;
    if (maxp > DF_STREAM_CHUNK_BYTES + DC_LOAD_OVERHEAD)
        maxp = DF_STREAM_CHUNK_BYTES + DC_LOAD_OVERHEAD;
    uint64_t chunk = maxp - DC_LOAD_OVERHEAD;
    uint64_t id = c->next_id++;
    for (uint64_t off = 0; off < len; off += chunk) {
        uint64_t n = len - off < chunk ? len - off : chunk;
        m.offset = off;
        m.data_len = (uint32_t)n;
        m.data = (const uint8_t *)bytes + off;
        df_buf_reset(&c->out);
        rc = df_msg_load_mesh_encode(&m, &c->out, err);
        if (rc)
            return rc;
        uint16_t flags = off + n < len ? DF_FLAG_MORE : 0;
        rc = df_client_send(c, DF_MSG_LOAD_MESH, flags, id, c->out.data, c->out.len, NULL, err);
        if (rc)
            return rc;
    }
    df_msg_load_reply r;
    rc = dc_wait_reply(c, DF_MSG_LOAD_MESH, id, reply_load, &r, err);
    if (rc == DF_OK && reply)
        *reply = r;
    return rc;
}

int df_client_load_mesh_bytes(df_client *c, const char *name, uint8_t format, const void *bytes,
                              uint64_t len, uint64_t part2_offset, df_msg_session_info *info,
                              df_error *err)
{
    df_msg_load_reply r;
    int rc = df_client_load_mesh_bytes_ex(c, name, NULL, format, bytes, len, part2_offset, &r, err);
    if (rc == DF_OK && info)
        *info = r.info;
    return rc;
}

static int ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && strcasecmp(s + a - b, suf) == 0;
}

static const char *base_name(const char *path)
{
    const char *b = strrchr(path, '/');
    return b ? b + 1 : path;
}

int df_client_load_mesh_file_ex(df_client *c, const char *path, const char *name,
                                df_msg_load_reply *reply, df_error *err)
{
    c->remote_err = 0;
    if (!path || !*path)
        return df_error_set(err, DF_EINVAL, "load mesh: empty path");
    char fname[DF_MAX_NAME_LEN + 1];
    snprintf(fname, sizeof fname, "%s", base_name(path));
    char *data = NULL;
    long long len = 0;
    int rc;
    if (ends_with(path, ".node") || ends_with(path, ".ele")) {
        size_t pl = strlen(path) + 8;
        char *other = malloc(pl);
        char *nt = NULL, *et = NULL;
        long long nlen = 0, elen = 0;
        if (!other)
            return df_error_set(err, DF_ENOMEM, "out of memory");
        df_mesh_tetgen_sibling(path, other, pl); /* keeps the case: T1.NODE -> T1.ELE */
        int is_node = ends_with(path, ".node");
        rc = dc_read_file(is_node ? path : other, &nt, &nlen, err);
        if (rc == DF_OK)
            rc = dc_read_file(is_node ? other : path, &et, &elen, err);
        free(other);
        if (rc == DF_OK && (nlen == 0 || elen == 0))
            rc = df_error_set(err, DF_EFORMAT, "%s: empty .node or .ele file", path);
        if (rc == DF_OK && !(data = malloc((size_t)(nlen + elen))))
            rc = df_error_set(err, DF_ENOMEM, "out of memory");
        if (rc == DF_OK) {
            memcpy(data, nt, (size_t)nlen);
            memcpy(data + nlen, et, (size_t)elen);
            rc = df_client_load_mesh_bytes_ex(c, name, fname, DF_FMT_TETGEN, data,
                                              (uint64_t)(nlen + elen), (uint64_t)nlen, reply,
                                              err);
        }
        free(nt);
        free(et);
        free(data);
        return rc;
    }
    df_mesh_format fmt = df_mesh_format_from_path(path);
    if (fmt == DF_FMT_AUTO)
        return df_error_set(err, DF_EINVAL, "%s: %s", path, DF_CLIENT_FORMATS_MSG);
    rc = dc_read_file(path, &data, &len, err);
    if (rc)
        return rc;
    if (len == 0)
        rc = df_error_set(err, DF_EFORMAT, "%s: empty file", path);
    else
        rc = df_client_load_mesh_bytes_ex(c, name, fname, (uint8_t)fmt, data, (uint64_t)len, 0,
                                          reply, err);
    free(data);
    return rc;
}

void df_client_set_load_flags(df_client *c, uint16_t flags)
{
    if (c)
        c->load_flags = flags;
}

int df_client_load_mesh_file(df_client *c, const char *path, const char *name,
                             df_msg_session_info *info, df_error *err)
{
    df_msg_load_reply r;
    int rc = df_client_load_mesh_file_ex(c, path, name, &r, err);
    if (rc == DF_OK && info)
        *info = r.info;
    return rc;
}

static int enc_load(const void *m, df_buf *out, df_error *err)
{
    return df_msg_load_mesh_encode(m, out, err);
}

int df_client_load_mesh_path_ex(df_client *c, const char *path, const char *name,
                                uint8_t format, df_msg_load_reply *reply, df_error *err)
{
    df_msg_load_mesh m;
    memset(&m, 0, sizeof m);
    m.source = DF_LOAD_PATH;
    m.format = format;
    m.options = (uint16_t)(DF_LOAD_OPT_EXT | c->load_flags);
    m.path = (char *)path;
    int rc = put_name(m.name, name, "name", err);
    if (rc)
        return rc;
    df_msg_load_reply r;
    rc = dc_request(c, DF_MSG_LOAD_MESH, enc_load, &m, reply_load, &r, err);
    if (rc == DF_OK && reply)
        *reply = r;
    return rc;
}

int df_client_load_mesh_path(df_client *c, const char *path, const char *name, uint8_t format,
                             df_msg_session_info *info, df_error *err)
{
    df_msg_load_reply r;
    int rc = df_client_load_mesh_path_ex(c, path, name, format, &r, err);
    if (rc == DF_OK && info)
        *info = r.info;
    return rc;
}

static int reply_list(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_session_list_decode(p, h->payload_len, user, err);
}

int df_client_list_sessions(df_client *c, df_msg_session_list *out, df_error *err)
{
    df_msg_session_list t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_LIST_SESSIONS, NULL, NULL, reply_list, &t, err);
    if (rc) {
        df_msg_session_list_free(&t);
        return rc;
    }
    *out = t;
    return DF_OK;
}

static int enc_open(const void *m, df_buf *out, df_error *err)
{
    return df_msg_open_session_encode(m, out, err);
}

int df_client_open_session(df_client *c, uint64_t session_id, const char *name,
                           df_msg_session_info *info, df_error *err)
{
    df_msg_open_session m;
    memset(&m, 0, sizeof m);
    m.session_id = session_id;
    size_t nl = name ? strlen(name) : 0;
    if (nl > DF_MAX_NAME_LEN)
        return df_error_set(err, DF_EINVAL, "open session: name longer than %u bytes",
                            DF_MAX_NAME_LEN);
    if (nl)
        memcpy(m.name, name, nl + 1);
    return dc_request(c, DF_MSG_OPEN_SESSION, enc_open, &m, dc_reply_session_info, info, err);
}

int df_client_close_session(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_CLOSE_SESSION, session_id, ack, err);
}

static int enc_sub(const void *m, df_buf *out, df_error *err)
{
    return df_msg_subscribe_encode(m, out, err);
}

int df_client_subscribe(df_client *c, uint64_t session_id, uint32_t flags,
                        df_msg_session_info *info, df_error *err)
{
    df_msg_subscribe m = {session_id, flags, 0};
    return dc_request(c, DF_MSG_SUBSCRIBE, enc_sub, &m, dc_reply_session_info, info, err);
}

int df_client_subscribe_from(df_client *c, uint64_t session_id, uint64_t from_version,
                             df_msg_session_info *info, df_error *err)
{
    df_msg_subscribe m = {session_id, DF_SUBSCRIBE_FROM_VERSION, from_version};
    return dc_request(c, DF_MSG_SUBSCRIBE, enc_sub, &m, dc_reply_session_info, info, err);
}

int df_client_unsubscribe(df_client *c, uint64_t session_id, df_error *err)
{
    int rc = dc_session_ref_call(c, DF_MSG_UNSUBSCRIBE, session_id, NULL, err);
    if (rc == DF_OK) dc_shm_drop(c, session_id);
    return rc;
}

static int reply_peers(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_peer_list_decode(p, h->payload_len, user, err);
}

int df_client_session_peers(df_client *c, uint64_t session_id, df_msg_peer_list *out,
                            df_error *err)
{
    df_msg_session_ref m = {session_id};
    df_msg_peer_list t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_SESSION_PEERS, dc_enc_session_ref, &m, reply_peers, &t, err);
    if (rc) {
        df_msg_peer_list_free(&t);
        return rc;
    }
    *out = t;
    return DF_OK;
}

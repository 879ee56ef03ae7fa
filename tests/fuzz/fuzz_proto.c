/* fuzz_proto.c — libFuzzer target for the wire format (proto/). For every input:
 *  1. decode it as a frame header; if that succeeds, decode the (possibly short) payload as the
 *     body that (type, flags) selects;
 *  2. run every body decoder on the whole input;
 *  3. oracle: whenever a decoder accepts bytes, re-encoding the decoded message must reproduce
 *     exactly those bytes (decoders and encoders agree on every field), and decoded values must
 *     pass the encoder's validation (no NaN, no out-of-range index ever escapes a decoder).
 * Seeds: tests/fuzz/corpus/proto (tests/fuzz/gen_proto_corpus.c writes them). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"

static int encode_any(const df_msg_any *m, df_buf *out, df_error *e)
{
    switch (m->which) {
    case DF_BODY_EMPTY: return DF_OK;
    case DF_BODY_ERROR: return df_msg_error_encode(&m->u.error, out, e);
    case DF_BODY_HELLO: return df_msg_hello_encode(&m->u.hello, out, e);
    case DF_BODY_HELLO_REPLY: return df_msg_hello_reply_encode(&m->u.hello_reply, out, e);
    case DF_BODY_AUTH: return df_msg_auth_encode(&m->u.auth, out, e);
    case DF_BODY_PING: return df_msg_ping_encode(&m->u.ping, out, e);
    case DF_BODY_LOAD_MESH: return df_msg_load_mesh_encode(&m->u.load_mesh, out, e);
    case DF_BODY_SESSION_REF: return df_msg_session_ref_encode(&m->u.session_ref, out, e);
    case DF_BODY_OPEN_SESSION: return df_msg_open_session_encode(&m->u.open_session, out, e);
    case DF_BODY_SUBSCRIBE: return df_msg_subscribe_encode(&m->u.subscribe, out, e);
    case DF_BODY_SESSION_INFO: return df_msg_session_info_encode(&m->u.session_info, out, e);
    case DF_BODY_SESSION_LIST: return df_msg_session_list_encode(&m->u.session_list, out, e);
    case DF_BODY_ACK: return df_msg_ack_encode(&m->u.ack, out, e);
    case DF_BODY_BRUSH: return df_msg_brush_encode(&m->u.brush, out, e);
    case DF_BODY_BRUSH_UPDATE: return df_msg_brush_update_encode(&m->u.brush_update, out, e);
    case DF_BODY_BRUSH_PARAM: return df_msg_brush_param_encode(&m->u.brush_param, out, e);
    case DF_BODY_HANDLES: return df_msg_handles_encode(&m->u.handles, out, e);
    case DF_BODY_HANDLE_MOVE: return df_msg_handle_move_encode(&m->u.handle_move, out, e);
    case DF_BODY_MOVE_RESULT: return df_msg_move_result_encode(&m->u.move_result, out, e);
    case DF_BODY_GET_MESH: return df_msg_get_mesh_encode(&m->u.get_mesh, out, e);
    case DF_BODY_MESH_CHUNK: return df_msg_mesh_chunk_encode(&m->u.mesh_chunk, out, e);
    case DF_BODY_SNAPSHOT_REQ: return df_msg_snapshot_req_encode(&m->u.snapshot_req, out, e);
    case DF_BODY_DISP: return df_msg_disp_encode(&m->u.disp, out, e);
    case DF_BODY_PROGRESS: return df_msg_progress_encode(&m->u.progress, out, e);
    case DF_BODY_STATS_REQ: return df_msg_stats_req_encode(&m->u.stats_req, out, e);
    case DF_BODY_STATS: return df_msg_stats_encode(&m->u.stats, out, e);
    }
    return DF_EINTERNAL;
}

/* Decodes p[0..n) as (type, flags); on success checks the re-encoding oracle. */
static void check(uint16_t type, uint16_t flags, const uint8_t *p, size_t n)
{
    df_msg_any m;
    df_error e;
    if (df_msg_any_decode(type, flags, p, n, &m, &e) != DF_OK) {
        if (e.code >= 0 || e.msg[0] == '\0')
            abort(); /* every failure must carry a code and a message */
        return;
    }
    df_buf out;
    df_buf_init(&out);
    if (encode_any(&m, &out, &e) != DF_OK || out.len != n || (n && memcmp(out.data, p, n)))
        abort();
    df_buf_free(&out);
    df_msg_any_free(&m);
}

/* One representative (type, flags) per body kind. */
static const uint16_t kinds[][2] = {
    {DF_MSG_UNDO, DF_FLAG_REPLY | DF_FLAG_ERROR}, {DF_MSG_HELLO, 0},
    {DF_MSG_HELLO, DF_FLAG_REPLY}, {DF_MSG_AUTH, 0}, {DF_MSG_AUTH, DF_FLAG_REPLY},
    {DF_MSG_PING, 0}, {DF_MSG_LOAD_MESH, 0}, {DF_MSG_UNDO, 0}, {DF_MSG_OPEN_SESSION, 0},
    {DF_MSG_SUBSCRIBE, 0}, {DF_MSG_SUBSCRIBE, DF_FLAG_REPLY}, {DF_MSG_LIST_SESSIONS, DF_FLAG_REPLY},
    {DF_MSG_UNDO, DF_FLAG_REPLY}, {DF_MSG_BRUSH_BEGIN, 0}, {DF_MSG_BRUSH_UPDATE, 0},
    {DF_MSG_SET_BRUSH_PARAM, 0}, {DF_MSG_HANDLES_SET, 0}, {DF_MSG_HANDLES_MOVE, 0},
    {DF_MSG_HANDLES_MOVE, DF_FLAG_REPLY}, {DF_MSG_GET_MESH, 0}, {DF_MSG_GET_MESH, DF_FLAG_REPLY},
    {DF_MSG_SNAPSHOT, 0}, {DF_MSG_DISPLACEMENT, DF_FLAG_EVENT}, {DF_MSG_PROGRESS, DF_FLAG_EVENT},
    {DF_MSG_STATS, 0}, {DF_MSG_STATS, DF_FLAG_REPLY},
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    df_frame_header h;
    df_error e;
    int rc = df_frame_header_decode(data, size, &h, &e);
    if (rc == DF_OK) {
        uint8_t raw[DF_FRAME_HEADER_SIZE];
        if (df_frame_header_encode(&h, raw, &e) != DF_OK || memcmp(raw, data, sizeof raw))
            abort();
        size_t n = size - DF_FRAME_HEADER_SIZE;
        if (n > h.payload_len)
            n = h.payload_len;
        df_body_kind k;
        if (df_msg_body_kind(h.type, h.flags, &k, &e) == DF_OK)
            check(h.type, h.flags, data + DF_FRAME_HEADER_SIZE, n);
    } else if (rc >= 0 || e.msg[0] == '\0') {
        abort();
    }
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        check(kinds[i][0], kinds[i][1], data, size);
    return 0;
}

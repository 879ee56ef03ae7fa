/* msg_any.c — generic decode of any body selected by (type, flags) (messages.h). */
#include <string.h>

#include "proto/messages.h"

int df_msg_any_decode(uint16_t type, uint16_t flags, const uint8_t *p, size_t n, df_msg_any *m,
                      df_error *err)
{
    df_body_kind k;
    int rc = df_msg_body_kind(type, flags, &k, err);
    if (rc)
        return rc;
    df_msg_any t;
    memset(&t, 0, sizeof t);
    t.which = k;
    switch (k) {
    case DF_BODY_EMPTY: rc = df_msg_empty_decode(p, n, err); break;
    case DF_BODY_ERROR: rc = df_msg_error_decode(p, n, &t.u.error, err); break;
    case DF_BODY_HELLO: rc = df_msg_hello_decode(p, n, &t.u.hello, err); break;
    case DF_BODY_HELLO_REPLY: rc = df_msg_hello_reply_decode(p, n, &t.u.hello_reply, err); break;
    case DF_BODY_AUTH: rc = df_msg_auth_decode(p, n, &t.u.auth, err); break;
    case DF_BODY_PING: rc = df_msg_ping_decode(p, n, &t.u.ping, err); break;
    case DF_BODY_LOAD_MESH: rc = df_msg_load_mesh_decode(p, n, &t.u.load_mesh, err); break;
    case DF_BODY_LOAD_REPLY: rc = df_msg_load_reply_decode(p, n, &t.u.load_reply, err); break;
    case DF_BODY_SESSION_REF: rc = df_msg_session_ref_decode(p, n, &t.u.session_ref, err); break;
    case DF_BODY_OPEN_SESSION:
        rc = df_msg_open_session_decode(p, n, &t.u.open_session, err);
        break;
    case DF_BODY_SUBSCRIBE: rc = df_msg_subscribe_decode(p, n, &t.u.subscribe, err); break;
    case DF_BODY_SESSION_INFO:
        rc = df_msg_session_info_decode(p, n, &t.u.session_info, err);
        break;
    case DF_BODY_SESSION_LIST:
        rc = df_msg_session_list_decode(p, n, &t.u.session_list, err);
        break;
    case DF_BODY_ACK: rc = df_msg_ack_decode(p, n, &t.u.ack, err); break;
    case DF_BODY_BRUSH: rc = df_msg_brush_decode(p, n, &t.u.brush, err); break;
    case DF_BODY_BRUSH_UPDATE:
        rc = df_msg_brush_update_decode(p, n, &t.u.brush_update, err);
        break;
    case DF_BODY_BRUSH_PARAM: rc = df_msg_brush_param_decode(p, n, &t.u.brush_param, err); break;
    case DF_BODY_HANDLES: rc = df_msg_handles_decode(p, n, &t.u.handles, err); break;
    case DF_BODY_HANDLE_MOVE: rc = df_msg_handle_move_decode(p, n, &t.u.handle_move, err); break;
    case DF_BODY_MOVE_RESULT: rc = df_msg_move_result_decode(p, n, &t.u.move_result, err); break;
    case DF_BODY_GET_MESH: rc = df_msg_get_mesh_decode(p, n, &t.u.get_mesh, err); break;
    case DF_BODY_MESH_CHUNK: rc = df_msg_mesh_chunk_decode(p, n, &t.u.mesh_chunk, err); break;
    case DF_BODY_SNAPSHOT_REQ:
        rc = df_msg_snapshot_req_decode(p, n, &t.u.snapshot_req, err);
        break;
    case DF_BODY_DISP: rc = df_msg_disp_decode(p, n, &t.u.disp, err); break;
    case DF_BODY_PROGRESS: rc = df_msg_progress_decode(p, n, &t.u.progress, err); break;
    case DF_BODY_STATS_REQ: rc = df_msg_stats_req_decode(p, n, &t.u.stats_req, err); break;
    case DF_BODY_STATS: rc = df_msg_stats_decode(p, n, &t.u.stats, err); break;
    case DF_BODY_SHM_INFO: rc = df_msg_shm_info_decode(p, n, &t.u.shm_info, err); break;
    case DF_BODY_SHM_REF: rc = df_msg_shm_ref_decode(p, n, &t.u.shm_ref, err); break;
    case DF_BODY_BRUSH_STATE_SET:
        rc = df_msg_brush_state_set_decode(p, n, &t.u.brush_state_set, err);
        break;
    case DF_BODY_BRUSH_STATE: rc = df_msg_brush_state_decode(p, n, &t.u.brush_state, err); break;
    case DF_BODY_BRUSH_CURSOR:
        rc = df_msg_brush_cursor_decode(p, n, &t.u.brush_cursor, err);
        break;
    /* devices (HID) */
    case DF_BODY_DEVICE_INFO: rc = df_msg_device_info_decode(p, n, &t.u.device_info, err); break;
    case DF_BODY_DEVICE_LIST: rc = df_msg_device_list_decode(p, n, &t.u.device_list, err); break;
    case DF_BODY_DEVICE_BIND: rc = df_msg_device_bind_decode(p, n, &t.u.device_bind, err); break;
    case DF_BODY_DEVICE_VIEW: rc = df_msg_device_view_decode(p, n, &t.u.device_view, err); break;
    case DF_BODY_SESSION_ACCESS:
        rc = df_msg_session_access_decode(p, n, &t.u.session_access, err);
        break;
    case DF_BODY_JOIN: rc = df_msg_join_decode(p, n, &t.u.join, err); break;
    case DF_BODY_ACCESS_INFO: rc = df_msg_access_info_decode(p, n, &t.u.access_info, err); break;
    case DF_BODY_WORK_PROGRESS:
        rc = df_msg_work_progress_decode(p, n, &t.u.work_progress, err);
        break;
    case DF_BODY_PEER_LIST: rc = df_msg_peer_list_decode(p, n, &t.u.peer_list, err); break;
    case DF_BODY_QDISP: rc = df_msg_qdisp_decode(p, n, &t.u.qdisp, err); break;
    case DF_BODY_ZFRAME: rc = df_msg_zframe_decode(p, n, &t.u.zframe, err); break;
    default: rc = df_error_set(err, DF_EINTERNAL, "body kind %d has no decoder", (int)k); break;
    }
    if (rc)
        return rc;
    *m = t;
    return DF_OK;
}

void df_msg_any_free(df_msg_any *m)
{
    if (!m)
        return;
    switch (m->which) {
    case DF_BODY_LOAD_MESH: df_msg_load_mesh_free(&m->u.load_mesh); break;
    case DF_BODY_SESSION_LIST: df_msg_session_list_free(&m->u.session_list); break;
    case DF_BODY_BRUSH: df_msg_brush_free(&m->u.brush); break;
    case DF_BODY_HANDLES: df_msg_handles_free(&m->u.handles); break;
    case DF_BODY_HANDLE_MOVE: df_msg_handle_move_free(&m->u.handle_move); break;
    case DF_BODY_MESH_CHUNK: df_msg_mesh_chunk_free(&m->u.mesh_chunk); break;
    case DF_BODY_DISP: df_msg_disp_free(&m->u.disp); break;
    case DF_BODY_PROGRESS: df_msg_progress_free(&m->u.progress); break;
    case DF_BODY_STATS: df_msg_stats_free(&m->u.stats); break;
    case DF_BODY_DEVICE_LIST: df_msg_device_list_free(&m->u.device_list); break;
    case DF_BODY_PEER_LIST: df_msg_peer_list_free(&m->u.peer_list); break;
    case DF_BODY_QDISP: df_msg_qdisp_free(&m->u.qdisp); break;
    default: break;
    }
}

int df_msg_any_encode(const df_msg_any *m, df_buf *out, df_error *e)
{
    switch (m->which) {
    case DF_BODY_EMPTY: return DF_OK;
    case DF_BODY_ERROR: return df_msg_error_encode(&m->u.error, out, e);
    case DF_BODY_HELLO: return df_msg_hello_encode(&m->u.hello, out, e);
    case DF_BODY_HELLO_REPLY: return df_msg_hello_reply_encode(&m->u.hello_reply, out, e);
    case DF_BODY_AUTH: return df_msg_auth_encode(&m->u.auth, out, e);
    case DF_BODY_PING: return df_msg_ping_encode(&m->u.ping, out, e);
    case DF_BODY_LOAD_MESH: return df_msg_load_mesh_encode(&m->u.load_mesh, out, e);
    case DF_BODY_LOAD_REPLY: return df_msg_load_reply_encode(&m->u.load_reply, out, e);
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
    case DF_BODY_QDISP: return df_msg_qdisp_encode(&m->u.qdisp, out, e);
    case DF_BODY_ZFRAME: return df_msg_zframe_encode(&m->u.zframe, out, e);
    case DF_BODY_STATS_REQ: return df_msg_stats_req_encode(&m->u.stats_req, out, e);
    case DF_BODY_STATS: return df_msg_stats_encode(&m->u.stats, out, e);
    case DF_BODY_SHM_INFO: return df_msg_shm_info_encode(&m->u.shm_info, out, e);
    case DF_BODY_SHM_REF: return df_msg_shm_ref_encode(&m->u.shm_ref, out, e);
    case DF_BODY_BRUSH_STATE_SET:
        return df_msg_brush_state_set_encode(&m->u.brush_state_set, out, e);
    case DF_BODY_BRUSH_STATE: return df_msg_brush_state_encode(&m->u.brush_state, out, e);
    case DF_BODY_BRUSH_CURSOR: return df_msg_brush_cursor_encode(&m->u.brush_cursor, out, e);
    /* devices (HID) */
    case DF_BODY_DEVICE_INFO: return df_msg_device_info_encode(&m->u.device_info, out, e);
    case DF_BODY_DEVICE_LIST: return df_msg_device_list_encode(&m->u.device_list, out, e);
    case DF_BODY_DEVICE_BIND: return df_msg_device_bind_encode(&m->u.device_bind, out, e);
    case DF_BODY_DEVICE_VIEW: return df_msg_device_view_encode(&m->u.device_view, out, e);
    case DF_BODY_SESSION_ACCESS:
        return df_msg_session_access_encode(&m->u.session_access, out, e);
    case DF_BODY_JOIN: return df_msg_join_encode(&m->u.join, out, e);
    case DF_BODY_ACCESS_INFO: return df_msg_access_info_encode(&m->u.access_info, out, e);
    case DF_BODY_WORK_PROGRESS: return df_msg_work_progress_encode(&m->u.work_progress, out, e);
    case DF_BODY_PEER_LIST: return df_msg_peer_list_encode(&m->u.peer_list, out, e);
    }
    return DF_EINTERNAL;
}

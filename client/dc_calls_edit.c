/* dc_calls_edit.c — libdeformclient calls that change a session: brush strokes, brush
 * parameters, handle sets and moves, reset rest, undo and redo. */
#include "client/dc_client.h"

static int enc_brush(const void *m, df_buf *out, df_error *err)
{
    return df_msg_brush_encode(m, out, err);
}

int df_client_brush_begin(df_client *c, const df_msg_brush *b, df_msg_ack *ack, df_error *err)
{
    return dc_request(c, DF_MSG_BRUSH_BEGIN, enc_brush, b, dc_reply_ack, ack, err);
}

static int enc_update(const void *m, df_buf *out, df_error *err)
{
    return df_msg_brush_update_encode(m, out, err);
}

int df_client_brush_update(df_client *c, const df_msg_brush_update *u, df_msg_ack *ack,
                           df_error *err)
{
    return dc_request(c, DF_MSG_BRUSH_UPDATE, enc_update, u, dc_reply_ack, ack, err);
}

int df_client_brush_end(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_BRUSH_END, session_id, ack, err);
}

int df_client_brush_cancel(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_BRUSH_CANCEL, session_id, ack, err);
}

static int enc_param(const void *m, df_buf *out, df_error *err)
{
    return df_msg_brush_param_encode(m, out, err);
}

int df_client_set_brush_param(df_client *c, uint64_t session_id, uint8_t param, double value,
                              df_error *err)
{
    df_msg_brush_param m = {session_id, param, value};
    return dc_request(c, DF_MSG_SET_BRUSH_PARAM, enc_param, &m, dc_reply_ack, NULL, err);
}

static int enc_handles(const void *m, df_buf *out, df_error *err)
{
    return df_msg_handles_encode(m, out, err);
}

int df_client_handles_set(df_client *c, const df_msg_handles *h, df_error *err)
{
    return dc_request(c, DF_MSG_HANDLES_SET, enc_handles, h, dc_reply_ack, NULL, err);
}

static int enc_move(const void *m, df_buf *out, df_error *err)
{
    return df_msg_handle_move_encode(m, out, err);
}

static int reply_move(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_move_result r;
    int rc = df_msg_move_result_decode(p, h->payload_len, &r, err);
    if (rc == DF_OK && user)
        *(df_msg_move_result *)user = r;
    return rc;
}

int df_client_handles_move(df_client *c, const df_msg_handle_move *m, df_msg_move_result *res,
                           df_error *err)
{
    return dc_request(c, DF_MSG_HANDLES_MOVE, enc_move, m, reply_move, res, err);
}

int df_client_reset_rest(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_RESET_REST, session_id, ack, err);
}

int df_client_undo(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_UNDO, session_id, ack, err);
}

int df_client_redo(df_client *c, uint64_t session_id, df_msg_ack *ack, df_error *err)
{
    return dc_session_ref_call(c, DF_MSG_REDO, session_id, ack, err);
}

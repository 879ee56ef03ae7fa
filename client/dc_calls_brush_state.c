/* dc_calls_brush_state.c — libdeformclient calls of the session brush: get and set
 * (PROTOCOL.md 4.14a, 4.14b). The BRUSH_STATE / BRUSH_CURSOR events reach the event callback. */
#include "client/dc_client.h"

static int reply_state(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_brush_state s;
    int rc = df_msg_brush_state_decode(p, h->payload_len, &s, err);
    if (rc == DF_OK && user)
        *(df_msg_brush_state *)user = s;
    return rc;
}

int df_client_brush_state_get(df_client *c, uint64_t session_id, df_msg_brush_state *out,
                              df_error *err)
{
    df_msg_session_ref r = {session_id};
    return dc_request(c, DF_MSG_BRUSH_STATE_GET, dc_enc_session_ref, &r, reply_state, out, err);
}

static int enc_set(const void *m, df_buf *out, df_error *err)
{
    return df_msg_brush_state_set_encode(m, out, err);
}

int df_client_brush_state_set(df_client *c, const df_msg_brush_state_set *m,
                              df_msg_brush_state *out, df_error *err)
{
    return dc_request(c, DF_MSG_BRUSH_STATE_SET, enc_set, m, reply_state, out, err);
}

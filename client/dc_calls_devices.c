/* dc_calls_devices.c — libdeformclient calls of the daemon's HID devices: list, bind, view
 * (PROTOCOL.md 4.30..4.33). DEVICE_STATE events reach the event callback of a subscriber. */
#include <string.h>

#include "client/dc_client.h"

static int reply_list(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_device_list_decode(p, h->payload_len, user, err);
}

static int reply_empty(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    (void)user;
    return df_msg_empty_decode(p, h->payload_len, err);
}

int df_client_devices_list(df_client *c, df_msg_device_list *out, df_error *err)
{
    df_msg_device_list t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_DEVICES_LIST, NULL, NULL, reply_list, &t, err);
    if (rc) {
        df_msg_device_list_free(&t);
        return rc;
    }
    *out = t;
    return DF_OK;
}

static int enc_bind(const void *m, df_buf *out, df_error *err)
{
    return df_msg_device_bind_encode(m, out, err);
}

int df_client_device_bind(df_client *c, uint64_t device_id, uint64_t session_id, df_error *err)
{
    df_msg_device_bind m = {device_id, session_id};
    return dc_request(c, DF_MSG_DEVICE_BIND, enc_bind, &m, reply_empty, NULL, err);
}

static int enc_view(const void *m, df_buf *out, df_error *err)
{
    return df_msg_device_view_encode(m, out, err);
}

int df_client_device_view(df_client *c, const df_msg_device_view *m, df_error *err)
{
    return dc_request(c, DF_MSG_DEVICE_VIEW, enc_view, m, reply_empty, NULL, err);
}

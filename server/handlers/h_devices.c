/* h_devices.c — DEVICES_LIST, DEVICE_BIND and DEVICE_VIEW (PROTOCOL.md 4.30..4.33): answered on
 * the loop thread at once from the HID manager's registry through srv->hid_ops (server.h; the
 * manager, server/hid/hid_manager.h, builds on the handlers, so they do not include it). Without
 * it the list is empty and every device is unknown. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/handlers/handlers.h"

typedef struct stats_acc {
    df_msg_stats st;
    uint32_t cap;
} stats_acc;

static void put(void *ctx, const char *key, double v)
{
    stats_acc *a = ctx;
    if (a->st.count >= a->cap) return;
    snprintf(a->st.items[a->st.count].key, sizeof a->st.items[0].key, "%s", key);
    a->st.items[a->st.count++].value = v;
}

int df_h_device_stats(df_req *r, uint64_t device_id, df_error *err)
{
    stats_acc a = {{0, calloc(DF_MAX_STATS_ENTRIES, sizeof(df_msg_stat))}, DF_MAX_STATS_ENTRIES};
    if (!a.st.items) return df_error_set(err, DF_ENOMEM, "stats: out of memory");
    const df_hid_ops *h = r->srv->hid_ops;
    int rc = h ? h->device_stats(r->srv, device_id, put, &a, err)
               : df_error_set(err, DF_ENOTFOUND, "stats: no device %llu",
                              (unsigned long long)device_id);
    if (rc == DF_OK) df_req_reply_stats(r, &a.st);
    free(a.st.items);
    return rc;
}

static int no_device(uint64_t id, const char *what, df_error *err)
{
    return df_error_set(err, DF_ENOTFOUND, "%s: no device %llu (no HID subsystem)", what,
                        (unsigned long long)id);
}

int df_h_devices_list(df_req *r, const uint8_t *p, df_error *err)
{
    int rc = df_msg_empty_decode(p, r->len, err);
    if (rc != DF_OK) return rc;
    df_msg_device_list l;
    memset(&l, 0, sizeof l);
    if (r->srv->hid_ops && (rc = r->srv->hid_ops->list(r->srv, &l, err)) != DF_OK) return rc;
    df_req_reply_device_list(r, &l);
    df_msg_device_list_free(&l);
    return DF_OK;
}

int df_h_device_bind(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_device_bind m;
    int rc = df_msg_device_bind_decode(p, r->len, &m, err);
    if (rc == DF_OK)
        rc = r->srv->hid_ops ? r->srv->hid_ops->bind(r->srv, m.device_id, m.session_id, err)
                             : no_device(m.device_id, "device_bind", err);
    if (rc == DF_OK) df_req_reply_empty(r);
    return rc;
}

int df_h_device_view(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_device_view m;
    int rc = df_msg_device_view_decode(p, r->len, &m, err);
    if (rc == DF_OK)
        rc = r->srv->hid_ops ? r->srv->hid_ops->view(r->srv, &m, err)
                             : no_device(m.device_id, "device_view", err);
    if (rc == DF_OK) df_req_reply_empty(r);
    return rc;
}

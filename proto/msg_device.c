/* msg_device.c — device (HID) bodies (messages.h, PROTOCOL.md 4.30..4.33).
 * device_info: u64 device_id, u8 class, u8 backend, u8 state, u8 bus, u16 vid, u16 pid,
 *              u64 bound_session, u64 active_session, u8 haptics, str name, str path,
 *              str error                                        (33 bytes + 3 strings)
 * device_list: u32 count, count x device_info
 * device_bind: u64 device_id, u64 session_id                    (16 bytes)
 * device_view: u64 device_id, u64 session_id, 16 f64 view_proj, 4 f64 viewport (176 bytes) */
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define INFO_FIXED 33u                 /* bytes before the strings */
#define INFO_MIN_SIZE (INFO_FIXED + 6) /* three empty strings */

static int info_check(const df_msg_device_info *m, df_error *err)
{
    if (m->device_id == 0)
        return df_error_set(err, DF_EINVAL, "device_info: device_id 0 is not a device");
    if (m->dev_class > DF_DEVCLASS_MAX)
        return df_error_set(err, DF_EINVAL, "device_info: class %u not in 0..%d", m->dev_class,
                            DF_DEVCLASS_MAX);
    if (m->backend < 1 || m->backend > DF_DEVBACKEND_MAX)
        return df_error_set(err, DF_EINVAL, "device_info: backend %u not in 1..%d", m->backend,
                            DF_DEVBACKEND_MAX);
    if (m->state < 1 || m->state > DF_DEVSTATE_MAX)
        return df_error_set(err, DF_EINVAL, "device_info: state %u not in 1..%d", m->state,
                            DF_DEVSTATE_MAX);
    if (m->haptics > 1)
        return df_error_set(err, DF_EINVAL, "device_info: haptics %u not 0/1", m->haptics);
    int rc = df_check_str(m->name, DF_MAX_NAME_LEN, "device_info", "name", err);
    if (!rc) rc = df_check_str(m->path, DF_MAX_PATH_LEN, "device_info", "path", err);
    if (!rc) rc = df_check_str(m->error, DF_MAX_ERROR_MSG_LEN, "device_info", "error", err);
    return rc;
}

static size_t info_size(const df_msg_device_info *m)
{
    return INFO_FIXED + df_str_size(m->name) + df_str_size(m->path) + df_str_size(m->error);
}

static void info_put(df_buf *out, const df_msg_device_info *m)
{
    df_buf_put_u64(out, m->device_id);
    df_buf_put_u8(out, m->dev_class);
    df_buf_put_u8(out, m->backend);
    df_buf_put_u8(out, m->state);
    df_buf_put_u8(out, m->bus);
    df_buf_put_u16(out, m->vid);
    df_buf_put_u16(out, m->pid);
    df_buf_put_u64(out, m->bound_session);
    df_buf_put_u64(out, m->active_session);
    df_buf_put_u8(out, m->haptics);
    df_put_str(out, m->name);
    df_put_str(out, m->path);
    df_put_str(out, m->error);
}

static void info_get(df_rd *r, df_msg_device_info *t)
{
    t->device_id = df_rd_u64(r, "device_id");
    t->dev_class = df_rd_u8(r, "class");
    t->backend = df_rd_u8(r, "backend");
    t->state = df_rd_u8(r, "state");
    t->bus = df_rd_u8(r, "bus");
    t->vid = df_rd_u16(r, "vid");
    t->pid = df_rd_u16(r, "pid");
    t->bound_session = df_rd_u64(r, "bound_session");
    t->active_session = df_rd_u64(r, "active_session");
    t->haptics = df_rd_u8(r, "haptics");
    df_rd_str(r, t->name, DF_MAX_NAME_LEN, "name");
    df_rd_str(r, t->path, DF_MAX_PATH_LEN, "path");
    df_rd_str(r, t->error, DF_MAX_ERROR_MSG_LEN, "error");
}

int df_msg_device_info_encode(const df_msg_device_info *m, df_buf *out, df_error *err)
{
    int rc = info_check(m, err);
    if (rc || (rc = df_enc_reserve(out, info_size(m), "device_info", err)))
        return rc;
    info_put(out, m);
    return DF_OK;
}

int df_msg_device_info_decode(const uint8_t *p, size_t n, df_msg_device_info *m, df_error *err)
{
    df_rd r;
    df_msg_device_info *t = malloc(sizeof *t); /* ~4.6 KB: not on the stack */
    if (!t)
        return df_error_set(err, DF_ENOMEM, "device_info: out of memory");
    df_rd_init(&r, p, n, "device_info", err);
    info_get(&r, t);
    int rc = df_rd_end(&r);
    if (!rc)
        rc = info_check(t, err);
    if (!rc)
        *m = *t;
    free(t);
    return rc;
}

/* A device_info in a list (the index is not part of its error text). */
static int item_check(const df_msg_device_info *m, uint32_t i, df_error *err)
{
    (void)i;
    return info_check(m, err);
}

DF_LIST_CODEC_DEFINE(device_list, df_msg_device_list, df_msg_device_info, DEVICE_LIST,
                     "device_list", "devices", DF_MAX_DEVICES, INFO_MIN_SIZE, item_check,
                     info_size, info_put, info_get)

void df_msg_device_list_free(df_msg_device_list *m)
{
    if (!m)
        return;
    free(m->items);
    m->items = NULL;
    m->count = 0;
}

/* ---- device_bind: u64 device_id, u64 session_id (0 = unbind) */
static int bind_check(const df_msg_device_bind *m, df_error *err)
{
    if (m->device_id == 0)
        return df_error_set(err, DF_EINVAL, "device_bind: device_id 0 is not a device");
    return DF_OK;
}

int df_msg_device_bind_encode(const df_msg_device_bind *m, df_buf *out, df_error *err)
{
    int rc = bind_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 16, "device_bind", err)))
        return rc;
    df_buf_put_u64(out, m->device_id);
    df_buf_put_u64(out, m->session_id);
    return DF_OK;
}

int df_msg_device_bind_decode(const uint8_t *p, size_t n, df_msg_device_bind *m, df_error *err)
{
    df_rd r;
    df_msg_device_bind t;
    df_rd_init(&r, p, n, "device_bind", err);
    t.device_id = df_rd_u64(&r, "device_id");
    t.session_id = df_rd_u64(&r, "session_id");
    int rc = df_rd_end(&r);
    if (rc || (rc = bind_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- device_view: u64 device_id, u64 session_id, 16 f64 view_proj, 4 f64 viewport */
static int view_check(const df_msg_device_view *m, df_error *err)
{
    if (m->device_id == 0)
        return df_error_set(err, DF_EINVAL, "device_view: device_id 0 is not a device");
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "device_view: session_id 0 is not a session");
    int rc = df_check_finite(m->view_proj, 16, "device_view", "view_proj", err);
    if (!rc) rc = df_check_finite(m->viewport, 4, "device_view", "viewport", err);
    if (!rc && !(m->viewport[2] > 0 && m->viewport[3] > 0))
        rc = df_error_set(err, DF_EINVAL, "device_view: viewport width %g x height %g is not "
                          "positive", m->viewport[2], m->viewport[3]);
    return rc;
}

int df_msg_device_view_encode(const df_msg_device_view *m, df_buf *out, df_error *err)
{
    int rc = view_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 176, "device_view", err)))
        return rc;
    df_buf_put_u64(out, m->device_id);
    df_buf_put_u64(out, m->session_id);
    for (int i = 0; i < 16; i++)
        df_buf_put_f64(out, m->view_proj[i]);
    for (int i = 0; i < 4; i++)
        df_buf_put_f64(out, m->viewport[i]);
    return DF_OK;
}

int df_msg_device_view_decode(const uint8_t *p, size_t n, df_msg_device_view *m, df_error *err)
{
    df_rd r;
    df_msg_device_view t;
    df_rd_init(&r, p, n, "device_view", err);
    t.device_id = df_rd_u64(&r, "device_id");
    t.session_id = df_rd_u64(&r, "session_id");
    for (int i = 0; i < 16; i++)
        t.view_proj[i] = df_rd_f64(&r, "view_proj");
    for (int i = 0; i < 4; i++)
        t.viewport[i] = df_rd_f64(&r, "viewport");
    int rc = df_rd_end(&r);
    if (rc || (rc = view_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

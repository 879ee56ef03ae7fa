/* hid_source.c — the backend-independent helpers of the device-source seam (hid_source.h). */
#include "server/hid/hid_source.h"

#include <stdlib.h>
#include <string.h>

void df_hid_devinfo_free_list(df_hid_devinfo *list, size_t n)
{
    if (!list)
        return;
    for (size_t i = 0; i < n; i++)
        free(list[i].desc);
    free(list);
}

int df_hid_devinfo_copy(df_hid_devinfo *dst, const df_hid_devinfo *src, df_error *err)
{
    if (!dst || !src)
        return df_error_set(err, DF_EINVAL, "hid devinfo copy: NULL argument");
    uint8_t *desc = NULL;
    if (src->desc && src->desc_len > 0) {
        desc = malloc(src->desc_len);
        if (!desc)
            return df_error_set(err, DF_ENOMEM, "hid devinfo copy: out of memory (%zu bytes)",
                                src->desc_len);
        memcpy(desc, src->desc, src->desc_len);
    }
    *dst = *src;
    dst->desc = desc;
    dst->desc_len = desc ? src->desc_len : 0;
    return DF_OK;
}

void df_hid_backend_destroy(df_hid_backend *b)
{
    if (b && b->destroy)
        b->destroy(b);
}

int df_hid_send_feature(df_hid_backend *b, df_hid_dev *d, const uint8_t *data, size_t len,
                        df_error *err)
{
    if (!b || !d) return df_error_set(err, DF_EINVAL, "hid: send_feature: NULL device");
    if (!b->send_feature)
        return df_error_set(err, DF_EUNSUPPORTED, "hid: the %s backend sends no feature reports",
                            b->name ? b->name : "?");
    return b->send_feature(d, data, len, err);
}

int df_hid_get_feature(df_hid_backend *b, df_hid_dev *d, uint8_t *buf, size_t cap,
                       df_error *err)
{
    if (!b || !d) return df_error_set(err, DF_EINVAL, "hid: get_feature: NULL device");
    if (!b->get_feature)
        return df_error_set(err, DF_EUNSUPPORTED, "hid: the %s backend reads no feature reports",
                            b->name ? b->name : "?");
    return b->get_feature(d, buf, cap, err);
}

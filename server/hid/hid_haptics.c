/* hid_haptics.c — Haptics page output reports from the descriptor: see hid_haptics.h. */
#include "server/hid/hid_haptics.h"

#include <string.h>

#define HAP(id) ((uint32_t)0x0E << 16 | (uint32_t)(id))
enum { H_WAVEFORM_LIST = 0x10, H_MANUAL_TRIGGER = 0x21, H_INTENSITY = 0x23, H_REPEAT = 0x24,
       H_RETRIGGER = 0x25, H_WAVE_NONE = 0x1001, H_WAVE_STOP = 0x1002, H_WAVE_LAST = 0x1fff };

/* The output variable-field element carrying `usage` in report `id` (-1: any), as a location. */
static int find_output(const df_hid_desc *d, uint32_t usage, int id, df_hid_loc *loc)
{
    return df_hid_loc_element(d, DF_HID_OUTPUT, usage, 0, id, 1, loc);
}

/* The Waveform List: ordinal fields (page 0x0A) of a 0x0E:0x10 collection with a constant
 * waveform usage in their physical (else logical) range. */
static void waveform_list(const df_hid_desc *d, df_hid_haptics *h)
{
    for (size_t i = 0; i < d->n_fields && h->n_waves < DF_HID_HAPTICS_MAX_WAVES; i++) {
        const df_hid_field *f = &d->fields[i];
        if (f->collection != HAP(H_WAVEFORM_LIST) || f->usage_min >> 16 != 0x0A) continue;
        if (f->usage_min != f->usage_max) continue; /* one ordinal per field */
        int64_t w = -1;
        if (f->physical_min == f->physical_max && f->physical_min > H_WAVE_STOP &&
            f->physical_min <= H_WAVE_LAST)
            w = f->physical_min;
        else if (f->logical_min == f->logical_max && f->logical_min > H_WAVE_STOP &&
                 f->logical_min <= H_WAVE_LAST)
            w = f->logical_min;
        uint32_t ordinal = f->usage_min & 0xffffu;
        if (w < 0 || ordinal < 3 || ordinal > 255) continue;
        h->wave_usage[h->n_waves] = (uint16_t)w;
        h->wave_index[h->n_waves] = (uint8_t)ordinal;
        h->n_waves++;
    }
}

int df_hid_haptics_init(const df_hid_desc *d, df_hid_haptics *h, df_error *err)
{
    if (!h) return df_error_set(err, DF_EINVAL, "hid haptics: NULL argument");
    memset(h, 0, sizeof *h);
    if (!d) return DF_OK;
    if (!find_output(d, HAP(H_MANUAL_TRIGGER), -1, &h->trigger)) return DF_OK;
    int id = h->trigger.report_id;
    const df_hid_report *r = df_hid_desc_report(d, DF_HID_OUTPUT, (unsigned)id);
    if (!r || r->bytes == 0 || r->bytes > DF_HID_MAX_REPORT_BYTES) {
        memset(h, 0, sizeof *h);
        return DF_OK;
    }
    h->present = 1;
    h->report_id = (uint8_t)id;
    h->report_bytes = r->bytes;
    find_output(d, HAP(H_REPEAT), id, &h->repeat);
    find_output(d, HAP(H_RETRIGGER), id, &h->retrigger);
    find_output(d, HAP(H_INTENSITY), id, &h->intensity);
    waveform_list(d, h);
    return DF_OK;
}

int df_hid_haptics_index(const df_hid_haptics *h, unsigned usage)
{
    if (!h || !h->present) return -1;
    if (usage == H_WAVE_NONE) return 1;
    if (usage == H_WAVE_STOP) return 2;
    for (int i = 0; i < h->n_waves; i++)
        if (h->wave_usage[i] == usage) return h->wave_index[i];
    return -1;
}

static void put_loc(uint8_t *buf, size_t n, const df_hid_loc *l, int64_t v)
{
    if (!l->present) return;
    if ((uint64_t)l->bit_offset + l->bit_size > (uint64_t)n * 8) return;
    if (l->logical_min <= l->logical_max) {
        if (v < l->logical_min) v = l->logical_min;
        if (v > l->logical_max) v = l->logical_max;
    }
    df_hid_put_bits(buf, l->bit_offset, l->bit_size, (uint64_t)v);
}

int df_hid_haptics_report(const df_hid_haptics *h, unsigned index, unsigned repeat,
                          unsigned retrigger_ms, uint8_t *out, size_t cap, size_t *n,
                          df_error *err)
{
    if (!h || !out || !n) return df_error_set(err, DF_EINVAL, "hid haptics: NULL argument");
    *n = 0;
    if (!h->present) return df_error_set(err, DF_EINVAL, "hid haptics: the device has none");
    if ((int64_t)index < h->trigger.logical_min || (int64_t)index > h->trigger.logical_max)
        return df_error_set(err, DF_EINVAL, "hid haptics: waveform index %u outside %lld..%lld",
                            index, (long long)h->trigger.logical_min,
                            (long long)h->trigger.logical_max);
    if (cap < h->report_bytes)
        return df_error_set(err, DF_ELIMIT, "hid haptics: report of %u bytes, buffer %zu",
                            h->report_bytes, cap);
    memset(out, 0, h->report_bytes);
    if (h->report_id) out[0] = h->report_id;
    put_loc(out, h->report_bytes, &h->trigger, (int64_t)index);
    put_loc(out, h->report_bytes, &h->repeat, (int64_t)repeat);
    put_loc(out, h->report_bytes, &h->retrigger, (int64_t)retrigger_ms);
    put_loc(out, h->report_bytes, &h->intensity, h->intensity.logical_max);
    *n = h->report_bytes;
    return DF_OK;
}

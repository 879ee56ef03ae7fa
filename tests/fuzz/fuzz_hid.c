/* libFuzzer target for server/hid: every input is parsed as a report descriptor (and, when it
 * parses, its first bytes as an input report decoded field by field) and as a hid-recorder text
 * recording, whose descriptors and events then go through the same parse and decode. Every
 * parsed descriptor is also classified (plain and under each quirk VID:PID) and, when it has a
 * class, fed through its mapper (zeroed reports of every input id, the input itself, an unplug)
 * and its haptic and PID force-feedback output reports built; the input is also fed as raw
 * PowerMate packets. Any inconsistency (a report longer than its limit, a field outside its
 * report, a decode that refuses a buffer of the report's own length, more actions than
 * DF_HID_MAX_ACTIONS, an output report of another length than its descriptor gives, a
 * non-finite or non-positive radius, an LED level outside 0..255) traps; sanitizers catch the
 * rest. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <math.h>

#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_ffb.h"
#include "server/hid/hid_haptics.h"
#include "server/hid/hid_mapper.h"
#include "server/hid/hid_recording.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void decode_all(const df_hid_desc *d, const uint8_t *buf, size_t n)
{
    const df_hid_report *r;
    if (df_hid_report_decode(d, buf, n, &r, NULL) != DF_OK) return;
    if (r->bytes > n || r->bytes > DF_HID_MAX_REPORT_BYTES) __builtin_trap();
    for (size_t i = r->first_field; i < r->first_field + r->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if ((uint64_t)f->bit_offset + (uint64_t)f->bit_size * f->count > (uint64_t)r->bytes * 8)
            __builtin_trap();
        for (unsigned j = 0; j < f->count && j < 64; j++) {
            int64_t v;
            int rc = df_hid_field_value(f, buf, n, j, &v, NULL);
            if (f->bit_size >= 1 && f->bit_size <= 32 && rc != DF_OK) __builtin_trap();
        }
    }
}

static void check_actions(const df_hid_action *a, size_t n)
{
    if (n > DF_HID_MAX_ACTIONS) __builtin_trap();
    for (size_t i = 0; i < n; i++) {
        if (a[i].n_bytes > DF_HID_ACT_BYTES_MAX) __builtin_trap();
        if (a[i].kind == DF_HID_ACT_BRUSH_SET && (a[i].mask & DF_HID_BS_RADIUS) &&
            !(isfinite(a[i].brush.radius) && a[i].brush.radius > 0))
            __builtin_trap();
        if (a[i].kind == DF_HID_ACT_LED && (a[i].led < 0 || a[i].led > 255)) __builtin_trap();
    }
}

/* Classify d (may be NULL) as vid:pid; when it has a class, feed the mapper. */
static void map_desc(const df_hid_desc *d, uint16_t vid, uint16_t pid, const uint8_t *report,
                     size_t rn)
{
    df_hid_class_info ci;
    if (df_hid_classify(d, vid, pid, &ci) != DF_OK || ci.cls == DF_HID_CLASS_NONE) return;
    df_hid_mapper m;
    if (df_hid_mapper_init(&m, &ci, d, NULL, NULL) != DF_OK) __builtin_trap();
    df_hid_brush b = {1, 1, 0.25, 0.45, 1.0};
    df_hid_action act[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    uint64_t t = 0;
    for (size_t i = 0; d && i < d->n_reports; i++) {
        const df_hid_report *r = &d->reports[i];
        if (r->kind != DF_HID_INPUT) continue;
        uint8_t *buf = calloc(1, r->bytes + 1);
        if (!buf) continue;
        buf[0] = d->uses_ids ? r->id : 0xff;
        if (df_hid_mapper_feed(&m, buf, r->bytes, t += 8000, &b, act, DF_HID_MAX_ACTIONS, &n,
                               NULL) == DF_OK)
            check_actions(act, n);
        free(buf);
    }
    for (int k = 0; k < 3 && report; k++) /* the input itself, three times (edges, dt) */
        if (df_hid_mapper_feed(&m, report, rn, t += 8000, &b, act, DF_HID_MAX_ACTIONS, &n, NULL) ==
            DF_OK)
            check_actions(act, n);
    if (df_hid_mapper_unplug(&m, act, DF_HID_MAX_ACTIONS, &n, NULL) != DF_OK) __builtin_trap();
    check_actions(act, n);
    df_hid_haptics h;
    if (df_hid_haptics_init(d, &h, NULL) != DF_OK) __builtin_trap();
    for (unsigned idx = 0; h.present && idx < 10; idx++) {
        uint8_t out[DF_HID_MAX_REPORT_BYTES];
        size_t on = 0;
        if (df_hid_haptics_report(&h, idx, idx, 80, out, sizeof out, &on, NULL) == DF_OK &&
            on != h.report_bytes)
            __builtin_trap();
    }
}

/* PID force-feedback reports: every builder either refuses or writes exactly its report. */
static void ffb_desc(const df_hid_desc *d)
{
    df_hid_ffb f;
    if (df_hid_ffb_init(d, &f, NULL) != DF_OK) __builtin_trap();
    uint8_t out[DF_HID_MAX_REPORT_BYTES];
    size_t n;
    df_hid_ffb_effect e = {1, 1000, 0.5, 1, 3, {90, 0}};
    if (df_hid_ffb_set_constant_effect(&f, &e, out, sizeof out, &n, NULL) == DF_OK &&
        n != f.effect.bytes)
        __builtin_trap();
    if (df_hid_ffb_constant_force(&f, 1, -0.5, out, sizeof out, &n, NULL) == DF_OK &&
        n != f.constant.bytes)
        __builtin_trap();
    if (df_hid_ffb_operation(&f, 1, DF_HID_PID_OP_START, 1, out, sizeof out, &n, NULL) == DF_OK &&
        n != f.operation.bytes)
        __builtin_trap();
    (void)df_hid_ffb_device_control(&f, DF_HID_PID_ENABLE_ACTUATORS, out, sizeof out, &n, NULL);
    (void)df_hid_ffb_device_gain(&f, 1.0, out, sizeof out, &n, NULL);
}

static void check_desc(const uint8_t *desc, size_t n, const uint8_t *report, size_t rn)
{
    df_hid_desc d;
    if (df_hid_desc_parse(desc, n, &d, NULL) != DF_OK) return;
    for (size_t i = 0; i < d.n_reports; i++) {
        const df_hid_report *r = &d.reports[i];
        if (r->bytes > DF_HID_MAX_REPORT_BYTES || r->first_field + r->n_fields > d.n_fields)
            __builtin_trap();
        if (r->kind != DF_HID_INPUT) continue;
        uint8_t *buf = calloc(1, r->bytes + 1); /* a zeroed report of the right length decodes */
        if (!buf) continue;
        buf[0] = d.uses_ids ? r->id : 0;
        decode_all(&d, buf, r->bytes);
        free(buf);
    }
    const df_hid_field *f;
    unsigned idx;
    (void)df_hid_find_input_usage(&d, 0x01, 0x37, &f, &idx, NULL);
    if (report) decode_all(&d, report, rn);
    static const uint16_t ids[][2] = {{0x1209, 0x0001}, {0x046d, 0xc626}, {0x256c, 0x0069},
                                      {0x256c, 0x8251}, {0x077d, 0x0410}};
    for (size_t k = 0; k < sizeof ids / sizeof ids[0]; k++)
        map_desc(&d, ids[k][0], ids[k][1], report, rn);
    ffb_desc(&d);
    df_hid_desc_free(&d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check_desc(data, size, data, size);
    df_hid_recording rec;
    if (df_hid_recording_parse((const char *)data, size, &rec, NULL) == DF_OK) {
        for (size_t i = 0; i < rec.n_events && i < 64; i++) {
            const df_hid_rec_event *e = &rec.events[i];
            const df_hid_rec_device *dev = &rec.devices[e->device];
            if (e->device >= rec.n_devices || !dev->desc) __builtin_trap();
            check_desc(dev->desc, dev->desc_len, df_hid_rec_event_bytes(&rec, e), e->len);
        }
        for (size_t k = 0; k < rec.n_devices; k++)
            if (rec.devices[k].desc) check_desc(rec.devices[k].desc, rec.devices[k].desc_len, NULL, 0);
        df_hid_recording_free(&rec);
    }
    map_desc(NULL, 0x077d, 0x0410, data, size); /* raw PowerMate packets */
    int64_t v;
    if (size >= 2) (void)df_hid_extract(data, size, data[0], (unsigned)(data[1] % 34), data[0] & 1, &v, NULL);
    return 0;
}

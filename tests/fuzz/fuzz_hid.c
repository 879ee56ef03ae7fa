/* libFuzzer target for server/hid: every input is parsed as a report descriptor (and, when it
 * parses, its first bytes as an input report decoded field by field) and as a hid-recorder text
 * recording, whose descriptors and events then go through the same parse and decode. Any
 * inconsistency (a report longer than its limit, a field outside its report, a decode that refuses
 * a buffer of the report's own length) traps; sanitizers catch the rest. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "server/hid/hid_desc.h"
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
    int64_t v;
    if (size >= 2) (void)df_hid_extract(data, size, data[0], (unsigned)(data[1] % 34), data[0] & 1, &v, NULL);
    return 0;
}

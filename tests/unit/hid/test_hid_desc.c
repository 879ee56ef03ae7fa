/* Unit tests for server/hid/hid_desc.c (issue 11, Devices): every .hid file of the shared HID
 * folder parses and every recorded report has the input length its descriptor gives; values
 * decoded by hand from ../shared/hid/README.md "Report layouts"; malformed descriptors refused. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <cmocka.h>

#include "server/hid/hid_desc.h"
#include "server/hid/hid_recording.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"

/* Loads `name` from the HID folder into rec (skips when the folder is missing). */
static void load(const char *name, df_hid_recording *rec)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, name, &n);
    if (!text) fail_msg("cannot read %s/%s", dir, name);
    df_error e;
    int rc = df_hid_recording_parse(text, n, rec, &e);
    free(text);
    if (rc != DF_OK) fail_msg("%s: %s", name, e.msg);
}

static void parse_dev(const df_hid_recording *rec, unsigned dev, df_hid_desc *d)
{
    df_error e;
    assert_true(dev < rec->n_devices);
    int rc = df_hid_desc_parse(rec->devices[dev].desc, rec->devices[dev].desc_len, d, &e);
    if (rc != DF_OK) fail_msg("device %u: %s", dev, e.msg);
}

static void test_every_file(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    DIR *dh = opendir(dir);
    assert_non_null(dh);
    int files = 0;
    size_t events = 0;
    struct dirent *ent;
    while ((ent = readdir(dh))) {
        size_t l = strlen(ent->d_name);
        if (l < 5 || strcmp(ent->d_name + l - 4, ".hid") != 0) continue;
        df_hid_recording rec;
        load(ent->d_name, &rec);
        assert_true(rec.n_devices > 0);
        df_hid_desc *descs = calloc(rec.n_devices, sizeof *descs);
        assert_non_null(descs);
        for (unsigned k = 0; k < rec.n_devices; k++) {
            assert_non_null(rec.devices[k].desc);
            parse_dev(&rec, k, &descs[k]);
            assert_true(descs[k].n_reports > 0);
        }
        for (size_t i = 0; i < rec.n_events; i++) {
            const df_hid_rec_event *ev = &rec.events[i];
            const uint8_t *b = df_hid_rec_event_bytes(&rec, ev);
            const df_hid_report *r = NULL;
            df_error e;
            if (df_hid_report_decode(&descs[ev->device], b, ev->len, &r, &e) != DF_OK)
                fail_msg("%s event %zu: %s", ent->d_name, i, e.msg);
            if (r->bytes != ev->len)
                fail_msg("%s event %zu: %zu bytes, descriptor gives %u for report %u", ent->d_name,
                         i, ev->len, r->bytes, r->id);
            for (size_t f = r->first_field; f < r->first_field + r->n_fields; f++) {
                const df_hid_field *fd = &descs[ev->device].fields[f];
                if (fd->bit_size > 32) continue;
                for (unsigned j = 0; j < fd->count; j++) {
                    int64_t v;
                    assert_int_equal(df_hid_field_value(fd, b, ev->len, j, &v, &e), DF_OK);
                }
            }
            events++;
        }
        for (unsigned k = 0; k < rec.n_devices; k++) df_hid_desc_free(&descs[k]);
        free(descs);
        df_hid_recording_free(&rec);
        files++;
    }
    closedir(dh);
    printf("parsed %d .hid files, %zu events\n", files, events);
    assert_true(files >= 14);
    assert_true(events >= 2800);
}

static int64_t value(const df_hid_field *f, const char *hex, unsigned index)
{
    uint8_t b[64];
    size_t n = 0;
    for (const char *s = hex; *s && n < sizeof b; ) {
        unsigned v;
        int used;
        if (sscanf(s, "%2x%n", &v, &used) != 1) break;
        b[n++] = (uint8_t)v;
        s += used;
        while (*s == ' ') s++;
    }
    int64_t out;
    df_error e;
    if (df_hid_field_value(f, b, n, index, &out, &e) != DF_OK) fail_msg("%s", e.msg);
    return out;
}

static void test_k20_puck(void **state)
{
    (void)state;
    df_hid_recording rec;
    load("huion-keydial-k20_256c-0069_usb_firmware-mode.hid", &rec);
    assert_int_equal(rec.n_devices, 3);
    assert_int_equal(rec.devices[2].desc_len, 108);
    assert_int_equal(rec.devices[1].desc_len, 135);
    assert_int_equal(rec.devices[2].vid, 0x256c);
    assert_int_equal(rec.devices[2].pid, 0x0069);
    assert_string_equal(rec.devices[2].name, "HUION Huion Keydial_K20");
    df_hid_desc d;
    parse_dev(&rec, 2, &d);
    const df_hid_field *f;
    unsigned idx;
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x37, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->report_id, 17);
    assert_int_equal(f->bit_offset, 16);
    assert_int_equal(f->bit_size, 16);
    assert_true(f->is_signed);
    assert_true(f->flags & DF_HID_F_RELATIVE);
    assert_true(f->flags & DF_HID_F_VARIABLE);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 17)->bytes, 9);
    assert_int_equal(value(f, "11 00 01 00 00 00 00 00 00", idx), 1);
    assert_int_equal(value(f, "11 00 ff ff 00 00 00 00 00", idx), -1);
    assert_int_equal(df_hid_find_input_usage(&d, 0x09, 0x01, &f, &idx, NULL), DF_OK); /* Button 1 */
    assert_int_equal(f->bit_offset + idx * f->bit_size, 8);
    assert_int_equal(value(f, "11 03 00 00 00 00 00 00 00", idx), 1);
    df_hid_desc_free(&d);
    parse_dev(&rec, 1, &d); /* report 3 boot keyboard 8 B, 4 consumer 3 B, 5 mouse 7 B */
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 3)->bytes, 8);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 4)->bytes, 3);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 5)->bytes, 7);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

static void test_spacenavigator(void **state)
{
    (void)state;
    df_hid_recording rec;
    load("3dconnexion-spacenavigator_046d-c626_usb.hid", &rec);
    df_hid_desc d;
    parse_dev(&rec, 0, &d);
    assert_int_equal(rec.devices[0].desc_len, 217);
    static const struct { uint16_t usage; unsigned id, off; } axes[] = {
        {0x30, 1, 8}, {0x31, 1, 24}, {0x32, 1, 40}, {0x33, 2, 8}, {0x34, 2, 24}, {0x35, 2, 40},
    };
    for (int k = 0; k < 6; k++) {
        const df_hid_field *f;
        unsigned idx;
        assert_int_equal(df_hid_find_input_usage(&d, 0x01, axes[k].usage, &f, &idx, NULL), DF_OK);
        assert_int_equal(f->report_id, axes[k].id);
        assert_int_equal(f->bit_offset + idx * f->bit_size, axes[k].off);
        assert_int_equal(f->bit_size, 16);
        assert_true(f->is_signed);
        assert_int_equal(f->logical_min, -350);
        assert_int_equal(f->logical_max, 350);
        assert_int_equal(f->application, 0x00010008); /* Multi-axis Controller */
    }
    const df_hid_field *f;
    unsigned idx;
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x34, &f, &idx, NULL), DF_OK); /* Ry */
    assert_int_equal(value(f, "02 00 00 e2 ff 00 00", idx), -30);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x30, &f, &idx, NULL), DF_OK); /* X */
    assert_int_equal(value(f, "01 05 00 00 00 fd ff", idx), 5);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x32, &f, &idx, NULL), DF_OK); /* Z */
    assert_int_equal(value(f, "01 05 00 00 00 fd ff", idx), -3);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 3)->bytes, 3);
    assert_non_null(df_hid_desc_report(&d, DF_HID_OUTPUT, 4));
    assert_int_equal(df_hid_desc_report(&d, DF_HID_OUTPUT, 4)->bytes, 2);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

static void test_surface_dial_haptics(void **state)
{
    (void)state;
    df_hid_recording rec;
    load("microsoft-surface-dial_045e-091b_bt.hid", &rec);
    df_hid_desc d;
    parse_dev(&rec, 0, &d);
    assert_int_equal(rec.devices[0].desc_len, 488);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 1)->bytes, 9);
    const df_hid_report *out = df_hid_desc_report(&d, DF_HID_OUTPUT, 1);
    assert_non_null(out);
    assert_int_equal(out->bytes, 5);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_FEATURE, 1)->bytes, 8);
    int haptic = 0;
    for (size_t i = out->first_field; i < out->first_field + out->n_fields; i++)
        if (d.fields[i].usage_min >> 16 == 0x0E && d.fields[i].collection >> 16 == 0x0E) haptic++;
    assert_true(haptic >= 2); /* Repeat Count, Manual Trigger, Retrigger Period */
    const df_hid_field *f;
    unsigned idx;
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x37, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->bit_offset + idx * f->bit_size, 16);
    assert_true(f->is_signed && (f->flags & DF_HID_F_RELATIVE));
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

static void test_sidewinder(void **state)
{
    (void)state;
    df_hid_recording rec;
    load("microsoft-sidewinder-ff2_045e-001b_usb.hid", &rec);
    assert_int_equal(rec.devices[0].desc_len, 1343);
    df_hid_desc d;
    parse_dev(&rec, 0, &d);
    const df_hid_field *f;
    unsigned idx;
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x30, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->bit_size, 10);
    assert_int_equal(f->bit_offset + idx * f->bit_size, 8);
    assert_true(f->is_signed);
    assert_int_equal(value(f, "01 ff 03 00 00 00 00 00 00 00 00 00 00", idx), -1);
    assert_int_equal(value(f, "01 ff 01 00 00 00 00 00 00 00 00 00 00", idx), 511);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 1)->bytes, 13);
    assert_int_equal(df_hid_desc_report(&d, DF_HID_INPUT, 2)->bytes, 3);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

static int parse(const uint8_t *b, size_t n, df_error *e)
{
    df_hid_desc d;
    int rc = df_hid_desc_parse(b, n, &d, e);
    df_hid_desc_free(&d);
    return rc;
}

#define REFUSE(code, text, ...) do { \
        static const uint8_t b_[] = {__VA_ARGS__}; \
        df_error e_; \
        assert_int_equal(parse(b_, sizeof b_, &e_), code); \
        if (!strstr(e_.msg, text)) fail_msg("message '%s' lacks '%s'", e_.msg, text); \
    } while (0)

static void test_malformed(void **state)
{
    (void)state;
    REFUSE(DF_EFORMAT, "byte 2: truncated item 0x26", 0x05, 0x01, 0x26, 0xff);
    REFUSE(DF_EFORMAT, "byte 0: truncated long item", 0xfe, 0x04, 0x00, 0x01);
    REFUSE(DF_EFORMAT, "1 collection(s) not closed", 0x05, 0x01, 0x09, 0x02, 0xa1, 0x01);
    REFUSE(DF_EFORMAT, "byte 0: End Collection without", 0xc0);
    REFUSE(DF_EFORMAT, "byte 2: Pop without a Push", 0x05, 0x01, 0xb4);
    REFUSE(DF_EFORMAT, "1 Push(es) without a Pop", 0xa4);
    REFUSE(DF_EFORMAT, "report id 0", 0x85, 0x00);
    REFUSE(DF_EFORMAT, "usage minimum 0x10003 above maximum 0x10001", 0x05, 0x01, 0x19, 0x03, 0x29, 0x01);
    REFUSE(DF_ELIMIT, "byte 7: report count 65536 > 32768",
           0x75, 0x01, 0x97, 0x00, 0x00, 0x01, 0x00, 0x81, 0x02);
    REFUSE(DF_ELIMIT, "report size 4096 bits > 256", 0x76, 0x00, 0x10, 0x95, 0x01, 0x81, 0x02);
    REFUSE(DF_ELIMIT, "report 1 longer than 8192 bytes",
           0x85, 0x01, 0x75, 0x08, 0x96, 0x00, 0x20, 0x81, 0x02);
    uint8_t deep[2 * (DF_HID_MAX_COLLECTIONS + 1)];
    for (size_t i = 0; i < sizeof deep; i += 2) { deep[i] = 0xa1; deep[i + 1] = 0x00; }
    df_error e;
    assert_int_equal(parse(deep, sizeof deep, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "nested deeper than 64"));
    assert_int_equal(parse(NULL, 0, &e), DF_OK);
}

static void test_items(void **state)
{
    (void)state;
    /* long item skipped; push/pop restore the page; extended usage; usage range as a variable run;
     * an array; a constant pad; report ids and the byte length with the id byte */
    static const uint8_t b[] = {
        0xfe, 0x02, 0x10, 0xaa, 0xbb,                   /* long item */
        0x05, 0x01, 0x09, 0x04, 0xa1, 0x01,             /* Generic Desktop, Joystick, Application */
        0x85, 0x07,                                     /* Report ID 7 */
        0xa4, 0x05, 0x09, 0x19, 0x01, 0x29, 0x03,       /* Push, Button page, Buttons 1..3 */
        0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x81, 0x02, /* 3 x 1 bit variable */
        0x95, 0x05, 0x81, 0x03,                         /* 5 bit constant pad */
        0xb4,                                           /* Pop: page 1 again */
        0x0b, 0x31, 0x00, 0x01, 0x00,                   /* extended usage 0x0001:0x0031 (Y) */
        0x09, 0x30,                                     /* X */
        0x16, 0x00, 0xf8, 0x26, 0xff, 0x07, 0x75, 0x0c, 0x95, 0x02, 0x81, 0x06, /* 2 x s12 rel */
        0x55, 0x0e, 0x65, 0x11, 0x35, 0x00, 0x46, 0xe8, 0x03,      /* exp -2, unit cm, phys */
        0x05, 0x07, 0x19, 0x00, 0x2a, 0xff, 0x00, 0x15, 0x00, 0x26, 0xff, 0x00,
        0x75, 0x08, 0x95, 0x02, 0x81, 0x00,             /* keyboard array of 2 bytes */
        0xc0,
    };
    df_hid_desc d;
    df_error e;
    assert_int_equal(df_hid_desc_parse(b, sizeof b, &d, &e), DF_OK);
    assert_true(d.uses_ids);
    const df_hid_report *r = df_hid_desc_report(&d, DF_HID_INPUT, 7);
    assert_non_null(r);
    assert_int_equal(r->bits, 8 + 24 + 16);
    assert_int_equal(r->bytes, 7);
    const df_hid_field *f;
    unsigned idx;
    assert_int_equal(df_hid_find_input_usage(&d, 0x09, 0x02, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->usage_min, 0x00090001);
    assert_int_equal(f->usage_max, 0x00090003);
    assert_int_equal(idx, 1);
    assert_int_equal(f->bit_offset, 8);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x31, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->bit_offset, 16);
    assert_int_equal(f->count, 1);
    assert_true(f->is_signed && (f->flags & DF_HID_F_RELATIVE));
    assert_int_equal(f->logical_min, -2048);
    assert_int_equal(f->logical_max, 2047);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x30, &f, &idx, NULL), DF_OK);
    assert_int_equal(f->bit_offset, 28);
    /* Y = -2048 (0x800), X = 2047 (0x7ff) across the byte boundary */
    static const uint8_t rep[] = {0x07, 0x05, 0x00, 0xf8, 0x7f, 0x04, 0x00};
    const df_hid_report *got;
    assert_int_equal(df_hid_report_decode(&d, rep, sizeof rep, &got, &e), DF_OK);
    assert_ptr_equal(got, r);
    int64_t v;
    assert_int_equal(df_hid_field_value(f, rep, sizeof rep, 0, &v, &e), DF_OK);
    assert_int_equal(v, 2047);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x31, &f, &idx, NULL), DF_OK);
    assert_int_equal(df_hid_field_value(f, rep, sizeof rep, 0, &v, &e), DF_OK);
    assert_int_equal(v, -2048);
    assert_int_equal(df_hid_find_input_usage(&d, 0x07, 0x04, &f, &idx, NULL), DF_OK);
    assert_false(f->flags & DF_HID_F_VARIABLE);
    assert_int_equal(f->count, 2);
    assert_int_equal(f->unit_exponent, -2);
    assert_int_equal(f->unit, 0x11);
    assert_int_equal(f->physical_max, 1000);
    assert_int_equal(f->logical_max, 255);
    assert_false(f->is_signed);
    assert_int_equal(f->application, 0x00010004);
    assert_int_equal(df_hid_field_value(f, rep, sizeof rep, 0, &v, &e), DF_OK);
    assert_int_equal(v, 4);
    assert_int_equal(df_hid_find_input_usage(&d, 0x01, 0x99, &f, &idx, &e), DF_ENOTFOUND);
    static const uint8_t shortrep[] = {0x07, 0x05};
    assert_int_equal(df_hid_report_decode(&d, shortrep, sizeof shortrep, &got, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "is 2 bytes, the descriptor gives 7"));
    static const uint8_t other[] = {0x09, 0x05};
    assert_int_equal(df_hid_report_decode(&d, other, sizeof other, &got, &e), DF_ENOTFOUND);
    df_hid_desc_free(&d);
}

static void test_extract(void **state)
{
    (void)state;
    static const uint8_t b[] = {0x78, 0x56, 0x34, 0x12, 0xff};
    int64_t v;
    df_error e;
    assert_int_equal(df_hid_extract(b, 5, 0, 32, 0, &v, &e), DF_OK);
    assert_int_equal(v, 0x12345678);
    assert_int_equal(df_hid_extract(b, 5, 8, 32, 0, &v, &e), DF_OK);
    assert_int_equal(v, 0xff123456);
    assert_int_equal(df_hid_extract(b, 5, 8, 32, 1, &v, &e), DF_OK);
    assert_int_equal(v, (int64_t)(int32_t)0xff123456u);
    assert_int_equal(df_hid_extract(b, 5, 4, 8, 0, &v, &e), DF_OK);
    assert_int_equal(v, 0x67);
    assert_int_equal(df_hid_extract(b, 5, 39, 1, 1, &v, &e), DF_OK);
    assert_int_equal(v, -1);
    assert_int_equal(df_hid_extract(b, 5, 36, 5, 0, &v, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "beyond the 5-byte report"));
    assert_int_equal(df_hid_extract(b, 5, 0, 33, 0, &v, &e), DF_EINVAL);
    assert_int_equal(df_hid_extract(b, 5, 0, 0, 0, &v, &e), DF_EINVAL);
    assert_int_equal(df_hid_extract(b, 5, 0xffffffffu, 32, 0, &v, &e), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_file),
        cmocka_unit_test(test_k20_puck),
        cmocka_unit_test(test_spacenavigator),
        cmocka_unit_test(test_surface_dial_haptics),
        cmocka_unit_test(test_sidewinder),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_items),
        cmocka_unit_test(test_extract),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

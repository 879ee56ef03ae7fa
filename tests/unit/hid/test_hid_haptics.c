/* Unit tests for server/hid/hid_haptics.c (issue 11, Haptics): the Surface Dial's output report
 * bytes equal a layout computed here by an independent walk of the raw descriptor bytes, the
 * README example `01 00 05 50 00`, the Waveform List indices, a hand-built haptic descriptor
 * without report ids whose list uses logical values, refusals, devices without haptics. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/hid/hid_action.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_haptics.h"
#include "server/hid/hid_recording.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"

/* A minimal walk of short items: for output report `want_id`, the bit offset and size of the
 * variable output element with usage page:id (first occurrence), and the ordinal whose physical
 * or logical value is waveform `wave` (Haptics page). Independent of hid_desc.c. */
typedef struct walk {
    int off[3], size[3];  /* Repeat Count 0x24, Manual Trigger 0x21, Retrigger Period 0x25 */
    int report_bytes;
    int ordinal;          /* of `wave`, -1 if none */
} walk;

static void walk_desc(const uint8_t *d, size_t n, unsigned want_id, unsigned wave, walk *w)
{
    static const unsigned want[3] = {0x24, 0x21, 0x25};
    memset(w, 0, sizeof *w);
    for (int k = 0; k < 3; k++) w->off[k] = -1;
    w->ordinal = -1;
    unsigned page = 0, rsize = 0, rcount = 0, rid = 0, usages[16], nu = 0;
    long lmin = 0, lmax = 0, pmin = 0, pmax = 0;
    unsigned out_bits = 0;
    for (size_t i = 0; i < n;) {
        uint8_t b = d[i];
        if (b == 0xfe) { i += 3 + (i + 1 < n ? d[i + 1] : 0); continue; }
        int sz = (b & 3) == 3 ? 4 : (b & 3);
        unsigned u = 0;
        for (int k = 0; k < sz; k++) u |= (unsigned)d[i + 1 + k] << (8 * k);
        long s = sz == 1 ? (long)(int8_t)u : sz == 2 ? (long)(int16_t)u : (long)(int32_t)u;
        switch (b & 0xfc) {
        case 0x04: page = u; break;
        case 0x14: lmin = s; break;
        case 0x24: lmax = sz == 4 ? s : (long)u; break;
        case 0x34: pmin = s; break;
        case 0x44: pmax = s; break;
        case 0x74: rsize = u; break;
        case 0x94: rcount = u; break;
        case 0x84: rid = u; break;
        case 0x08: if (nu < 16) usages[nu++] = page << 16 | u; break;
        case 0x90: /* Output */
            if (rid == want_id) {
                for (unsigned e = 0; e < rcount; e++) {
                    unsigned us = nu ? usages[e < nu ? e : nu - 1] : 0;
                    for (int k = 0; k < 3; k++)
                        if (us == (0x0Eu << 16 | want[k]) && w->off[k] < 0) {
                            w->off[k] = (int)(8 + out_bits + e * rsize);
                            w->size[k] = (int)rsize;
                        }
                }
                out_bits += rsize * rcount;
            }
            nu = 0;
            break;
        case 0xb0: /* Feature: a Waveform List entry is an Ordinal with a constant waveform */
            if (nu == 1 && usages[0] >> 16 == 0x0A && ((pmin == pmax && pmin == (long)wave) ||
                                                      (lmin == lmax && lmin == (long)wave)) &&
                w->ordinal < 0)
                w->ordinal = (int)(usages[0] & 0xffff);
            nu = 0;
            break;
        case 0x80: case 0xa0: case 0xc0: nu = 0; break;
        default: break;
        }
        i += 1 + (size_t)sz;
    }
    w->report_bytes = (int)((out_bits + 7) / 8 + (want_id ? 1 : 0));
}

static void put(uint8_t *buf, int off, int size, unsigned v)
{
    for (int b = 0; b < size; b++)
        if ((v >> b) & 1) buf[(off + b) / 8] |= (uint8_t)(1u << ((off + b) % 8));
}

static void load_dial(df_hid_recording *rec, df_hid_desc *d)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, "microsoft-surface-dial_045e-091b_bt.hid", &n);
    assert_non_null(text);
    assert_int_equal(df_hid_recording_parse(text, n, rec, NULL), DF_OK);
    free(text);
    assert_int_equal(df_hid_desc_parse(rec->devices[0].desc, rec->devices[0].desc_len, d, NULL),
                     DF_OK);
}

static void test_surface_dial(void **state)
{
    (void)state;
    df_hid_recording rec;
    df_hid_desc d;
    load_dial(&rec, &d);
    df_hid_haptics h;
    df_error e;
    assert_int_equal(df_hid_haptics_init(&d, &h, &e), DF_OK);
    assert_int_equal(h.present, 1);
    walk wc, wb;
    walk_desc(rec.devices[0].desc, rec.devices[0].desc_len, 1, DF_HID_WAVE_CLICK, &wc);
    walk_desc(rec.devices[0].desc, rec.devices[0].desc_len, 1, DF_HID_WAVE_BUZZ, &wb);
    assert_int_equal(h.report_id, 1);
    assert_int_equal((int)h.report_bytes, wc.report_bytes);
    for (int k = 0; k < 3; k++) assert_true(wc.off[k] >= 8);
    /* the waveform indices from the list */
    assert_true(wc.ordinal >= 3 && wb.ordinal >= 3);
    assert_int_equal(df_hid_haptics_index(&h, DF_HID_WAVE_CLICK), wc.ordinal);
    assert_int_equal(df_hid_haptics_index(&h, DF_HID_WAVE_BUZZ), wb.ordinal);
    assert_int_equal(df_hid_haptics_index(&h, 0x1001), 1); /* None */
    assert_int_equal(df_hid_haptics_index(&h, 0x1002), 2); /* Stop */
    assert_int_equal(df_hid_haptics_index(&h, 0x1007), -1); /* Release: not listed */
    /* click, repeated twice more, 80 ms apart: every field where the walk put it */
    uint8_t got[16], want[16];
    size_t n = 0;
    assert_int_equal(df_hid_haptics_report(&h, (unsigned)wc.ordinal, 2, 80, got, sizeof got, &n, &e),
                     DF_OK);
    assert_int_equal((int)n, wc.report_bytes);
    memset(want, 0, sizeof want);
    want[0] = 1;
    put(want, wc.off[0], wc.size[0], 2);
    put(want, wc.off[1], wc.size[1], (unsigned)wc.ordinal);
    put(want, wc.off[2], wc.size[2], 80);
    assert_memory_equal(got, want, n);
    /* the README's example bytes */
    const uint8_t readme[5] = {0x01, 0x00, 0x05, 0x50, 0x00};
    assert_int_equal(df_hid_haptics_report(&h, 5, 0, 0x50, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal(n, 5);
    assert_memory_equal(got, readme, 5);
    /* clamps to the logical ranges: repeat 0..255, retrigger 1..2000 */
    assert_int_equal(df_hid_haptics_report(&h, 3, 1000, 0, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal(got[1], 255);
    assert_int_equal(got[3] | got[4] << 8, 1);
    /* refusals */
    assert_int_equal(df_hid_haptics_report(&h, 0, 0, 80, got, sizeof got, &n, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "waveform index 0"));
    assert_int_equal(df_hid_haptics_report(&h, 8, 0, 80, got, sizeof got, &n, &e), DF_EINVAL);
    assert_int_equal(df_hid_haptics_report(&h, 3, 0, 80, got, 4, &n, &e), DF_ELIMIT);
    assert_int_equal(df_hid_haptics_report(NULL, 3, 0, 80, got, 4, &n, &e), DF_EINVAL);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

/* A haptic controller without report ids: Manual Trigger u8, Intensity u8 (0..100), Retrigger
 * u16; list: ordinal 3 = Click and ordinal 4 = Buzz as *logical* constants. */
static const uint8_t k_hand[] = {
    0x05, 0x0e, 0x09, 0x01, 0xa1, 0x01,
    0x15, 0x01, 0x25, 0x07, 0x75, 0x08, 0x95, 0x01, 0x09, 0x21, 0x91, 0x02,   /* trigger */
    0x15, 0x00, 0x25, 0x64, 0x09, 0x23, 0x91, 0x02,                           /* intensity */
    0x15, 0x01, 0x26, 0xd0, 0x07, 0x75, 0x10, 0x09, 0x25, 0x91, 0x02,        /* retrigger */
    0x09, 0x10, 0xa1, 0x02, 0x05, 0x0a, 0x75, 0x10,
    0x16, 0x03, 0x10, 0x26, 0x03, 0x10, 0x09, 0x03, 0xb1, 0x03,              /* 3 = click */
    0x16, 0x04, 0x10, 0x26, 0x04, 0x10, 0x09, 0x04, 0xb1, 0x03,              /* 4 = buzz */
    0xc0, 0xc0};

static void test_hand_built(void **state)
{
    (void)state;
    df_hid_desc d;
    df_error e;
    if (df_hid_desc_parse(k_hand, sizeof k_hand, &d, &e) != DF_OK) fail_msg("%s", e.msg);
    df_hid_haptics h;
    assert_int_equal(df_hid_haptics_init(&d, &h, &e), DF_OK);
    assert_int_equal(h.present, 1);
    assert_int_equal(h.report_id, 0);
    walk w;
    walk_desc(k_hand, sizeof k_hand, 0, DF_HID_WAVE_BUZZ, &w);
    assert_int_equal((int)h.report_bytes, w.report_bytes);
    assert_int_equal(df_hid_haptics_index(&h, DF_HID_WAVE_CLICK), 3);
    assert_int_equal(df_hid_haptics_index(&h, DF_HID_WAVE_BUZZ), w.ordinal);
    uint8_t got[8];
    size_t n = 0;
    assert_int_equal(df_hid_haptics_report(&h, 4, 5, 300, got, sizeof got, &n, &e), DF_OK);
    /* [trigger 4][intensity 100 = its logical max][retrigger 300 LE]; no repeat field */
    const uint8_t want[4] = {4, 100, 300 & 0xff, 300 >> 8};
    assert_int_equal(n, 4);
    assert_memory_equal(got, want, 4);
    df_hid_desc_free(&d);
}

static void test_no_haptics(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, "3dconnexion-spacenavigator_046d-c626_usb.hid", &n);
    assert_non_null(text);
    df_hid_recording rec;
    assert_int_equal(df_hid_recording_parse(text, n, &rec, NULL), DF_OK);
    free(text);
    df_hid_desc d;
    assert_int_equal(df_hid_desc_parse(rec.devices[0].desc, rec.devices[0].desc_len, &d, NULL), DF_OK);
    df_hid_haptics h;
    assert_int_equal(df_hid_haptics_init(&d, &h, NULL), DF_OK);
    assert_int_equal(h.present, 0); /* an LED output report is not haptics */
    assert_int_equal(df_hid_haptics_index(&h, DF_HID_WAVE_CLICK), -1);
    uint8_t b[8];
    assert_int_equal(df_hid_haptics_report(&h, 3, 0, 80, b, sizeof b, &n, NULL), DF_EINVAL);
    assert_int_equal(df_hid_haptics_init(NULL, &h, NULL), DF_OK);
    assert_int_equal(h.present, 0);
    assert_int_equal(df_hid_haptics_init(&d, NULL, NULL), DF_EINVAL);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_surface_dial),
        cmocka_unit_test(test_hand_built),
        cmocka_unit_test(test_no_haptics),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

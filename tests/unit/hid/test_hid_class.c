/* Unit tests for server/hid/hid_class.c (issue 11): the expected class of every node of every
 * file in the shared HID folder (classes by usage, quirks by VID:PID), a hand-built DIY knob
 * descriptor, a mouse whose wheel is not a knob, descriptors without the needed parts. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <cmocka.h>

#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_recording.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"

enum { N = DF_HID_CLASS_NONE, K = DF_HID_CLASS_KNOB, M = DF_HID_CLASS_MOUSE3D,
       P = DF_HID_CLASS_PEN };

typedef struct expect {
    const char *file;
    int n_nodes;
    int cls[4];          /* per D: node */
    unsigned quirks[4];
} expect;

/* Every .hid file of ../shared/hid (the test fails when a new file appears without a row). */
static const expect k_expect[] = {
    {"3dconnexion-spacemouse-wireless_256f-c62e_usb.hid", 1, {M}, {0}},
    {"3dconnexion-spacenavigator_046d-c626_usb.hid", 1, {M}, {DF_HID_QUIRK_AXES_ABSOLUTE}},
    {"goodix-gxtp-pen_27c6-0113_i2c.hid", 1, {P}, {0}},
    /* D:0 vendor node (descriptor is not the layout), D:1 pen, D:2 dial + keyboard */
    {"huion-dial-2_256c-0060_usb.hid", 3, {N, P, K}, {0, 0, DF_HID_QUIRK_DIAL_DETENTS}},
    /* D:0 vendor, D:1 keyboard + consumer + mouse (its wheel is a mouse wheel), D:2 puck */
    {"huion-keydial-k20_256c-0069_usb_firmware-mode.hid", 3, {N, N, K},
     {0, 0, DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_NO_RELEASE}},
    {"huion-keydial-k20_256c-0069_usb_vendor-mode.hid", 1, {N}, {0}},
    /* D:0 Dial (silent), D:1 mouse-shaped node whose wheel is the dial (quirk) */
    {"huion-keydial-k20_256c-8251_bt.hid", 2, {K, K},
     {DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_WHEEL_KNOB,
      DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_WHEEL_KNOB}},
    {"lenovo-miix2-sensor-hub_2047-0855_i2c.hid", 1, {N}, {0}},
    {"microsoft-sidewinder-ff2_045e-001b_usb.hid", 1, {N}, {0}},
    {"microsoft-surface-dial_045e-091b_bt.hid", 1, {K}, {0}},
    {"ntrig-duosense-pen_1b96-1000_usb.hid", 1, {P}, {0}},
    {"sony-ps3-controller_054c-0268_usb.hid", 1, {N}, {0}},
    {"wacom-intuos-pro-s_056a-0314_usb.hid", 1, {N}, {0}},
    /* a wheel sent as Ctrl+Keypad+/- key presses: a keyboard, not a knob */
    {"xppen-ack05-remote_28bd-0202_usb.hid", 1, {N}, {0}},
};
#define N_EXPECT (sizeof k_expect / sizeof k_expect[0])

static void classify_file(const char *dir, const expect *x)
{
    size_t n = 0;
    char *text = hid_read_file(dir, x->file, &n);
    if (!text) fail_msg("cannot read %s/%s", dir, x->file);
    df_hid_recording rec;
    df_error e;
    if (df_hid_recording_parse(text, n, &rec, &e) != DF_OK) fail_msg("%s: %s", x->file, e.msg);
    free(text);
    if ((int)rec.n_devices != x->n_nodes)
        fail_msg("%s: %zu nodes, expected %d", x->file, rec.n_devices, x->n_nodes);
    for (size_t k = 0; k < rec.n_devices; k++) {
        df_hid_desc d;
        const df_hid_rec_device *dev = &rec.devices[k];
        assert_int_equal(df_hid_desc_parse(dev->desc, dev->desc_len, &d, &e), DF_OK);
        df_hid_class_info ci;
        assert_int_equal(df_hid_classify(&d, (uint16_t)dev->vid, (uint16_t)dev->pid, &ci), DF_OK);
        if (ci.cls != x->cls[k] || ci.quirks != x->quirks[k])
            fail_msg("%s D:%zu: class %s quirks 0x%x (%s), expected %s quirks 0x%x", x->file, k,
                     df_hid_class_name(ci.cls), ci.quirks, ci.reason, df_hid_class_name(x->cls[k]),
                     x->quirks[k]);
        assert_true(ci.reason[0] != '\0');
        if (ci.cls == K) {
            assert_true(ci.ctl[DF_HID_CTL_DIAL].present && ci.ctl[DF_HID_CTL_DIAL].relative);
            assert_true(ci.ctl[DF_HID_CTL_BUTTON].present);
        } else if (ci.cls == M) {
            for (int a = 0; a < 6; a++) {
                assert_true(ci.ctl[DF_HID_CTL_X + a].present);
                assert_int_equal(ci.ctl[DF_HID_CTL_X + a].logical_max, 350);
                assert_int_equal(ci.ctl[DF_HID_CTL_X + a].relative, 0); /* quirk or Absolute */
            }
            assert_true(ci.ctl[DF_HID_CTL_BUTTON].present && ci.ctl[DF_HID_CTL_BUTTON2].present);
        } else if (ci.cls == P) {
            assert_true(ci.ctl[DF_HID_CTL_TIP].present && ci.ctl[DF_HID_CTL_PRESSURE].present);
            assert_true(ci.ctl[DF_HID_CTL_X].present && ci.ctl[DF_HID_CTL_Y].present);
            assert_true(ci.ctl[DF_HID_CTL_IN_RANGE].present && ci.ctl[DF_HID_CTL_BARREL].present);
        } else if (strstr(x->file, "wacom") || strstr(x->file, "vendor-mode")) {
            assert_non_null(strstr(ci.reason, "vendor-defined page")); /* said plainly */
        }
        df_hid_desc_free(&d);
    }
    df_hid_recording_free(&rec);
}

static void test_every_shared_file(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    for (size_t i = 0; i < N_EXPECT; i++) classify_file(dir, &k_expect[i]);
    /* every .hid file has a row */
    DIR *dh = opendir(dir);
    assert_non_null(dh);
    struct dirent *ent;
    while ((ent = readdir(dh))) {
        size_t l = strlen(ent->d_name);
        if (l < 5 || strcmp(ent->d_name + l - 4, ".hid") != 0) continue;
        int found = 0;
        for (size_t i = 0; i < N_EXPECT; i++) found |= strcmp(k_expect[i].file, ent->d_name) == 0;
        if (!found) fail_msg("%s has no expected class in this test", ent->d_name);
    }
    closedir(dh);
}

/* A home-made knob (rotary encoder + push button on a microcontroller) with a plain descriptor:
 * Generic Desktop / Dial, 8-bit relative, 1 button, 7 bits padding, no report id, an unknown
 * VID:PID. It must be a knob. */
static const uint8_t k_diy_knob[] = {
    0x05, 0x01, 0x09, 0x0e, 0xa1, 0x01,       /* Generic Desktop, System Multi-Axis, App */
    0x05, 0x09, 0x19, 0x01, 0x29, 0x01,       /* Button 1 */
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02,
    0x75, 0x07, 0x81, 0x03,                   /* padding */
    0x05, 0x01, 0x09, 0x37,                   /* Dial */
    0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95, 0x01, 0x81, 0x06, /* -127..127 relative */
    0xc0};

static void test_diy_knob(void **state)
{
    (void)state;
    df_hid_desc d;
    df_error e;
    assert_int_equal(df_hid_desc_parse(k_diy_knob, sizeof k_diy_knob, &d, &e), DF_OK);
    df_hid_class_info ci;
    assert_int_equal(df_hid_classify(&d, 0x1209, 0x0001, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_KNOB);
    assert_int_equal(ci.quirks, 0);
    assert_string_equal(df_hid_class_name(ci.cls), "knob");
    /* the report [buttons][dial]: button bit 0 of byte 0, dial s8 in byte 1 */
    const uint8_t r[2] = {0x01, 0xfd};
    int64_t v;
    assert_int_equal(df_hid_loc_read(&ci.ctl[DF_HID_CTL_BUTTON], r, 2, &v), 1);
    assert_int_equal(v, 1);
    assert_int_equal(df_hid_loc_read(&ci.ctl[DF_HID_CTL_DIAL], r, 2, &v), 1);
    assert_int_equal(v, -3);
    assert_int_equal(df_hid_loc_read(&ci.ctl[DF_HID_CTL_DIAL], r, 1, &v), 0); /* short */
    df_hid_desc_free(&d);
}

/* An ordinary mouse: X, Y, Wheel, 3 buttons. Its wheel is not a knob. */
static const uint8_t k_mouse[] = {
    0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x01, 0xa1, 0x00,
    0x05, 0x09, 0x19, 0x01, 0x29, 0x03, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x81, 0x02,
    0x75, 0x05, 0x95, 0x01, 0x81, 0x03,
    0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x09, 0x38, 0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95, 0x03,
    0x81, 0x06, 0xc0, 0xc0};

/* A dial without any button: not a knob by the rule (Dial/Wheel *with a button*). */
static const uint8_t k_dial_no_button[] = {
    0x05, 0x01, 0x09, 0x0e, 0xa1, 0x01, 0x09, 0x37, 0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95, 0x01,
    0x81, 0x06, 0xc0};

static void test_not_knobs(void **state)
{
    (void)state;
    df_hid_desc d;
    df_hid_class_info ci;
    assert_int_equal(df_hid_desc_parse(k_mouse, sizeof k_mouse, &d, NULL), DF_OK);
    assert_int_equal(df_hid_classify(&d, 0x046d, 0xc077, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_NONE);
    df_hid_desc_free(&d);
    assert_int_equal(df_hid_desc_parse(k_dial_no_button, sizeof k_dial_no_button, &d, NULL), DF_OK);
    assert_int_equal(df_hid_classify(&d, 0x1209, 0x0002, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_NONE);
    df_hid_desc_free(&d);
    /* no descriptor: NONE, unless the quirk table knows the device (PowerMate) */
    assert_int_equal(df_hid_classify(NULL, 0x1234, 0x5678, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_NONE);
    assert_non_null(strstr(ci.reason, "no report descriptor"));
    assert_int_equal(df_hid_classify(NULL, 0x077d, 0x0410, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_KNOB);
    assert_int_equal(ci.quirks, DF_HID_QUIRK_RAW_POWERMATE);
    const uint8_t pm[6] = {0x01, 0xfe, 0x00, 0x80, 0x10, 0x00};
    int64_t v;
    assert_int_equal(df_hid_loc_read(&ci.ctl[DF_HID_CTL_DIAL], pm, 6, &v), 1);
    assert_int_equal(v, -2);
    assert_int_equal(df_hid_loc_read(&ci.ctl[DF_HID_CTL_BUTTON], pm, 6, &v), 1);
    assert_int_equal(v, 1);
    assert_int_equal(df_hid_classify(NULL, 0, 0, NULL), DF_EINVAL);
}

static void test_names(void **state)
{
    (void)state;
    assert_string_equal(df_hid_class_name(DF_HID_CLASS_KNOB), "knob");
    assert_string_equal(df_hid_class_name(DF_HID_CLASS_MOUSE3D), "3d-mouse");
    assert_string_equal(df_hid_class_name(DF_HID_CLASS_PEN), "pen");
    assert_string_equal(df_hid_class_name(DF_HID_CLASS_NONE), "none");
    assert_string_equal(df_hid_class_name(42), "none");
    for (int c = 0; c < DF_HID_CLASS_COUNT; c++)
        assert_int_equal(df_hid_class_from_name(df_hid_class_name(c)), c);
    assert_int_equal(df_hid_class_from_name("mouse"), -1);
    assert_int_equal(df_hid_class_from_name(NULL), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_shared_file),
        cmocka_unit_test(test_diy_knob),
        cmocka_unit_test(test_not_knobs),
        cmocka_unit_test(test_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

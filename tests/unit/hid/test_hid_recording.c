/* Unit tests for server/hid/hid_recording.c: the hid-recorder text format (../shared/hid/README.md
 * "File format") from memory: several devices, comments, CRLF and trailing blanks, and refusals
 * naming the line. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/hid/hid_recording.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"

static int parse(const char *text, df_hid_recording *rec, df_error *e)
{
    return df_hid_recording_parse(text, strlen(text), rec, e);
}

static void test_two_devices(void **state)
{
    (void)state;
    static const char text[] =
        "# comment\n"
        "D: 0\n"
        "R: 3 05 01 c0\n"
        "N: Knob one\r\n"
        "P: usb-0000:00:14.0-1/input0\n"
        "I: 3 256c 0069\n"
        "\n"
        "D: 1\n"
        "R: 2 a1 01  \n"
        "N: Second\n"
        "I: 18 27c6 113\n"
        "E: 000001.000002 3 11 00 ff\n"
        "D: 0\n"
        "E: 12.5 1 0a\n"
        "#  trailing comment\n"
        "E: 000000.000000 0";
    df_hid_recording rec;
    df_error e;
    assert_int_equal(parse(text, &rec, &e), DF_OK);
    assert_int_equal(rec.n_devices, 2);
    assert_int_equal(rec.devices[0].desc_len, 3);
    assert_memory_equal(rec.devices[0].desc, "\x05\x01\xc0", 3);
    assert_string_equal(rec.devices[0].name, "Knob one");
    assert_string_equal(rec.devices[0].phys, "usb-0000:00:14.0-1/input0");
    assert_int_equal(rec.devices[0].bus, 3);
    assert_int_equal(rec.devices[0].vid, 0x256c);
    assert_int_equal(rec.devices[0].pid, 0x69);
    assert_int_equal(rec.devices[1].bus, 0x18);
    assert_int_equal(rec.devices[1].pid, 0x113);
    assert_int_equal(rec.devices[1].desc_len, 2);
    assert_int_equal(rec.n_events, 3);
    assert_int_equal(rec.events[0].device, 1);
    assert_int_equal(rec.events[0].time_us, 1000002);
    assert_int_equal(rec.events[0].len, 3);
    assert_memory_equal(df_hid_rec_event_bytes(&rec, &rec.events[0]), "\x11\x00\xff", 3);
    assert_int_equal(rec.events[1].device, 0);
    assert_int_equal(rec.events[1].time_us, 12500000);
    assert_int_equal(df_hid_rec_event_bytes(&rec, &rec.events[1])[0], 0x0a);
    assert_int_equal(rec.events[2].len, 0);
    df_hid_recording_free(&rec);
    df_hid_recording_free(&rec); /* zeroed: a second free is harmless */
}

#define REFUSE(code, text, what) do { \
        df_hid_recording r_; \
        df_error e_; \
        assert_int_equal(parse(text, &r_, &e_), code); \
        if (!strstr(e_.msg, what)) fail_msg("message '%s' lacks '%s'", e_.msg, what); \
        assert_int_equal(r_.n_devices, 0); \
    } while (0)

static void test_refusals(void **state)
{
    (void)state;
    REFUSE(DF_EFORMAT, "R: 3 05 01\n", "line 1: 2 bytes, 3 declared");
    REFUSE(DF_EFORMAT, "R: 1 05 01\n", "line 1: more than the 1 bytes declared");
    REFUSE(DF_EFORMAT, "# x\nR: 1 0g\n", "line 2: bad hex byte");
    REFUSE(DF_EFORMAT, "R: 1 105\n", "line 1: bad hex byte");
    REFUSE(DF_EFORMAT, "R: x 05\n", "line 1: bad byte count");
    REFUSE(DF_EFORMAT, "X: 1\n", "line 1: unknown line type 'X:'");
    REFUSE(DF_EFORMAT, "hello\n", "line 1: not a '<letter>:' line");
    REFUSE(DF_EFORMAT, "E: 0.0 1 00\n", "line 1: E: for device 0, which has no R: line");
    REFUSE(DF_EFORMAT, "R: 1 c0\nE: 0 1 00\n", "line 2: bad timestamp");
    REFUSE(DF_EFORMAT, "R: 1 c0\nE: 0.1234567 1 00\n", "line 2: bad timestamp");
    REFUSE(DF_EFORMAT, "R: 1 c0\nR: 1 c0\n", "line 2: second R: for device 0");
    REFUSE(DF_EFORMAT, "D: -1\n", "line 1: bad device index");
    REFUSE(DF_ELIMIT, "D: 64\n", "line 1: device 64 >= 64");
    REFUSE(DF_ELIMIT, "R: 70000\n", "line 1: 70000 bytes > 65536");
    REFUSE(DF_EFORMAT, "I: 3 256c\n", "line 1: bad I: line");
    df_hid_recording rec;
    assert_int_equal(df_hid_recording_parse(NULL, 0, &rec, NULL), DF_OK);
    assert_int_equal(rec.n_devices + rec.n_events, 0);
    assert_int_equal(df_hid_recording_parse("R: 1 c0", 3, &rec, NULL), DF_EFORMAT); /* cut short */
}

static void test_shared_file(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, "ntrig-duosense-pen_1b96-1000_usb.hid", &n);
    assert_non_null(text);
    df_hid_recording rec;
    df_error e;
    if (df_hid_recording_parse(text, n, &rec, &e) != DF_OK) fail_msg("%s", e.msg);
    assert_int_equal(rec.n_events, 1583);
    assert_int_equal(rec.devices[0].vid, 0x1b96);
    assert_int_equal(rec.devices[0].pid, 0x1000);
    for (size_t i = 1; i < rec.n_events; i++)
        assert_true(rec.events[i].time_us >= rec.events[i - 1].time_us);
    df_hid_recording_free(&rec);
    free(text);
}

/* DF_HID_REC_RAW: E: lines without an R: line (the PowerMate raw file) parse, desc stays NULL;
 * without the flag they are refused as before. */
static void test_raw_flag(void **state)
{
    (void)state;
    static const char text[] = "# raw\nE: 000000.024000 6 00 01 00 80 10 00\nD: 1\nE: 1.000001 1 ff\n";
    df_hid_recording rec;
    df_error e;
    assert_int_equal(df_hid_recording_parse(text, strlen(text), &rec, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "line 2"));
    assert_int_equal(df_hid_recording_parse_flags(text, strlen(text), DF_HID_REC_RAW, &rec, &e), DF_OK);
    assert_int_equal(rec.n_devices, 2);
    assert_null(rec.devices[0].desc);
    assert_null(rec.devices[1].desc);
    assert_int_equal(rec.n_events, 2);
    assert_int_equal(rec.events[0].device, 0);
    assert_int_equal(rec.events[0].time_us, 24000);
    assert_int_equal(rec.events[0].len, 6);
    assert_memory_equal(df_hid_rec_event_bytes(&rec, &rec.events[0]), "\x00\x01\x00\x80\x10\x00", 6);
    assert_int_equal(rec.events[1].device, 1);
    assert_int_equal(rec.events[1].time_us, 1000001);
    df_hid_recording_free(&rec);
    /* other refusals still apply with the flag */
    assert_int_equal(df_hid_recording_parse_flags("E: 1.0 2 00\n", 12, DF_HID_REC_RAW, &rec, &e),
                     DF_EFORMAT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_devices),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_shared_file),
        cmocka_unit_test(test_raw_flag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

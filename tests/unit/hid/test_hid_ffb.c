/* Unit tests for server/hid/hid_ffb.c (issue 11, optional force feedback): the SideWinder Force
 * Feedback 2's PID output reports built from its descriptor equal the example bytes written in
 * the file's trailing comments (read here from the file); direction and magnitude conversions;
 * devices without a PID page; refusals. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/hid/hid_ffb.h"
#include "tests/unit/hid/hid_replay.h"

#define SW "microsoft-sidewinder-ff2_045e-001b_usb.hid"

/* The bytes of the comment line of SW whose text after the hex contains `label`. */
static size_t example(const char *label, uint8_t *out, size_t cap)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, SW, &n);
    assert_non_null(text);
    text = realloc(text, n + 1);
    assert_non_null(text);
    text[n] = '\0';
    size_t k = 0;
    for (char *line = strtok(text, "\n"); line && !k; line = strtok(NULL, "\n")) {
        if (strncmp(line, "# ", 2) != 0 || !strstr(line, label)) continue;
        const char *p = line + 2;
        unsigned v;
        int used;
        while (k < cap && sscanf(p, "%2x%n", &v, &used) == 1 && used == 2 &&
               (p[2] == ' ' || p[2] == '\0')) {
            out[k++] = (uint8_t)v;
            p += 3;
        }
    }
    free(text);
    if (!k) fail_msg("no example '%s' in %s", label, SW);
    return k;
}

static void test_sidewinder_examples(void **state)
{
    (void)state;
    replay r;
    replay_load(SW, &r);
    assert_int_equal(r.ci[0].cls, DF_HID_CLASS_NONE); /* a joystick: no mapper class */
    df_hid_ffb f;
    df_error e;
    assert_int_equal(df_hid_ffb_init(&r.desc[0], &f, &e), DF_OK);
    assert_int_equal(f.present, 1);
    uint8_t want[32], got[32];
    size_t wn, n;

    wn = example("Device Control: DC Enable Actuators", want, sizeof want);
    assert_int_equal(df_hid_ffb_device_control(&f, DF_HID_PID_ENABLE_ACTUATORS, got, sizeof got,
                                               &n, &e), DF_OK);
    assert_int_equal(n, wn);
    assert_memory_equal(got, want, n);

    wn = example("Device Gain 255", want, sizeof want);
    assert_int_equal(df_hid_ffb_device_gain(&f, 1.0, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal(n, wn);
    assert_memory_equal(got, want, n);

    wn = example("Set Effect: block 1, ET Constant Force", want, sizeof want);
    df_hid_ffb_effect fx = {.block = 1, .duration_ms = 1000, .gain = 1.0, .trigger_button = 1,
                            .axes = 3, .direction_deg = {0, 0}};
    assert_int_equal(df_hid_ffb_set_constant_effect(&f, &fx, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal(n, wn);
    assert_memory_equal(got, want, n);

    wn = example("Set Constant Force: block 1, Magnitude +128", want, sizeof want);
    assert_int_equal(df_hid_ffb_constant_force(&f, 1, 128.0 / 255.0, got, sizeof got, &n, &e),
                     DF_OK);
    assert_int_equal(n, wn);
    assert_memory_equal(got, want, n);

    wn = example("Effect Operation: block 1, Op Effect Start", want, sizeof want);
    assert_int_equal(df_hid_ffb_operation(&f, 1, DF_HID_PID_OP_START, 1, got, sizeof got, &n, &e),
                     DF_OK);
    assert_int_equal(n, wn);
    assert_memory_equal(got, want, n);

    /* direction 90 degrees: physical 0..36000 (0.01 degree) onto logical 0..255 -> 64; the
     * magnitude's sign and clamp: -2 -> -255 */
    fx.direction_deg[0] = 90;
    fx.trigger_button = 0;
    assert_int_equal(df_hid_ffb_set_constant_effect(&f, &fx, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal(got[12], (uint8_t)lround(9000.0 * 255 / 36000));
    assert_int_equal(got[10], 0); /* no trigger button: the field's null */
    assert_int_equal(df_hid_ffb_constant_force(&f, 1, -2.0, got, sizeof got, &n, &e), DF_OK);
    assert_int_equal((int16_t)(got[2] | got[3] << 8), -255);
    /* refusals */
    assert_int_equal(df_hid_ffb_operation(&f, 1, 0x90, 1, got, sizeof got, &n, &e), DF_EINVAL);
    assert_int_equal(df_hid_ffb_device_control(&f, 0x50, got, sizeof got, &n, &e), DF_EINVAL);
    assert_int_equal(df_hid_ffb_set_constant_effect(&f, &fx, got, 4, &n, &e), DF_ELIMIT);
    replay_free(&r);
}

static void test_polar_and_absent(void **state)
{
    (void)state;
    double m, deg;
    const double east[2] = {2, 0}, south[2] = {0, -1}, big[2] = {30, 40};
    df_hid_ffb_polar(east, 4, &m, &deg);
    assert_true(fabs(m - 0.5) < 1e-15 && fabs(deg - 90) < 1e-12);
    df_hid_ffb_polar(south, 1, &m, &deg);
    assert_true(fabs(m - 1) < 1e-15 && fabs(deg - 180) < 1e-12);
    df_hid_ffb_polar(big, 10, &m, &deg);
    assert_true(m == 1.0);
    assert_true(fabs(deg - atan2(30, 40) * 180 / 3.14159265358979323846) < 1e-12);
    replay r;
    replay_load("3dconnexion-spacenavigator_046d-c626_usb.hid", &r);
    df_hid_ffb f;
    assert_int_equal(df_hid_ffb_init(&r.desc[0], &f, NULL), DF_OK);
    assert_int_equal(f.present, 0);
    uint8_t b[16];
    size_t n = 7;
    df_error e;
    assert_int_equal(df_hid_ffb_constant_force(&f, 1, 0.5, b, sizeof b, &n, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "no set constant force report"));
    assert_int_equal(n, 0);
    assert_int_equal(df_hid_ffb_init(NULL, &f, NULL), DF_OK);
    assert_int_equal(df_hid_ffb_init(&r.desc[0], NULL, NULL), DF_EINVAL);
    replay_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sidewinder_examples),
        cmocka_unit_test(test_polar_and_absent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

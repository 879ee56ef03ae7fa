/* Unit tests for server/hid/hid_config.c (issue 11, config per class and per device): defaults,
 * unknown keys, bad values, keys of another class, the override order defaults <- class <-
 * device, the device-section limit, cross-key checks, nothing changed on error. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"
#include "server/hid/hid_action.h"
#include "server/hid/hid_config.h"

static df_hid_params resolve(const df_hid_config *c, int cls, uint16_t vid, uint16_t pid)
{
    df_hid_params p;
    df_error e;
    int rc = df_hid_config_resolve(c, cls, vid, pid, &p, &e);
    if (rc != DF_OK) fail_msg("resolve: %s", e.msg);
    return p;
}

static void test_defaults(void **state)
{
    (void)state;
    df_hid_config c;
    memset(&c, 0, sizeof c);
    df_hid_params p = resolve(&c, DF_HID_CLASS_KNOB, 0x045e, 0x091b), d;
    df_hid_params_defaults(&d);
    assert_memory_equal(&p, &d, sizeof p);
    assert_true(p.haptics);
    assert_true(p.nu_min == -1.0 && p.nu_max == 0.5);
    assert_int_equal(p.rotate, DF_HID_TGT_RADIUS);
    assert_int_equal(p.press_rotate, DF_HID_TGT_NU);
    assert_int_equal(p.press, DF_HID_PRESS_FALLOFF);
    assert_int_equal(df_hid_config_check(&c, NULL), DF_OK);
    /* NULL config: the defaults */
    p = resolve(NULL, DF_HID_CLASS_PEN, 0, 0);
    assert_memory_equal(&p, &d, sizeof p);
    /* local mirrors of wire numbers agree with proto/wire_schema.h */
    assert_int_equal(DF_HID_BRUSH_GRAB, DF_BRUSH_GRAB);
    assert_int_equal(DF_HID_BRUSH_TWIST, DF_BRUSH_TWIST);
    assert_int_equal(DF_HID_BRUSH_SCALE, DF_BRUSH_SCALE);
    assert_int_equal(DF_HID_BRUSH_PINCH, DF_BRUSH_PINCH);
    assert_int_equal(DF_HID_BRUSH_AFFINE, DF_BRUSH_AFFINE);
    assert_int_equal(DF_HID_FALLOFF_LIMIT, DF_MAX_FALLOFF);
    /* hid_action.h's brush-state bits and cursor flags are the wire's DF_BS_* / DF_CURSOR_* */
    assert_int_equal(DF_HID_BS_TYPE, DF_BS_TYPE);
    assert_int_equal(DF_HID_BS_RADIUS, DF_BS_RADIUS);
    assert_int_equal(DF_HID_BS_NU, DF_BS_NU);
    assert_int_equal(DF_HID_BS_STRENGTH, DF_BS_STRENGTH);
    assert_int_equal(DF_HID_BS_FALLOFF, DF_BS_FALLOFF);
    assert_int_equal(DF_HID_BS_RATIO, DF_BS_RATIO);
    assert_int_equal(DF_HID_BS_INTEGRATOR, DF_BS_INTEGRATOR);
    assert_int_equal(DF_HID_BS_MIRROR, DF_BS_MIRROR);
    assert_int_equal(DF_HID_CUR_IN_RANGE, DF_CURSOR_IN_RANGE);
    assert_int_equal(DF_HID_CUR_STROKE, DF_CURSOR_STROKE_ACTIVE);
}

static void expect_error(df_hid_config *c, const char *key, const char *value, int code,
                         const char *needle)
{
    df_hid_config before = *c;
    df_error e;
    e.msg[0] = '\0';
    int rc = df_hid_config_set(c, key, value, &e);
    if (rc != code) fail_msg("%s = %s: rc %d (%s), expected %d", key, value, rc, e.msg, code);
    if (!strstr(e.msg, needle)) fail_msg("%s = %s: message '%s' lacks '%s'", key, value, e.msg, needle);
    assert_memory_equal(&before, c, sizeof before); /* nothing changed */
}

static void test_errors(void **state)
{
    (void)state;
    df_hid_config c;
    memset(&c, 0, sizeof c);
    assert_int_equal(df_hid_config_set(&c, "hid.knob.radius_step", "1.25", NULL), DF_OK);
    expect_error(&c, "hid.knob.radius_stepp", "1.2", DF_EINVAL, "radius_stepp");
    expect_error(&c, "hid.mouse.deadzone", "0.1", DF_EINVAL, "knob|3d-mouse|pen");
    expect_error(&c, "hid.knob", "1", DF_EINVAL, "hid.<class>.<key>");
    expect_error(&c, "hid.knob.", "1", DF_EINVAL, "hid.<class>.<key>");
    expect_error(&c, "hid.none.haptics", "yes", DF_EINVAL, "section 'none'");
    expect_error(&c, "hid.knob.deadzone", "0.1", DF_EINVAL, "not a knob key");
    expect_error(&c, "hid.pen.radius_step", "1.1", DF_EINVAL, "not a pen key");
    expect_error(&c, "hid.knob.radius_step", "1", DF_EINVAL, "radius_step");      /* <= 1 */
    expect_error(&c, "hid.knob.radius_step", "abc", DF_EINVAL, "'abc'");
    expect_error(&c, "hid.knob.radius_step", "nan", DF_EINVAL, "'nan'");
    expect_error(&c, "hid.knob.radius_step", "1.2x", DF_EINVAL, "'1.2x'");
    expect_error(&c, "hid.knob.radius_step", "", DF_EINVAL, "radius_step");
    expect_error(&c, "hid.knob.nu_max", "0.6", DF_EINVAL, "nu_max");             /* > 0.5 */
    expect_error(&c, "hid.knob.nu_min", "-1.5", DF_EINVAL, "nu_min");
    expect_error(&c, "hid.knob.falloff_max", "9", DF_EINVAL, "falloff_max");
    expect_error(&c, "hid.knob.falloff_max", "2.5", DF_EINVAL, "integer");
    expect_error(&c, "hid.knob.haptics", "maybe", DF_EINVAL, "yes or no");
    expect_error(&c, "hid.knob.rotate", "size", DF_EINVAL, "radius|nu|strength|none");
    expect_error(&c, "hid.pen.barrel", "undo", DF_EINVAL, "falloff|type|none");
    expect_error(&c, "hid.pen.type_cycle", "grab,smudge", DF_EINVAL, "grab|twist");
    expect_error(&c, "hid.pen.type_cycle", "", DF_EINVAL, "type_cycle");
    expect_error(&c, "hid.3d-mouse.deadzone", "1", DF_EINVAL, "deadzone");
    expect_error(&c, "hid.3d-mouse.sensitivity", "0", DF_EINVAL, "sensitivity");
    expect_error(&c, "hid.3d-mouse.stroke_button", "3", DF_EINVAL, "stroke_button");
    expect_error(&c, "hid.46d:c626.deadzone", "0.1", DF_EINVAL, "VID:PID");
    expect_error(&c, "hid.046d-c626.deadzone", "0.1", DF_EINVAL, "VID:PID");
    expect_error(&c, "hid.046g:c626.deadzone", "0.1", DF_EINVAL, "VID:PID");
    expect_error(&c, "hid.046d:c626.bogus", "1", DF_EINVAL, "bogus");
    expect_error(&c, "knob.radius_step", "1.1", DF_EINVAL, "not hid");
    assert_int_equal(df_hid_config_set(NULL, "hid.knob.haptics", "no", NULL), DF_EINVAL);
    /* the device-section limit */
    char key[64];
    for (int i = 0; i < DF_HID_CONFIG_MAX_DEVICES; i++) {
        snprintf(key, sizeof key, "hid.1209:%04x.haptics", i);
        assert_int_equal(df_hid_config_set(&c, key, "no", NULL), DF_OK);
    }
    assert_int_equal(c.n_dev, DF_HID_CONFIG_MAX_DEVICES);
    assert_int_equal(df_hid_config_set(&c, "hid.1209:0000.deadzone", "0.2", NULL), DF_OK);
    expect_error(&c, "hid.1209:ffff.haptics", "no", DF_ELIMIT, "device sections");
}

static void test_override_order(void **state)
{
    (void)state;
    df_hid_config c;
    memset(&c, 0, sizeof c);
    assert_int_equal(df_hid_config_set(&c, "hid.3d-mouse.deadzone", "0.1", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.3d-mouse.sensitivity", "2", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.046d:C626.deadzone", "0.2", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.046d:c626.invert_y", "yes", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.knob.haptics", "no", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.pen.type_cycle", "scale, pinch ,grab", NULL), DF_OK);
    assert_int_equal(c.n_dev, 1); /* C626 and c626 are one section */
    df_hid_params d;
    df_hid_params_defaults(&d);
    /* the SpaceNavigator: device deadzone over the class's, class sensitivity, device inversion */
    df_hid_params p = resolve(&c, DF_HID_CLASS_MOUSE3D, 0x046d, 0xc626);
    assert_true(p.deadzone == 0.2);
    assert_true(p.sensitivity == 2.0);
    assert_int_equal(p.invert[1], 1);
    assert_int_equal(p.invert[0], 0);
    assert_true(p.haptics); /* knob key does not reach 3d mice */
    /* another 3d mouse: class values only */
    p = resolve(&c, DF_HID_CLASS_MOUSE3D, 0x256f, 0xc62e);
    assert_true(p.deadzone == 0.1);
    assert_int_equal(p.invert[1], 0);
    /* knobs: haptics off by class; the pen cycle */
    p = resolve(&c, DF_HID_CLASS_KNOB, 0x045e, 0x091b);
    assert_int_equal(p.haptics, 0);
    assert_true(p.deadzone == d.deadzone);
    p = resolve(&c, DF_HID_CLASS_PEN, 0x1b96, 0x1000);
    assert_int_equal(p.n_type_cycle, 3);
    assert_int_equal(p.type_cycle[0], DF_HID_BRUSH_SCALE);
    assert_int_equal(p.type_cycle[1], DF_HID_BRUSH_PINCH);
    assert_int_equal(p.type_cycle[2], DF_HID_BRUSH_GRAB);
    /* a later line of the same key wins */
    assert_int_equal(df_hid_config_set(&c, "hid.3d-mouse.deadzone", "0.3", NULL), DF_OK);
    p = resolve(&c, DF_HID_CLASS_MOUSE3D, 0x256f, 0xc62e);
    assert_true(p.deadzone == 0.3);
    /* a device key overrides a knob key too: haptics back on for the Surface Dial only */
    assert_int_equal(df_hid_config_set(&c, "hid.045e:091b.haptics", "yes", NULL), DF_OK);
    assert_int_equal(resolve(&c, DF_HID_CLASS_KNOB, 0x045e, 0x091b).haptics, 1);
    assert_int_equal(resolve(&c, DF_HID_CLASS_KNOB, 0x256c, 0x0069).haptics, 0);
}

static void test_cross_checks(void **state)
{
    (void)state;
    df_hid_config c;
    memset(&c, 0, sizeof c);
    /* order-independent: each line alone is in range; the pair is checked after the file */
    assert_int_equal(df_hid_config_set(&c, "hid.knob.led_min_radius", "5", NULL), DF_OK);
    df_error e;
    df_hid_params p;
    assert_int_equal(df_hid_config_check(&c, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "led_min_radius"));
    assert_int_equal(df_hid_config_resolve(&c, DF_HID_CLASS_KNOB, 0, 0, &p, &e), DF_EINVAL);
    assert_int_equal(df_hid_config_set(&c, "hid.knob.led_max_radius", "50", NULL), DF_OK);
    assert_int_equal(df_hid_config_check(&c, &e), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.knob.nu_min", "0.2", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&c, "hid.256c:0069.nu_max", "0.1", NULL), DF_OK);
    assert_int_equal(df_hid_config_check(&c, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "hid.256c:0069: nu_min 0.2 above nu_max 0.1"));
    assert_int_equal(df_hid_config_set(&c, "hid.256c:0069.nu_min", "-0.5", NULL), DF_OK);
    assert_int_equal(df_hid_config_check(&c, &e), DF_OK);
    p = resolve(&c, DF_HID_CLASS_KNOB, 0x256c, 0x0069);
    assert_true(p.nu_min == -0.5 && p.nu_max == 0.1);
    assert_true(p.led_min_radius == 5 && p.led_max_radius == 50);
    assert_int_equal(df_hid_config_set(&c, "hid.knob.radius_max", "1e-5", NULL), DF_OK);
    assert_int_equal(df_hid_config_check(&c, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "radius_min"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_override_order),
        cmocka_unit_test(test_cross_checks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

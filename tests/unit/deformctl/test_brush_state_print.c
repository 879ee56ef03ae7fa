/* Unit tests for client/deformctl/cmd_brush_state.c's printers: the `brush-state` key value
 * lines, and the one-line BRUSH_STATE / BRUSH_CURSOR forms of `deformctl watch` (text and JSON),
 * each with its origin. A BRUSH_CURSOR needs a device to be sent, so its output is checked here
 * from a decoded event body. Output goes to stdout: captured through a temporary file. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformctl/ctl.h"

/* Runs fn(arg) with stdout redirected into a buffer; returns the malloc'd text. */
static char *capture(void (*fn)(const void *arg, int json), const void *arg, int json)
{
    fflush(stdout);
    FILE *tmp = tmpfile();
    assert_non_null(tmp);
    int saved = dup(STDOUT_FILENO);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(tmp), STDOUT_FILENO) >= 0);
    fn(arg, json);
    fflush(stdout);
    assert_true(dup2(saved, STDOUT_FILENO) >= 0);
    close(saved);
    long n = ftell(tmp);
    assert_true(n >= 0);
    char *out = calloc((size_t)n + 1, 1);
    rewind(tmp);
    assert_int_equal(fread(out, 1, (size_t)n, tmp), (size_t)n);
    fclose(tmp);
    return out;
}

static void print_state(const void *arg, int json)
{
    ctl_ctx ctx = {.json = json, .prog = "deformctl"};
    ctl_brush_state_print(&ctx, arg, 0);
}

static void print_state_event(const void *arg, int json)
{
    ctl_ctx ctx = {.json = json, .prog = "deformctl"};
    ctl_brush_state_print(&ctx, arg, 1);
}

static void print_cursor(const void *arg, int json)
{
    ctl_ctx ctx = {.json = json, .prog = "deformctl"};
    ctl_brush_cursor_print(&ctx, arg);
}

static df_msg_brush_state sample_state(void)
{
    df_msg_brush_state s;
    memset(&s, 0, sizeof s);
    s.session_id = 3;
    s.seq = 7;
    s.changed = DF_BS_RADIUS | DF_BS_NU;
    s.origin_kind = DF_ORIGIN_DEVICE;
    s.origin_id = (1ull << 63) | 2;
    snprintf(s.origin_name, sizeof s.origin_name, "Surface Dial");
    df_msg_brush_values_defaults(&s.v);
    s.v.radius = 0.25;
    s.v.nu = 0.45;
    return s;
}

static void test_key_value_lines(void **state)
{
    (void)state;
    df_msg_brush_state s = sample_state();
    char *t = capture(print_state, &s, 0);
    /* one 'key value' per line, shortest round-trip numbers */
    const char *want[] = {"session 3\n", "type grab\n", "radius 0.25\n", "nu 0.45\n",
                          "strength 1\n", "falloff 1\n", "ratio 1.1\n", "integrator euler\n",
                          "steps 1\n", "mirror off\n", "seq 7\n", "changed radius,nu\n",
                          "origin device\n", "origin_id 9223372036854775810\n",
                          "origin_name Surface Dial\n"};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++)
        if (!strstr(t, want[i]))
            fail_msg("missing line %s in:\n%s", want[i], t);
    free(t);
    s.v.has_mirror = 1;
    s.v.mirror_normal[0] = 0;
    s.v.mirror_normal[1] = 1;
    s.v.nu = -INFINITY;
    t = capture(print_state, &s, 1);
    assert_non_null(strstr(t, "\"nu\":\"-inf\""));
    assert_non_null(strstr(t, "\"mirror\":[0,0,0,0,1,0]"));
    assert_non_null(strstr(t, "\"changed\":[\"radius\",\"nu\"]"));
    assert_non_null(strstr(t, "\"origin\":\"device\",\"origin_id\":9223372036854775810,"
                              "\"origin_name\":\"Surface Dial\""));
    free(t);
}

static void test_watch_lines(void **state)
{
    (void)state;
    df_msg_brush_state s = sample_state();
    char *t = capture(print_state_event, &s, 0);
    assert_string_equal(t, "brush_state seq 7 changed radius,nu by device 9223372036854775810 "
                           "'Surface Dial': type grab radius 0.25 nu 0.45 strength 1 falloff 1 "
                           "ratio 1.1 integrator euler steps 1 mirror off\n");
    free(t);
    t = capture(print_state_event, &s, 1);
    const char *head = "{\"kind\":\"brush_state\",\"session\":3,\"seq\":7,";
    assert_true(!strncmp(t, head, strlen(head)));
    assert_int_equal(strchr(t, '\n') - t, (long)strlen(t) - 1); /* one line */
    free(t);
    df_msg_brush_cursor c = {3, DF_ORIGIN_DEVICE, 5, DF_CURSOR_IN_RANGE, {0.5, -0.25, 1e-3}, 0.2};
    t = capture(print_cursor, &c, 0);
    assert_string_equal(t, "brush_cursor device 5 center 0.5,-0.25,0.001 radius 0.2 in_range\n");
    free(t);
    c.flags = DF_CURSOR_IN_RANGE | DF_CURSOR_STROKE_ACTIVE;
    c.origin_kind = DF_ORIGIN_CLIENT;
    t = capture(print_cursor, &c, 1);
    assert_string_equal(t, "{\"kind\":\"brush_cursor\",\"session\":3,\"origin\":\"client\","
                           "\"origin_id\":5,\"center\":[0.5,-0.25,0.001],\"radius\":0.2,"
                           "\"in_range\":true,\"stroke_active\":true}\n");
    free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_key_value_lines),
        cmocka_unit_test(test_watch_lines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

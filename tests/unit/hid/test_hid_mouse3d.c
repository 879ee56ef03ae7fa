/* Unit tests for the 3d-mouse mapper (server/hid/hid_mouse3d.c, issue 11): the SpaceNavigator and
 * SpaceMouse Wireless recordings replayed through classify + mapper; cursor motion and stroke
 * tips equal the integral of the recorded axes computed here from the bytes (README layouts:
 * int16 LE, logical max 350) with the documented rule (deadzone, sensitivity, dt from event
 * times clamped to 50 ms, scale); strokes from button edges; inversion; unplug mid-stroke. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/hid/hid_config.h"
#include "server/hid/hid_mapper.h"
#include "tests/unit/hid/hid_replay.h"

#define NAV "3dconnexion-spacenavigator_046d-c626_usb.hid"
#define SMW "3dconnexion-spacemouse-wireless_256f-c62e_usb.hid"

/* Integral of the recorded axes: per report with id `tid` (translation) or `rid` (rotation),
 * values int16 LE from byte 1 (3 axes per report, or 6 when tid == rid), dt since the previous
 * report of the same id clamped to 50 ms; events from index `from` on. */
typedef struct integral { double move[3], twist[3]; } integral;

static void integrate(const df_hid_recording *rec, uint8_t tid, uint8_t rid, double dz,
                      double sens, double tsens, double scale, const int inv[6], size_t from,
                      uint64_t shift, integral *out)
{
    memset(out, 0, sizeof *out);
    uint64_t last[256] = {0};
    int seen[256] = {0};
    for (size_t i = from; i < rec->n_events; i++) {
        const uint8_t *b = df_hid_rec_event_bytes(rec, &rec->events[i]);
        if (b[0] != tid && b[0] != rid) continue;
        uint64_t t = rec->events[i].time_us + shift;
        double dt = seen[b[0]] ? (double)(t - last[b[0]] > 50000 ? 50000 : t - last[b[0]]) * 1e-6 : 0;
        seen[b[0]] = 1;
        last[b[0]] = t;
        int naxes = tid == rid ? 6 : 3, first = b[0] == tid ? 0 : 3;
        for (int a = 0; a < naxes; a++) {
            int axis = first + a;
            double f = (int16_t)(b[1 + 2 * a] | b[2 + 2 * a] << 8) / 350.0;
            if (fabs(f) <= dz) f = 0;
            if (inv && inv[axis]) f = -f;
            if (axis < 3) out->move[axis] += f * sens * dt * scale;
            else out->twist[axis - 3] += f * tsens * dt;
        }
    }
}

static void near3(const double *got, const double *want)
{
    for (int k = 0; k < 3; k++)
        if (fabs(got[k] - want[k]) > 1e-12 * (1 + fabs(want[k])))
            fail_msg("component %d: %.17g, expected %.17g", k, got[k], want[k]);
}

/* The recordings as they are: cursor deltas sum to the integral; strokes = button-1 edges. */
static void replay_as_recorded(const char *file, uint8_t tid, uint8_t rid)
{
    replay r;
    replay_load(file, &r);
    assert_int_equal(r.ci[0].cls, DF_HID_CLASS_MOUSE3D);
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 1.0};
    replay_out o;
    memset(&o, 0, sizeof o);
    const double scale = 2.5;
    replay_node(&r, 0, NULL, scale, &b, &o);
    df_hid_params p;
    df_hid_params_defaults(&p);
    integral want;
    integrate(&r.rec, tid, rid, p.deadzone, p.sensitivity, p.twist_sensitivity, scale, NULL, 0, 0,
              &want);
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < o.n; i++)
        if (o.v[i].a.kind == DF_HID_ACT_CURSOR) {
            assert_int_equal(o.v[i].a.cursor_mode, DF_HID_CUR_DELTA);
            for (int k = 0; k < 3; k++) sum[k] += o.v[i].a.move[k];
        }
    near3(sum, want.move);
    assert_true(fabs(want.move[0]) > 0); /* the recording moves */
    /* strokes: rising / falling edges of bit 0 of report 3's byte 1 */
    size_t rise = 0, fall = 0;
    int was = 0;
    for (size_t i = 0; i < r.rec.n_events; i++) {
        const uint8_t *e = df_hid_rec_event_bytes(&r.rec, &r.rec.events[i]);
        if (e[0] != 3) continue;
        int now = e[1] & 1;
        rise += !was && now;
        fall += was && !now;
        was = now;
    }
    assert_true(rise > 0);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), rise);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_END), fall);
    free(o.v);
    replay_free(&r);
}

static void test_recordings(void **state)
{
    (void)state;
    replay_as_recorded(NAV, 1, 2);
    replay_as_recorded(SMW, 1, 1);
}

/* A stroke over the recorded motion: button 1 down (report 3 = 03 01 00) before the first axis
 * report, the recorded axis reports, button up. The stroke's tip and twist are the integral. */
static void stroke_over_recording(const char *file, uint8_t tid, uint8_t rid, const char *inv_key)
{
    replay r;
    replay_load(file, &r);
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    assert_int_equal(df_hid_config_set(&cfg, "hid.3d-mouse.sensitivity", "3", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&cfg, "hid.3d-mouse.twist_sensitivity", "2", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&cfg, "hid.3d-mouse.deadzone", "0.02", NULL), DF_OK);
    int inv[6] = {0};
    if (inv_key) {
        assert_int_equal(df_hid_config_set(&cfg, inv_key, "yes", NULL), DF_OK);
        inv[strstr(inv_key, "invert_y") ? 1 : 5] = 1;
    }
    df_hid_mapper m;
    assert_int_equal(df_hid_mapper_init(&m, &r.ci[0], &r.desc[0], &cfg, NULL), DF_OK);
    df_hid_mapper_set_scale(&m, 0.75);
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 0.8};
    replay_out o;
    memset(&o, 0, sizeof o);
    const uint8_t down[3] = {3, 1, 0}, up[3] = {3, 0, 0};
    const uint64_t shift = 1000000; /* the recorded axis reports, 1 s later */
    replay_feed(&m, down, 3, 0, &b, &o, 0);
    uint64_t t_end = 0;
    for (size_t i = 0; i < r.rec.n_events; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        const uint8_t *e = df_hid_rec_event_bytes(&r.rec, ev);
        if (e[0] != tid && e[0] != rid) continue;
        replay_feed(&m, e, ev->len, ev->time_us + shift, &b, &o, i);
        t_end = ev->time_us + shift;
    }
    replay_feed(&m, up, 3, t_end + 1000, &b, &o, 0);
    integral want;
    integrate(&r.rec, tid, rid, 0.02, 3, 2, 0.75, inv, 0, shift, &want);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), 1);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_END), 1);
    assert_true(replay_count(&o, DF_HID_ACT_STROKE_UPDATE) > 0);
    const df_hid_action *end = NULL, *begin = NULL;
    for (size_t i = 0; i < o.n; i++) {
        if (o.v[i].a.kind == DF_HID_ACT_STROKE_END) end = &o.v[i].a;
        if (o.v[i].a.kind == DF_HID_ACT_STROKE_BEGIN) begin = &o.v[i].a;
    }
    assert_true(begin->move[0] == 0 && begin->twist[2] == 0);
    assert_true(begin->strength == 0.8 && begin->brush.radius == 0.25);
    near3(end->move, want.move);
    near3(end->twist, want.twist);
    assert_true(fabs(want.move[0]) > 0 && fabs(want.twist[0]) + fabs(want.twist[2]) > 0);
    /* no haptics page on these devices */
    assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), 0);
    free(o.v);
    replay_free(&r);
}

static void test_stroke_tip_is_integral(void **state)
{
    (void)state;
    stroke_over_recording(NAV, 1, 2, NULL);
    stroke_over_recording(SMW, 1, 1, NULL);
    stroke_over_recording(NAV, 1, 2, "hid.046d:c626.invert_y");
    stroke_over_recording(SMW, 1, 1, "hid.3d-mouse.invert_rz");
}

static void test_dt_deadzone_unplug(void **state)
{
    (void)state;
    replay r;
    replay_load(SMW, &r);
    df_hid_mapper m;
    assert_int_equal(df_hid_mapper_init(&m, &r.ci[0], &r.desc[0], NULL, NULL), DF_OK);
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 1.0};
    replay_out o;
    memset(&o, 0, sizeof o);
    /* full X deflection (350): the first report moves nothing (no previous time), the next
     * one a second later counts 50 ms: 1 * 0.5 (sensitivity) * 0.05 * 1 (scale) */
    uint8_t rep[13] = {1, 0x5e, 0x01};
    replay_feed(&m, rep, 13, 5000000, &b, &o, 0);
    assert_int_equal(o.n, 0);
    replay_feed(&m, rep, 13, 6000000, &b, &o, 1);
    assert_int_equal(o.n, 1);
    assert_true(fabs(o.v[0].a.move[0] - 0.5 * 0.05) < 1e-15);
    /* inside the deadzone: 3/350 < 0.01 */
    rep[1] = 3;
    rep[2] = 0;
    replay_feed(&m, rep, 13, 6010000, &b, &o, 2);
    assert_int_equal(o.n, 1);
    /* a stroke with button 2 configured: button 1 does nothing */
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    assert_int_equal(df_hid_config_set(&cfg, "hid.3d-mouse.stroke_button", "2", NULL), DF_OK);
    assert_int_equal(df_hid_mapper_init(&m, &r.ci[0], &r.desc[0], &cfg, NULL), DF_OK);
    const uint8_t b1[3] = {3, 1, 0}, b2[3] = {3, 2, 0};
    replay_feed(&m, b1, 3, 0, &b, &o, 3);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), 0);
    replay_feed(&m, b2, 3, 0, &b, &o, 4);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), 1);
    rep[1] = 0xa2; /* X = -350 */
    rep[2] = 0xfe;
    replay_feed(&m, rep, 13, 10000, &b, &o, 5);
    replay_feed(&m, rep, 13, 30000, &b, &o, 6);
    /* unplug mid-stroke: one STROKE_END with the tip so far (-1 * 0.5 * 0.02 s) */
    df_hid_action act[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    assert_int_equal(df_hid_mapper_unplug(&m, act, DF_HID_MAX_ACTIONS, &n, NULL), DF_OK);
    assert_int_equal(n, 1);
    assert_int_equal(act[0].kind, DF_HID_ACT_STROKE_END);
    assert_true(fabs(act[0].move[0] - (-0.5 * 0.02)) < 1e-15);
    assert_int_equal(df_hid_mapper_unplug(&m, act, DF_HID_MAX_ACTIONS, &n, NULL), DF_OK);
    assert_int_equal(n, 0); /* once */
    /* a short axis report is refused, nothing changes */
    df_hid_mapper before = m;
    df_error e;
    assert_int_equal(df_hid_mapper_feed(&m, rep, 7, 0, &b, act, DF_HID_MAX_ACTIONS, &n, &e), DF_EFORMAT);
    assert_memory_equal(&m, &before, sizeof m);
    /* the battery report (id 0x17) is not used */
    const uint8_t bat[3] = {0x17, 0x64, 0x01};
    assert_int_equal(df_hid_mapper_feed(&m, bat, 3, 0, &b, act, DF_HID_MAX_ACTIONS, &n, &e), DF_OK);
    assert_int_equal(n, 0);
    free(o.v);
    replay_free(&r);
}

/* A home-made 3D mouse with a haptic motor: report 1 = 6 axes s16 (-350..350) + button 1 (+ 7
 * pad bits); output report 2 = [02][Manual Trigger 1..7][Repeat Count]; Waveform List ordinal 3
 * = Buzz (0x1004), ordinal 4 = Click (0x1003). Stroke begin and end buzz; haptics = no silences. */
static const uint8_t k_haptic_3d[] = {
    0x05, 0x01, 0x09, 0x08, 0xa1, 0x01, 0x85, 0x01,
    0x16, 0xa2, 0xfe, 0x26, 0x5e, 0x01, 0x75, 0x10, 0x95, 0x06,
    0x09, 0x30, 0x09, 0x31, 0x09, 0x32, 0x09, 0x33, 0x09, 0x34, 0x09, 0x35, 0x81, 0x02,
    0x05, 0x09, 0x09, 0x01, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02,
    0x75, 0x07, 0x81, 0x03,
    0x05, 0x0e, 0x09, 0x01, 0xa1, 0x02, 0x85, 0x02, 0x75, 0x08, 0x95, 0x01,
    0x15, 0x01, 0x25, 0x07, 0x09, 0x21, 0x91, 0x02,
    0x15, 0x00, 0x25, 0x0a, 0x09, 0x24, 0x91, 0x02,
    0x09, 0x10, 0xa1, 0x02, 0x05, 0x0a, 0x85, 0x03, 0x75, 0x10,
    0x16, 0x04, 0x10, 0x26, 0x04, 0x10, 0x09, 0x03, 0xb1, 0x03,
    0x16, 0x03, 0x10, 0x26, 0x03, 0x10, 0x09, 0x04, 0xb1, 0x03,
    0xc0, 0xc0, 0xc0};

static void test_haptic_strokes(void **state)
{
    (void)state;
    df_hid_desc d;
    df_error e;
    if (df_hid_desc_parse(k_haptic_3d, sizeof k_haptic_3d, &d, &e) != DF_OK) fail_msg("%s", e.msg);
    df_hid_class_info ci;
    assert_int_equal(df_hid_classify(&d, 0x1209, 0x3d3d, &ci), DF_OK);
    assert_int_equal(ci.cls, DF_HID_CLASS_MOUSE3D);
    for (int off = 0; off < 2; off++) {
        df_hid_config cfg;
        memset(&cfg, 0, sizeof cfg);
        if (off) assert_int_equal(df_hid_config_set(&cfg, "hid.3d-mouse.haptics", "no", NULL), DF_OK);
        df_hid_mapper m;
        assert_int_equal(df_hid_mapper_init(&m, &ci, &d, &cfg, &e), DF_OK);
        df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 1.0};
        replay_out o;
        memset(&o, 0, sizeof o);
        uint8_t r[14] = {1};
        r[13] = 1; /* button down, no deflection */
        replay_feed(&m, r, 14, 0, &b, &o, 0);
        r[1] = 0x5e; /* X = 350 */
        r[2] = 0x01;
        replay_feed(&m, r, 14, 10000, &b, &o, 1);
        r[13] = 0;
        replay_feed(&m, r, 14, 20000, &b, &o, 2);
        assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), 1);
        assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_END), 1);
        assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), off ? 0 : 2);
        for (size_t i = 0; i < o.n; i++) {
            const df_hid_action *a = &o.v[i].a;
            if (a->kind == DF_HID_ACT_HAPTIC) {
                const uint8_t want[3] = {0x02, 0x03, 0x00}; /* report 2, Buzz = ordinal 3 */
                assert_int_equal(a->waveform, DF_HID_WAVE_BUZZ);
                assert_int_equal(a->n_bytes, 3);
                assert_memory_equal(a->bytes, want, 3);
                assert_true(o.v[i - 1].a.kind == DF_HID_ACT_STROKE_BEGIN ||
                            o.v[i - 1].a.kind == DF_HID_ACT_STROKE_END);
            }
            /* the full deflection of the report at 10 ms and of the release report at 20 ms
             * (axes before the release edge) add 350/350 * 0.5 * 0.01 s each */
            if (a->kind == DF_HID_ACT_STROKE_END) assert_true(fabs(a->move[0] - 0.5 * 0.02) < 1e-15);
        }
        free(o.v);
    }
    df_hid_desc_free(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_recordings),
        cmocka_unit_test(test_stroke_tip_is_integral),
        cmocka_unit_test(test_dt_deadzone_unplug),
        cmocka_unit_test(test_haptic_strokes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

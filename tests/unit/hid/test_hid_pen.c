/* Unit tests for the pen mapper (server/hid/hid_pen.c, issue 11): the N-trig (recorded), GXTP
 * and Huion Dial 2 pen files replayed through classify + mapper; stroke begin/update/end, their
 * strength (pressure / logical max, gamma from the config), normalized position, tilt and twist,
 * barrel -> next brush type and in-range cursor events, all computed here from the recorded
 * bytes with the README byte layouts; unplug mid-stroke. */
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

#define PI 3.14159265358979323846

/* One pen layout from ../shared/hid/README.md. */
typedef struct pen_layout {
    const char *file;
    unsigned node;
    uint8_t rid;
    int in_range_bit, tip_bit, barrel_bit;  /* bits of byte 1 */
    int x_byte, y_byte, p_byte;             /* u16 LE */
    double x_max, y_max, p_max;
    int tilt_byte, tilt_wide;               /* -1: none; s8 degrees, or s16 in 0.01 degrees */
} pen_layout;

static const pen_layout k_pens[] = {
    {"ntrig-duosense-pen_1b96-1000_usb.hid", 0, 0x01, 0, 1, 2, 2, 4, 6, 9600, 7200, 256, -1, 0},
    {"goodix-gxtp-pen_27c6-0113_i2c.hid", 0, 0x08, 5, 0, 1, 3, 5, 7, 5120, 3200, 4095, 9, 1},
    {"huion-dial-2_256c-0060_usb.hid", 1, 0x0a, 6, 0, 1, 2, 4, 6, 32767, 32767, 8191, 8, 0},
};

typedef struct pen_sample { int in_range, tip, barrel; double x, y, p, tx, ty; } pen_sample;

static pen_sample decode(const pen_layout *L, const uint8_t *b)
{
    pen_sample s;
    s.in_range = (b[1] >> L->in_range_bit) & 1;
    s.tip = ((b[1] >> L->tip_bit) & 1) && s.in_range;
    s.barrel = (b[1] >> L->barrel_bit) & 1;
    s.x = (b[L->x_byte] | b[L->x_byte + 1] << 8) / L->x_max;
    s.y = (b[L->y_byte] | b[L->y_byte + 1] << 8) / L->y_max;
    s.p = (b[L->p_byte] | b[L->p_byte + 1] << 8) / L->p_max;
    s.tx = s.ty = 0;
    if (L->tilt_byte >= 0) {
        if (L->tilt_wide) {
            s.tx = (int16_t)(b[L->tilt_byte] | b[L->tilt_byte + 1] << 8) * 0.01;
            s.ty = (int16_t)(b[L->tilt_byte + 2] | b[L->tilt_byte + 3] << 8) * 0.01;
        } else {
            s.tx = (int8_t)b[L->tilt_byte];
            s.ty = (int8_t)b[L->tilt_byte + 1];
        }
        s.tx *= PI / 180;
        s.ty *= PI / 180;
    }
    return s;
}

static void check_pen(const pen_layout *L, double gamma)
{
    replay r;
    replay_load(L->file, &r);
    assert_int_equal(r.ci[L->node].cls, DF_HID_CLASS_PEN);
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    char g[32];
    snprintf(g, sizeof g, "%g", gamma);
    assert_int_equal(df_hid_config_set(&cfg, "hid.pen.pressure_gamma", g, NULL), DF_OK);
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 1.0};
    replay_out o;
    memset(&o, 0, sizeof o);
    replay_node(&r, L->node, &cfg, 1.0, &b, &o);

    /* expected stroke actions, cursor count, type changes from the bytes */
    size_t oi = 0, begins = 0, ends = 0, cursors = 0, barrels = 0;
    int stroke = 0, was_in = 0, was_barrel = 0;
    double last_strength = 0;
    for (size_t i = 0; i < r.rec.n_events; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        const uint8_t *e = df_hid_rec_event_bytes(&r.rec, ev);
        if (ev->device != L->node || e[0] != L->rid) continue;
        pen_sample s = decode(L, e);
        cursors += s.in_range + (was_in && !s.in_range);
        barrels += s.barrel && !was_barrel && s.in_range;
        was_barrel = s.barrel;
        was_in = s.in_range;
        int kind = -1;
        if (s.tip && !stroke) { kind = DF_HID_ACT_STROKE_BEGIN; stroke = 1; begins++; }
        else if (s.tip) kind = DF_HID_ACT_STROKE_UPDATE;
        else if (stroke) { kind = DF_HID_ACT_STROKE_END; stroke = 0; ends++; }
        if (kind < 0) continue;
        while (oi < o.n && (o.v[oi].event != i || o.v[oi].a.kind < DF_HID_ACT_STROKE_BEGIN ||
                            o.v[oi].a.kind > DF_HID_ACT_STROKE_END))
            oi++;
        if (oi == o.n) fail_msg("%s event %zu: no stroke action", L->file, i);
        const df_hid_action *a = &o.v[oi++].a;
        assert_int_equal(a->kind, kind);
        double want = kind == DF_HID_ACT_STROKE_END ? last_strength : pow(s.p, gamma);
        if (fabs(a->strength - want) > 1e-12)
            fail_msg("%s event %zu: strength %.17g, expected %.17g", L->file, i, a->strength, want);
        last_strength = want;
        assert_true(fabs(a->xy[0] - s.x) < 1e-12 && fabs(a->xy[1] - s.y) < 1e-12);
        assert_true(fabs(a->pressure - s.p) < 1e-12);
        assert_true(fabs(a->tilt[0] - s.tx) < 1e-9 && fabs(a->tilt[1] - s.ty) < 1e-9);
        if (kind != DF_HID_ACT_STROKE_END) {
            /* twist: pen axis normalize(tan tx, tan ty, 1) * 0.5 rad * pressure */
            double ax[3] = {tan(s.tx), tan(s.ty), 1}, n = 0;
            for (int k = 0; k < 3; k++) n += ax[k] * ax[k];
            for (int k = 0; k < 3; k++)
                assert_true(fabs(a->twist[k] - ax[k] / sqrt(n) * 0.5 * s.p) < 1e-9);
        }
    }
    assert_true(begins > 0);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), begins);
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_END), ends);
    assert_int_equal(replay_count(&o, DF_HID_ACT_CURSOR), cursors);
    assert_int_equal(replay_count(&o, DF_HID_ACT_BRUSH_SET), barrels);
    assert_true(barrels > 0);
    /* the barrel walks the default type cycle grab -> twist -> grab ... */
    assert_int_equal(b.type, barrels % 2 ? DF_HID_BRUSH_TWIST : DF_HID_BRUSH_GRAB);
    for (size_t i = 0; i < o.n; i++)
        if (o.v[i].a.kind == DF_HID_ACT_CURSOR)
            assert_true(o.v[i].a.cursor_mode == DF_HID_CUR_NORMALIZED);
    free(o.v);
    replay_free(&r);
}

static void test_pens(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof k_pens / sizeof k_pens[0]; i++) {
        check_pen(&k_pens[i], 1.0);
        check_pen(&k_pens[i], 2.0);
    }
}

static void test_unplug_mid_stroke(void **state)
{
    (void)state;
    replay r;
    replay_load(k_pens[0].file, &r);
    df_hid_mapper m;
    assert_int_equal(df_hid_mapper_init(&m, &r.ci[0], &r.desc[0], NULL, NULL), DF_OK);
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.5, 0.5};
    replay_out o;
    memset(&o, 0, sizeof o);
    size_t i = 0;
    for (; i < r.rec.n_events && replay_count(&o, DF_HID_ACT_STROKE_UPDATE) < 3; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        replay_feed(&m, df_hid_rec_event_bytes(&r.rec, ev), ev->len, ev->time_us, &b, &o, i);
    }
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_UPDATE), 3);
    const df_hid_action *last = &o.v[o.n - 1].a;
    assert_int_equal(last->kind, DF_HID_ACT_STROKE_UPDATE);
    /* strength = session strength (0.5) * pressure / 256 */
    const uint8_t *e = df_hid_rec_event_bytes(&r.rec, &r.rec.events[i - 1]);
    assert_true(fabs(last->strength - 0.5 * (e[6] | e[7] << 8) / 256.0) < 1e-12);
    df_hid_action act[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    assert_int_equal(df_hid_mapper_unplug(&m, act, DF_HID_MAX_ACTIONS, &n, NULL), DF_OK);
    assert_int_equal(n, 2);
    assert_int_equal(act[0].kind, DF_HID_ACT_STROKE_END);
    assert_true(act[0].strength == last->strength);
    assert_int_equal(act[1].kind, DF_HID_ACT_CURSOR);
    assert_int_equal(act[1].cursor_flags, 0);
    /* after the unplug the next tip-down report begins a new stroke */
    size_t before = replay_count(&o, DF_HID_ACT_STROKE_BEGIN);
    for (; i < r.rec.n_events && replay_count(&o, DF_HID_ACT_STROKE_BEGIN) == before; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        replay_feed(&m, df_hid_rec_event_bytes(&r.rec, ev), ev->len, ev->time_us, &b, &o, i);
    }
    assert_int_equal(replay_count(&o, DF_HID_ACT_STROKE_BEGIN), before + 1);
    free(o.v);
    replay_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pens),
        cmocka_unit_test(test_unplug_mid_stroke),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

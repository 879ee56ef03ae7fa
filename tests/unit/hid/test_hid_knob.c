/* Unit tests for the knob mapper (server/hid/hid_knob.c, issue 11): every knob recording of the
 * shared folder replayed through classify + mapper, with the expected radius / falloff / nu /
 * haptic / LED values computed here from the recorded bytes (README byte layouts, not the
 * descriptor parser) and the config; nu clamps at the 0.5 detent; press mappings; errors. */
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

/* The session brush every replay starts from. */
static df_hid_brush start_brush(void)
{
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.2, 1.0};
    return b;
}

/* Expected outcome of a knob recording, computed from (button, rotation units) per report with
 * the documented rules: detent position = floor(accumulated units / units per detent); plain
 * rotation -> radius * step^detents; rotation while held -> nu + nu_step * detents (clamped);
 * press + release without rotation -> next falloff. */
typedef struct knob_model {
    double upd;               /* units per detent */
    int no_release;           /* quirk: the press edge is the press */
    double acc;
    long pos;
    int held, rotated;
    df_hid_brush b;
    int radius_changes, clicks;
} knob_model;

static void model_step(knob_model *k, const df_hid_params *p, int button, long units)
{
    long det = 0;
    if (units) {
        k->acc += (double)units;
        long pos = (long)floor(k->acc / k->upd);
        det = pos - k->pos;
        k->pos = pos;
    }
    int was = k->held;
    if (k->no_release) {
        if (!was && button) {
            k->b.falloff = (uint8_t)(k->b.falloff % p->falloff_max + 1);
            k->clicks++;
        }
        k->held = button;
        was = button = 0; /* rotation is always plain */
    } else if (!was && button) {
        k->held = 1;
        k->rotated = 0;
    }
    if (det) {
        if (was || button) {
            k->rotated = 1;
            double nu = k->b.nu + p->nu_step * (double)det;
            nu = nu < p->nu_min ? p->nu_min : nu > p->nu_max ? p->nu_max : nu;
            if (nu != k->b.nu) k->clicks++;
            k->b.nu = nu;
        } else {
            k->b.radius *= pow(p->radius_step, (double)det);
            k->radius_changes++;
            k->clicks++;
        }
    }
    if (!k->no_release && was && !button) {
        k->held = 0;
        if (!k->rotated) {
            k->b.falloff = (uint8_t)(k->b.falloff % p->falloff_max + 1);
            k->clicks++;
        }
    }
}

static void check_brush(const df_hid_brush *got, const df_hid_brush *want)
{
    if (fabs(got->radius - want->radius) > 1e-12 * want->radius)
        fail_msg("radius %.17g, expected %.17g", got->radius, want->radius);
    if (fabs(got->nu - want->nu) > 1e-12) fail_msg("nu %.17g, expected %.17g", got->nu, want->nu);
    assert_int_equal(got->falloff, want->falloff);
    assert_int_equal(got->type, want->type);
}

/* Replays node `node` of `file`; rotation units and button read from the report bytes at
 * dial_byte (s16 when wide, else s8) and button_byte/bit, for reports starting with rid. */
static void knob_file(const char *file, unsigned node, uint8_t rid, int dial_byte, int wide,
                      int button_byte, int button_mask, const df_hid_config *cfg, double upd,
                      int no_release, replay_out *out, knob_model *k)
{
    replay r;
    replay_load(file, &r);
    assert_int_equal(r.ci[node].cls, DF_HID_CLASS_KNOB);
    df_hid_params p;
    assert_int_equal(df_hid_config_resolve(cfg, DF_HID_CLASS_KNOB, (uint16_t)r.rec.devices[node].vid,
                                           (uint16_t)r.rec.devices[node].pid, &p, NULL), DF_OK);
    memset(k, 0, sizeof *k);
    k->upd = upd;
    k->no_release = no_release;
    k->b = start_brush();
    for (size_t i = 0; i < r.rec.n_events; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        const uint8_t *b = df_hid_rec_event_bytes(&r.rec, ev);
        if (ev->device != node || b[0] != rid) continue;
        long units = wide ? (int16_t)(b[dial_byte] | b[dial_byte + 1] << 8) : (int8_t)b[dial_byte];
        if (dial_byte < 0) units = 0;
        int button = button_byte >= 0 && (b[button_byte] & button_mask) != 0;
        if (button_byte < 0) button = k->held;
        model_step(k, &p, button, units);
    }
    df_hid_brush b = start_brush();
    memset(out, 0, sizeof *out);
    replay_node(&r, node, cfg, 1.0, &b, out);
    check_brush(&b, &k->b);
    replay_free(&r);
}

static void test_surface_dial(void **state)
{
    (void)state;
    const char *f = "microsoft-surface-dial_045e-091b_bt.hid";
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    replay_out o;
    knob_model k;
    /* default: 3600 units per turn (Resolution Multiplier) / 36 detents = 100 units per detent */
    knob_file(f, 0, 0x01, 2, 1, 1, 0x01, &cfg, 3600.0 / 36, 0, &o, &k);
    assert_int_equal(k.radius_changes, 0); /* the recorded turns stay below one detent */
    assert_int_equal(replay_count(&o, DF_HID_ACT_BRUSH_SET), 1); /* the press: falloff 1 -> 2 */
    assert_int_equal(k.b.falloff, 2);
    assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), (size_t)k.clicks);
    free(o.v);
    /* one unit per detent, then 3: radius = r0 * 1.1 ^ floor(sum / upd) */
    const double upds[2] = {1, 3};
    for (int u = 0; u < 2; u++) {
        char val[16];
        snprintf(val, sizeof val, "%g", upds[u]);
        assert_int_equal(df_hid_config_set(&cfg, "hid.knob.dial_units_per_detent", val, NULL), DF_OK);
        knob_file(f, 0, 0x01, 2, 1, 1, 0x01, &cfg, upds[u], 0, &o, &k);
        assert_true(k.radius_changes > 0);
        assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), (size_t)k.clicks);
        /* every haptic report is a click laid out as [01][repeat][3 = Click][80 ms u16]:
         * repeat = |detents of that report| - 1 for a turn, 0 for the press; computed here
         * from the recorded dial values (s16 in bytes 2-3 of report 1, button byte 1 bit 0) */
        replay r;
        replay_load(f, &r);
        unsigned want_rep[64];
        size_t nw = 0;
        double acc = 0;
        int held = 0;
        for (size_t i = 0; i < r.rec.n_events; i++) {
            const uint8_t *eb = df_hid_rec_event_bytes(&r.rec, &r.rec.events[i]);
            if (eb[0] != 0x01) continue;
            long units = (int16_t)(eb[2] | eb[3] << 8);
            long d = (long)floor((acc + (double)units) / upds[u]) - (long)floor(acc / upds[u]);
            acc += (double)units;
            if (d) want_rep[nw++] = (unsigned)(labs(d) - 1);
            if (held && !(eb[1] & 1)) want_rep[nw++] = 0; /* release without turning */
            held = eb[1] & 1;
        }
        replay_free(&r);
        size_t h = 0;
        for (size_t i = 0; i < o.n; i++) {
            if (o.v[i].a.kind != DF_HID_ACT_HAPTIC) continue;
            const df_hid_action *a = &o.v[i].a;
            assert_true(h < nw);
            assert_int_equal(a->n_bytes, 5);
            assert_int_equal(a->waveform, DF_HID_WAVE_CLICK);
            const uint8_t want[5] = {0x01, (uint8_t)want_rep[h++], 0x03, 80, 0};
            assert_memory_equal(a->bytes, want, 5);
        }
        assert_int_equal(h, nw);
        free(o.v);
    }
    /* haptics off by config: the same replay, no output report */
    assert_int_equal(df_hid_config_set(&cfg, "hid.045e:091b.haptics", "no", NULL), DF_OK);
    knob_file(f, 0, 0x01, 2, 1, 1, 0x01, &cfg, 3, 0, &o, &k);
    assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), 0);
    assert_int_equal(replay_count(&o, DF_HID_ACT_LED), 0);
    free(o.v);
}

static void test_huion_dials(void **state)
{
    (void)state;
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    replay_out o;
    knob_model k;
    /* Dial 2 pad node: report 17 [11][b0 button][dial s16]; one unit per detent (quirk) */
    knob_file("huion-dial-2_256c-0060_usb.hid", 2, 0x11, 2, 1, 1, 0x01, &cfg, 1, 0, &o, &k);
    assert_true(k.radius_changes > 0);
    assert_int_equal(k.b.falloff, 2);
    assert_int_equal(replay_count(&o, DF_HID_ACT_HAPTIC), 0); /* no haptics page */
    free(o.v);
    /* K20 firmware mode: the press is never released; it still cycles the falloff once */
    knob_file("huion-keydial-k20_256c-0069_usb_firmware-mode.hid", 2, 0x11, 2, 1, 1, 0x01, &cfg, 1,
              1, &o, &k);
    assert_true(fabs(k.b.radius - 0.25 * 1.1) < 1e-15);
    assert_int_equal(k.b.falloff, 2);
    free(o.v);
    /* K20 Bluetooth: the dial is the mouse node's wheel (report 5, s8 in byte 6), the button
     * Consumer Play/Pause (report 2 = 02 cd 00), read here by hand */
    replay r;
    replay_load("huion-keydial-k20_256c-8251_bt.hid", &r);
    df_hid_params p;
    df_hid_params_defaults(&p);
    memset(&k, 0, sizeof k);
    k.upd = 1;
    k.b = start_brush();
    for (size_t i = 0; i < r.rec.n_events; i++) {
        const df_hid_rec_event *ev = &r.rec.events[i];
        const uint8_t *b = df_hid_rec_event_bytes(&r.rec, ev);
        if (ev->device != 1) continue;
        if (b[0] == 0x05) model_step(&k, &p, k.held, (int8_t)b[6]);
        if (b[0] == 0x02) model_step(&k, &p, (b[1] | b[2] << 8) == 0xcd, 0);
    }
    df_hid_brush b = start_brush();
    memset(&o, 0, sizeof o);
    replay_node(&r, 1, NULL, 1.0, &b, &o);
    check_brush(&b, &k.b);
    assert_true(k.b.radius < 0.25 && k.b.falloff == 2);
    free(o.v);
    replay_free(&r);
}

/* PowerMate: raw 6-byte packets [button][s8 rotation][0][led][pulse][speed]; LED follows r. */
static void test_powermate(void **state)
{
    (void)state;
    raw_event ev[64];
    size_t n = replay_raw_events("griffin-powermate_077d-0410_usb.raw.txt", ev, 64);
    assert_true(n > 0);
    df_hid_class_info ci;
    assert_int_equal(df_hid_classify(NULL, 0x077d, 0x0410, &ci), DF_OK);
    df_hid_params p;
    df_hid_params_defaults(&p);
    knob_model k;
    memset(&k, 0, sizeof k);
    k.upd = 1;
    k.b = start_brush();
    for (size_t i = 0; i < n; i++) model_step(&k, &p, ev[i].b[0] & 1, (int8_t)ev[i].b[1]);
    df_hid_mapper m;
    assert_int_equal(df_hid_mapper_init(&m, &ci, NULL, NULL, NULL), DF_OK);
    df_hid_brush b = start_brush();
    replay_out o;
    memset(&o, 0, sizeof o);
    for (size_t i = 0; i < n; i++) replay_feed(&m, ev[i].b, ev[i].len, ev[i].t, &b, &o, i);
    check_brush(&b, &k.b);
    assert_true(b.nu > 0.2);          /* the file turns while pressed: nu moved */
    assert_int_equal(b.falloff, 2);   /* and presses once without turning */
    /* one LED action after every radius change, brightness from log r in [0.01, 1] */
    size_t leds = 0;
    for (size_t i = 0; i < o.n; i++) {
        if (o.v[i].a.kind != DF_HID_ACT_LED) continue;
        leds++;
        assert_true(i > 0 && o.v[i - 1].a.kind == DF_HID_ACT_BRUSH_SET);
        double r = o.v[i - 1].a.brush.radius;
        double t = (log(r) - log(0.01)) / (log(1.0) - log(0.01));
        int want = (int)lround(255 * (t < 0 ? 0 : t > 1 ? 1 : t));
        assert_int_equal(o.v[i].a.led, want);
    }
    assert_int_equal(leds, (size_t)k.radius_changes);
    assert_true(leds > 0);
    /* the level for a given radius (what the manager sends at attach): ends and middle */
    assert_int_equal(df_hid_mapper_led_level(&m, 0.01), 0);
    assert_int_equal(df_hid_mapper_led_level(&m, 1.0), 255);
    assert_int_equal(df_hid_mapper_led_level(&m, 0.1),
                     lround(255 * (log(0.1) - log(0.01)) / (log(1.0) - log(0.01))));
    assert_int_equal(df_hid_mapper_led_level(&m, 1e-6), 0);
    assert_int_equal(df_hid_mapper_led_level(&m, 50), 255);
    assert_int_equal(df_hid_mapper_led_level(&m, -1), -1);
    free(o.v);
}

/* The DIY knob of test_hid_class.c: [b0 button][s8 dial], no report id. */
static const uint8_t k_diy[] = {
    0x05, 0x01, 0x09, 0x0e, 0xa1, 0x01, 0x05, 0x09, 0x19, 0x01, 0x29, 0x01,
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, 0x75, 0x07, 0x81, 0x03,
    0x05, 0x01, 0x09, 0x37, 0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95, 0x01, 0x81, 0x06, 0xc0};

static void diy_mapper(df_hid_mapper *m, df_hid_desc *d, const df_hid_config *cfg)
{
    assert_int_equal(df_hid_desc_parse(k_diy, sizeof k_diy, d, NULL), DF_OK);
    df_hid_class_info ci;
    assert_int_equal(df_hid_classify(d, 0x1209, 0x0001, &ci), DF_OK);
    assert_int_equal(df_hid_mapper_init(m, &ci, d, cfg, NULL), DF_OK);
}

static void feed2(df_hid_mapper *m, uint8_t button, int8_t dial, df_hid_brush *b, replay_out *o)
{
    const uint8_t r[2] = {button, (uint8_t)dial};
    replay_feed(m, r, 2, 0, b, o, 0);
}

static void test_nu_detent_and_limits(void **state)
{
    (void)state;
    df_hid_mapper m;
    df_hid_desc d;
    diy_mapper(&m, &d, NULL);
    df_hid_brush b = start_brush();
    b.nu = 0.45;
    replay_out o;
    memset(&o, 0, sizeof o);
    feed2(&m, 1, 0, &b, &o);   /* press */
    feed2(&m, 1, 3, &b, &o);   /* +3 detents held: 0.45 + 0.15 stops at the 0.5 detent */
    assert_true(b.nu == 0.5);
    size_t sets = replay_count(&o, DF_HID_ACT_BRUSH_SET);
    feed2(&m, 1, 1, &b, &o);   /* at the limit: nothing to set */
    assert_int_equal(replay_count(&o, DF_HID_ACT_BRUSH_SET), sets);
    feed2(&m, 1, -2, &b, &o);
    assert_true(fabs(b.nu - 0.4) < 1e-15);
    feed2(&m, 0, 0, &b, &o);   /* release after turning: no falloff change */
    assert_int_equal(b.falloff, 1);
    assert_true(b.radius == 0.25);
    feed2(&m, 1, -127, &b, &o); /* a press edge with rotation in the same report is held */
    feed2(&m, 1, -127, &b, &o);
    assert_true(b.nu == -1.0);
    feed2(&m, 0, 0, &b, &o);
    /* plain rotation: radius clamps at radius_min */
    for (int i = 0; i < 20; i++) feed2(&m, 0, -127, &b, &o);
    assert_true(b.radius == 1e-4);
    free(o.v);
    df_hid_desc_free(&d);

    /* mappings from the config: rotate = strength, press = type, inverted dial */
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    assert_int_equal(df_hid_config_set(&cfg, "hid.knob.rotate", "strength", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&cfg, "hid.knob.press", "type", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&cfg, "hid.1209:0001.invert_dial", "yes", NULL), DF_OK);
    assert_int_equal(df_hid_config_set(&cfg, "hid.knob.falloff_max", "2", NULL), DF_OK);
    diy_mapper(&m, &d, &cfg);
    b = start_brush();
    memset(&o, 0, sizeof o);
    feed2(&m, 0, -2, &b, &o);
    assert_true(fabs(b.strength - 1.21) < 1e-12 && b.radius == 0.25);
    feed2(&m, 1, 0, &b, &o);
    feed2(&m, 0, 0, &b, &o);
    assert_int_equal(b.type, DF_HID_BRUSH_TWIST);
    feed2(&m, 1, 0, &b, &o);
    feed2(&m, 0, 0, &b, &o);
    assert_int_equal(b.type, DF_HID_BRUSH_GRAB);
    free(o.v);
    df_hid_desc_free(&d);
}

static void test_errors(void **state)
{
    (void)state;
    df_hid_mapper m, before;
    df_hid_desc d;
    diy_mapper(&m, &d, NULL);
    df_hid_action act[DF_HID_MAX_ACTIONS];
    size_t n = 99;
    df_error e;
    const uint8_t one[1] = {1};
    before = m;
    assert_int_equal(df_hid_mapper_feed(&m, one, 1, 0, NULL, act, DF_HID_MAX_ACTIONS, &n, &e),
                     DF_EFORMAT);
    assert_non_null(strstr(e.msg, "too short"));
    assert_int_equal(n, 0);
    assert_memory_equal(&m, &before, sizeof m); /* state unchanged */
    const uint8_t two[2] = {0, 1};
    assert_int_equal(df_hid_mapper_feed(&m, two, 2, 0, NULL, act, 2, &n, &e), DF_EINVAL);
    assert_int_equal(df_hid_mapper_feed(NULL, two, 2, 0, NULL, act, 8, &n, &e), DF_EINVAL);
    assert_int_equal(df_hid_mapper_feed(&m, NULL, 2, 0, NULL, act, 8, &n, &e), DF_EINVAL);
    /* NULL brush: the wire defaults (radius 1) */
    assert_int_equal(df_hid_mapper_feed(&m, two, 2, 0, NULL, act, 8, &n, &e), DF_OK);
    assert_int_equal(n, 1);
    assert_true(fabs(act[0].brush.radius - 1.1) < 1e-15);
    /* no class / inconsistent config */
    df_hid_class_info none;
    memset(&none, 0, sizeof none);
    assert_int_equal(df_hid_mapper_init(&m, &none, &d, NULL, &e), DF_EINVAL);
    df_hid_class_info ci;
    df_hid_classify(&d, 0x1209, 0x0001, &ci);
    df_hid_config cfg;
    memset(&cfg, 0, sizeof cfg);
    df_hid_config_set(&cfg, "hid.knob.nu_min", "0.4", NULL);
    df_hid_config_set(&cfg, "hid.knob.nu_max", "0.3", NULL);
    assert_int_equal(df_hid_mapper_init(&m, &ci, &d, &cfg, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "nu_min"));
    /* unplug of a knob: nothing to end */
    assert_int_equal(df_hid_mapper_init(&m, &ci, &d, NULL, &e), DF_OK);
    assert_int_equal(df_hid_mapper_unplug(&m, act, DF_HID_MAX_ACTIONS, &n, &e), DF_OK);
    assert_int_equal(n, 0);
    assert_int_equal(df_hid_mapper_led_level(&m, 0.5), -1); /* no LED */
    df_hid_desc_free(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_surface_dial),
        cmocka_unit_test(test_huion_dials),
        cmocka_unit_test(test_powermate),
        cmocka_unit_test(test_nu_detent_and_limits),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

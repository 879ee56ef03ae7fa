/* hid_knob.c — knob mapper (Dial/Wheel + button, PowerMate): see hid_mapper.h "Knob". */
#include "server/hid/hid_mapper.h"

#include <math.h>
#include <string.h>

static df_hid_action *push(df_hid_action *out, size_t *n, int kind)
{
    df_hid_action *a = &out[(*n)++];
    memset(a, 0, sizeof *a);
    a->kind = kind;
    return a;
}

static void brush_set(df_hid_action *out, size_t *n, const df_hid_brush *cur, unsigned mask,
                      const df_hid_brush *v)
{
    df_hid_action *a = push(out, n, DF_HID_ACT_BRUSH_SET);
    a->mask = mask;
    a->brush = *cur;
    if (mask & DF_HID_BS_TYPE) a->brush.type = v->type;
    if (mask & DF_HID_BS_FALLOFF) a->brush.falloff = v->falloff;
    if (mask & DF_HID_BS_RADIUS) a->brush.radius = v->radius;
    if (mask & DF_HID_BS_NU) a->brush.nu = v->nu;
    if (mask & DF_HID_BS_STRENGTH) a->brush.strength = v->strength;
}

/* PowerMate LED brightness for radius r: linear in log r over [led_min, led_max]. */
static int led_level(const df_hid_params *p, double r)
{
    if (!(r > 0) || !isfinite(r)) return 0;
    double lo = log(p->led_min_radius), hi = log(p->led_max_radius);
    double t = (log(r) - lo) / (hi - lo);
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    return (int)lround(t * 255.0);
}

int df_hid_mapper_led_level(const df_hid_mapper *m, double radius)
{
    if (!m || !(m->info.quirks & DF_HID_QUIRK_RAW_POWERMATE) || !(radius > 0) || !isfinite(radius))
        return -1;
    return led_level(&m->p, radius);
}

static double clampd(double v, double lo, double hi, int *limited)
{
    if (v < lo) { *limited = 1; return lo; }
    if (v > hi) { *limited = 1; return hi; }
    return v;
}

/* Applies `det` detents to target tgt. */
static void rotate(df_hid_mapper *m, int tgt, int64_t det, const df_hid_brush *cur,
                   df_hid_action *out, size_t *n)
{
    const df_hid_params *p = &m->p;
    df_hid_brush v = *cur;
    unsigned mask = 0;
    int limited = 0;
    switch (tgt) {
    case DF_HID_TGT_RADIUS: {
        double r = isfinite(cur->radius) && cur->radius > 0 ? cur->radius : 1.0;
        v.radius = clampd(r * pow(p->radius_step, (double)det), p->radius_min, p->radius_max,
                          &limited);
        if (v.radius != cur->radius) mask = DF_HID_BS_RADIUS;
        break;
    }
    case DF_HID_TGT_NU: {
        /* classic falloff (+-inf) or out of range: start from the nearer bound */
        double nu = cur->nu;
        if (!(nu >= p->nu_min)) nu = p->nu_min;
        if (!(nu <= p->nu_max)) nu = p->nu_max;
        v.nu = clampd(nu + p->nu_step * (double)det, p->nu_min, p->nu_max, &limited);
        if (v.nu != cur->nu) mask = DF_HID_BS_NU;
        break;
    }
    case DF_HID_TGT_STRENGTH: {
        double s = isfinite(cur->strength) ? cur->strength : 1.0;
        v.strength = clampd(s * pow(p->strength_step, (double)det), -1e6, 1e6, &limited);
        if (v.strength != cur->strength) mask = DF_HID_BS_STRENGTH;
        break;
    }
    default: return;
    }
    if (mask) brush_set(out, n, cur, mask, &v);
    if (mask || limited) {
        uint64_t ad = (uint64_t)(det < 0 ? -det : det);
        df_hid_mapper_haptic(m, DF_HID_WAVE_CLICK, mask && !limited && ad > 1 ? (unsigned)(ad - 1) : 0,
                             out, n);
    }
    if ((mask & DF_HID_BS_RADIUS) && (m->info.quirks & DF_HID_QUIRK_RAW_POWERMATE)) {
        df_hid_action *a = push(out, n, DF_HID_ACT_LED);
        a->led = led_level(p, v.radius);
    }
}

/* press + release without rotation (or the press edge of a NO_RELEASE knob) */
static void press(df_hid_mapper *m, const df_hid_brush *cur, df_hid_action *out, size_t *n)
{
    df_hid_brush v = *cur;
    unsigned mask = 0;
    if (m->p.press == DF_HID_PRESS_FALLOFF) {
        v.falloff = (uint8_t)(cur->falloff >= 1 && cur->falloff < m->p.falloff_max ? cur->falloff + 1 : 1);
        if (v.falloff != cur->falloff) mask = DF_HID_BS_FALLOFF;
    } else if (m->p.press == DF_HID_PRESS_TYPE) {
        v.type = df_hid_mapper_next_type(&m->p, cur->type);
        if (v.type != cur->type) mask = DF_HID_BS_TYPE;
    }
    if (!mask) return;
    brush_set(out, n, cur, mask, &v);
    df_hid_mapper_haptic(m, DF_HID_WAVE_CLICK, 0, out, n);
}

int df_hid_knob_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                     const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err)
{
    (void)t;
    (void)err;
    int64_t v;
    int was = m->pressed, now = was;
    if (df_hid_loc_read(&m->info.ctl[DF_HID_CTL_BUTTON], r, len, &v)) now = v != 0;
    int64_t det = 0;
    if (df_hid_loc_read(&m->info.ctl[DF_HID_CTL_DIAL], r, len, &v) && v != 0) {
        m->acc_units += (double)(m->p.invert_dial ? -v : v);
        int64_t pos = (int64_t)floor(m->acc_units / m->units_per_detent);
        det = pos - m->detent_pos;
        m->detent_pos = pos;
    }
    if (m->info.quirks & DF_HID_QUIRK_NO_RELEASE) {
        /* the release is never reported: the press edge is the whole press; rotation is plain */
        if (!was && now) press(m, cur, out, n);
        m->pressed = now;
        if (det) rotate(m, m->p.rotate, det, cur, out, n);
        return DF_OK;
    }
    if (!was && now) {
        m->pressed = 1;
        m->rotated_while_pressed = 0;
    }
    if (det) {
        int held = was || now;
        if (held) m->rotated_while_pressed = 1;
        /* a press edge in this report applied nothing yet: cur is still the session's value */
        rotate(m, held ? m->p.press_rotate : m->p.rotate, det, cur, out, n);
    }
    if (was && !now) {
        m->pressed = 0;
        if (!m->rotated_while_pressed) press(m, cur, out, n);
    }
    return DF_OK;
}

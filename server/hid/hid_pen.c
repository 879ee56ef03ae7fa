/* hid_pen.c — pen mapper (Digitizer pen): see hid_mapper.h "Pen". */
#include "server/hid/hid_mapper.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846
#define UNIT_DEGREES 0x14  /* HID unit: English Rotation, degrees */

static double norm01(const df_hid_loc *l, int64_t v)
{
    double lo = (double)l->logical_min, hi = (double)l->logical_max;
    if (!(hi > lo)) return 0;
    double t = ((double)v - lo) / (hi - lo);
    return t < 0 ? 0 : t > 1 ? 1 : t;
}

/* Tilt in radians: physical degrees (with the unit exponent) when the unit says degrees and the
 * physical range is set, else the logical value read as degrees (the Digitizer page default). */
static double tilt_rad(const df_hid_loc *l, int64_t v)
{
    double deg = (double)v;
    if (l->physical_min != l->physical_max && l->logical_max > l->logical_min &&
        l->unit == UNIT_DEGREES) {
        double t = ((double)v - (double)l->logical_min) /
                   ((double)l->logical_max - (double)l->logical_min);
        deg = ((double)l->physical_min + t * (double)(l->physical_max - l->physical_min)) *
              pow(10.0, l->unit_exponent);
    }
    if (deg > 89.9) deg = 89.9;
    if (deg < -89.9) deg = -89.9;
    return deg * PI / 180.0;
}

static df_hid_action *push(df_hid_action *out, size_t *n, int kind)
{
    df_hid_action *a = &out[(*n)++];
    memset(a, 0, sizeof *a);
    a->kind = kind;
    return a;
}

int df_hid_pen_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                    const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err)
{
    (void)t;
    (void)err;
    const df_hid_params *p = &m->p;
    const df_hid_loc *c = m->info.ctl;
    int64_t vx, vy, v;
    if (!df_hid_loc_read(&c[DF_HID_CTL_X], r, len, &vx) ||
        !df_hid_loc_read(&c[DF_HID_CTL_Y], r, len, &vy))
        return DF_OK; /* not the pen's report */
    int in_range = 1;
    if (df_hid_loc_read(&c[DF_HID_CTL_IN_RANGE], r, len, &v)) in_range = v != 0;
    double pressure = 0;
    if (df_hid_loc_read(&c[DF_HID_CTL_PRESSURE], r, len, &v)) pressure = norm01(&c[DF_HID_CTL_PRESSURE], v);
    int tip = pressure > 0;
    if (df_hid_loc_read(&c[DF_HID_CTL_TIP], r, len, &v)) tip = v != 0;
    int barrel = 0;
    if (df_hid_loc_read(&c[DF_HID_CTL_BARREL], r, len, &v)) barrel = v != 0;
    double tilt[2] = {0, 0};
    if (df_hid_loc_read(&c[DF_HID_CTL_XTILT], r, len, &v)) tilt[0] = tilt_rad(&c[DF_HID_CTL_XTILT], v);
    if (df_hid_loc_read(&c[DF_HID_CTL_YTILT], r, len, &v)) tilt[1] = tilt_rad(&c[DF_HID_CTL_YTILT], v);
    tip = tip && in_range;
    double xy[2] = {norm01(&c[DF_HID_CTL_X], vx), norm01(&c[DF_HID_CTL_Y], vy)};
    /* twist: the pen axis (x right, y down, z into the surface) times twist_angle * pressure */
    double ax[3] = {tan(tilt[0]), tan(tilt[1]), 1.0};
    double an = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    double twist[3];
    for (int k = 0; k < 3; k++) twist[k] = ax[k] / an * p->twist_angle * pressure;

    if (in_range) {
        df_hid_action *a = push(out, n, DF_HID_ACT_CURSOR);
        a->cursor_mode = DF_HID_CUR_NORMALIZED;
        a->cursor_flags = DF_HID_CUR_IN_RANGE | (tip ? DF_HID_CUR_STROKE : 0u);
        memcpy(a->xy, xy, sizeof xy);
        memcpy(a->tilt, tilt, sizeof tilt);
        a->pressure = pressure;
    }
    if (barrel && !m->barrel_down && in_range && p->barrel != DF_HID_PRESS_NONE) {
        df_hid_action *a = push(out, n, DF_HID_ACT_BRUSH_SET);
        a->brush = *cur;
        if (p->barrel == DF_HID_PRESS_TYPE) {
            a->brush.type = df_hid_mapper_next_type(p, cur->type);
            a->mask = DF_HID_BS_TYPE;
        } else {
            int fmax = p->falloff_max;
            a->brush.falloff = (uint8_t)(cur->falloff >= 1 && cur->falloff < fmax ? cur->falloff + 1 : 1);
            a->mask = DF_HID_BS_FALLOFF;
        }
    }
    m->barrel_down = barrel;
    int kind = -1;
    if (tip && !m->stroke) {
        m->stroke = 1;
        m->stroke_strength = cur->strength;
        kind = DF_HID_ACT_STROKE_BEGIN;
    } else if (tip) {
        kind = DF_HID_ACT_STROKE_UPDATE;
    } else if (m->stroke) {
        m->stroke = 0;
        kind = DF_HID_ACT_STROKE_END;
    }
    if (kind >= 0) {
        df_hid_action *a = push(out, n, kind);
        a->brush = *cur;
        if (kind == DF_HID_ACT_STROKE_END) { /* the last values of the stroke */
            a->strength = m->last_strength;
            memcpy(a->twist, m->pen_twist, sizeof a->twist);
        } else {
            a->strength = m->stroke_strength * p->strength_max * pow(pressure, p->pressure_gamma);
            m->last_strength = a->strength;
            memcpy(a->twist, twist, sizeof twist);
            memcpy(m->pen_twist, twist, sizeof twist);
        }
        memcpy(a->xy, xy, sizeof xy);
        memcpy(a->tilt, tilt, sizeof tilt);
        a->pressure = pressure;
        if (kind != DF_HID_ACT_STROKE_UPDATE) df_hid_mapper_haptic(m, DF_HID_WAVE_BUZZ, 0, out, n);
    }
    m->tip_down = tip;
    if (!in_range && m->in_range) {
        df_hid_action *a = push(out, n, DF_HID_ACT_CURSOR);
        a->cursor_mode = DF_HID_CUR_NORMALIZED;
        a->cursor_flags = 0;
        memcpy(a->xy, xy, sizeof xy);
    }
    m->in_range = in_range;
    return DF_OK;
}

/* hid_mouse3d.c — 3d-mouse mapper (Multi-axis Controller): see hid_mapper.h "3d-mouse". */
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

static void stroke_action(const df_hid_mapper *m, int kind, df_hid_action *out, size_t *n,
                          const df_hid_brush *cur)
{
    df_hid_action *a = push(out, n, kind);
    memcpy(a->move, m->tip, sizeof a->move);
    memcpy(a->twist, m->twist, sizeof a->twist);
    a->strength = m->stroke_strength;
    a->brush = *cur;
}

/* axis value v of control loc as a fraction of its logical max, 0 inside the deadzone */
static double deflection(const df_hid_loc *loc, int64_t v, double deadzone)
{
    double lmax = (double)loc->logical_max;
    if (!(lmax > 0)) lmax = (double)(loc->logical_min < 0 ? -loc->logical_min : 1);
    double f = (double)v / lmax;
    if (fabs(f) <= deadzone) return 0;
    if (f > 1) f = 1;
    if (f < -1) f = -1;
    return f;
}

int df_hid_mouse3d_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                        const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err)
{
    (void)err;
    const df_hid_params *p = &m->p;
    int64_t v;
    int buttons = m->buttons;
    if (df_hid_loc_read(&m->info.ctl[DF_HID_CTL_BUTTON], r, len, &v))
        buttons = (buttons & ~1) | (v ? 1 : 0);
    if (df_hid_loc_read(&m->info.ctl[DF_HID_CTL_BUTTON2], r, len, &v))
        buttons = (buttons & ~2) | (v ? 2 : 0);
    int sb = p->stroke_button == 2 ? 2 : 1;
    int was = (m->buttons & sb) != 0, now = (buttons & sb) != 0;
    m->buttons = buttons;
    if (!was && now && !m->stroke) {
        memset(m->tip, 0, sizeof m->tip);
        memset(m->twist, 0, sizeof m->twist);
        m->stroke = 1;
        m->stroke_strength = m->last_strength = cur->strength;
        stroke_action(m, DF_HID_ACT_STROKE_BEGIN, out, n, cur);
        df_hid_mapper_haptic(m, DF_HID_WAVE_BUZZ, 0, out, n);
    }
    double f[6];
    int have = 0;
    for (int k = 0; k < 6; k++) {
        f[k] = 0;
        const df_hid_loc *loc = &m->info.ctl[DF_HID_CTL_X + k];
        if (!df_hid_loc_read(loc, r, len, &v)) continue;
        have = 1;
        f[k] = deflection(loc, v, p->deadzone) * (p->invert[k] ? -1.0 : 1.0);
    }
    if (have) {
        unsigned rid = len ? r[0] : 0;
        if (!m->info.ctl[DF_HID_CTL_X].report_id && !m->info.ctl[DF_HID_CTL_RX].report_id) rid = 0;
        uint64_t prev = m->last_us[rid];
        double dt = 0;
        if (prev && t + 1 > prev) {
            uint64_t d = t + 1 - prev;
            dt = (double)(d > DF_HID_MAX_DT_US ? DF_HID_MAX_DT_US : d) * 1e-6;
        }
        m->last_us[rid] = t + 1;
        double d3[3], w3[3];
        int moved = 0, turned = 0;
        for (int k = 0; k < 3; k++) {
            d3[k] = f[k] * p->sensitivity * dt * m->scale;
            w3[k] = f[k + 3] * p->twist_sensitivity * dt;
            if (d3[k] != 0) moved = 1;
            if (w3[k] != 0) turned = 1;
        }
        if (moved) {
            df_hid_action *a = push(out, n, DF_HID_ACT_CURSOR);
            a->cursor_mode = DF_HID_CUR_DELTA;
            a->cursor_flags = DF_HID_CUR_IN_RANGE | (m->stroke ? DF_HID_CUR_STROKE : 0u);
            memcpy(a->move, d3, sizeof d3);
        }
        if (m->stroke && (moved || turned)) {
            for (int k = 0; k < 3; k++) {
                m->tip[k] += d3[k];
                m->twist[k] += w3[k];
            }
            stroke_action(m, DF_HID_ACT_STROKE_UPDATE, out, n, cur);
        }
    }
    if (was && !now && m->stroke) {
        stroke_action(m, DF_HID_ACT_STROKE_END, out, n, cur);
        m->stroke = 0;
        df_hid_mapper_haptic(m, DF_HID_WAVE_BUZZ, 0, out, n);
    }
    return DF_OK;
}

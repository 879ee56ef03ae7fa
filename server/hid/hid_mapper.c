/* hid_mapper.c — mapper state, dispatch by class, unplug, shared helpers: see hid_mapper.h. */
#include "server/hid/hid_mapper.h"

#include <math.h>
#include <string.h>

int df_hid_mapper_init(df_hid_mapper *m, const df_hid_class_info *info, const df_hid_desc *desc,
                       const df_hid_config *cfg, df_error *err)
{
    if (!m || !info) return df_error_set(err, DF_EINVAL, "hid mapper: NULL argument");
    if (info->cls <= DF_HID_CLASS_NONE || info->cls >= DF_HID_CLASS_COUNT)
        return df_error_set(err, DF_EINVAL, "hid mapper: device %04x:%04x has no class (%s)",
                            info->vid, info->pid, info->reason);
    df_hid_params p;
    int rc = df_hid_config_resolve(cfg, info->cls, info->vid, info->pid, &p, err);
    if (rc != DF_OK) return rc;
    memset(m, 0, sizeof *m);
    m->info = *info;
    m->p = p;
    m->scale = 1.0;
    rc = df_hid_haptics_init(desc, &m->hap, err);
    if (rc != DF_OK) return rc;
    if (p.dial_units_per_detent > 0)
        m->units_per_detent = p.dial_units_per_detent;
    else if (info->dial_units_per_turn > 0 && !(info->quirks & DF_HID_QUIRK_DIAL_DETENTS))
        m->units_per_detent = info->dial_units_per_turn / p.detents_per_turn;
    else
        m->units_per_detent = 1.0;
    return DF_OK;
}

void df_hid_mapper_set_scale(df_hid_mapper *m, double scale)
{
    if (m && isfinite(scale) && scale > 0) m->scale = scale;
}

/* A report that carries a control must be long enough for it. */
static int check_len(const df_hid_mapper *m, const uint8_t *r, size_t len, df_error *err)
{
    for (int k = 0; k < DF_HID_CTL_COUNT; k++) {
        const df_hid_loc *l = &m->info.ctl[k];
        if (!l->present) continue;
        if (l->report_id && (len == 0 || r[0] != l->report_id)) continue;
        uint64_t end = (uint64_t)l->bit_offset + (uint64_t)l->bit_size * (l->array ? l->count : 1);
        if (end > (uint64_t)len * 8)
            return df_error_set(err, DF_EFORMAT, "hid %s %04x:%04x: report %u of %zu bytes is "
                                "too short for its controls (%llu bits)",
                                df_hid_class_name(m->info.cls), m->info.vid, m->info.pid,
                                l->report_id, len, (unsigned long long)end);
    }
    return DF_OK;
}

int df_hid_mapper_feed(df_hid_mapper *m, const uint8_t *report, size_t len, uint64_t time_us,
                       const df_hid_brush *cur, df_hid_action *out, size_t cap, size_t *n,
                       df_error *err)
{
    if (n) *n = 0;
    if (!m || (!report && len) || !out || !n)
        return df_error_set(err, DF_EINVAL, "hid mapper: NULL argument");
    if (cap < DF_HID_MAX_ACTIONS)
        return df_error_set(err, DF_EINVAL, "hid mapper: room for %zu actions, need %d", cap,
                            DF_HID_MAX_ACTIONS);
    df_hid_brush defaults = {DF_HID_BRUSH_GRAB, 1, 1.0, 0.5, 1.0};
    if (!cur) cur = &defaults;
    int rc = check_len(m, report, len, err);
    if (rc != DF_OK) return rc;
    df_hid_mapper next = *m; /* all or nothing: the state changes only on success */
    size_t k = 0;
    switch (m->info.cls) {
    case DF_HID_CLASS_KNOB: rc = df_hid_knob_feed(&next, report, len, time_us, cur, out, &k, err); break;
    case DF_HID_CLASS_MOUSE3D:
        rc = df_hid_mouse3d_feed(&next, report, len, time_us, cur, out, &k, err);
        break;
    case DF_HID_CLASS_PEN: rc = df_hid_pen_feed(&next, report, len, time_us, cur, out, &k, err); break;
    default: rc = df_error_set(err, DF_EINVAL, "hid mapper: no class");
    }
    if (rc != DF_OK) return rc;
    *m = next;
    *n = k;
    return DF_OK;
}

int df_hid_mapper_unplug(df_hid_mapper *m, df_hid_action *out, size_t cap, size_t *n,
                         df_error *err)
{
    if (n) *n = 0;
    if (!m || !out || !n) return df_error_set(err, DF_EINVAL, "hid mapper: NULL argument");
    if (cap < DF_HID_MAX_ACTIONS)
        return df_error_set(err, DF_EINVAL, "hid mapper: room for %zu actions, need %d", cap,
                            DF_HID_MAX_ACTIONS);
    size_t k = 0;
    if (m->stroke) {
        df_hid_action *a = &out[k++];
        memset(a, 0, sizeof *a);
        a->kind = DF_HID_ACT_STROKE_END;
        if (m->info.cls == DF_HID_CLASS_MOUSE3D) {
            memcpy(a->move, m->tip, sizeof a->move);
            memcpy(a->twist, m->twist, sizeof a->twist);
        } else {
            memcpy(a->twist, m->pen_twist, sizeof a->twist);
        }
        a->strength = m->last_strength;
    }
    if (m->info.cls == DF_HID_CLASS_PEN && m->in_range) {
        df_hid_action *a = &out[k++];
        memset(a, 0, sizeof *a);
        a->kind = DF_HID_ACT_CURSOR;
        a->cursor_mode = DF_HID_CUR_NORMALIZED;
        a->cursor_flags = 0;
    }
    m->stroke = 0;
    m->in_range = m->tip_down = m->barrel_down = 0;
    m->pressed = m->rotated_while_pressed = 0;
    m->buttons = 0;
    memset(m->last_us, 0, sizeof m->last_us);
    *n = k;
    return DF_OK;
}

void df_hid_mapper_haptic(const df_hid_mapper *m, unsigned wave, unsigned repeat,
                          df_hid_action *out, size_t *n)
{
    if (!m->p.haptics || !m->hap.present || *n >= DF_HID_MAX_ACTIONS) return;
    int idx = df_hid_haptics_index(&m->hap, wave);
    if (idx < 0) return;
    df_hid_action *a = &out[*n];
    memset(a, 0, sizeof *a);
    if (df_hid_haptics_report(&m->hap, (unsigned)idx, repeat, (unsigned)m->p.haptic_retrigger_ms,
                              a->bytes, sizeof a->bytes, &a->n_bytes, NULL) != DF_OK)
        return;
    a->kind = DF_HID_ACT_HAPTIC;
    a->waveform = wave;
    (*n)++;
}

uint8_t df_hid_mapper_next_type(const df_hid_params *p, uint8_t type)
{
    if (p->n_type_cycle <= 0) return type;
    for (int i = 0; i < p->n_type_cycle; i++)
        if (p->type_cycle[i] == type) return p->type_cycle[(i + 1) % p->n_type_cycle];
    return p->type_cycle[0];
}

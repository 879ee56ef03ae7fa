/* hid_class.c — device classes by usage plus the quirk table: see hid_class.h. */
#include "server/hid/hid_class.h"

#include <stdio.h>
#include <string.h>

#define U(page, id) ((uint32_t)(page) << 16 | (uint32_t)(id))

enum {
    GD_POINTER = 0x01, GD_MOUSE = 0x02, GD_MULTI_AXIS = 0x08, GD_X = 0x30, GD_Y = 0x31,
    GD_Z = 0x32, GD_RX = 0x33, GD_RY = 0x34, GD_RZ = 0x35, GD_DIAL = 0x37, GD_WHEEL = 0x38,
    GD_RES_MULT = 0x48
};
enum { DG_PEN = 0x02, DG_STYLUS = 0x20, DG_TIP_PRESSURE = 0x30, DG_IN_RANGE = 0x32,
       DG_XTILT = 0x3D, DG_YTILT = 0x3E, DG_TIP_SWITCH = 0x42, DG_BARREL = 0x44 };

/* The quirk table: hardware whose descriptor lies or is missing. Kept small; each row says
 * what is wrong and what we do instead. */
typedef struct quirk {
    uint16_t vid, pid;
    unsigned bits;
    const char *why;
} quirk;

static const quirk k_quirks[] = {
    /* Kernel fixup Logitech__SpaceNavigator: axes say Relative (0x06) but report the cap's
     * absolute displacement from rest. We read them as absolute deflections. */
    {0x046d, 0xc626, DF_HID_QUIRK_AXES_ABSOLUTE, "SpaceNavigator: axes declared Relative are absolute"},
    /* No hidraw node and no descriptor we could read: 6-byte libusb interrupt packets
     * [button][s8 rotation][0][led][pulse][speed] (../shared/hid/README.md). */
    {0x077d, 0x0410, DF_HID_QUIRK_RAW_POWERMATE, "PowerMate: raw 6-byte packets, no descriptor"},
    /* Huion K20 (USB, firmware mode): the puck's centre button never reports its release
     * (udev-hid-bpf doc). Its dial sends +-1 per detent although the descriptor carries a
     * 0..3600 Resolution Multiplier copied from the Surface Dial. */
    {0x256c, 0x0069, DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_NO_RELEASE,
     "Huion K20: dial in detents, button release never reported"},
    {0x256c, 0x0060, DF_HID_QUIRK_DIAL_DETENTS, "Huion Dial 2: dial in detents"},
    /* Huion K20 over Bluetooth: the node with the Dial usage never sends; the dial arrives on
     * the mouse node as Wheel (one step then a zero report), its button as Consumer Play/Pause. */
    {0x256c, 0x8251, DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_WHEEL_KNOB,
     "Huion K20 BT: dial as mouse wheel, button as Play/Pause"},
};

const char *df_hid_class_name(int cls)
{
    switch (cls) {
    case DF_HID_CLASS_KNOB: return "knob";
    case DF_HID_CLASS_MOUSE3D: return "3d-mouse";
    case DF_HID_CLASS_PEN: return "pen";
    default: return "none";
    }
}

int df_hid_class_from_name(const char *name)
{
    if (!name) return -1;
    for (int c = 0; c < DF_HID_CLASS_COUNT; c++)
        if (strcmp(name, df_hid_class_name(c)) == 0) return c;
    return -1;
}

static void loc_from_field(const df_hid_field *f, unsigned index, uint32_t usage, df_hid_loc *loc)
{
    memset(loc, 0, sizeof *loc);
    loc->present = 1;
    loc->report_id = f->report_id;
    loc->is_signed = f->is_signed;
    loc->relative = (f->flags & DF_HID_F_RELATIVE) ? 1 : 0;
    loc->bit_size = f->bit_size;
    loc->usage = usage;
    loc->logical_min = f->logical_min;
    loc->logical_max = f->logical_max;
    loc->physical_min = f->physical_min;
    loc->physical_max = f->physical_max;
    loc->unit = f->unit;
    loc->unit_exponent = f->unit_exponent;
    if (f->flags & DF_HID_F_VARIABLE) {
        loc->count = 1;
        loc->bit_offset = f->bit_offset + index * f->bit_size;
    } else {
        loc->array = 1;
        loc->count = f->count;
        loc->bit_offset = f->bit_offset;
        loc->array_usage_min = f->usage_min;
    }
}

int df_hid_loc_find(const df_hid_desc *d, uint32_t usage, uint32_t application, int prefer_id,
                    df_hid_loc *loc)
{
    memset(loc, 0, sizeof *loc);
    if (!d) return 0;
    const df_hid_field *best = NULL;
    unsigned best_index = 0;
    for (size_t i = 0; i < d->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if (f->kind != DF_HID_INPUT || (f->flags & DF_HID_F_CONSTANT)) continue;
        if (f->bit_size < 1 || f->bit_size > 32 || f->count == 0) continue;
        if (application && f->application != application) continue;
        if (usage < f->usage_min || usage > f->usage_max) continue;
        unsigned index = 0;
        if ((f->flags & DF_HID_F_VARIABLE) && f->usage_min != f->usage_max)
            index = usage - f->usage_min;
        if (index >= f->count) continue;
        if (!best || (prefer_id >= 0 && f->report_id == prefer_id && best->report_id != prefer_id)) {
            best = f;
            best_index = index;
        }
    }
    if (!best) return 0;
    loc_from_field(best, best_index, usage, loc);
    return 1;
}

int df_hid_loc_read(const df_hid_loc *loc, const uint8_t *buf, size_t n, int64_t *value)
{
    if (!loc || !loc->present || !value || (!buf && n)) return 0;
    if (loc->report_id && (n == 0 || buf[0] != loc->report_id)) return 0;
    int64_t v;
    if (!loc->array) {
        if (df_hid_extract(buf, n, loc->bit_offset, loc->bit_size, loc->is_signed, &v, NULL) != DF_OK)
            return 0;
        *value = v;
        return 1;
    }
    int hit = 0;
    for (unsigned k = 0; k < loc->count; k++) {
        if (df_hid_extract(buf, n, loc->bit_offset + k * loc->bit_size, loc->bit_size,
                           loc->is_signed, &v, NULL) != DF_OK)
            return 0;
        if (v < loc->logical_min || v > loc->logical_max) continue; /* out of range = empty */
        if ((uint64_t)loc->array_usage_min + (uint64_t)(v - loc->logical_min) == loc->usage) hit = 1;
    }
    *value = hit;
    return 1;
}

/* Application collections present in d: the distinct `application` usages of input fields. */
static size_t applications(const df_hid_desc *d, uint32_t *apps, size_t cap)
{
    size_t n = 0;
    for (size_t i = 0; i < d->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if (f->kind != DF_HID_INPUT) continue;
        size_t k = 0;
        while (k < n && apps[k] != f->application) k++;
        if (k == n && n < cap) apps[n++] = f->application;
    }
    return n;
}

/* Some button of the Button page in application `app`, button 1 preferred. */
static int find_button(const df_hid_desc *d, uint32_t app, int prefer_id, int nth, df_hid_loc *loc)
{
    if (df_hid_loc_find(d, U(0x09, nth), app, prefer_id, loc)) return 1;
    if (nth != 1) return 0;
    for (uint32_t b = 2; b <= 16; b++)
        if (df_hid_loc_find(d, U(0x09, b), app, prefer_id, loc)) return 1;
    return 0;
}

/* The Resolution Multiplier feature's physical (else logical) max in application `app`. */
static double res_mult(const df_hid_desc *d, uint32_t app)
{
    for (size_t i = 0; i < d->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if (f->kind != DF_HID_FEATURE || f->application != app) continue;
        if (U(0x01, GD_RES_MULT) < f->usage_min || U(0x01, GD_RES_MULT) > f->usage_max) continue;
        int64_t m = f->physical_max > 0 ? f->physical_max : f->logical_max;
        return m > 1 ? (double)m : 0;
    }
    return 0;
}

static int try_knob(const df_hid_desc *d, const uint32_t *apps, size_t na, unsigned quirks,
                    df_hid_class_info *out)
{
    for (size_t a = 0; a < na; a++) {
        df_hid_loc dial, btn, x;
        int wheel = 0;
        if (!df_hid_loc_find(d, U(0x01, GD_DIAL), apps[a], -1, &dial)) {
            if (!df_hid_loc_find(d, U(0x01, GD_WHEEL), apps[a], -1, &dial)) continue;
            /* a wheel next to X/Y is a mouse wheel, unless the quirk says this node's wheel is
             * the dial */
            if (df_hid_loc_find(d, U(0x01, GD_X), apps[a], -1, &x) &&
                !(quirks & DF_HID_QUIRK_WHEEL_KNOB))
                continue;
            wheel = 1;
        }
        int has_btn = 0;
        if (wheel && (quirks & DF_HID_QUIRK_WHEEL_KNOB)) /* Consumer Play/Pause, any app */
            has_btn = df_hid_loc_find(d, U(0x0C, 0xCD), 0, -1, &btn);
        if (!has_btn) has_btn = find_button(d, apps[a], dial.report_id, 1, &btn);
        if (!has_btn) continue;
        out->cls = DF_HID_CLASS_KNOB;
        out->application = apps[a];
        out->ctl[DF_HID_CTL_DIAL] = dial;
        out->ctl[DF_HID_CTL_DIAL].relative = 1;
        out->ctl[DF_HID_CTL_BUTTON] = btn;
        out->dial_units_per_turn = (quirks & DF_HID_QUIRK_DIAL_DETENTS) ? 0 : res_mult(d, apps[a]);
        snprintf(out->reason, sizeof out->reason, "%s 0x01:0x%02x with a button in application "
                 "0x%08x", wheel ? "Wheel" : "Dial", wheel ? GD_WHEEL : GD_DIAL, apps[a]);
        return 1;
    }
    return 0;
}

static int try_mouse3d(const df_hid_desc *d, const uint32_t *apps, size_t na, unsigned quirks,
                       df_hid_class_info *out)
{
    for (size_t a = 0; a < na; a++) {
        if (apps[a] != U(0x01, GD_MULTI_AXIS)) continue;
        df_hid_loc ax[6];
        int all = 1;
        for (int k = 0; k < 6 && all; k++)
            all = df_hid_loc_find(d, U(0x01, GD_X + k), apps[a], -1, &ax[k]);
        if (!all) continue;
        out->cls = DF_HID_CLASS_MOUSE3D;
        out->application = apps[a];
        for (int k = 0; k < 6; k++) {
            out->ctl[DF_HID_CTL_X + k] = ax[k];
            if (quirks & DF_HID_QUIRK_AXES_ABSOLUTE) out->ctl[DF_HID_CTL_X + k].relative = 0;
        }
        find_button(d, apps[a], -1, 1, &out->ctl[DF_HID_CTL_BUTTON]);
        find_button(d, apps[a], -1, 2, &out->ctl[DF_HID_CTL_BUTTON2]);
        snprintf(out->reason, sizeof out->reason,
                 "Multi-axis Controller 0x01:0x08 with X Y Z Rx Ry Rz");
        return 1;
    }
    return 0;
}

static int try_pen(const df_hid_desc *d, const uint32_t *apps, size_t na, df_hid_class_info *out)
{
    for (size_t a = 0; a < na; a++) {
        if (apps[a] >> 16 != 0x0D) continue;
        /* the pen's controls: in a Pen application, or in a Stylus collection of another */
        uint32_t app = apps[a];
        int stylus = 0;
        for (size_t i = 0; i < d->n_fields; i++)
            if (d->fields[i].application == app && d->fields[i].collection == U(0x0D, DG_STYLUS))
                stylus = 1;
        if (app != U(0x0D, DG_PEN) && !stylus) continue;
        df_hid_loc tip, pres, x, y;
        int has_tip = df_hid_loc_find(d, U(0x0D, DG_TIP_SWITCH), app, -1, &tip);
        int has_pres = df_hid_loc_find(d, U(0x0D, DG_TIP_PRESSURE), app, -1, &pres);
        if (!has_tip && !has_pres) continue;
        int rid = has_tip ? tip.report_id : pres.report_id;
        if (!df_hid_loc_find(d, U(0x01, GD_X), app, rid, &x) ||
            !df_hid_loc_find(d, U(0x01, GD_Y), app, rid, &y))
            continue;
        out->cls = DF_HID_CLASS_PEN;
        out->application = app;
        out->ctl[DF_HID_CTL_TIP] = tip;
        out->ctl[DF_HID_CTL_PRESSURE] = pres;
        out->ctl[DF_HID_CTL_X] = x;
        out->ctl[DF_HID_CTL_Y] = y;
        df_hid_loc_find(d, U(0x0D, DG_IN_RANGE), app, rid, &out->ctl[DF_HID_CTL_IN_RANGE]);
        df_hid_loc_find(d, U(0x0D, DG_BARREL), app, rid, &out->ctl[DF_HID_CTL_BARREL]);
        df_hid_loc_find(d, U(0x0D, DG_XTILT), app, rid, &out->ctl[DF_HID_CTL_XTILT]);
        df_hid_loc_find(d, U(0x0D, DG_YTILT), app, rid, &out->ctl[DF_HID_CTL_YTILT]);
        snprintf(out->reason, sizeof out->reason, "Digitizer pen with %s%s%s in application "
                 "0x%08x", has_tip ? "Tip Switch" : "", has_tip && has_pres ? " and " : "",
                 has_pres ? "Tip Pressure" : "", app);
        return 1;
    }
    return 0;
}

/* What the descriptor is mostly about, for a NONE reason: the first application's page. */
static void none_reason(const df_hid_desc *d, const uint32_t *apps, size_t na,
                        df_hid_class_info *out)
{
    out->cls = DF_HID_CLASS_NONE;
    if (!d || d->n_fields == 0) {
        snprintf(out->reason, sizeof out->reason, "no report descriptor: not a known device");
        return;
    }
    int vendor = na > 0;
    for (size_t a = 0; a < na; a++)
        if (apps[a] >> 16 < 0xff00) vendor = 0;
    if (vendor)
        snprintf(out->reason, sizeof out->reason, "vendor-defined page 0x%04x only: the "
                 "descriptor does not describe the real layout", apps[0] >> 16);
    else
        snprintf(out->reason, sizeof out->reason, "no Dial/Wheel with a button, no Multi-axis "
                 "Controller with 6 axes, no Digitizer pen (first application 0x%08x)",
                 na ? apps[0] : 0u);
}

int df_hid_classify(const df_hid_desc *d, uint16_t vid, uint16_t pid, df_hid_class_info *out)
{
    if (!out) return DF_EINVAL;
    memset(out, 0, sizeof *out);
    out->vid = vid;
    out->pid = pid;
    unsigned quirks = 0;
    for (size_t i = 0; i < sizeof k_quirks / sizeof k_quirks[0]; i++)
        if (k_quirks[i].vid == vid && k_quirks[i].pid == pid) quirks = k_quirks[i].bits;
    if ((quirks & DF_HID_QUIRK_RAW_POWERMATE) && (!d || d->n_fields == 0)) {
        out->cls = DF_HID_CLASS_KNOB;
        out->quirks = DF_HID_QUIRK_RAW_POWERMATE;
        df_hid_loc *b = &out->ctl[DF_HID_CTL_BUTTON], *r = &out->ctl[DF_HID_CTL_DIAL];
        b->present = 1; b->bit_offset = 0; b->bit_size = 1; b->count = 1;
        b->logical_max = 1; b->usage = U(0x09, 1);
        r->present = 1; r->bit_offset = 8; r->bit_size = 8; r->count = 1; r->is_signed = 1;
        r->relative = 1; r->logical_min = -128; r->logical_max = 127; r->usage = U(0x01, GD_DIAL);
        snprintf(out->reason, sizeof out->reason, "quirk %04x:%04x: PowerMate raw 6-byte packets",
                 vid, pid);
        return DF_OK;
    }
    uint32_t apps[64];
    size_t na = d ? applications(d, apps, 64) : 0;
    int found = 0;
    if (d && d->n_fields) {
        found = try_knob(d, apps, na, quirks, out) || try_mouse3d(d, apps, na, quirks, out) ||
                try_pen(d, apps, na, out);
    }
    if (!found) {
        none_reason(d, apps, na, out);
        return DF_OK;
    }
    /* keep only the quirks that concern the class found */
    unsigned keep = out->cls == DF_HID_CLASS_KNOB
                        ? (DF_HID_QUIRK_DIAL_DETENTS | DF_HID_QUIRK_NO_RELEASE | DF_HID_QUIRK_WHEEL_KNOB)
                        : out->cls == DF_HID_CLASS_MOUSE3D ? DF_HID_QUIRK_AXES_ABSOLUTE : 0;
    out->quirks = quirks & keep;
    if (out->quirks) {
        size_t l = strlen(out->reason);
        snprintf(out->reason + l, sizeof out->reason - l, "; quirk %04x:%04x", vid, pid);
    }
    return DF_OK;
}

int df_hid_loc_element(const df_hid_desc *d, int kind, uint32_t usage, uint32_t coll, int id,
                       int variable_only, df_hid_loc *loc)
{
    memset(loc, 0, sizeof *loc);
    for (size_t i = 0; i < d->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if (f->kind != kind || (f->flags & DF_HID_F_CONSTANT)) continue;
        if (variable_only && !(f->flags & DF_HID_F_VARIABLE)) continue;
        if (coll && f->collection != coll) continue;
        if (id >= 0 && f->report_id != id) continue;
        if (usage < f->usage_min || usage > f->usage_max || f->count == 0) continue;
        if (f->bit_size < 1 || f->bit_size > 32) continue;
        unsigned index = 0;
        if ((f->flags & DF_HID_F_VARIABLE) && f->usage_min != f->usage_max)
            index = usage - f->usage_min;
        if (index >= f->count) continue;
        loc_from_field(f, index, usage, loc);
        loc->count = 1;                      /* an array field: its first slot */
        loc->array_usage_min = f->usage_min; /* variable fields too (status / ordinal ranges) */
        return 1;
    }
    return 0;
}

void df_hid_put_bits(uint8_t *buf, uint32_t off, unsigned bits, uint64_t v)
{
    for (unsigned b = 0; b < bits; b++) {
        uint32_t at = off + b;
        uint8_t mask = (uint8_t)(1u << (at % 8));
        if ((v >> b) & 1) buf[at / 8] |= mask;
        else buf[at / 8] &= (uint8_t)~mask;
    }
}

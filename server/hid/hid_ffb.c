/* hid_ffb.c — PID force-feedback output reports from the descriptor: see hid_ffb.h. */
#include "server/hid/hid_ffb.h"

#include <math.h>
#include <string.h>

#define PID(id) ((uint32_t)0x0F << 16 | (uint32_t)(id))
#define GD(id) ((uint32_t)0x01 << 16 | (uint32_t)(id))
#define ORD(id) ((uint32_t)0x0A << 16 | (uint32_t)(id))

enum { C_CREATE = 0xAB, C_BLOCK_LOAD = 0x89, C_BL_STATUS = 0x8B, C_BLOCK_FREE = 0x90,
       C_SET_EFFECT = 0x21, C_EFFECT_TYPE = 0x25, C_AXES = 0x55, C_DIRECTION = 0x57,
       C_CONSTANT = 0x73, C_OPERATION = 0x77, C_OP_ARRAY = 0x78, C_GAIN = 0x7D,
       C_CONTROL = 0x96 };

/* An output / feature element, array fields included (df_hid_loc_element). */
static int find_kind(const df_hid_desc *d, int kind, uint32_t usage, uint32_t coll, int id,
                     df_hid_loc *loc)
{
    return df_hid_loc_element(d, kind, usage, coll, id, 0, loc);
}

static int find(const df_hid_desc *d, uint32_t usage, uint32_t coll, int id, df_hid_loc *loc)
{
    return find_kind(d, DF_HID_OUTPUT, usage, coll, id, loc);
}

static void report_kind(const df_hid_desc *d, int kind, const df_hid_loc *l,
                        df_hid_ffb_report *r)
{
    memset(r, 0, sizeof *r);
    if (!l->present) return;
    const df_hid_report *rep = df_hid_desc_report(d, kind, l->report_id);
    if (!rep || rep->bytes == 0 || rep->bytes > DF_HID_MAX_REPORT_BYTES) return;
    r->present = 1;
    r->id = l->report_id;
    r->bytes = rep->bytes;
}

static void report_of(const df_hid_desc *d, const df_hid_loc *l, df_hid_ffb_report *r)
{
    report_kind(d, DF_HID_OUTPUT, l, r);
}

int df_hid_ffb_init(const df_hid_desc *d, df_hid_ffb *f, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    memset(f, 0, sizeof *f);
    if (!d) return DF_OK;
    if (find(d, PID(0x22), PID(C_SET_EFFECT), -1, &f->se_block)) {
        int id = f->se_block.report_id;
        report_of(d, &f->se_block, &f->effect);
        find(d, PID(DF_HID_PID_ET_CONSTANT), PID(C_EFFECT_TYPE), id, &f->se_type);
        find(d, PID(0x50), PID(C_SET_EFFECT), id, &f->se_duration);
        find(d, PID(0x54), PID(C_SET_EFFECT), id, &f->se_repeat);
        find(d, PID(0x51), PID(C_SET_EFFECT), id, &f->se_period);
        find(d, PID(0x52), PID(C_SET_EFFECT), id, &f->se_gain);
        find(d, PID(0x53), PID(C_SET_EFFECT), id, &f->se_button);
        find(d, GD(0x30), PID(C_AXES), id, &f->se_axis[0]);
        find(d, GD(0x31), PID(C_AXES), id, &f->se_axis[1]);
        find(d, PID(0x56), PID(C_SET_EFFECT), id, &f->se_dir_enable);
        find(d, ORD(1), PID(C_DIRECTION), id, &f->se_dir[0]);
        find(d, ORD(2), PID(C_DIRECTION), id, &f->se_dir[1]);
        find(d, PID(0xA7), PID(C_SET_EFFECT), id, &f->se_delay);
    }
    if (find(d, PID(0x22), PID(C_CONSTANT), -1, &f->cf_block)) {
        report_of(d, &f->cf_block, &f->constant);
        find(d, PID(0x70), PID(C_CONSTANT), f->cf_block.report_id, &f->cf_magnitude);
    }
    if (find(d, PID(0x22), PID(C_OPERATION), -1, &f->op_block)) {
        report_of(d, &f->op_block, &f->operation);
        find(d, PID(DF_HID_PID_OP_START), PID(C_OP_ARRAY), f->op_block.report_id, &f->op_op);
        find(d, PID(0x7C), PID(C_OPERATION), f->op_block.report_id, &f->op_loop);
    }
    if (find(d, PID(DF_HID_PID_ENABLE_ACTUATORS), PID(C_CONTROL), -1, &f->dc))
        report_of(d, &f->dc, &f->control);
    if (find(d, PID(0x7E), PID(C_GAIN), -1, &f->dg)) report_of(d, &f->dg, &f->gain);
    const int FT = DF_HID_FEATURE;
    if (find_kind(d, FT, PID(DF_HID_PID_ET_CONSTANT), PID(C_EFFECT_TYPE), -1, &f->cn_type) &&
        f->cn_type.report_id) { /* the Create New Effect collection's type array */
        df_hid_loc bytes;
        report_kind(d, FT, &f->cn_type, &f->create);
        if (find_kind(d, FT, GD(0x3B), PID(C_CREATE), f->cn_type.report_id, &bytes))
            f->cn_bytes = bytes;
    }
    if (find_kind(d, FT, PID(0x22), PID(C_BLOCK_LOAD), -1, &f->bl_block)) {
        report_kind(d, FT, &f->bl_block, &f->block_load);
        find_kind(d, FT, PID(DF_HID_PID_BLOCK_LOAD_SUCCESS), PID(C_BL_STATUS),
                  f->bl_block.report_id, &f->bl_status);
    }
    if (find(d, PID(0x22), PID(C_BLOCK_FREE), -1, &f->bf_block))
        report_of(d, &f->bf_block, &f->block_free);
    f->present = f->effect.present && f->constant.present && f->se_type.present &&
                 f->cf_magnitude.present;
    return DF_OK;
}

/* Writes logical value v (clamped to the field's range) at l. */
static void put(uint8_t *buf, size_t n, const df_hid_loc *l, int64_t v)
{
    if (!l->present || (uint64_t)l->bit_offset + l->bit_size > (uint64_t)n * 8) return;
    if (l->logical_min <= l->logical_max) {
        if (v < l->logical_min) v = l->logical_min;
        if (v > l->logical_max) v = l->logical_max;
    }
    df_hid_put_bits(buf, l->bit_offset, l->bit_size, (uint64_t)v);
}

/* A physical value x (in the field's physical units, after the unit exponent when `scaled`)
 * mapped linearly onto the logical range; the logical value itself without a physical range. */
static int64_t to_logical(const df_hid_loc *l, double x)
{
    double lmin = (double)l->logical_min, lmax = (double)l->logical_max;
    double pmin = (double)l->physical_min, pmax = (double)l->physical_max;
    double v = x;
    if (pmax > pmin && lmax > lmin) v = lmin + (x - pmin) * (lmax - lmin) / (pmax - pmin);
    if (!isfinite(v)) v = lmin;
    return (int64_t)llround(v);
}

/* An array element selecting `usage` (index from logical_min). */
static int64_t array_value(const df_hid_loc *l, unsigned usage)
{
    return l->logical_min + (int64_t)((uint32_t)usage - (l->array_usage_min & 0xffffu));
}

static int begin(const df_hid_ffb_report *r, const char *what, uint8_t *out, size_t cap,
                 size_t *n, df_error *err)
{
    if (!out || !n) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    *n = 0;
    if (!r->present) return df_error_set(err, DF_EINVAL, "hid ffb: the device has no %s report", what);
    if (cap < r->bytes)
        return df_error_set(err, DF_ELIMIT, "hid ffb: %s report of %u bytes, buffer %zu", what,
                            r->bytes, cap);
    memset(out, 0, r->bytes);
    if (r->id) out[0] = r->id;
    *n = r->bytes;
    return DF_OK;
}

int df_hid_ffb_device_control(const df_hid_ffb *f, unsigned usage, uint8_t *out, size_t cap,
                              size_t *n, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int64_t v = f->dc.present ? array_value(&f->dc, usage) : 0;
    if (f->dc.present && (v < f->dc.logical_min || v > f->dc.logical_max))
        return df_error_set(err, DF_EINVAL, "hid ffb: device control 0x%x not in the array", usage);
    int rc = begin(&f->control, "device control", out, cap, n, err);
    if (rc == DF_OK) put(out, *n, &f->dc, v);
    return rc;
}

int df_hid_ffb_device_gain(const df_hid_ffb *f, double gain, uint8_t *out, size_t cap, size_t *n,
                           df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int rc = begin(&f->gain, "device gain", out, cap, n, err);
    if (rc != DF_OK) return rc;
    const df_hid_loc *l = &f->dg;
    put(out, *n, l, llround((double)l->logical_min + gain * (double)(l->logical_max - l->logical_min)));
    return DF_OK;
}

int df_hid_ffb_set_constant_effect(const df_hid_ffb *f, const df_hid_ffb_effect *e, uint8_t *out,
                                   size_t cap, size_t *n, df_error *err)
{
    if (!f || !e) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int rc = begin(&f->effect, "set effect", out, cap, n, err);
    if (rc != DF_OK) return rc;
    size_t len = *n;
    put(out, len, &f->se_block, e->block);
    put(out, len, &f->se_type, array_value(&f->se_type, DF_HID_PID_ET_CONSTANT));
    if (e->duration_ms == DF_HID_FFB_INFINITE && f->se_duration.present &&
        (uint64_t)f->se_duration.bit_offset + f->se_duration.bit_size <= (uint64_t)len * 8)
        df_hid_put_bits(out, f->se_duration.bit_offset, f->se_duration.bit_size,
                        ~(uint64_t)0); /* null */
    else
        put(out, len, &f->se_duration, e->duration_ms); /* ms: unit seconds, exponent -3 */
    put(out, len, &f->se_repeat, 0);
    put(out, len, &f->se_period, 0);
    const df_hid_loc *g = &f->se_gain;
    double gain = e->gain < 0 ? 0 : e->gain > 1 ? 1 : e->gain;
    put(out, len, g, llround((double)g->logical_min + gain * (double)(g->logical_max - g->logical_min)));
    if (e->trigger_button > 0) put(out, len, &f->se_button, e->trigger_button);
    put(out, len, &f->se_axis[0], e->axes & 1);
    put(out, len, &f->se_axis[1], (e->axes >> 1) & 1);
    put(out, len, &f->se_dir_enable, e->polar ? 1 : 0);
    for (int k = 0; k < 2; k++) { /* degrees -> physical (degrees * 10^-exponent) -> logical */
        const df_hid_loc *l = &f->se_dir[k];
        double deg = fmod(e->direction_deg[k], 360.0);
        if (deg < 0) deg += 360.0;
        put(out, len, l, to_logical(l, deg * pow(10.0, -l->unit_exponent)));
    }
    put(out, len, &f->se_delay, 0);
    return DF_OK;
}

int df_hid_ffb_constant_force(const df_hid_ffb *f, unsigned block, double magnitude,
                              uint8_t *out, size_t cap, size_t *n, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int rc = begin(&f->constant, "set constant force", out, cap, n, err);
    if (rc != DF_OK) return rc;
    const df_hid_loc *l = &f->cf_magnitude;
    double m = magnitude < -1 ? -1 : magnitude > 1 ? 1 : isfinite(magnitude) ? magnitude : 0;
    put(out, *n, &f->cf_block, block);
    put(out, *n, l, llround(m * (double)l->logical_max));
    return DF_OK;
}

int df_hid_ffb_operation(const df_hid_ffb *f, unsigned block, unsigned op_usage,
                         unsigned loop_count, uint8_t *out, size_t cap, size_t *n, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int64_t v = f->op_op.present ? array_value(&f->op_op, op_usage) : 0;
    if (f->op_op.present && (v < f->op_op.logical_min || v > f->op_op.logical_max))
        return df_error_set(err, DF_EINVAL, "hid ffb: effect operation 0x%x not in the array",
                            op_usage);
    int rc = begin(&f->operation, "effect operation", out, cap, n, err);
    if (rc != DF_OK) return rc;
    put(out, *n, &f->op_block, block);
    put(out, *n, &f->op_op, v);
    put(out, *n, &f->op_loop, loop_count);
    return DF_OK;
}

void df_hid_ffb_polar(const double force[2], double full, double *magnitude, double *deg)
{
    double r = hypot(force[0], force[1]);
    double m = full > 0 && isfinite(r) ? r / full : 0;
    *magnitude = m > 1 ? 1 : m;
    double a = r > 0 ? atan2(force[0], force[1]) * 180.0 / 3.14159265358979323846 : 0;
    *deg = a < 0 ? a + 360.0 : a;
}

int df_hid_ffb_create_new_effect(const df_hid_ffb *f, unsigned byte_count, uint8_t *out,
                                 size_t cap, size_t *n, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int rc = begin(&f->create, "create new effect", out, cap, n, err);
    if (rc != DF_OK) return rc;
    put(out, *n, &f->cn_type, array_value(&f->cn_type, DF_HID_PID_ET_CONSTANT));
    put(out, *n, &f->cn_bytes, byte_count);
    return DF_OK;
}

int df_hid_ffb_block_load_request(const df_hid_ffb *f, uint8_t *out, size_t cap, size_t *n,
                                  df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    return begin(&f->block_load, "block load", out, cap, n, err);
}

/* Reads the field at l from buf (n bytes); 0 when it lies outside. */
static int64_t get(const uint8_t *buf, size_t n, const df_hid_loc *l)
{
    if (!l->present || (uint64_t)l->bit_offset + l->bit_size > (uint64_t)n * 8) return 0;
    uint64_t v = 0;
    for (unsigned b = 0; b < l->bit_size; b++) {
        uint32_t at = l->bit_offset + b;
        if (buf[at / 8] >> (at % 8) & 1) v |= (uint64_t)1 << b;
    }
    if (l->is_signed && l->bit_size < 64 && (v >> (l->bit_size - 1) & 1))
        return (int64_t)(v | ~(((uint64_t)1 << l->bit_size) - 1));
    return (int64_t)v;
}

int df_hid_ffb_block_load_parse(const df_hid_ffb *f, const uint8_t *buf, size_t n,
                                unsigned *block, unsigned *status, df_error *err)
{
    if (!f || !buf || !block || !status) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    if (!f->block_load.present)
        return df_error_set(err, DF_EINVAL, "hid ffb: the device has no block load report");
    if (f->block_load.id && (n == 0 || buf[0] != f->block_load.id))
        return df_error_set(err, DF_EINVAL, "hid ffb: block load reply has report id %d, not %u",
                            n ? buf[0] : -1, f->block_load.id);
    if (n < f->block_load.bytes)
        return df_error_set(err, DF_EFORMAT, "hid ffb: block load reply of %zu bytes, the report "
                            "has %u", n, f->block_load.bytes);
    *block = (unsigned)get(buf, n, &f->bl_block);
    int64_t s = get(buf, n, &f->bl_status);
    const df_hid_loc *l = &f->bl_status;
    *status = l->present && s >= l->logical_min && s <= l->logical_max
                  ? (unsigned)((l->array_usage_min & 0xffffu) + (uint64_t)(s - l->logical_min))
                  : 0;
    return DF_OK;
}

int df_hid_ffb_block_free(const df_hid_ffb *f, unsigned block, uint8_t *out, size_t cap,
                          size_t *n, df_error *err)
{
    if (!f) return df_error_set(err, DF_EINVAL, "hid ffb: NULL argument");
    int rc = begin(&f->block_free, "block free", out, cap, n, err);
    if (rc == DF_OK) put(out, *n, &f->bf_block, block);
    return rc;
}

void df_hid_ffb_from_force(const double force[3], double gain, double *magnitude, double *deg)
{
    *magnitude = 0;
    *deg = 0;
    if (!(gain > 0) || !isfinite(gain) || !isfinite(force[0]) || !isfinite(force[1])) return;
    const double xy[2] = {force[0], force[1]};
    df_hid_ffb_polar(xy, 1.0 / gain, magnitude, deg);
}

/* hid_config.c — hid.<class>.<key> / hid.<vvvv:pppp>.<key> settings: see hid_config.h. */
#include "server/hid/hid_config.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

enum { T_BOOL, T_INT, T_DBL, T_TGT, T_PRESS, T_TYPES };

#define C_KNOB (1u << DF_HID_CLASS_KNOB)
#define C_M3D (1u << DF_HID_CLASS_MOUSE3D)
#define C_PEN (1u << DF_HID_CLASS_PEN)
#define C_ALL (C_KNOB | C_M3D | C_PEN)

typedef struct key_def {
    const char *name;
    unsigned classes;        /* C_* where a class section may set it */
    int type;                /* T_* */
    size_t off, size;        /* the field in df_hid_params */
    double min, max;         /* numbers: inclusive range, or (min, max] when min_open */
    int min_open;
} key_def;

#define F(field) offsetof(df_hid_params, field), sizeof(((df_hid_params *)0)->field)

static const key_def k_keys[] = {
    {"haptics", C_ALL, T_BOOL, F(haptics), 0, 1, 0},
    {"haptic_retrigger_ms", C_ALL, T_INT, F(haptic_retrigger_ms), 1, 10000, 0},
    {"rotate", C_KNOB, T_TGT, F(rotate), 0, 0, 0},
    {"press_rotate", C_KNOB, T_TGT, F(press_rotate), 0, 0, 0},
    {"press", C_KNOB, T_PRESS, F(press), 0, 0, 0},
    {"radius_step", C_KNOB, T_DBL, F(radius_step), 1.0001, 10, 0},
    {"radius_min", C_KNOB, T_DBL, F(radius_min), 0, 1e12, 1},
    {"radius_max", C_KNOB, T_DBL, F(radius_max), 0, 1e12, 1},
    {"nu_step", C_KNOB, T_DBL, F(nu_step), 0.001, 1.5, 0},
    {"nu_min", C_KNOB, T_DBL, F(nu_min), -1, 0.5, 0},
    {"nu_max", C_KNOB, T_DBL, F(nu_max), -1, 0.5, 0},
    {"strength_step", C_KNOB, T_DBL, F(strength_step), 1.0001, 10, 0},
    {"falloff_max", C_KNOB, T_INT, F(falloff_max), 1, DF_HID_FALLOFF_LIMIT, 0},
    {"detents_per_turn", C_KNOB, T_DBL, F(detents_per_turn), 1, 3600, 0},
    {"dial_units_per_detent", C_KNOB, T_DBL, F(dial_units_per_detent), 0, 1e6, 0},
    {"invert_dial", C_KNOB, T_BOOL, F(invert_dial), 0, 1, 0},
    {"led_min_radius", C_KNOB, T_DBL, F(led_min_radius), 0, 1e12, 1},
    {"led_max_radius", C_KNOB, T_DBL, F(led_max_radius), 0, 1e12, 1},
    {"deadzone", C_M3D, T_DBL, F(deadzone), 0, 0.99, 0},
    {"sensitivity", C_M3D, T_DBL, F(sensitivity), 0, 1e6, 1},
    {"twist_sensitivity", C_M3D, T_DBL, F(twist_sensitivity), 0, 1e6, 1},
    {"invert_x", C_M3D, T_BOOL, F(invert[0]), 0, 1, 0},
    {"invert_y", C_M3D, T_BOOL, F(invert[1]), 0, 1, 0},
    {"invert_z", C_M3D, T_BOOL, F(invert[2]), 0, 1, 0},
    {"invert_rx", C_M3D, T_BOOL, F(invert[3]), 0, 1, 0},
    {"invert_ry", C_M3D, T_BOOL, F(invert[4]), 0, 1, 0},
    {"invert_rz", C_M3D, T_BOOL, F(invert[5]), 0, 1, 0},
    {"stroke_button", C_M3D, T_INT, F(stroke_button), 1, 2, 0},
    {"pressure_gamma", C_PEN, T_DBL, F(pressure_gamma), 0.1, 10, 0},
    {"strength_max", C_PEN, T_DBL, F(strength_max), 0, 1e6, 1},
    {"twist_angle", C_PEN, T_DBL, F(twist_angle), 0, 6.3, 0},
    {"barrel", C_PEN, T_PRESS, F(barrel), 0, 0, 0},
    {"type_cycle", C_PEN | C_KNOB, T_TYPES, F(type_cycle), 0, 0, 0},
};
#define N_KEYS (sizeof k_keys / sizeof k_keys[0])

void df_hid_params_defaults(df_hid_params *p)
{
    memset(p, 0, sizeof *p);
    p->haptics = 1;
    p->haptic_retrigger_ms = 80;
    p->rotate = DF_HID_TGT_RADIUS;
    p->press_rotate = DF_HID_TGT_NU;
    p->press = DF_HID_PRESS_FALLOFF;
    p->radius_step = 1.1;
    p->radius_min = 1e-4;
    p->radius_max = 1e4;
    p->nu_step = 0.05;
    p->nu_min = -1.0;
    p->nu_max = 0.5;
    p->strength_step = 1.1;
    p->falloff_max = 3;
    p->detents_per_turn = 36;
    p->dial_units_per_detent = 0;
    p->led_min_radius = 0.01;
    p->led_max_radius = 1.0;
    p->deadzone = 0.01;
    p->sensitivity = 0.5;
    p->twist_sensitivity = 1.0;
    p->stroke_button = 1;
    p->pressure_gamma = 1.0;
    p->strength_max = 1.0;
    p->twist_angle = 0.5;
    p->barrel = DF_HID_PRESS_TYPE;
    p->type_cycle[0] = DF_HID_BRUSH_GRAB;
    p->type_cycle[1] = DF_HID_BRUSH_TWIST;
    p->n_type_cycle = 2;
}

static int parse_bool(const char *s, int *out)
{
    static const char *const yes[] = {"yes", "true", "on", "1"}, *const no[] = {"no", "false",
                                                                                 "off", "0"};
    for (int i = 0; i < 4; i++) {
        if (strcasecmp(s, yes[i]) == 0) return *out = 1, DF_OK;
        if (strcasecmp(s, no[i]) == 0) return *out = 0, DF_OK;
    }
    return DF_EINVAL;
}

static int parse_double(const char *s, double *out)
{
    if (!s[0] || isspace((unsigned char)s[0])) return DF_EINVAL;
    errno = 0;
    char *end = NULL;
    double v = strtod(s, &end);
    if (errno || !end || *end || !isfinite(v)) return DF_EINVAL;
    *out = v;
    return DF_OK;
}

static const char *const k_type_names[] = {NULL, "grab", "twist", "scale", "pinch", "affine"};

static int parse_types(const char *s, uint8_t *types, int *n)
{
    int k = 0;
    const char *p = s;
    while (*p) {
        while (*p == ' ' || *p == '\t') p++;
        size_t l = strcspn(p, ",");
        size_t t = l;
        while (t && (p[t - 1] == ' ' || p[t - 1] == '\t')) t--;
        int found = 0;
        for (int i = 1; i <= DF_HID_BRUSH_AFFINE; i++)
            if (t == strlen(k_type_names[i]) && strncasecmp(p, k_type_names[i], t) == 0) {
                if (k >= DF_HID_MAX_TYPE_CYCLE) return DF_EINVAL;
                types[k++] = (uint8_t)i;
                found = 1;
            }
        if (!found) return DF_EINVAL;
        p += l;
        if (*p == ',') p++;
    }
    if (k == 0) return DF_EINVAL;
    *n = k;
    return DF_OK;
}

/* Parses value for key kd into the params v. */
static int parse_value(const key_def *kd, const char *key, const char *value, df_hid_params *v,
                       df_error *err)
{
    char *field = (char *)v + kd->off;
    double d;
    int i;
    switch (kd->type) {
    case T_BOOL:
        if (parse_bool(value, &i) != DF_OK)
            return df_error_set(err, DF_EINVAL, "%s: '%s' is not yes or no", key, value);
        *(int *)field = i;
        return DF_OK;
    case T_INT:
    case T_DBL:
        if (parse_double(value, &d) != DF_OK || d < kd->min || d > kd->max ||
            (kd->min_open && d <= kd->min) || (kd->type == T_INT && d != floor(d)))
            return df_error_set(err, DF_EINVAL, "%s: '%s' is not %s %s %g and <= %g", key, value,
                                kd->type == T_INT ? "an integer" : "a number",
                                kd->min_open ? ">" : ">=", kd->min, kd->max);
        if (kd->type == T_INT) *(int *)field = (int)d;
        else *(double *)field = d;
        return DF_OK;
    case T_TGT: {
        static const char *const names[] = {"none", "radius", "nu", "strength"};
        for (i = 0; i < 4; i++)
            if (strcasecmp(value, names[i]) == 0) return *(int *)field = i, DF_OK;
        return df_error_set(err, DF_EINVAL, "%s: '%s' is not radius|nu|strength|none", key, value);
    }
    case T_PRESS: {
        static const char *const names[] = {"none", "falloff", "type"};
        for (i = 0; i < 3; i++)
            if (strcasecmp(value, names[i]) == 0) return *(int *)field = i, DF_OK;
        return df_error_set(err, DF_EINVAL, "%s: '%s' is not falloff|type|none", key, value);
    }
    case T_TYPES:
        if (parse_types(value, v->type_cycle, &v->n_type_cycle) != DF_OK)
            return df_error_set(err, DF_EINVAL, "%s: '%s' is not a comma list of 1..%d of "
                                "grab|twist|scale|pinch|affine", key, value, DF_HID_MAX_TYPE_CYCLE);
        return DF_OK;
    default: return df_error_set(err, DF_EINVAL, "%s: internal key type", key);
    }
}

/* "vvvv:pppp" (exactly 4 + 4 hex digits) -> vid, pid. */
static int parse_vidpid(const char *s, size_t l, uint16_t *vid, uint16_t *pid)
{
    if (l != 9 || s[4] != ':') return DF_EINVAL;
    unsigned v = 0, p = 0;
    for (size_t i = 0; i < 9; i++) {
        if (i == 4) continue;
        if (!isxdigit((unsigned char)s[i])) return DF_EINVAL;
        unsigned dgt = isdigit((unsigned char)s[i]) ? (unsigned)(s[i] - '0')
                                                    : (unsigned)(tolower((unsigned char)s[i]) - 'a' + 10);
        if (i < 4) v = v * 16 + dgt;
        else p = p * 16 + dgt;
    }
    *vid = (uint16_t)v;
    *pid = (uint16_t)p;
    return DF_OK;
}

int df_hid_config_set(df_hid_config *c, const char *key, const char *value, df_error *err)
{
    if (!c || !key || !value) return df_error_set(err, DF_EINVAL, "hid config: NULL argument");
    if (strncmp(key, "hid.", 4) != 0)
        return df_error_set(err, DF_EINVAL, "unknown config key '%s' (not hid.*)", key);
    const char *sec = key + 4, *dot = strchr(sec, '.');
    if (!dot || dot == sec || !dot[1])
        return df_error_set(err, DF_EINVAL, "unknown config key '%s' (expected hid.<class>.<key> "
                            "or hid.<vvvv:pppp>.<key>, class knob|3d-mouse|pen)", key);
    size_t sl = (size_t)(dot - sec);
    const char *name = dot + 1;
    char cls_name[16];
    int cls = -1;
    uint16_t vid = 0, pid = 0;
    if (sl < sizeof cls_name) {
        memcpy(cls_name, sec, sl);
        cls_name[sl] = '\0';
        cls = df_hid_class_from_name(cls_name);
        if (cls == DF_HID_CLASS_NONE) cls = -1;
    }
    if (cls < 0 && parse_vidpid(sec, sl, &vid, &pid) != DF_OK)
        return df_error_set(err, DF_EINVAL, "unknown config key '%s': section '%.*s' is not "
                            "knob|3d-mouse|pen or a VID:PID like 046d:c626", key, (int)sl, sec);
    const key_def *kd = NULL;
    size_t ki = 0;
    for (; ki < N_KEYS; ki++)
        if (strcmp(k_keys[ki].name, name) == 0) { kd = &k_keys[ki]; break; }
    if (!kd)
        return df_error_set(err, DF_EINVAL, "unknown config key '%s': no hid key '%s'", key, name);
    if (cls >= 0 && !(kd->classes & (1u << cls)))
        return df_error_set(err, DF_EINVAL, "unknown config key '%s': '%s' is not a %s key", key,
                            name, df_hid_class_name(cls));
    df_hid_layer *l;
    int new_dev = 0;
    if (cls >= 0) {
        l = &c->cls[cls];
    } else {
        int k = 0;
        while (k < c->n_dev && !(c->dev[k].vid == vid && c->dev[k].pid == pid)) k++;
        if (k == c->n_dev) {
            if (c->n_dev >= DF_HID_CONFIG_MAX_DEVICES)
                return df_error_set(err, DF_ELIMIT, "%s: more than %d hid device sections", key,
                                    DF_HID_CONFIG_MAX_DEVICES);
            new_dev = 1;
        }
        l = &c->dev[k].l;
    }
    df_hid_layer tmp = new_dev ? (df_hid_layer){0} : *l;
    int rc = parse_value(kd, key, value, &tmp.v, err);
    if (rc != DF_OK) return rc;
    tmp.set |= (uint64_t)1 << ki;
    if (new_dev) {
        c->dev[c->n_dev].vid = vid;
        c->dev[c->n_dev].pid = pid;
        l = &c->dev[c->n_dev].l;
        c->n_dev++;
    }
    *l = tmp;
    return DF_OK;
}

static void apply_layer(const df_hid_layer *l, df_hid_params *out)
{
    for (size_t k = 0; k < N_KEYS; k++) {
        if (!(l->set & ((uint64_t)1 << k))) continue;
        const key_def *kd = &k_keys[k];
        memcpy((char *)out + kd->off, (const char *)&l->v + kd->off, kd->size);
        if (kd->type == T_TYPES) out->n_type_cycle = l->v.n_type_cycle;
    }
}

int df_hid_config_resolve(const df_hid_config *c, int cls, uint16_t vid, uint16_t pid,
                          df_hid_params *out, df_error *err)
{
    if (!out) return df_error_set(err, DF_EINVAL, "hid config: NULL argument");
    df_hid_params p;
    df_hid_params_defaults(&p);
    df_hid_params_defaults(out);
    if (!c) return DF_OK;
    const char *cname = df_hid_class_name(cls);
    if (cls > DF_HID_CLASS_NONE && cls < DF_HID_CLASS_COUNT) apply_layer(&c->cls[cls], &p);
    char sec[16];
    snprintf(sec, sizeof sec, "%s", cname);
    for (int k = 0; k < c->n_dev; k++)
        if (c->dev[k].vid == vid && c->dev[k].pid == pid) {
            apply_layer(&c->dev[k].l, &p);
            snprintf(sec, sizeof sec, "%04x:%04x", vid, pid);
        }
    if (p.nu_min > p.nu_max)
        return df_error_set(err, DF_EINVAL, "hid.%s: nu_min %g above nu_max %g", sec, p.nu_min,
                            p.nu_max);
    if (p.radius_min >= p.radius_max)
        return df_error_set(err, DF_EINVAL, "hid.%s: radius_min %g not below radius_max %g", sec,
                            p.radius_min, p.radius_max);
    if (p.led_min_radius >= p.led_max_radius)
        return df_error_set(err, DF_EINVAL, "hid.%s: led_min_radius %g not below led_max_radius "
                            "%g", sec, p.led_min_radius, p.led_max_radius);
    *out = p;
    return DF_OK;
}

int df_hid_config_check(const df_hid_config *c, df_error *err)
{
    if (!c) return DF_OK;
    df_hid_params p;
    for (int cls = 1; cls < DF_HID_CLASS_COUNT; cls++) {
        int rc = df_hid_config_resolve(c, cls, 0, 0, &p, err);
        if (rc != DF_OK) return rc;
        for (int k = 0; k < c->n_dev; k++) {
            rc = df_hid_config_resolve(c, cls, c->dev[k].vid, c->dev[k].pid, &p, err);
            if (rc != DF_OK) return rc;
        }
    }
    return DF_OK;
}

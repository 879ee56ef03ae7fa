/* hid_config.h — config of the HID mappers (issue 11, "Config section per class and per device").
 *
 * Keys (config file `key = value`, routed here by server/config.c for every key starting with
 * `hid.`): `hid.<class>.<key>` with class knob | 3d-mouse | pen, and `hid.<vvvv:pppp>.<key>`
 * (4 hex digits each) for one device model. Resolution for a device: built-in defaults, then
 * its class's keys, then its VID:PID's keys (device keys override class keys override
 * defaults). A class key must belong to that class; a device key may be any key.
 *
 *   key                 class      value (default)
 *   haptics             all        yes|no (yes): haptic output reports on detents/limits/strokes
 *   haptic_retrigger_ms all        1..10000 (80): Retrigger Period of a haptic report, ms
 *   rotate              knob       radius|nu|strength|none (radius): plain rotation
 *   press_rotate        knob       radius|nu|strength|none (nu): rotation while pressed
 *   press               knob       falloff|type|none (falloff): press+release without rotation
 *   radius_step         knob       1.0001..10 (1.1): radius *= radius_step ^ detents
 *   radius_min          knob       > 0 (1e-4);  radius_max > 0 (1e4): radius clamp
 *   nu_step             knob       0.001..1.5 (0.05): nu += nu_step * detents
 *   nu_min, nu_max      knob       -1..0.5 (-1, 0.5): nu clamp (0.5 = incompressible limit)
 *   strength_step       knob       1.0001..10 (1.1): strength *= strength_step ^ detents
 *   falloff_max         knob       1..8 (3): press cycles the falloff order 1..falloff_max
 *   detents_per_turn    knob       1..3600 (36): detents per turn of a dial that reports its
 *                                  units per turn (Resolution Multiplier, Surface Dial 3600)
 *   dial_units_per_detent knob     0 or > 0 (0 = from the descriptor, see hid_mapper.h)
 *   invert_dial         knob       yes|no (no): counter-clockwise grows
 *   led_min_radius      knob       > 0 (0.01); led_max_radius > 0 (1): PowerMate LED range:
 *                                  brightness 0..255 linear in log(radius) between them
 *   deadzone            3d-mouse   0..0.99 (0.01): fraction of the logical max ignored
 *   sensitivity         3d-mouse   > 0 (0.5): scale units per second at full deflection
 *   twist_sensitivity   3d-mouse   > 0 (1.0): radians per second at full deflection
 *   invert_x .. invert_rz 3d-mouse yes|no (no): negate that axis
 *   stroke_button       3d-mouse   1|2 (1): the button that begins/ends a stroke
 *   pressure_gamma      pen        0.1..10 (1): strength = strength_max * pressure ^ gamma
 *   strength_max        pen        > 0, <= 1e6 (1)
 *   twist_angle         pen        0..6.3 (0.5): radians of twist at full pressure
 *   barrel              pen        type|falloff|none (type): barrel press action
 *   type_cycle          pen/knob   comma list of grab|twist|scale|pinch|affine (grab,twist):
 *                                  the brush types "next type" walks
 * Errors: unknown key (or a key of another class), bad value, malformed VID:PID, more than
 * DF_HID_CONFIG_MAX_DEVICES device sections: DF_EINVAL / DF_ELIMIT with a message naming the key;
 * config.c prefixes file:line. Nothing changes on error. Pure; whoever owns the struct. */
#ifndef DF_SERVER_HID_CONFIG_H
#define DF_SERVER_HID_CONFIG_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "server/hid/hid_class.h"

#define DF_HID_CONFIG_MAX_DEVICES 16
#define DF_HID_MAX_TYPE_CYCLE 8
#define DF_HID_FALLOFF_LIMIT 8   /* = DF_MAX_FALLOFF of the wire */

/* Brush types as on the wire (DF_BRUSH_*; tests check they agree). */
enum { DF_HID_BRUSH_GRAB = 1, DF_HID_BRUSH_TWIST = 2, DF_HID_BRUSH_SCALE = 3,
       DF_HID_BRUSH_PINCH = 4, DF_HID_BRUSH_AFFINE = 5 };

/* Knob targets (rotate, press_rotate) and press/barrel actions. */
enum { DF_HID_TGT_NONE = 0, DF_HID_TGT_RADIUS = 1, DF_HID_TGT_NU = 2, DF_HID_TGT_STRENGTH = 3 };
enum { DF_HID_PRESS_NONE = 0, DF_HID_PRESS_FALLOFF = 1, DF_HID_PRESS_TYPE = 2 };

/* The resolved settings of one device (see the key table above for meaning and units). */
typedef struct df_hid_params {
    int haptics;
    int haptic_retrigger_ms;
    int rotate, press_rotate, press;       /* DF_HID_TGT_*, DF_HID_TGT_*, DF_HID_PRESS_* */
    double radius_step, radius_min, radius_max;
    double nu_step, nu_min, nu_max;
    double strength_step;
    int falloff_max;
    double detents_per_turn, dial_units_per_detent;
    int invert_dial;
    double led_min_radius, led_max_radius;
    double deadzone, sensitivity, twist_sensitivity;
    int invert[6];                          /* x y z rx ry rz */
    int stroke_button;
    double pressure_gamma, strength_max, twist_angle;
    int barrel;                             /* DF_HID_PRESS_* */
    uint8_t type_cycle[DF_HID_MAX_TYPE_CYCLE];
    int n_type_cycle;
} df_hid_params;

/* Keys set in one section: `set` has bit k for key k of the table in hid_config.c. */
typedef struct df_hid_layer {
    uint64_t set;
    df_hid_params v;
} df_hid_layer;

/* All hid.* settings. A zeroed struct means "nothing set" (every device gets the defaults).
 * Plain values only (no pointers): copying the struct copies the settings. */
typedef struct df_hid_config {
    df_hid_layer cls[DF_HID_CLASS_COUNT];   /* by DF_HID_CLASS_* (NONE unused) */
    int n_dev;
    struct { uint16_t vid, pid; df_hid_layer l; } dev[DF_HID_CONFIG_MAX_DEVICES];
} df_hid_config;

/* The built-in defaults (the table above) into *p. */
void df_hid_params_defaults(df_hid_params *p);

/* Applies `key` (the whole key, "hid.knob.radius_step") = `value` (trimmed). Errors as in the
 * header comment; *c unchanged on error. */
int df_hid_config_set(df_hid_config *c, const char *key, const char *value, df_error *err);

/* The settings of a device of class `cls` with ids vid:pid: defaults <- class keys <- device
 * keys. Errors: DF_EINVAL when the result is inconsistent (nu_min > nu_max, radius_min >=
 * radius_max, led_min_radius >= led_max_radius), naming the keys; *out then holds the defaults. */
int df_hid_config_resolve(const df_hid_config *c, int cls, uint16_t vid, uint16_t pid,
                          df_hid_params *out, df_error *err);

/* Resolves every class and every device section (each device section against every class) and
 * returns the first error: what config.c calls once after a file is parsed. */
int df_hid_config_check(const df_hid_config *c, df_error *err);

#endif

/* hid_mapper.h — one mapper state per device: reports in, actions out (issue 11, "HID mapping").
 *
 * Pure: no I/O, no threads, no clock. Time is the report's event time in microseconds (replay:
 * recorded; live: read time), so runs are deterministic. One mapper is used by one thread at a
 * time (the device manager's loop thread). Dispatches by class to hid_knob.c, hid_mouse3d.c,
 * hid_pen.c; haptic reports come from hid_haptics.h.
 *
 * Knob: rotation in detents. Units per detent: config dial_units_per_detent when > 0; else, when
 * the dial's collection has a Resolution Multiplier (0x01:0x48) feature and no
 * DF_HID_QUIRK_DIAL_DETENTS, its physical max is the units per turn (Surface Dial: 3600, as the
 * device boots) divided by detents_per_turn (default 36: 10 degrees, 100 units); else one unit
 * per detent (Huion dials, DIY wheels, PowerMate s8 rotation). Units accumulate across reports
 * and a detent counts when the running sum crosses a multiple of units-per-detent (so slow
 * turns and fractions are never lost). Plain rotation = `rotate` target (radius: radius *=
 * radius_step ^ detents, clamped to [radius_min, radius_max]; nu: nu += nu_step * detents
 * clamped to [nu_min, nu_max]; the 0.5 detent: nu stops exactly at the incompressible limit,
 * never above, with a click). Rotation while the button is held = `press_rotate` (nu by
 * default). Press and release without rotation = `press` (falloff: next order, 1..falloff_max
 * cyclic; type: next in type_cycle). Haptics (when the device has them and `haptics` is yes):
 * Click per report that changed a value by whole detents (Repeat Count = detents - 1), Click
 * on a limit reached and on a press action. PowerMate (raw): LED action after every radius
 * change, brightness = 255 * (log r - log led_min) / (log led_max - log led_min), clamped.
 * DF_HID_QUIRK_NO_RELEASE: the press edge is the press action; press_rotate is never used.
 *
 * 3d-mouse: every report carrying axes adds, per axis a with value v, f = v / logical_max
 * (0 when |f| <= deadzone, clamped to [-1, 1]) * (invert ? -1 : 1), the translation
 * d[a] = f * sensitivity * dt * scale and the rotation w[a] = f * twist_sensitivity * dt,
 * dt = time since the previous report with the same report id, clamped to 50 ms (0 for the
 * first). Translation emits CURSOR deltas; while a stroke is active (stroke_button held)
 * STROKE_UPDATE carries the cumulative tip and twist. Press = STROKE_BEGIN (strength = the
 * session's), release = STROKE_END (Buzz on both when haptics); in one report the press comes
 * before the axes and the release after them. Axes are read as deflections
 * (absolute); the SpaceNavigator's, declared Relative, are absolute by quirk, and every known
 * 3Dconnexion device reports deflection, so a Relative flag does not change the rule.
 *
 * Pen: in range -> CURSOR (normalized x/y, tilt radians, flags) per report; out of range -> one
 * CURSOR with flags 0. Tip switch rising edge -> STROKE_BEGIN, falling edge (or leaving range)
 * -> STROKE_END; reports in between -> STROKE_UPDATE with strength = (session strength when
 * the stroke began) * strength_max * (pressure / logical_max) ^ pressure_gamma, and twist = the
 * pen axis from tilt normalize(tan tx, tan ty, 1) (x right, y down, z into the surface) *
 * twist_angle * pressure. Tilt: physical degrees with the unit exponent when the field's unit is
 * degrees (GXTP: 0.01 degree), else the logical value read as degrees (Digitizer default,
 * Huion s8). STROKE_END repeats the last strength and twist. A pen's grab tip is not the
 * mapper's: move[] stays 0 and the device manager takes the tip from its ray hits. Eraser and
 * Invert are ignored (no stroke without the Tip Switch). Barrel rising edge in range ->
 * `barrel` action (next brush type by default; falloff; none). */
#ifndef DF_SERVER_HID_MAPPER_H
#define DF_SERVER_HID_MAPPER_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/hid/hid_action.h"
#include "server/hid/hid_class.h"
#include "server/hid/hid_config.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_haptics.h"

#define DF_HID_MAX_DT_US 50000   /* 3d-mouse integration step clamp */

typedef struct df_hid_mapper {
    df_hid_class_info info;
    df_hid_params p;
    df_hid_haptics hap;
    double scale;            /* 3d-mouse: mesh units of "full scale" (bounding-box diagonal) */
    /* knob */
    double units_per_detent;
    double acc_units;        /* dial units accumulated, in detents * units_per_detent */
    int64_t detent_pos;      /* detents counted so far (floor of acc / units_per_detent) */
    int pressed, rotated_while_pressed;
    /* 3d-mouse */
    uint64_t last_us[256];   /* per report id: time of its previous report, +1 (0: none) */
    double tip[3], twist[3];
    int buttons;             /* bit0 button 1, bit1 button 2 */
    /* pen */
    int in_range, tip_down, barrel_down;
    double pen_twist[3];
    /* shared */
    int stroke;              /* 1: a stroke is open */
    double stroke_strength;  /* session strength when the stroke began */
    double last_strength;    /* strength of the stroke's last action */
} df_hid_mapper;

/* Prepares *m for a device classified as *info with descriptor desc (may be NULL for raw
 * devices; only read during the call: m keeps no pointer), the settings resolved from cfg (NULL:
 * defaults) for info's class and VID:PID. scale: see df_hid_mapper_set_scale (starts at 1).
 * Errors: DF_EINVAL (NULL m/info, class NONE, inconsistent config: message from
 * df_hid_config_resolve). */
int df_hid_mapper_init(df_hid_mapper *m, const df_hid_class_info *info, const df_hid_desc *desc,
                       const df_hid_config *cfg, df_error *err);

/* 3d-mouse integration scale (mesh units; the device manager passes the session's bounding-box
 * diagonal). Non-finite or <= 0 is ignored. */
void df_hid_mapper_set_scale(df_hid_mapper *m, double scale);

/* Feeds one input report (len bytes as read, report-id byte first when ids are used) received
 * at time_us, with the session's current brush values `cur` (NULL: wire defaults). Appends up to
 * DF_HID_MAX_ACTIONS actions to out[0..cap) and sets *n. A report the mapper does not use
 * (another report id, a battery report) gives *n = 0 and DF_OK. Errors: DF_EINVAL (NULL
 * arguments, cap < DF_HID_MAX_ACTIONS), DF_EFORMAT (a report shorter than its controls need).
 * On error *n = 0 and the state is unchanged. */
int df_hid_mapper_feed(df_hid_mapper *m, const uint8_t *report, size_t len, uint64_t time_us,
                       const df_hid_brush *cur, df_hid_action *out, size_t cap, size_t *n,
                       df_error *err);

/* The device went away (error, unplug, end of a replay): ends an open stroke (one STROKE_END
 * with the last cumulative values), a pen in range gets a CURSOR with flags 0. Sets *n (0..2).
 * Errors: DF_EINVAL (NULL arguments, cap < DF_HID_MAX_ACTIONS). */
int df_hid_mapper_unplug(df_hid_mapper *m, df_hid_action *out, size_t cap, size_t *n,
                         df_error *err);

/* Per-class feeds (hid_knob.c, hid_mouse3d.c, hid_pen.c), called by df_hid_mapper_feed after
 * argument checks with *n = 0; each appends to out via *n. Same errors. */
int df_hid_knob_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                     const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err);
int df_hid_mouse3d_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                        const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err);
int df_hid_pen_feed(df_hid_mapper *m, const uint8_t *r, size_t len, uint64_t t,
                    const df_hid_brush *cur, df_hid_action *out, size_t *n, df_error *err);

/* Appends a HAPTIC action for waveform `wave` (DF_HID_WAVE_*) repeated `repeat` extra times when
 * the device has haptics, the config enables them and the waveform is listed; else nothing. */
void df_hid_mapper_haptic(const df_hid_mapper *m, unsigned wave, unsigned repeat,
                          df_hid_action *out, size_t *n);

/* The LED brightness (0..255) a PowerMate-style knob shows for `radius` (led_min_radius ..
 * led_max_radius, linear in log radius), or -1 when the device has no LED (not a raw PowerMate)
 * or radius is not finite and positive: what the device manager sends when a knob starts
 * driving a session, before any turn. */
int df_hid_mapper_led_level(const df_hid_mapper *m, double radius);

/* The next brush type after `type` in the configured cycle (the first when type is not in it). */
uint8_t df_hid_mapper_next_type(const df_hid_params *p, uint8_t type);

#endif

/* hid_action.h — what a device mapper outputs for one report (issue 11): an array of actions,
 * several per report, in the order they must be applied. The device manager turns them into the
 * requests a client would send (BRUSH_STATE_SET, BRUSH_BEGIN/UPDATE/END, BRUSH_CURSOR, output
 * reports, PowerMate LED control transfers).
 *
 * Brush field bits: DF_HID_BS_* carry the same values as the wire's DF_BS_* (proto/wire_schema.h
 * of the brush-state piece: TYPE 1<<0, RADIUS 1<<1, NU 1<<2, STRENGTH 1<<3, FALLOFF 1<<4, RATIO
 * 1<<5, INTEGRATOR 1<<6, MIRROR 1<<7). They are defined here because server/hid/ may not include
 * proto/ (tests/check_layers.sh); tests/unit/hid/test_hid_config.c checks they equal DF_BS_*,
 * and the cursor flags DF_CURSOR_*. */
#ifndef DF_SERVER_HID_ACTION_H
#define DF_SERVER_HID_ACTION_H

#include <stddef.h>
#include <stdint.h>

enum {
    DF_HID_BS_TYPE = 1u << 0, DF_HID_BS_RADIUS = 1u << 1, DF_HID_BS_NU = 1u << 2,
    DF_HID_BS_STRENGTH = 1u << 3, DF_HID_BS_FALLOFF = 1u << 4, DF_HID_BS_RATIO = 1u << 5,
    DF_HID_BS_INTEGRATOR = 1u << 6, DF_HID_BS_MIRROR = 1u << 7
};

/* The session brush fields a mapper reads and writes (a subset of the session's df_brush_state:
 * the caller copies them in before each feed). Units and ranges as on the wire. */
typedef struct df_hid_brush {
    uint8_t type;            /* DF_HID_BRUSH_* (1..5) */
    uint8_t falloff;         /* 1..8 */
    double radius;           /* > 0, mesh units */
    double nu;               /* Poisson ratio, [-1, 0.5] */
    double strength;         /* load multiplier */
} df_hid_brush;

enum {
    DF_HID_ACT_BRUSH_SET,    /* mask DF_HID_BS_* + brush: session brush change */
    DF_HID_ACT_CURSOR,       /* cursor moved: delta (3d-mouse) or absolute normalized (pen) */
    DF_HID_ACT_STROKE_BEGIN, DF_HID_ACT_STROKE_UPDATE, DF_HID_ACT_STROKE_END,
    DF_HID_ACT_HAPTIC,       /* output report bytes to send (haptic waveform) */
    DF_HID_ACT_LED           /* PowerMate brightness 0..255 (vendor control transfer) */
};

/* Cursor modes and flags (flags = the wire's BRUSH_CURSOR flags). */
enum { DF_HID_CUR_DELTA = 1, DF_HID_CUR_NORMALIZED = 2 };
enum { DF_HID_CUR_IN_RANGE = 1u << 0, DF_HID_CUR_STROKE = 1u << 1 };

/* Haptic waveforms (Haptics page 0x0E usage ids; hid_haptics.h) named in actions. */
enum { DF_HID_WAVE_CLICK = 0x1003, DF_HID_WAVE_BUZZ = 0x1004 };

#define DF_HID_ACT_BYTES_MAX 64  /* largest output report a mapper emits */
#define DF_HID_MAX_ACTIONS 8     /* a feed never emits more: pass cap >= this */

typedef struct df_hid_action {
    int kind;                /* DF_HID_ACT_* */
    /* BRUSH_SET: the fields in `mask` of `brush` are the new values. STROKE_BEGIN: `brush` holds
     * the session values in force when the stroke began (mask 0). */
    unsigned mask;
    df_hid_brush brush;
    /* CURSOR: mode DF_HID_CUR_DELTA -> move[] is the displacement since the previous cursor
     * action in mesh units (3d-mouse, already times sensitivity, dt and scale); mode
     * DF_HID_CUR_NORMALIZED -> xy[] (0..1 of the logical range, y down) and tilt[]. flags:
     * DF_HID_CUR_*. */
    int cursor_mode;
    unsigned cursor_flags;
    /* STROKE_BEGIN/UPDATE/END: cumulative since the stroke began. move[] the grab tip (3d-mouse;
     * a pen's tip comes from its ray hits, move[] = 0), twist[] a rotation vector (radians),
     * strength the load multiplier. Pens also fill xy[], tilt[], pressure. */
    double move[3];
    double twist[3];
    double strength;
    double xy[2];            /* pen: normalized X/Y, 0..1 */
    double tilt[2];          /* pen: X/Y tilt, radians (0 when the pen has none) */
    double pressure;         /* pen: 0..1 */
    /* HAPTIC: the output report (report-id byte first when the descriptor uses ids). */
    uint8_t bytes[DF_HID_ACT_BYTES_MAX];
    size_t n_bytes;
    unsigned waveform;       /* HAPTIC: DF_HID_WAVE_* it plays */
    /* LED: brightness 0..255 (PowerMate: control transfer 0x41/0x01, wValue 0x01, wIndex it). */
    int led;
} df_hid_action;

#endif

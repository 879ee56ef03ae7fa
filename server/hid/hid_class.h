/* hid_class.h — device classes by usage (issue 11, Devices): knob, 3d-mouse, pen.
 *
 * Pure C (no I/O, no threads, no clock). df_hid_classify looks at a parsed report descriptor
 * (hid_desc.h) and decides the class from the usages it declares, never from a VID:PID list:
 *   knob      Generic Desktop Dial (0x01:0x37), or Wheel (0x01:0x38) in an application collection
 *             without X/Y pointer axes (a mouse wheel is not a knob), plus a button (Button page
 *             0x09) in the same application collection. A DIY knob with a standard descriptor is
 *             a knob.
 *   3d-mouse  Multi-axis Controller application (0x01:0x08) with input X, Y, Z, Rx, Ry, Rz
 *             (0x01:0x30..0x35).
 *   pen       Digitizer page (0x0D) with Tip Pressure (0x0D:0x30) or Tip Switch (0x0D:0x42), plus
 *             X/Y, in a Pen application (0x0D:0x02) or a Stylus collection (0x0D:0x20).
 * Checked in that order (a pen tablet with a dial node classifies per node: each hidraw node /
 * `D:` section has its own descriptor and is classified on its own).
 *
 * Quirk table (hardware that lies; applied by VID:PID after the usage check, each documented in
 * hid_class.c): SpaceNavigator 046d:c626 (axes declared Relative carry absolute displacement),
 * Griffin PowerMate 077d:0410 (no descriptor: knob with the raw 6-byte packet layout), Huion
 * K20 / Dial 2 256c:0069, 256c:0060, 256c:8251 (dial sends one unit per mechanical detent, its
 * Resolution Multiplier is a copy of the Surface Dial's and is not honoured; 256c:0069 firmware
 * mode never reports the centre button's release: a press edge is a click and press+rotate is
 * unavailable; 256c:8251's dial arrives on a mouse-shaped node as the wheel, its button as
 * Consumer Play/Pause). Devices whose descriptor does not describe the real layout (Wacom vendor
 * page 0xff0d, Huion vendor nodes) classify as NONE: their data cannot be read from the
 * descriptor, and this layer says so in `reason` instead of guessing. So does a wheel sent as
 * key presses (XP-Pen ACK05: Ctrl + Keypad +/-): that node is a keyboard. */
#ifndef DF_SERVER_HID_CLASS_H
#define DF_SERVER_HID_CLASS_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/hid/hid_desc.h"

/* Classes; the numbers equal the wire's DF_DEVCLASS_* (DEVICES_LIST `class`). */
enum { DF_HID_CLASS_NONE = 0, DF_HID_CLASS_KNOB = 1, DF_HID_CLASS_MOUSE3D = 2,
       DF_HID_CLASS_PEN = 3, DF_HID_CLASS_COUNT = 4 };

/* Quirk bits (df_hid_class_info.quirks). */
enum {
    DF_HID_QUIRK_AXES_ABSOLUTE = 1u << 0,   /* axes declared Relative are absolute (3d-mouse) */
    DF_HID_QUIRK_RAW_POWERMATE = 1u << 1,   /* no descriptor: [button][s8 rotation][0][led]... */
    DF_HID_QUIRK_DIAL_DETENTS = 1u << 2,    /* one dial unit per detent; ignore the Res. Mult. */
    DF_HID_QUIRK_NO_RELEASE = 1u << 3,      /* the knob button never reports its release */
    DF_HID_QUIRK_WHEEL_KNOB = 1u << 4       /* a mouse-shaped node whose wheel is the dial */
};

/* Where one control lives in the input reports: enough to read it without the descriptor. */
typedef struct df_hid_loc {
    uint8_t present;         /* 0: the device has no such control (the rest is zero) */
    uint8_t report_id;       /* input report id (0 when the descriptor uses none) */
    uint8_t is_signed;       /* two's complement elements */
    uint8_t relative;        /* 1: Relative (after quirks) */
    uint8_t array;           /* 1: array field: pressed when any element selects `usage` */
    uint16_t bit_size;       /* 1..32 */
    uint16_t count;          /* array: elements to scan; variable: 1 */
    uint32_t bit_offset;     /* of the element, report-id byte included (bits 0..7) */
    uint32_t usage;          /* page << 16 | id */
    uint32_t array_usage_min;/* array: usage of logical_min */
    int64_t logical_min, logical_max;
    int64_t physical_min, physical_max;
    uint32_t unit;           /* HID unit code (0x14: degrees) */
    int8_t unit_exponent;
} df_hid_loc;

/* Controls a mapper reads (df_hid_class_info.ctl index). */
enum {
    DF_HID_CTL_DIAL,        /* knob rotation (Dial, or Wheel), relative */
    DF_HID_CTL_BUTTON,      /* knob button; 3d-mouse button 1; pen: unused */
    DF_HID_CTL_BUTTON2,     /* 3d-mouse button 2 */
    DF_HID_CTL_X, DF_HID_CTL_Y, DF_HID_CTL_Z,       /* 3d-mouse translation; pen X/Y */
    DF_HID_CTL_RX, DF_HID_CTL_RY, DF_HID_CTL_RZ,    /* 3d-mouse rotation */
    DF_HID_CTL_TIP,         /* pen Tip Switch (0x0D:0x42) */
    DF_HID_CTL_IN_RANGE,    /* pen In Range (0x0D:0x32) */
    DF_HID_CTL_BARREL,      /* pen Barrel Switch (0x0D:0x44) */
    DF_HID_CTL_PRESSURE,    /* pen Tip Pressure (0x0D:0x30) */
    DF_HID_CTL_XTILT, DF_HID_CTL_YTILT,             /* pen X/Y Tilt (0x0D:0x3D/0x3E) */
    DF_HID_CTL_COUNT
};

#define DF_HID_REASON_MAX 160

typedef struct df_hid_class_info {
    int cls;                 /* DF_HID_CLASS_* */
    unsigned quirks;         /* DF_HID_QUIRK_* applied */
    uint16_t vid, pid;
    uint32_t application;    /* usage of the application collection the class came from */
    df_hid_loc ctl[DF_HID_CTL_COUNT];
    double dial_units_per_turn; /* knob: from a Resolution Multiplier feature (0x01:0x48)
                                 * physical max in the dial's collection; 0 when none/ignored */
    char reason[DF_HID_REASON_MAX]; /* one line: why this class, or why NONE */
} df_hid_class_info;

/* Classifies the device with descriptor `d` (NULL for a device without one, e.g. the raw
 * PowerMate) and ids vid:pid. Fills *out (always, also for NONE: cls, reason). A NULL or
 * empty descriptor is NONE unless the quirk table knows the VID:PID. Returns DF_OK, or
 * DF_EINVAL when out is NULL. Any thread (pure). */
int df_hid_classify(const df_hid_desc *d, uint16_t vid, uint16_t pid, df_hid_class_info *out);

/* "knob", "3d-mouse", "pen", or "none" (also for values out of range). Static string. */
const char *df_hid_class_name(int cls);

/* The class named `name` ("knob", "3d-mouse", "pen"; "none" gives NONE), or -1 if unknown. */
int df_hid_class_from_name(const char *name);

/* Reads control `loc` from the input report at buf (n bytes, report-id byte first when ids are
 * used). Returns 1 and sets *value when the report carries it (report id matches and the bits
 * lie within n), else 0 (absent control, other report, short buffer). Array locations give 1 in
 * *value when an element selects loc->usage, else 0. */
int df_hid_loc_read(const df_hid_loc *loc, const uint8_t *buf, size_t n, int64_t *value);

/* Builds the location of input usage page:id inside application collection `application`
 * (0: any) of d, preferring report `prefer_id` (-1: any); variable fields by element, array
 * fields by range. Returns 1 and fills *loc when found, else 0 (loc zeroed). */
int df_hid_loc_find(const df_hid_desc *d, uint32_t usage, uint32_t application, int prefer_id,
                    df_hid_loc *loc);

/* Builds the location of one element of kind `kind` (DF_HID_OUTPUT / DF_HID_FEATURE / input)
 * carrying `usage` (page << 16 | id) whose innermost collection is `coll` (0: any) in report
 * `id` (-1: any): the first non-constant field of 1..32-bit elements whose usage span holds it.
 * Variable fields give that usage's element; array fields (skipped when variable_only) give
 * their first slot (count 1, array = 1). array_usage_min is the field's usage_min in both cases;
 * relative follows the field's flag.
 * Returns 1 and fills *loc, else 0 (loc zeroed). Pure; any thread. */
int df_hid_loc_element(const df_hid_desc *d, int kind, uint32_t usage, uint32_t coll, int id,
                       int variable_only, df_hid_loc *loc);

/* Writes the low `bits` bits of v at bit `off` of buf (little-endian, as HID lays fields); the
 * caller has checked off + bits <= 8 x its buffer bytes. Other bits are kept. Any thread. */
void df_hid_put_bits(uint8_t *buf, uint32_t off, unsigned bits, uint64_t v);

#endif

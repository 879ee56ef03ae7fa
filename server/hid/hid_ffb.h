/* hid_ffb.h — Physical Interface Device (PID, page 0x0F) force-feedback output reports laid out
 * from the descriptor (issue 11, optional part: "a constant force proportional to the live
 * grab's force"). The pure layout layer, checked against the SideWinder Force Feedback 2 file's
 * constructed examples; hid_mgr_ffb.h sends them (off by default).
 *
 * Reports (found by the usages of their collections, whatever their ids and field order):
 *   Device Control  (0x0F:0x96) array of 0x97 Enable Actuators .. 0x9C Device Continue
 *   Device Gain     (0x0F:0x7D) 0x7E Device Gain
 *   Set Effect      (0x0F:0x21) 0x22 Effect Block Index, Effect Type array (0x25 collection,
 *                   0x26 ET Constant Force first), 0x50 Duration, 0x54 Trigger Repeat Interval,
 *                   0x51 Sample Period, 0x52 Gain, 0x53 Trigger Button, Axes Enable (0x55:
 *                   Generic Desktop X/Y bits), 0x56 Direction Enable, Direction (0x57: Ordinal
 *                   1, 2), 0xA7 Start Delay
 *   Set Constant Force (0x0F:0x73) 0x22 block, 0x70 Magnitude
 *   Effect Operation (0x0F:0x77) 0x22 block, array 0x79 Start / 0x7A Start Solo / 0x7B Stop,
 *                   0x7C Loop Count
 *   Create New Effect (feature, 0x0F:0xAB) Effect Type array (0x25, ET Constant Force), Byte
 *                   Count (Generic Desktop 0x3B)
 *   Block Load      (feature, 0x0F:0x89) 0x22 block, Block Load Status array 0x8B (0x8C Success,
 *                   0x8D Full, 0x8E Error), 0xAC RAM Pool Available (read with GET_REPORT)
 *   Block Free      (0x0F:0x90) 0x22 block
 * Values are given in physical terms (ms, 0..1 gains, -1..1 magnitude, degrees) and converted
 * to the field's logical range (linear over the physical range when one is declared), clamped.
 * Pure; no state beyond the struct. */
#ifndef DF_SERVER_HID_FFB_H
#define DF_SERVER_HID_FFB_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"

/* PID usages callers name (page 0x0F ids). */
enum {
    DF_HID_PID_ENABLE_ACTUATORS = 0x97, DF_HID_PID_DISABLE_ACTUATORS = 0x98,
    DF_HID_PID_STOP_ALL = 0x99, DF_HID_PID_RESET = 0x9A,
    DF_HID_PID_OP_START = 0x79, DF_HID_PID_OP_START_SOLO = 0x7A, DF_HID_PID_OP_STOP = 0x7B,
    DF_HID_PID_ET_CONSTANT = 0x26,
    DF_HID_PID_BLOCK_LOAD_SUCCESS = 0x8C, DF_HID_PID_BLOCK_LOAD_FULL = 0x8D,
    DF_HID_PID_BLOCK_LOAD_ERROR = 0x8E
};

/* df_hid_ffb_effect.duration_ms for an effect that plays until stopped: the Duration field
 * gets its null value (all bits set, outside its logical range), as the PID spec says. */
#define DF_HID_FFB_INFINITE 0xffffffffu

/* One output report: id, length, and the locations of its fields (present flags). */
typedef struct df_hid_ffb_report {
    int present;
    uint8_t id;
    uint32_t bytes;          /* report-id byte included */
} df_hid_ffb_report;

typedef struct df_hid_ffb {
    int present;             /* 1: Set Effect and Set Constant Force were found */
    df_hid_ffb_report control, gain, effect, constant, operation;
    df_hid_loc dc;                               /* Device Control array */
    df_hid_loc dg;                               /* Device Gain */
    df_hid_loc se_block, se_type, se_duration, se_repeat, se_period, se_gain, se_button,
               se_axis[2], se_dir_enable, se_dir[2], se_delay;
    df_hid_loc cf_block, cf_magnitude;
    df_hid_loc op_block, op_op, op_loop;
    df_hid_ffb_report create, block_load, block_free; /* create / block_load: feature reports */
    df_hid_loc cn_type, cn_bytes;                /* Create New Effect */
    df_hid_loc bl_block, bl_status;              /* Block Load */
    df_hid_loc bf_block;                         /* Block Free */
} df_hid_ffb;

/* A constant-force effect (Set Effect). */
typedef struct df_hid_ffb_effect {
    unsigned block;          /* effect block index (from Create New Effect; 1 on the SideWinder) */
    unsigned duration_ms;    /* clamped to the field's range; DF_HID_FFB_INFINITE: null */
    double gain;             /* 0..1 */
    int trigger_button;      /* 1..: button that fires it; 0: none (field left at its null) */
    int axes;                /* bit 0 X, bit 1 Y enabled */
    double direction_deg[2]; /* polar direction (ordinal 1), second angle (ordinal 2) */
    int polar;               /* 1: Direction Enable set (the first direction is a polar angle
                                over the enabled axes, as Linux's pidff sends it); 0: clear */
} df_hid_ffb_effect;

/* Finds the PID output reports of d (NULL: none). Fills *f (present 0 without them: not an
 * error). Errors: DF_EINVAL on NULL f. */
int df_hid_ffb_init(const df_hid_desc *d, df_hid_ffb *f, df_error *err);

/* Output reports (out: cap bytes; *n = the report's length). Errors: DF_EINVAL (NULL, no such
 * report, usage not in the control/operation array), DF_ELIMIT (cap too small). */
int df_hid_ffb_device_control(const df_hid_ffb *f, unsigned usage, uint8_t *out, size_t cap,
                              size_t *n, df_error *err);
int df_hid_ffb_device_gain(const df_hid_ffb *f, double gain, uint8_t *out, size_t cap, size_t *n,
                           df_error *err);
int df_hid_ffb_set_constant_effect(const df_hid_ffb *f, const df_hid_ffb_effect *e, uint8_t *out,
                                   size_t cap, size_t *n, df_error *err);
int df_hid_ffb_constant_force(const df_hid_ffb *f, unsigned block, double magnitude,
                              uint8_t *out, size_t cap, size_t *n, df_error *err);
int df_hid_ffb_operation(const df_hid_ffb *f, unsigned block, unsigned op_usage,
                         unsigned loop_count, uint8_t *out, size_t cap, size_t *n, df_error *err);

/* Create New Effect (a FEATURE report, sent with SET_REPORT) for a constant force; byte_count:
 * the Byte Count field (0 for a predefined effect type). Errors as above. */
int df_hid_ffb_create_new_effect(const df_hid_ffb *f, unsigned byte_count, uint8_t *out,
                                 size_t cap, size_t *n, df_error *err);

/* The Block Load feature report's request buffer: its report id in out[0], *n = its length
 * (what GET_REPORT needs). Errors as above. */
int df_hid_ffb_block_load_request(const df_hid_ffb *f, uint8_t *out, size_t cap, size_t *n,
                                  df_error *err);

/* Parses a Block Load feature report (buf[0..n), report id first): *block = the effect block
 * index, *status = the selected status usage (DF_HID_PID_BLOCK_LOAD_*; 0 when none). Errors:
 * DF_EINVAL (NULL, no Block Load report, wrong report id), DF_EFORMAT (shorter than the
 * report). */
int df_hid_ffb_block_load_parse(const df_hid_ffb *f, const uint8_t *buf, size_t n,
                                unsigned *block, unsigned *status, df_error *err);

/* Block Free of `block` (an output report). Errors as above. */
int df_hid_ffb_block_free(const df_hid_ffb *f, unsigned block, uint8_t *out, size_t cap,
                          size_t *n, df_error *err);

/* The joystick's constant force for a 3-vector force (any units): the projection onto the
 * device's two axes is (force[0], force[1]) (the mesh's x and y: the joystick's X and Y), then
 * magnitude = min(1, gain * |projection|) (0..1 of the Set Constant Force magnitude range) and
 * direction in degrees as df_hid_ffb_polar (0 = +y, clockwise towards +x). Non-finite input or
 * gain <= 0: magnitude 0, direction 0. Pure. */
void df_hid_ffb_from_force(const double force[3], double gain, double *magnitude, double *deg);

/* A planar force (x, y: any units) as the constant force's polar form: magnitude |f| / full
 * (clamped to 1) and direction in degrees, 0 = +y (north), clockwise towards +x, 0..360. */
void df_hid_ffb_polar(const double force[2], double full, double *magnitude, double *deg);

#endif

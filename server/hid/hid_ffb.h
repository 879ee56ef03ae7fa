/* hid_ffb.h — Physical Interface Device (PID, page 0x0F) force-feedback output reports laid out
 * from the descriptor (issue 11, optional part: "a constant force proportional to the live
 * grab's force"). Off by default: nothing in the daemon sends these yet; this is the pure layout
 * layer, checked against the SideWinder Force Feedback 2 file's constructed examples.
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
    DF_HID_PID_ET_CONSTANT = 0x26
};

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
} df_hid_ffb;

/* A constant-force effect (Set Effect). */
typedef struct df_hid_ffb_effect {
    unsigned block;          /* effect block index (from Create New Effect; 1 on the SideWinder) */
    unsigned duration_ms;    /* clamped to the field's range */
    double gain;             /* 0..1 */
    int trigger_button;      /* 1..: button that fires it; 0: none (field left at its null) */
    int axes;                /* bit 0 X, bit 1 Y enabled */
    double direction_deg[2]; /* polar direction (ordinal 1), second angle (ordinal 2) */
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

/* A planar force (x, y: any units) as the constant force's polar form: magnitude |f| / full
 * (clamped to 1) and direction in degrees, 0 = +y (north), clockwise towards +x, 0..360. */
void df_hid_ffb_polar(const double force[2], double full, double *magnitude, double *deg);

#endif

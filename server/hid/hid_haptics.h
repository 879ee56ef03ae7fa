/* hid_haptics.h — Haptics page (0x0E) output reports laid out from the descriptor (issue 11).
 *
 * A Simple Haptic Controller (0x0E:0x01) declares, in an output report, Manual Trigger
 * (0x0E:0x21: the waveform index to play), and optionally Repeat Count (0x0E:0x24), Retrigger
 * Period (0x0E:0x25, ms) and Intensity (0x0E:0x23). Its Waveform List collection (0x0E:0x10,
 * in a feature report) names the waveforms behind indices 3.. with Ordinal usages (page 0x0A):
 * ordinal n is index n, its waveform usage (0x0E:0x1003 Click, 0x1004 Buzz, ...) is the field's
 * physical value when that lies in 0x1000..0x1fff, else its logical value (both forms occur).
 * Indices 1 and 2 are always None and Stop (HID Usage Tables, Haptics). The Surface Dial:
 * output report 1 = [01][Repeat Count][Manual Trigger][Retrigger Period u16], list 3 = Click,
 * 4 = Buzz, 5 = Buzz. Pure. */
#ifndef DF_SERVER_HID_HAPTICS_H
#define DF_SERVER_HID_HAPTICS_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"

#define DF_HID_HAPTICS_MAX_WAVES 16

typedef struct df_hid_haptics {
    int present;             /* 1: the descriptor has a haptic output report */
    uint8_t report_id;       /* of the output report (0: no ids) */
    uint32_t report_bytes;   /* its length, report-id byte included */
    df_hid_loc trigger, repeat, retrigger, intensity;  /* output fields (present flags) */
    int n_waves;
    uint16_t wave_usage[DF_HID_HAPTICS_MAX_WAVES];     /* 0x1001.. (page 0x0E ids) */
    uint8_t wave_index[DF_HID_HAPTICS_MAX_WAVES];      /* the Manual Trigger value for it */
} df_hid_haptics;

/* Finds the haptic output report of d (NULL: none). Fills *h (present 0 when there is none;
 * that is not an error). Returns DF_OK, or DF_EINVAL on NULL h. */
int df_hid_haptics_init(const df_hid_desc *d, df_hid_haptics *h, df_error *err);

/* The Manual Trigger index of waveform `usage` (0x0E page id, e.g. DF_HID_WAVE_CLICK) from the
 * Waveform List (None 0x1001 -> 1, Stop 0x1002 -> 2 always), or -1 when the device lists none. */
int df_hid_haptics_index(const df_hid_haptics *h, unsigned usage);

/* Lays out an output report playing waveform index `index` `repeat` extra times every
 * `retrigger_ms` ms: every field at its bit offset and size, values clamped to the field's
 * logical range, Intensity at its logical max, the rest 0. Writes h->report_bytes bytes to out.
 * Errors: DF_EINVAL (no haptics, NULL, index outside the trigger's logical range), DF_ELIMIT
 * (cap < report_bytes). */
int df_hid_haptics_report(const df_hid_haptics *h, unsigned index, unsigned repeat,
                          unsigned retrigger_ms, uint8_t *out, size_t cap, size_t *n,
                          df_error *err);

#endif

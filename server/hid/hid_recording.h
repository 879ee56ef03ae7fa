/* hid_recording.h — parser of the hid-recorder text format (hid-tools; ../shared/hid/README.md
 * "File format") from a memory buffer: `#` comments, `D: <n>` device index, `R: <len> <hex>`
 * descriptor, `N: <name>`, `P: <phys>`, `I: <bus> <vid> <pid>` (hex), `E: <sec>.<usec> <len> <hex>`
 * input reports. Several devices per file; lines before any `D:` belong to device 0. Pure C. */
#ifndef DF_SERVER_HID_RECORDING_H
#define DF_SERVER_HID_RECORDING_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_HID_REC_MAX_DEVICES 64       /* D: indices 0..63 */
#define DF_HID_REC_MAX_LINE_BYTES 65536 /* R: or E: byte count */
#define DF_HID_REC_MAX_EVENTS (1u << 22)
#define DF_HID_REC_NAME_MAX 256

typedef struct df_hid_rec_device {
    uint8_t *desc;           /* R: bytes (NULL when the device has no R: line) */
    size_t desc_len;
    char name[DF_HID_REC_NAME_MAX]; /* N: (truncated), "" when absent */
    char phys[DF_HID_REC_NAME_MAX]; /* P:, "" when absent */
    uint32_t bus, vid, pid;  /* I:, 0 when absent */
    int seen;                /* 1 when some line named this device */
} df_hid_rec_device;

typedef struct df_hid_rec_event {
    unsigned device;         /* index into devices */
    uint64_t time_us;        /* sec * 1000000 + usec */
    size_t offset, len;      /* bytes at recording.bytes + offset */
} df_hid_rec_event;

typedef struct df_hid_recording {
    df_hid_rec_device *devices; /* n_devices = 1 + highest index named (D: or implicit 0) */
    size_t n_devices;
    df_hid_rec_event *events;   /* in file order */
    size_t n_events;
    uint8_t *bytes;             /* all event bytes */
    size_t n_bytes;
} df_hid_recording;

/* Parses the n bytes at text (need not be NUL-terminated; lines end in \n, a trailing \r and
 * trailing blanks are ignored, empty lines too). On DF_OK *out owns everything (free with
 * df_hid_recording_free); on error *out is zeroed. Errors, each naming the 1-based line:
 * DF_EINVAL (NULL arguments), DF_EFORMAT (unknown line type, bad number or hex byte, a byte count
 * that differs from the declared len, an E: line for a device without an R: line, a second R: for
 * one device), DF_ELIMIT (device index >= DF_HID_REC_MAX_DEVICES, len > DF_HID_REC_MAX_LINE_BYTES,
 * more than DF_HID_REC_MAX_EVENTS events), DF_ENOMEM. */
int df_hid_recording_parse(const char *text, size_t n, df_hid_recording *out, df_error *err);

/* df_hid_recording_parse with flags: DF_HID_REC_RAW accepts E: lines for a device without an R:
 * line (its desc stays NULL): the PowerMate raw file (E: lines only). 0 = df_hid_recording_parse. */
enum { DF_HID_REC_RAW = 1 };
int df_hid_recording_parse_flags(const char *text, size_t n, unsigned flags, df_hid_recording *out,
                                 df_error *err);

/* Frees what df_hid_recording_parse allocated and zeroes *rec (NULL is fine). */
void df_hid_recording_free(df_hid_recording *rec);

/* The bytes of event e (owned by rec). */
const uint8_t *df_hid_rec_event_bytes(const df_hid_recording *rec, const df_hid_rec_event *e);

#endif

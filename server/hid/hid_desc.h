/* hid_desc.h — HID report-descriptor parser and input-report decoder (issue 11, Devices).
 *
 * Pure C: no I/O, no threads, no global state. df_hid_desc_parse turns the bytes of a report
 * descriptor (HID 1.11 section 6.2.2: short and long items; main, global and local items; push/pop
 * of the global state; report ids; logical/physical ranges; unit and unit exponent; 1-2 byte
 * usages resolved against the usage page in force at the main item, 4-byte extended usages taken
 * as page:id; usage minimum/maximum; collections) into reports, one per (kind, report id), each
 * with its fields and its byte length. Limits below are refused with DF_ELIMIT; malformed
 * descriptors (truncated item, unbalanced collections or push/pop, report id 0) with DF_EFORMAT;
 * every message names the byte offset of the offending item. */
#ifndef DF_SERVER_HID_DESC_H
#define DF_SERVER_HID_DESC_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_HID_MAX_DESC_BYTES    65536 /* descriptor length */
#define DF_HID_MAX_REPORT_BYTES  8192  /* one report, report-id byte included */
#define DF_HID_MAX_REPORT_SIZE   256   /* Report Size, bits per element */
#define DF_HID_MAX_REPORT_COUNT  32768 /* Report Count, elements per main item */
#define DF_HID_MAX_FIELDS        16384 /* fields over all reports */
#define DF_HID_MAX_USAGES        1024  /* Usage / Usage Min-Max items per main item */
#define DF_HID_MAX_PUSH          16    /* Push depth */
#define DF_HID_MAX_COLLECTIONS   64    /* collection nesting depth */

enum { DF_HID_INPUT = 0, DF_HID_OUTPUT = 1, DF_HID_FEATURE = 2 };

/* Main item data bits (HID 1.11 6.2.2.5), kept as given in df_hid_field.flags. */
enum {
    DF_HID_F_CONSTANT = 0x01, /* else data */
    DF_HID_F_VARIABLE = 0x02, /* else array */
    DF_HID_F_RELATIVE = 0x04, /* else absolute */
    DF_HID_F_WRAP = 0x08,
    DF_HID_F_NONLINEAR = 0x10,
    DF_HID_F_NOPREFERRED = 0x20,
    DF_HID_F_NULLSTATE = 0x40,
    DF_HID_F_VOLATILE = 0x80,
    DF_HID_F_BUFFERED = 0x100
};

/* One run of `count` elements of `bit_size` bits each, starting at bit `bit_offset` of the report
 * as read (the report-id byte, when the report has one, is bits 0..7).
 * Variable fields: element i has usage usage_min + i when usage_min < usage_max, else every
 * element has usage_min (a main item with a usage list becomes several fields, one per run).
 * Array fields: each element holds an index into the usage range usage_min..usage_max (the span
 * of the item's usages; logical_min selects usage_min). Usages are 32-bit page << 16 | id. */
typedef struct df_hid_field {
    uint32_t usage_min, usage_max;
    uint32_t bit_offset;
    uint16_t bit_size;
    uint16_t count;
    uint16_t flags;          /* DF_HID_F_* */
    uint8_t kind;            /* DF_HID_INPUT/OUTPUT/FEATURE */
    uint8_t report_id;       /* 0 when the descriptor uses no report ids */
    uint8_t is_signed;       /* 1 when logical_min < 0: elements are two's complement */
    int8_t unit_exponent;    /* -8..7 */
    uint32_t unit;
    int64_t logical_min, logical_max;   /* logical_max unsigned when logical_min >= 0 */
    int64_t physical_min, physical_max;
    uint32_t collection;     /* usage of the innermost enclosing collection, 0 when none */
    uint32_t application;    /* usage of the outermost enclosing collection, 0 when none */
} df_hid_field;

typedef struct df_hid_report {
    uint8_t kind;            /* DF_HID_INPUT/OUTPUT/FEATURE */
    uint8_t id;              /* 0 when the descriptor uses no report ids */
    uint32_t bits;           /* data bits, report-id byte not included */
    uint32_t bytes;          /* byte length as read/written: ceil(bits/8) + (id != 0) */
    size_t first_field;      /* its fields are fields[first_field .. first_field + n_fields) */
    size_t n_fields;
} df_hid_report;

typedef struct df_hid_desc {
    df_hid_report *reports;  /* in order of first appearance */
    size_t n_reports;
    df_hid_field *fields;    /* grouped by report */
    size_t n_fields;
    int uses_ids;            /* 1 when any Report ID item appears */
} df_hid_desc;

/* Parses the n bytes at d (d may be NULL when n == 0). On DF_OK *out owns malloc'ed arrays (free
 * with df_hid_desc_free); on error *out is zeroed and owns nothing. Errors: DF_EINVAL (NULL out),
 * DF_EFORMAT (truncated item, End Collection or Pop without a match, collections or pushes open at
 * the end, report id 0, usage minimum above maximum), DF_ELIMIT (any DF_HID_MAX_* above),
 * DF_ENOMEM. */
int df_hid_desc_parse(const uint8_t *d, size_t n, df_hid_desc *out, df_error *err);

/* Frees what df_hid_desc_parse allocated and zeroes *desc (NULL and zeroed descs are fine). */
void df_hid_desc_free(df_hid_desc *desc);

/* The report of `kind` with report id `id` (0 when ids are not used), or NULL. */
const df_hid_report *df_hid_desc_report(const df_hid_desc *desc, int kind, unsigned id);

/* Finds the first input-report element whose usage is page:usage (variable fields by element,
 * array fields when the usage lies in their range). On DF_OK sets *field (pointer into desc) and
 * *index (the element, 0 for arrays); DF_ENOTFOUND when absent, DF_EINVAL on NULL arguments. */
int df_hid_find_input_usage(const df_hid_desc *desc, uint16_t page, uint16_t usage,
                            const df_hid_field **field, unsigned *index, df_error *err);

/* Identifies the input report in the n bytes read at buf: by its first byte when the descriptor
 * uses ids, else the single id-0 input report. Sets *report. Errors: DF_EINVAL (NULL arguments),
 * DF_ENOTFOUND (no input report with that id), DF_EFORMAT (n shorter than the report's bytes;
 * longer buffers are accepted, the tail is ignored). */
int df_hid_report_decode(const df_hid_desc *desc, const uint8_t *buf, size_t n,
                         const df_hid_report **report, df_error *err);

/* Extracts `bits` (1..32) bits little-endian from bit `bit_offset` of the n bytes at buf, sign-
 * extended when is_signed, into *out. Errors: DF_EINVAL (bits out of range, NULL arguments, or the
 * bits not all within buf). */
int df_hid_extract(const uint8_t *buf, size_t n, uint32_t bit_offset, unsigned bits,
                   int is_signed, int64_t *out, df_error *err);

/* Element `index` of `field` in the report at buf (n bytes): df_hid_extract with the field's
 * offset, size and signedness. Errors: DF_EINVAL (index >= count, bit_size 0 or > 32, the element
 * beyond n). */
int df_hid_field_value(const df_hid_field *field, const uint8_t *buf, size_t n, unsigned index,
                       int64_t *out, df_error *err);

#endif

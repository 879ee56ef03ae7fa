/* hid_desc.c — HID report-descriptor parser and input-report decoder: see hid_desc.h. */
#include "server/hid/hid_desc.h"

#include <stdlib.h>
#include <string.h>

typedef struct hid_global {
    uint32_t usage_page;
    int64_t logical_min, logical_max_raw; /* max kept raw + size: signedness decided at main */
    uint32_t logical_max_u;
    int64_t physical_min, physical_max;
    uint32_t unit;
    int8_t unit_exponent;
    uint32_t report_size, report_count;
    uint32_t report_id;
} hid_global;

typedef struct hid_range { /* usages min..max; ext: given as 4 bytes (page in the high half) */
    uint32_t min, max;
    uint8_t min_ext, max_ext;
} hid_range;

typedef struct hid_collection { uint32_t usage; } hid_collection;

typedef struct parser {
    const uint8_t *d;
    size_t n, at;
    hid_global g;
    hid_global stack[DF_HID_MAX_PUSH];
    int depth;
    hid_range usages[DF_HID_MAX_USAGES];
    size_t n_usages;
    int pending_min; /* a Usage Minimum waits for its Maximum in usages[n_usages] */
    hid_collection coll[DF_HID_MAX_COLLECTIONS];
    int n_coll;
    df_hid_report *reports;
    size_t n_reports, cap_reports;
    df_hid_field *fields; /* in item order; grouped by report at the end */
    size_t n_fields, cap_fields;
    uint16_t *field_report; /* report index of each field */
    int uses_ids;
    df_error *err;
} parser;

static uint32_t resolve(uint32_t u, int ext, uint32_t page)
{
    return ext ? u : (page << 16) | (u & 0xffffu);
}

static df_hid_report *get_report(parser *p, int kind, uint32_t id, size_t *idx)
{
    for (size_t i = 0; i < p->n_reports; i++)
        if (p->reports[i].kind == kind && p->reports[i].id == id) { *idx = i; return &p->reports[i]; }
    if (p->n_reports == p->cap_reports) {
        size_t cap = p->cap_reports ? p->cap_reports * 2 : 8;
        df_hid_report *r = realloc(p->reports, cap * sizeof *r);
        if (!r) return NULL;
        p->reports = r;
        p->cap_reports = cap;
    }
    df_hid_report *r = &p->reports[p->n_reports];
    memset(r, 0, sizeof *r);
    r->kind = (uint8_t)kind;
    r->id = (uint8_t)id;
    *idx = p->n_reports++;
    return r;
}

static int add_field(parser *p, const df_hid_field *f, size_t report)
{
    if (p->n_fields >= DF_HID_MAX_FIELDS)
        return df_error_set(p->err, DF_ELIMIT, "hid descriptor: byte %zu: more than %d fields",
                            p->at, DF_HID_MAX_FIELDS);
    if (p->n_fields == p->cap_fields) {
        size_t cap = p->cap_fields ? p->cap_fields * 2 : 32;
        df_hid_field *nf = realloc(p->fields, cap * sizeof *nf);
        if (!nf) return df_error_set(p->err, DF_ENOMEM, "hid descriptor: out of memory");
        p->fields = nf;
        uint16_t *nr = realloc(p->field_report, cap * sizeof *nr);
        if (!nr) return df_error_set(p->err, DF_ENOMEM, "hid descriptor: out of memory");
        p->field_report = nr;
        p->cap_fields = cap;
    }
    p->fields[p->n_fields] = *f;
    p->field_report[p->n_fields] = (uint16_t)report;
    p->n_fields++;
    return DF_OK;
}

/* The usage of element i of a variable item walks the usage ranges with a cursor (r, k). */
static int next_usage(const parser *p, size_t *r, uint32_t *k, uint32_t *u)
{
    if (*r >= p->n_usages) return 0;
    const hid_range *h = &p->usages[*r];
    uint32_t page = p->g.usage_page;
    uint32_t lo = resolve(h->min, h->min_ext, page), hi = resolve(h->max, h->max_ext, page);
    *u = lo + *k;
    if (lo + *k >= hi) { (*r)++; *k = 0; } else (*k)++;
    return 1;
}

static int main_item(parser *p, int kind, uint32_t data)
{
    const hid_global *g = &p->g;
    if (g->report_size > DF_HID_MAX_REPORT_SIZE)
        return df_error_set(p->err, DF_ELIMIT, "hid descriptor: byte %zu: report size %u bits > %d",
                            p->at, g->report_size, DF_HID_MAX_REPORT_SIZE);
    if (g->report_count > DF_HID_MAX_REPORT_COUNT)
        return df_error_set(p->err, DF_ELIMIT, "hid descriptor: byte %zu: report count %u > %d",
                            p->at, g->report_count, DF_HID_MAX_REPORT_COUNT);
    size_t ri;
    df_hid_report *rep = get_report(p, kind, g->report_id, &ri);
    if (!rep) return df_error_set(p->err, DF_ENOMEM, "hid descriptor: out of memory");
    uint64_t bits = (uint64_t)g->report_size * g->report_count;
    uint64_t total = rep->bits + bits;
    if ((total + 7) / 8 + (g->report_id ? 1 : 0) > DF_HID_MAX_REPORT_BYTES)
        return df_error_set(p->err, DF_ELIMIT,
                            "hid descriptor: byte %zu: report %u longer than %d bytes",
                            p->at, g->report_id, DF_HID_MAX_REPORT_BYTES);
    uint32_t base = rep->bits + (g->report_id ? 8u : 0u);
    df_hid_field f;
    memset(&f, 0, sizeof f);
    f.bit_size = (uint16_t)g->report_size;
    f.flags = (uint16_t)(data & 0x1ff);
    f.kind = (uint8_t)kind;
    f.report_id = (uint8_t)g->report_id;
    f.logical_min = g->logical_min;
    f.is_signed = g->logical_min < 0;
    f.logical_max = f.is_signed ? g->logical_max_raw : (int64_t)g->logical_max_u;
    f.physical_min = g->physical_min;
    f.physical_max = g->physical_max;
    f.unit = g->unit;
    f.unit_exponent = g->unit_exponent;
    f.collection = p->n_coll ? p->coll[p->n_coll - 1].usage : 0;
    f.application = p->n_coll ? p->coll[0].usage : 0;
    rep->bits = (uint32_t)total;
    if (g->report_count == 0 || g->report_size == 0) return DF_OK;
    int rc;
    if (!(data & DF_HID_F_VARIABLE)) { /* array: one field over the span of its usages */
        uint32_t lo = 0, hi = 0;
        for (size_t i = 0; i < p->n_usages; i++) {
            const hid_range *h = &p->usages[i];
            uint32_t a = resolve(h->min, h->min_ext, g->usage_page);
            uint32_t b = resolve(h->max, h->max_ext, g->usage_page);
            if (i == 0 || a < lo) lo = a;
            if (i == 0 || b > hi) hi = b;
        }
        f.usage_min = lo;
        f.usage_max = hi;
        f.bit_offset = base;
        f.count = (uint16_t)g->report_count;
        return add_field(p, &f, ri);
    }
    size_t r = 0;
    uint32_t k = 0, last = 0;
    uint32_t i = 0;
    while (i < g->report_count) {
        uint32_t u;
        if (!next_usage(p, &r, &k, &u)) { /* the rest repeat the last usage: one run */
            f.usage_min = f.usage_max = last;
            f.bit_offset = base + i * g->report_size;
            f.count = (uint16_t)(g->report_count - i);
            return add_field(p, &f, ri);
        }
        last = u;
        f.usage_min = f.usage_max = u;
        f.bit_offset = base + i * g->report_size;
        f.count = 1;
        i++;
        /* extend the run while usages keep increasing by one (a range) or stay equal */
        while (i < g->report_count) {
            size_t r2 = r;
            uint32_t k2 = k, v;
            if (!next_usage(p, &r2, &k2, &v)) {
                if (f.usage_min == f.usage_max && last == f.usage_min) {
                    f.count = (uint16_t)(f.count + (g->report_count - i));
                    i = g->report_count;
                }
                break;
            }
            int range_ok = f.usage_min != 0xffffffffu && (f.count == 1 || f.usage_max > f.usage_min)
                           && v == f.usage_max + 1 && (v & 0xffffu) != 0;
            int same_ok = f.usage_min == f.usage_max && v == f.usage_min;
            if (!range_ok && !same_ok) break;
            if (range_ok) f.usage_max = v;
            f.count++;
            r = r2; k = k2; last = v; i++;
        }
        if ((rc = add_field(p, &f, ri)) != DF_OK) return rc;
    }
    return DF_OK;
}

static void clear_local(parser *p)
{
    p->n_usages = 0;
    p->pending_min = 0;
}

static int add_usage(parser *p, uint32_t min, uint32_t max, int min_ext, int max_ext)
{
    if (p->n_usages >= DF_HID_MAX_USAGES)
        return df_error_set(p->err, DF_ELIMIT, "hid descriptor: byte %zu: more than %d usages",
                            p->at, DF_HID_MAX_USAGES);
    hid_range *h = &p->usages[p->n_usages++];
    h->min = min; h->max = max;
    h->min_ext = (uint8_t)min_ext; h->max_ext = (uint8_t)max_ext;
    return DF_OK;
}

static int item(parser *p, int type, int tag, uint32_t u, int32_t s, int size)
{
    hid_global *g = &p->g;
    if (type == 0) { /* main */
        int rc = DF_OK;
        if (tag == 0x8 || tag == 0x9 || tag == 0xB) {
            rc = main_item(p, tag == 0x8 ? DF_HID_INPUT : tag == 0x9 ? DF_HID_OUTPUT : DF_HID_FEATURE, u);
        } else if (tag == 0xA) {
            if (p->n_coll >= DF_HID_MAX_COLLECTIONS)
                return df_error_set(p->err, DF_ELIMIT,
                                    "hid descriptor: byte %zu: collections nested deeper than %d",
                                    p->at, DF_HID_MAX_COLLECTIONS);
            uint32_t cu = 0;
            if (p->n_usages) cu = resolve(p->usages[0].min, p->usages[0].min_ext, g->usage_page);
            p->coll[p->n_coll++].usage = cu;
        } else if (tag == 0xC) {
            if (p->n_coll == 0)
                return df_error_set(p->err, DF_EFORMAT,
                                    "hid descriptor: byte %zu: End Collection without a Collection",
                                    p->at);
            p->n_coll--;
        }
        clear_local(p);
        return rc;
    }
    if (type == 1) { /* global */
        switch (tag) {
        case 0x0: g->usage_page = u & 0xffffu; break;
        case 0x1: g->logical_min = s; break;
        case 0x2: g->logical_max_raw = s; g->logical_max_u = u; break;
        case 0x3: g->physical_min = s; break;
        case 0x4: g->physical_max = s; break;
        case 0x5: g->unit_exponent = (int8_t)(u <= 15 ? (u & 8 ? (int)u - 16 : (int)u) : s); break;
        case 0x6: g->unit = u; break;
        case 0x7: g->report_size = u; break;
        case 0x8:
            if (u == 0 || u > 255)
                return df_error_set(p->err, DF_EFORMAT, "hid descriptor: byte %zu: report id %u "
                                    "(must be 1..255)", p->at, u);
            g->report_id = u;
            p->uses_ids = 1;
            break;
        case 0x9: g->report_count = u; break;
        case 0xA:
            if (p->depth >= DF_HID_MAX_PUSH)
                return df_error_set(p->err, DF_ELIMIT, "hid descriptor: byte %zu: Push deeper than %d",
                                    p->at, DF_HID_MAX_PUSH);
            p->stack[p->depth++] = *g;
            break;
        case 0xB:
            if (p->depth == 0)
                return df_error_set(p->err, DF_EFORMAT, "hid descriptor: byte %zu: Pop without a Push",
                                    p->at);
            *g = p->stack[--p->depth];
            break;
        default: break;
        }
        return DF_OK;
    }
    if (type == 2) { /* local */
        int ext = size == 4;
        if (tag == 0x0) return add_usage(p, u, u, ext, ext);
        if (tag == 0x1) {
            int rc = add_usage(p, u, u, ext, ext);
            if (rc == DF_OK) { p->n_usages--; p->pending_min = 1; }
            return rc;
        }
        if (tag == 0x2) {
            if (!p->pending_min) return add_usage(p, u, u, ext, ext); /* lone maximum: one usage */
            hid_range *h = &p->usages[p->n_usages];
            uint32_t lo = resolve(h->min, h->min_ext, g->usage_page), hi = resolve(u, ext, g->usage_page);
            if (lo > hi)
                return df_error_set(p->err, DF_EFORMAT, "hid descriptor: byte %zu: usage minimum "
                                    "0x%x above maximum 0x%x", p->at, lo, hi);
            p->pending_min = 0;
            return add_usage(p, h->min, u, h->min_ext, ext);
        }
        return DF_OK;
    }
    return DF_OK; /* reserved item type: ignored */
}

static int finish(parser *p, df_hid_desc *out)
{
    /* group fields by report, keeping item order within a report */
    df_hid_field *sorted = p->n_fields ? malloc(p->n_fields * sizeof *sorted) : NULL;
    if (p->n_fields && !sorted) return df_error_set(p->err, DF_ENOMEM, "hid descriptor: out of memory");
    size_t at = 0;
    for (size_t r = 0; r < p->n_reports; r++) {
        p->reports[r].first_field = at;
        for (size_t i = 0; i < p->n_fields; i++)
            if (p->field_report[i] == r) sorted[at++] = p->fields[i];
        p->reports[r].n_fields = at - p->reports[r].first_field;
        p->reports[r].bytes = (p->reports[r].bits + 7) / 8 + (p->reports[r].id ? 1u : 0u);
    }
    free(p->fields);
    free(p->field_report);
    out->fields = sorted;
    out->n_fields = p->n_fields;
    out->reports = p->reports;
    out->n_reports = p->n_reports;
    out->uses_ids = p->uses_ids;
    return DF_OK;
}

int df_hid_desc_parse(const uint8_t *d, size_t n, df_hid_desc *out, df_error *err)
{
    if (!out || (!d && n)) return df_error_set(err, DF_EINVAL, "hid descriptor: NULL argument");
    memset(out, 0, sizeof *out);
    if (n > DF_HID_MAX_DESC_BYTES)
        return df_error_set(err, DF_ELIMIT, "hid descriptor: %zu bytes > %d", n, DF_HID_MAX_DESC_BYTES);
    parser *p = calloc(1, sizeof *p);
    if (!p) return df_error_set(err, DF_ENOMEM, "hid descriptor: out of memory");
    p->d = d; p->n = n; p->err = err;
    int rc = DF_OK;
    size_t i = 0;
    while (i < n && rc == DF_OK) {
        p->at = i;
        uint8_t b = d[i];
        if (b == 0xFE) { /* long item: FE size tag data... */
            if (n - i < 3) {
                rc = df_error_set(err, DF_EFORMAT, "hid descriptor: byte %zu: truncated long item", i);
                break;
            }
            size_t len = d[i + 1];
            if (n - i - 3 < len) {
                rc = df_error_set(err, DF_EFORMAT, "hid descriptor: byte %zu: truncated long item "
                                  "(%zu data bytes, %zu left)", i, len, n - i - 3);
                break;
            }
            i += 3 + len;
            continue;
        }
        int size = (b & 3) == 3 ? 4 : (b & 3);
        if (n - i - 1 < (size_t)size) {
            rc = df_error_set(err, DF_EFORMAT, "hid descriptor: byte %zu: truncated item 0x%02x "
                              "(%d data bytes, %zu left)", i, b, size, n - i - 1);
            break;
        }
        uint32_t u = 0;
        for (int k = 0; k < size; k++) u |= (uint32_t)d[i + 1 + k] << (8 * k);
        int32_t s = size == 1 ? (int8_t)u : size == 2 ? (int16_t)u : size == 4 ? (int32_t)u : 0;
        rc = item(p, (b >> 2) & 3, b >> 4, u, s, size);
        i += 1 + (size_t)size;
    }
    if (rc == DF_OK && p->n_coll)
        rc = df_error_set(err, DF_EFORMAT, "hid descriptor: byte %zu: %d collection(s) not closed "
                          "at the end", n, p->n_coll);
    if (rc == DF_OK && p->depth)
        rc = df_error_set(err, DF_EFORMAT, "hid descriptor: byte %zu: %d Push(es) without a Pop "
                          "at the end", n, p->depth);
    if (rc == DF_OK) rc = finish(p, out);
    if (rc != DF_OK) {
        free(p->reports);
        free(p->fields);
        free(p->field_report);
        memset(out, 0, sizeof *out);
    }
    free(p);
    return rc;
}

void df_hid_desc_free(df_hid_desc *desc)
{
    if (!desc) return;
    free(desc->reports);
    free(desc->fields);
    memset(desc, 0, sizeof *desc);
}

const df_hid_report *df_hid_desc_report(const df_hid_desc *desc, int kind, unsigned id)
{
    if (!desc) return NULL;
    for (size_t i = 0; i < desc->n_reports; i++)
        if (desc->reports[i].kind == kind && desc->reports[i].id == id) return &desc->reports[i];
    return NULL;
}

int df_hid_find_input_usage(const df_hid_desc *desc, uint16_t page, uint16_t usage,
                            const df_hid_field **field, unsigned *index, df_error *err)
{
    if (!desc || !field || !index) return df_error_set(err, DF_EINVAL, "hid usage: NULL argument");
    uint32_t want = (uint32_t)page << 16 | usage;
    for (size_t i = 0; i < desc->n_fields; i++) {
        const df_hid_field *f = &desc->fields[i];
        if (f->kind != DF_HID_INPUT || want < f->usage_min || want > f->usage_max) continue;
        if (f->flags & DF_HID_F_VARIABLE) {
            *index = f->usage_min == f->usage_max ? 0 : want - f->usage_min;
        } else {
            *index = 0;
        }
        *field = f;
        return DF_OK;
    }
    return df_error_set(err, DF_ENOTFOUND, "hid usage 0x%04x:0x%04x not in any input report",
                        page, usage);
}

int df_hid_report_decode(const df_hid_desc *desc, const uint8_t *buf, size_t n,
                         const df_hid_report **report, df_error *err)
{
    if (!desc || !report || (!buf && n)) return df_error_set(err, DF_EINVAL, "hid report: NULL argument");
    unsigned id = 0;
    if (desc->uses_ids) {
        if (n == 0) return df_error_set(err, DF_EFORMAT, "hid report: empty (no report id byte)");
        id = buf[0];
    }
    const df_hid_report *r = df_hid_desc_report(desc, DF_HID_INPUT, id);
    if (!r) return df_error_set(err, DF_ENOTFOUND, "hid report: no input report with id %u", id);
    if (n < r->bytes)
        return df_error_set(err, DF_EFORMAT, "hid report: input report %u is %zu bytes, "
                            "the descriptor gives %u", id, n, r->bytes);
    *report = r;
    return DF_OK;
}

int df_hid_extract(const uint8_t *buf, size_t n, uint32_t bit_offset, unsigned bits,
                   int is_signed, int64_t *out, df_error *err)
{
    if (!out || (!buf && n)) return df_error_set(err, DF_EINVAL, "hid extract: NULL argument");
    if (bits < 1 || bits > 32)
        return df_error_set(err, DF_EINVAL, "hid extract: %u bits (must be 1..32)", bits);
    if ((uint64_t)bit_offset + bits > (uint64_t)n * 8)
        return df_error_set(err, DF_EINVAL, "hid extract: bits %u..%u beyond the %zu-byte report",
                            bit_offset, bit_offset + bits - 1, n);
    uint64_t v = 0;
    size_t first = bit_offset / 8, last = (bit_offset + bits - 1) / 8;
    for (size_t k = first; k <= last; k++) v |= (uint64_t)buf[k] << (8 * (k - first));
    v >>= bit_offset % 8;
    v &= bits == 32 ? 0xffffffffu : ((uint64_t)1 << bits) - 1;
    if (is_signed && (v >> (bits - 1)) & 1) *out = (int64_t)v - ((int64_t)1 << bits);
    else *out = (int64_t)v;
    return DF_OK;
}

int df_hid_field_value(const df_hid_field *field, const uint8_t *buf, size_t n, unsigned index,
                       int64_t *out, df_error *err)
{
    if (!field) return df_error_set(err, DF_EINVAL, "hid field: NULL argument");
    if (index >= field->count)
        return df_error_set(err, DF_EINVAL, "hid field: element %u of %u", index, field->count);
    return df_hid_extract(buf, n, field->bit_offset + (uint32_t)index * field->bit_size,
                          field->bit_size, field->is_signed, out, err);
}

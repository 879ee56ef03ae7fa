/* hid_recording.c — hid-recorder text format parser: see hid_recording.h. */
#include "server/hid/hid_recording.h"

#include <stdlib.h>
#include <string.h>

typedef struct cursor {
    const char *s, *end;
} cursor;

static void skip_blanks(cursor *c)
{
    while (c->s < c->end && (*c->s == ' ' || *c->s == '\t')) c->s++;
}

static int hexval(char ch)
{
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

/* An unsigned number (base 10 or 16) of at most `maxdigits` digits, then a blank, '.' or the end. */
static int number(cursor *c, int base, int maxdigits, uint64_t *v)
{
    skip_blanks(c);
    int nd = 0;
    uint64_t x = 0;
    while (c->s < c->end) {
        int h = hexval(*c->s);
        if (h < 0 || h >= base) break;
        if (++nd > maxdigits) return -1;
        x = x * (uint64_t)base + (uint64_t)h;
        c->s++;
    }
    if (nd == 0) return -1;
    if (c->s < c->end && *c->s != ' ' && *c->s != '\t' && *c->s != '.') return -1;
    *v = x;
    return 0;
}

typedef struct rec_parser {
    df_hid_recording *r;
    size_t cap_events, cap_bytes;
    df_error *err;
    size_t line;
    unsigned flags;          /* DF_HID_REC_* */
} rec_parser;

/* `len` (decimal) then exactly len hex bytes, appended into *buf (grown) at *used. */
static int hex_bytes(rec_parser *p, cursor *c, uint8_t **buf, size_t *used, size_t *cap, size_t *len)
{
    uint64_t want;
    if (number(c, 10, 9, &want) != 0)
        return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad byte count", p->line);
    if (want > DF_HID_REC_MAX_LINE_BYTES)
        return df_error_set(p->err, DF_ELIMIT, "hid recording: line %zu: %llu bytes > %d", p->line,
                            (unsigned long long)want, DF_HID_REC_MAX_LINE_BYTES);
    if (*cap - *used < want) {
        size_t nc = *cap ? *cap : 256;
        while (nc - *used < want) nc *= 2;
        uint8_t *nb = realloc(*buf, nc);
        if (!nb) return df_error_set(p->err, DF_ENOMEM, "hid recording: out of memory");
        *buf = nb;
        *cap = nc;
    }
    size_t got = 0;
    for (;;) {
        skip_blanks(c);
        if (c->s >= c->end) break;
        uint64_t v;
        if (number(c, 16, 2, &v) != 0 || (c->s < c->end && *c->s == '.'))
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad hex byte", p->line);
        if (got == want)
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: more than the %llu "
                                "bytes declared", p->line, (unsigned long long)want);
        (*buf)[*used + got++] = (uint8_t)v;
    }
    if (got != want)
        return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: %zu bytes, %llu declared",
                            p->line, got, (unsigned long long)want);
    *len = got;
    return DF_OK;
}

static int device(rec_parser *p, unsigned idx, df_hid_rec_device **dev)
{
    df_hid_recording *r = p->r;
    if (idx >= DF_HID_REC_MAX_DEVICES)
        return df_error_set(p->err, DF_ELIMIT, "hid recording: line %zu: device %u >= %d", p->line,
                            idx, DF_HID_REC_MAX_DEVICES);
    if (idx >= r->n_devices) {
        df_hid_rec_device *nd = realloc(r->devices, (idx + 1) * sizeof *nd);
        if (!nd) return df_error_set(p->err, DF_ENOMEM, "hid recording: out of memory");
        memset(nd + r->n_devices, 0, (idx + 1 - r->n_devices) * sizeof *nd);
        r->devices = nd;
        r->n_devices = idx + 1;
    }
    *dev = &r->devices[idx];
    (*dev)->seen = 1;
    return DF_OK;
}

static void copy_text(char *dst, const cursor *c)
{
    size_t k = (size_t)(c->end - c->s);
    if (k >= DF_HID_REC_NAME_MAX) k = DF_HID_REC_NAME_MAX - 1;
    memcpy(dst, c->s, k);
    dst[k] = '\0';
}

static int line(rec_parser *p, cursor *c, unsigned *cur)
{
    df_hid_recording *r = p->r;
    if (c->s >= c->end || *c->s == '#') return DF_OK;
    if (c->end - c->s < 2 || c->s[1] != ':')
        return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: not a '<letter>:' line", p->line);
    char kind = c->s[0];
    c->s += 2;
    df_hid_rec_device *dev;
    int rc;
    uint64_t v[3];
    switch (kind) {
    case 'D':
        if (number(c, 10, 6, &v[0]) != 0 || (skip_blanks(c), c->s != c->end))
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad device index", p->line);
        if ((rc = device(p, v[0] < DF_HID_REC_MAX_DEVICES ? (unsigned)v[0] : DF_HID_REC_MAX_DEVICES, &dev)))
            return rc;
        *cur = (unsigned)v[0];
        return DF_OK;
    case 'R': {
        if ((rc = device(p, *cur, &dev))) return rc;
        if (dev->desc)
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: second R: for device %u",
                                p->line, *cur);
        uint8_t *buf = NULL;
        size_t used = 0, cap = 0, len = 0;
        rc = hex_bytes(p, c, &buf, &used, &cap, &len);
        if (rc == DF_OK && len == 0) { /* keep desc non-NULL for an empty descriptor */
            free(buf);
            buf = malloc(1);
            if (!buf) rc = df_error_set(p->err, DF_ENOMEM, "hid recording: out of memory");
        }
        if (rc != DF_OK) { free(buf); return rc; }
        dev->desc = buf;
        dev->desc_len = len;
        return DF_OK;
    }
    case 'N':
    case 'P':
        if ((rc = device(p, *cur, &dev))) return rc;
        skip_blanks(c);
        copy_text(kind == 'N' ? dev->name : dev->phys, c);
        return DF_OK;
    case 'I':
        if ((rc = device(p, *cur, &dev))) return rc;
        for (int k = 0; k < 3; k++)
            if (number(c, 16, 8, &v[k]) != 0 || (c->s < c->end && *c->s == '.'))
                return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad I: line", p->line);
        skip_blanks(c);
        if (c->s != c->end)
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad I: line", p->line);
        dev->bus = (uint32_t)v[0]; dev->vid = (uint32_t)v[1]; dev->pid = (uint32_t)v[2];
        return DF_OK;
    case 'E': {
        if ((p->flags & DF_HID_REC_RAW) && (rc = device(p, *cur, &dev))) return rc;
        if (!(p->flags & DF_HID_REC_RAW) && (*cur >= r->n_devices || !r->devices[*cur].desc))
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: E: for device %u, which "
                                "has no R: line", p->line, *cur);
        uint64_t sec, usec;
        if (number(c, 10, 12, &sec) != 0 || c->s >= c->end || *c->s != '.')
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad timestamp", p->line);
        c->s++;
        const char *u0 = c->s;
        if (c->s >= c->end || *c->s == ' ' || number(c, 10, 6, &usec) != 0
            || (c->s < c->end && *c->s == '.'))
            return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: bad timestamp", p->line);
        for (long k = (long)(c->s - u0); k < 6; k++) usec *= 10; /* ".5" is 500000 us */
        if (r->n_events >= DF_HID_REC_MAX_EVENTS)
            return df_error_set(p->err, DF_ELIMIT, "hid recording: line %zu: more than %u events",
                                p->line, DF_HID_REC_MAX_EVENTS);
        if (r->n_events == p->cap_events) {
            size_t nc = p->cap_events ? p->cap_events * 2 : 64;
            df_hid_rec_event *ne = realloc(r->events, nc * sizeof *ne);
            if (!ne) return df_error_set(p->err, DF_ENOMEM, "hid recording: out of memory");
            r->events = ne;
            p->cap_events = nc;
        }
        size_t len;
        if ((rc = hex_bytes(p, c, &r->bytes, &r->n_bytes, &p->cap_bytes, &len))) return rc;
        df_hid_rec_event *e = &r->events[r->n_events++];
        e->device = *cur;
        e->time_us = sec * 1000000u + usec;
        e->offset = r->n_bytes;
        e->len = len;
        r->n_bytes += len;
        return DF_OK;
    }
    default:
        return df_error_set(p->err, DF_EFORMAT, "hid recording: line %zu: unknown line type '%c:'",
                            p->line, kind);
    }
}

int df_hid_recording_parse(const char *text, size_t n, df_hid_recording *out, df_error *err)
{
    return df_hid_recording_parse_flags(text, n, 0, out, err);
}

int df_hid_recording_parse_flags(const char *text, size_t n, unsigned flags, df_hid_recording *out,
                                 df_error *err)
{
    if (!out || (!text && n)) return df_error_set(err, DF_EINVAL, "hid recording: NULL argument");
    memset(out, 0, sizeof *out);
    rec_parser p = { .r = out, .err = err, .flags = flags };
    unsigned cur = 0;
    size_t i = 0;
    int rc = DF_OK;
    while (i < n && rc == DF_OK) {
        const char *nl = memchr(text + i, '\n', n - i);
        size_t e = nl ? (size_t)(nl - text) : n;
        cursor c = { text + i, text + e };
        while (c.end > c.s && (c.end[-1] == '\r' || c.end[-1] == ' ' || c.end[-1] == '\t')) c.end--;
        p.line++;
        rc = line(&p, &c, &cur);
        i = e + 1;
    }
    if (rc != DF_OK) df_hid_recording_free(out);
    return rc;
}

void df_hid_recording_free(df_hid_recording *rec)
{
    if (!rec) return;
    for (size_t i = 0; i < rec->n_devices; i++) free(rec->devices[i].desc);
    free(rec->devices);
    free(rec->events);
    free(rec->bytes);
    memset(rec, 0, sizeof *rec);
}

const uint8_t *df_hid_rec_event_bytes(const df_hid_recording *rec, const df_hid_rec_event *e)
{
    return rec->bytes ? rec->bytes + e->offset : NULL;
}

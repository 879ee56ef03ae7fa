/* Shared by the hid replay tests: an independent reader of the hid-recorder text format (and of
 * the PowerMate raw file), written with sscanf/strtoul apart from server/hid/hid_recording.c, that
 * gives what the replay backend must deliver: the devices (path, ids, name, descriptor) and each
 * device's reports in file order with their recorded times. */
#ifndef DF_TESTS_UNIT_HID_EXPECT_H
#define DF_TESTS_UNIT_HID_EXPECT_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EX_MAX_NODES 64

typedef struct ex_event {
    unsigned node;
    uint64_t time_us;
    size_t off, len;
} ex_event;

typedef struct ex_node {
    int seen, has_r, n_e;
    uint8_t *r;
    size_t r_len;
    char name[256];
    unsigned bus, vid, pid;
} ex_node;

typedef struct ex_file {
    ex_node nodes[EX_MAX_NODES];
    unsigned n_nodes;
    ex_event *ev;
    size_t n_ev;
    uint8_t *bytes;
    size_t n_bytes;
    int any_r;              /* 0: a raw PowerMate file */
    uint64_t end_us;        /* last recorded time */
} ex_file;

/* Reads `len` hex bytes after *p into a malloc'd array; returns it or NULL on a mismatch. */
static inline uint8_t *ex_hex(const char *p, size_t len)
{
    uint8_t *b = malloc(len ? len : 1);
    char *q;
    for (size_t i = 0; i < len; i++) {
        unsigned long v = strtoul(p, &q, 16);
        if (q == p || v > 255) { free(b); return NULL; }
        b[i] = (uint8_t)v;
        p = q;
    }
    while (*p == ' ' || *p == '\t') p++;
    if (*p) { free(b); return NULL; }
    return b;
}

static inline ex_node *ex_at(ex_file *f, unsigned d)
{
    if (d >= EX_MAX_NODES) return NULL;
    if (d + 1 > f->n_nodes) f->n_nodes = d + 1;
    f->nodes[d].seen = 1;
    return &f->nodes[d];
}

/* Parses text (NUL-terminated, modified in place). 0 on success, -1 on anything unexpected. */
static inline int ex_parse(char *text, ex_file *f)
{
    memset(f, 0, sizeof *f);
    unsigned cur = 0;
    size_t cap_ev = 0, cap_b = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        size_t l = strlen(line);
        while (l && (line[l - 1] == '\r' || line[l - 1] == ' ' || line[l - 1] == '\t')) line[--l] = 0;
        if (l == 0 || line[0] == '#') continue;
        if (l < 2 || line[1] != ':') return -1;
        char *p = line + 2;
        ex_node *n;
        switch (line[0]) {
        case 'D':
            if (sscanf(p, "%u", &cur) != 1 || !ex_at(f, cur)) return -1;
            break;
        case 'R': {
            char *q;
            size_t len = strtoul(p, &q, 10);
            if (!(n = ex_at(f, cur)) || !(n->r = ex_hex(q, len))) return -1;
            n->r_len = len;
            n->has_r = 1;
            f->any_r = 1;
            break;
        }
        case 'N':
            if (!(n = ex_at(f, cur))) return -1;
            while (*p == ' ' || *p == '\t') p++;
            snprintf(n->name, sizeof n->name, "%s", p);
            break;
        case 'P':
            break;
        case 'I':
            if (!(n = ex_at(f, cur)) || sscanf(p, "%x %x %x", &n->bus, &n->vid, &n->pid) != 3)
                return -1;
            break;
        case 'E': {
            char *q, *r;
            uint64_t sec = strtoull(p, &q, 10);
            if (*q != '.') return -1;
            uint64_t usec = strtoull(q + 1, &r, 10);
            if (r - (q + 1) != 6) return -1; /* every shared file writes 6 digits */
            size_t len = strtoul(r, &q, 10);
            uint8_t *b = ex_hex(q, len);
            if (!b || !(n = ex_at(f, cur))) { free(b); return -1; }
            if (f->n_ev == cap_ev) {
                cap_ev = cap_ev ? 2 * cap_ev : 256;
                f->ev = realloc(f->ev, cap_ev * sizeof *f->ev);
            }
            while (f->n_bytes + len > cap_b) {
                cap_b = cap_b ? 2 * cap_b : 65536;
                f->bytes = realloc(f->bytes, cap_b);
            }
            memcpy(f->bytes + f->n_bytes, b, len);
            free(b);
            f->ev[f->n_ev++] = (ex_event){ cur, sec * 1000000u + usec, f->n_bytes, len };
            f->n_bytes += len;
            n->n_e++;
            if (sec * 1000000u + usec > f->end_us) f->end_us = sec * 1000000u + usec;
            break;
        }
        default:
            return -1;
        }
    }
    return 0;
}

/* 1 when node d of f is a replay device: an R: node, or in a raw file a node that sends. */
static inline int ex_is_device(const ex_file *f, unsigned d)
{
    return f->any_r ? f->nodes[d].has_r : f->nodes[d].n_e > 0;
}

static inline void ex_free(ex_file *f)
{
    for (unsigned i = 0; i < f->n_nodes; i++) free(f->nodes[i].r);
    free(f->ev);
    free(f->bytes);
    memset(f, 0, sizeof *f);
}

#endif

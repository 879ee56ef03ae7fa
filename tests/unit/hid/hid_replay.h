/* Shared by the hid mapper unit tests: loads a shared HID file, classifies its nodes, feeds the
 * events of one node through a mapper the way the device manager does (the session brush takes
 * every BRUSH_SET before the next report) and collects the actions with their event index. The
 * PowerMate raw file (E: lines, no descriptor) is read by replay_raw_events. Include after
 * <cmocka.h>. */
#ifndef DF_TESTS_UNIT_HID_REPLAY_H
#define DF_TESTS_UNIT_HID_REPLAY_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/hid/hid_class.h"
#include "server/hid/hid_desc.h"
#include "server/hid/hid_mapper.h"
#include "server/hid/hid_recording.h"
#include "tests/unit/hid/hid_files.h"
#include "tests/unit/unit_skip.h"

#define REPLAY_MAX_NODES 8

typedef struct replay {
    df_hid_recording rec;
    df_hid_desc desc[REPLAY_MAX_NODES];
    df_hid_class_info ci[REPLAY_MAX_NODES];
} replay;

/* One action with the index of the event that produced it (SIZE_MAX: unplug). */
typedef struct replay_act {
    df_hid_action a;
    size_t event;
    uint64_t t;
} replay_act;

typedef struct replay_out {
    replay_act *v;
    size_t n, cap;
} replay_out;

static inline void replay_load(const char *file, replay *r)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, file, &n);
    if (!text) fail_msg("cannot read %s/%s", dir, file);
    df_error e;
    memset(r, 0, sizeof *r);
    if (df_hid_recording_parse(text, n, &r->rec, &e) != DF_OK) fail_msg("%s: %s", file, e.msg);
    free(text);
    assert_true(r->rec.n_devices <= REPLAY_MAX_NODES);
    for (size_t k = 0; k < r->rec.n_devices; k++) {
        const df_hid_rec_device *d = &r->rec.devices[k];
        assert_int_equal(df_hid_desc_parse(d->desc, d->desc_len, &r->desc[k], &e), DF_OK);
        assert_int_equal(df_hid_classify(&r->desc[k], (uint16_t)d->vid, (uint16_t)d->pid, &r->ci[k]),
                         DF_OK);
    }
}

static inline void replay_free(replay *r)
{
    for (size_t k = 0; k < r->rec.n_devices; k++) df_hid_desc_free(&r->desc[k]);
    df_hid_recording_free(&r->rec);
}

static inline void replay_push(replay_out *o, const df_hid_action *a, size_t ev, uint64_t t)
{
    if (o->n == o->cap) {
        o->cap = o->cap ? o->cap * 2 : 64;
        o->v = realloc(o->v, o->cap * sizeof *o->v);
        assert_non_null(o->v);
    }
    o->v[o->n].a = *a;
    o->v[o->n].event = ev;
    o->v[o->n].t = t;
    o->n++;
}

/* What the device manager does with a BRUSH_SET: the session brush takes the masked fields. */
static inline void replay_apply(df_hid_brush *b, const df_hid_action *a)
{
    if (a->kind != DF_HID_ACT_BRUSH_SET) return;
    if (a->mask & DF_HID_BS_TYPE) b->type = a->brush.type;
    if (a->mask & DF_HID_BS_FALLOFF) b->falloff = a->brush.falloff;
    if (a->mask & DF_HID_BS_RADIUS) b->radius = a->brush.radius;
    if (a->mask & DF_HID_BS_NU) b->nu = a->brush.nu;
    if (a->mask & DF_HID_BS_STRENGTH) b->strength = a->brush.strength;
}

/* Feeds one report; appends its actions to o and applies them to *b. */
static inline void replay_feed(df_hid_mapper *m, const uint8_t *bytes, size_t len, uint64_t t,
                               df_hid_brush *b, replay_out *o, size_t ev)
{
    df_hid_action act[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    df_error e;
    if (df_hid_mapper_feed(m, bytes, len, t, b, act, DF_HID_MAX_ACTIONS, &n, &e) != DF_OK)
        fail_msg("event %zu: %s", ev, e.msg);
    assert_true(n <= DF_HID_MAX_ACTIONS);
    for (size_t i = 0; i < n; i++) {
        replay_push(o, &act[i], ev, t);
        replay_apply(b, &act[i]);
    }
}

/* Feeds every event of node `node` of r through a fresh mapper (config cfg, scale) into o. */
static inline void replay_node(replay *r, unsigned node, const df_hid_config *cfg, double scale,
                               df_hid_brush *b, replay_out *o)
{
    df_hid_mapper m;
    df_error e;
    if (df_hid_mapper_init(&m, &r->ci[node], &r->desc[node], cfg, &e) != DF_OK)
        fail_msg("init: %s", e.msg);
    df_hid_mapper_set_scale(&m, scale);
    for (size_t i = 0; i < r->rec.n_events; i++) {
        const df_hid_rec_event *ev = &r->rec.events[i];
        if (ev->device != node) continue;
        replay_feed(&m, df_hid_rec_event_bytes(&r->rec, ev), ev->len, ev->time_us, b, o, i);
    }
}

static inline size_t replay_count(const replay_out *o, int kind)
{
    size_t c = 0;
    for (size_t i = 0; i < o->n; i++) c += o->v[i].a.kind == kind;
    return c;
}

/* The E: lines of a raw file (no descriptor): times and bytes, at most cap events of 64 bytes. */
typedef struct raw_event {
    uint64_t t;
    size_t len;
    uint8_t b[64];
} raw_event;

static inline size_t replay_raw_events(const char *file, raw_event *ev, size_t cap)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, file, &n);
    if (!text) fail_msg("cannot read %s/%s", dir, file);
    text = realloc(text, n + 1);
    assert_non_null(text);
    text[n] = '\0';
    size_t k = 0;
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        if (strncmp(line, "E: ", 3) != 0) continue;
        assert_true(k < cap);
        unsigned long sec, usec;
        int len, used;
        if (sscanf(line + 3, "%lu.%lu %d%n", &sec, &usec, &len, &used) != 3 || len < 1 || len > 64)
            fail_msg("bad raw line '%s'", line);
        ev[k].t = (uint64_t)sec * 1000000u + usec;
        ev[k].len = (size_t)len;
        const char *p = line + 3 + used;
        for (int i = 0; i < len; i++) {
            unsigned v;
            int u2;
            if (sscanf(p, " %x%n", &v, &u2) != 1) fail_msg("bad raw byte in '%s'", line);
            ev[k].b[i] = (uint8_t)v;
            p += u2;
        }
        k++;
    }
    free(text);
    return k;
}

#endif

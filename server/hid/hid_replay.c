/* hid_replay.c — the replay backend of the device-source seam (hid_source.h): hid-recorder files
 * and the PowerMate raw file delivered at their recorded timestamps; every output report and
 * control transfer a caller sends is captured for tests (df_hid_replay_outputs).
 *
 * Time: a device opened at clock time t0 delivers its report recorded at r (us from the start of
 * the recording) at t0 + r / speed, with *time_us = r (+ the loop offset, see LOOP). The device's
 * end is the file's last recorded time (all nodes of one file unplug together, silent ones too).
 * Zero-length E: reports are skipped (hidraw never delivers one). Locking: b->mu guards the slots'
 * open/gone flags, each device's last_us/gone and the capture list; the reader thread owns the
 * rest of its device and sleeps without the lock. */
#include "server/hid/hid_source.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server/hid/hid_recording.h"

#define RP_MAX_FILE_BYTES (64u << 20) /* 64 MiB: far above any recording here */
#define RP_LOOP_GAP_US 10000u         /* LOOP: pause between two passes */

typedef struct rp_file {
    char *path;
    df_hid_recording rec;
    uint64_t end_us;              /* last recorded time of the file */
} rp_file;

typedef struct rp_slot {
    df_hid_devinfo info;          /* desc points into the recording (not owned) */
    size_t file;
    size_t *ev, n_ev;             /* indices into rec.events of this node, zero-length ones out */
    int open, gone;               /* under mu */
} rp_slot;

typedef struct rp_backend {
    df_hid_backend base;          /* first: the vtable the caller holds */
    df_hid_replay_opts opts;
    rp_file *files;
    size_t n_files;
    rp_slot *slots;
    size_t n_slots;
    pthread_mutex_t mu;
    df_hid_replay_output *outs;   /* under mu */
    size_t n_outs, cap_outs;
} rp_backend;

typedef struct rp_dev {
    rp_backend *b;
    rp_slot *s;
    size_t next;                  /* next index into s->ev (reader only) */
    uint64_t t0;                  /* clock at open */
    uint64_t loop_off;            /* recorded-time offset of the current pass (reader only) */
    uint64_t last_us;             /* recorded time of the last delivered report (under mu) */
    int gone;                     /* written under mu by the reader */
} rp_dev;

static uint64_t mono_now_us(void *ctx)
{
    (void)ctx;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static void mono_sleep_us(void *ctx, uint64_t us)
{
    (void)ctx;
    struct timespec ts = { (time_t)(us / 1000000u), (long)(us % 1000000u) * 1000L };
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {}
}

static int read_whole(const char *path, char **text, size_t *n, df_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return df_error_set(err, DF_EIO, "hid replay: %s: cannot open: %s", path, strerror(errno));
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int rc = DF_OK;
    for (;;) {
        if (cap - len < 4096) {
            if (cap >= RP_MAX_FILE_BYTES) {
                rc = df_error_set(err, DF_ELIMIT, "hid replay: %s: larger than %u bytes", path,
                                  RP_MAX_FILE_BYTES);
                break;
            }
            size_t nc = cap ? cap * 2 : 65536;
            char *nb = realloc(buf, nc);
            if (!nb) { rc = df_error_set(err, DF_ENOMEM, "hid replay: %s: out of memory", path); break; }
            buf = nb;
            cap = nc;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) {
            if (ferror(f))
                rc = df_error_set(err, DF_EIO, "hid replay: %s: cannot read: %s", path,
                                  strerror(errno));
            break;
        }
    }
    fclose(f);
    if (rc != DF_OK) { free(buf); return rc; }
    *text = buf;
    *n = len;
    return DF_OK;
}

/* 1 when no line of text starts with "R:" (a PowerMate raw file). */
static int is_raw_text(const char *t, size_t n)
{
    for (size_t i = 0; i < n;) {
        if (n - i >= 2 && t[i] == 'R' && t[i + 1] == ':') return 0;
        const char *nl = memchr(t + i, '\n', n - i);
        if (!nl) break;
        i = (size_t)(nl - t) + 1;
    }
    return 1;
}

static int load_file(rp_backend *b, size_t fi, const char *path, df_error *err)
{
    rp_file *f = &b->files[fi];
    f->path = strdup(path);
    if (!f->path) return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
    char *text = NULL;
    size_t n = 0;
    int rc = read_whole(path, &text, &n, err);
    if (rc) return rc;
    int raw = is_raw_text(text, n);
    df_error pe;
    rc = df_hid_recording_parse_flags(text, n, raw ? DF_HID_REC_RAW : 0, &f->rec, &pe);
    free(text);
    if (rc) return df_error_set(err, rc, "hid replay: %s: %s", path, pe.msg);
    const df_hid_recording *r = &f->rec;
    for (size_t e = 0; e < r->n_events; e++)
        if (r->events[e].time_us > f->end_us) f->end_us = r->events[e].time_us;
    size_t added = 0;
    for (unsigned d = 0; d < r->n_devices; d++) {
        const df_hid_rec_device *rd = &r->devices[d];
        if (!rd->seen || (!raw && !rd->desc)) continue;
        if (raw) { /* a raw node is a device when it sends something */
            int any = 0;
            for (size_t e = 0; e < r->n_events && !any; e++) any = r->events[e].device == d;
            if (!any) continue;
        }
        rp_slot *nsl = realloc(b->slots, (b->n_slots + 1) * sizeof *nsl);
        if (!nsl) return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
        b->slots = nsl;
        rp_slot *s = &b->slots[b->n_slots];
        memset(s, 0, sizeof *s);
        s->file = fi;
        df_hid_devinfo *in = &s->info;
        int k = snprintf(in->path, sizeof in->path, "replay:%s#%u", path, d);
        if (k < 0 || (size_t)k >= sizeof in->path)
            return df_error_set(err, DF_ELIMIT, "hid replay: %s: path longer than %d bytes", path,
                                DF_HID_PATH_MAX - 1);
        in->backend = DF_HID_BACKEND_REPLAY;
        if (raw) {
            in->raw_powermate = 1;
            in->vid = rd->vid ? (uint16_t)rd->vid : DF_HID_POWERMATE_VID;
            in->pid = rd->pid ? (uint16_t)rd->pid : DF_HID_POWERMATE_PID;
            in->bus = rd->bus ? (uint8_t)rd->bus : DF_HID_BUS_USB;
            snprintf(in->name, sizeof in->name, "%s", rd->name[0] ? rd->name : "Griffin PowerMate");
        } else {
            in->vid = (uint16_t)rd->vid;
            in->pid = (uint16_t)rd->pid;
            in->bus = (uint8_t)rd->bus;
            in->desc = rd->desc_len ? rd->desc : NULL;
            in->desc_len = rd->desc_len;
            snprintf(in->name, sizeof in->name, "%s", rd->name);
        }
        for (size_t e = 0; e < r->n_events; e++)
            if (r->events[e].device == d && r->events[e].len > 0) s->n_ev++;
        if (s->n_ev) {
            s->ev = malloc(s->n_ev * sizeof *s->ev);
            if (!s->ev) return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
            size_t j = 0;
            for (size_t e = 0; e < r->n_events; e++)
                if (r->events[e].device == d && r->events[e].len > 0) s->ev[j++] = e;
        }
        b->n_slots++;
        added++;
    }
    if (added == 0)
        return df_error_set(err, DF_EFORMAT, "hid replay: %s: no device (no D: node with an R: "
                            "descriptor, and no E: line for a raw PowerMate file)", path);
    return DF_OK;
}

static int rp_enumerate(df_hid_backend *bb, df_hid_devinfo **out, size_t *n, df_error *err)
{
    rp_backend *b = (rp_backend *)bb;
    if (!b || !out || !n) return df_error_set(err, DF_EINVAL, "hid replay: enumerate: NULL argument");
    df_hid_devinfo *list = NULL;
    size_t k = 0;
    int rc = DF_OK;
    pthread_mutex_lock(&b->mu);
    if (b->n_slots) {
        list = calloc(b->n_slots, sizeof *list);
        if (!list) rc = df_error_set(err, DF_ENOMEM, "hid replay: enumerate: out of memory");
    }
    for (size_t i = 0; rc == DF_OK && i < b->n_slots; i++) {
        if (b->slots[i].gone) continue;
        if ((rc = df_hid_devinfo_copy(&list[k], &b->slots[i].info, err)) == DF_OK) k++;
    }
    pthread_mutex_unlock(&b->mu);
    if (rc != DF_OK) { df_hid_devinfo_free_list(list, k); return rc; }
    if (k == 0) { free(list); list = NULL; }
    *out = list;
    *n = k;
    return DF_OK;
}

static int rp_open(df_hid_backend *bb, const char *path, df_hid_dev **out, df_error *err)
{
    rp_backend *b = (rp_backend *)bb;
    if (!b || !path || !out) return df_error_set(err, DF_EINVAL, "hid replay: open: NULL argument");
    if (strncmp(path, "replay:", 7) != 0)
        return df_error_set(err, DF_EINVAL, "hid replay: open: '%s' is not a replay path "
                            "(replay:FILE#n)", path);
    rp_dev *d = calloc(1, sizeof *d);
    if (!d) return df_error_set(err, DF_ENOMEM, "hid replay: open: out of memory");
    int rc = DF_OK;
    rp_slot *s = NULL;
    pthread_mutex_lock(&b->mu);
    for (size_t i = 0; i < b->n_slots && !s; i++)
        if (strcmp(b->slots[i].info.path, path) == 0) s = &b->slots[i];
    if (!s)
        rc = df_error_set(err, DF_ENOTFOUND, "hid replay: open: no device '%s'", path);
    else if (s->gone)
        rc = df_error_set(err, DF_ENOTFOUND, "hid replay: open: '%s' is unplugged (its replay "
                          "ended)", path);
    else if (s->open)
        rc = df_error_set(err, DF_EIO, "hid replay: open: '%s' is already open", path);
    else
        s->open = 1;
    pthread_mutex_unlock(&b->mu);
    if (rc != DF_OK) { free(d); return rc; }
    d->b = b;
    d->s = s;
    d->t0 = b->opts.now_us(b->opts.clock_ctx);
    *out = (df_hid_dev *)d;
    return DF_OK;
}

static uint64_t scaled(const rp_backend *b, uint64_t rel)
{
    return b->opts.speed == 1.0 ? rel : (uint64_t)((double)rel / b->opts.speed);
}

static int rp_read(df_hid_dev *dd, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                   df_error *err)
{
    rp_dev *d = (rp_dev *)dd;
    if (!d || !buf || !time_us || cap == 0 || timeout_ms < 0)
        return df_error_set(err, DF_EINVAL, "hid replay: read: NULL buffer, cap 0 or timeout < 0");
    rp_backend *b = d->b;
    const rp_slot *s = d->s;
    const rp_file *f = &b->files[s->file];
    if (d->gone)
        return df_error_set(err, DF_ENOTFOUND, "unplugged: end of the recording");
    uint64_t timeout_us = (uint64_t)timeout_ms * 1000u;
    int at_end = b->opts.at_end;
    for (;;) {
        int event = d->next < s->n_ev;
        if (!event && (at_end == DF_HID_REPLAY_END_HOLD || (at_end == DF_HID_REPLAY_END_LOOP
                                                            && s->n_ev == 0))) {
            if (timeout_us) b->opts.sleep_us(b->opts.clock_ctx, timeout_us);
            return 0;
        }
        const df_hid_rec_event *ev = event ? &f->rec.events[s->ev[d->next]] : NULL;
        uint64_t rel = (event ? ev->time_us : f->end_us) + d->loop_off;
        if (!b->opts.no_wait) {
            uint64_t due = d->t0 + scaled(b, rel), now = b->opts.now_us(b->opts.clock_ctx);
            if (now < due) {
                if (due - now > timeout_us) {
                    if (timeout_us) b->opts.sleep_us(b->opts.clock_ctx, timeout_us);
                    return 0;
                }
                b->opts.sleep_us(b->opts.clock_ctx, due - now);
            }
        }
        if (event) {
            size_t len = ev->len < cap ? ev->len : cap;
            memcpy(buf, df_hid_rec_event_bytes(&f->rec, ev), len);
            d->next++;
            pthread_mutex_lock(&b->mu);
            d->last_us = rel;
            pthread_mutex_unlock(&b->mu);
            *time_us = rel;
            return (int)len;
        }
        if (at_end == DF_HID_REPLAY_END_LOOP) {
            d->loop_off += f->end_us + RP_LOOP_GAP_US;
            d->next = 0;
            continue;
        }
        pthread_mutex_lock(&b->mu);
        d->gone = 1;
        d->s->gone = 1;
        pthread_mutex_unlock(&b->mu);
        return df_error_set(err, DF_ENOTFOUND, "unplugged: end of the recording");
    }
}

/* Appends one capture; under no lock on entry. */
static int capture(rp_dev *d, const df_hid_replay_output *o, const uint8_t *data, df_error *err)
{
    rp_backend *b = d->b;
    uint8_t *copy = NULL;
    if (data) {
        copy = malloc(o->len);
        if (!copy) return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
        memcpy(copy, data, o->len);
    }
    int rc = DF_OK;
    pthread_mutex_lock(&b->mu);
    if (d->gone) {
        rc = df_error_set(err, DF_ENOTFOUND, "hid replay: %s: unplugged", d->s->info.path);
    } else if (b->n_outs == b->cap_outs) {
        size_t nc = b->cap_outs ? b->cap_outs * 2 : 64;
        df_hid_replay_output *no = realloc(b->outs, nc * sizeof *no);
        if (!no) rc = df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
        else { b->outs = no; b->cap_outs = nc; }
    }
    if (rc == DF_OK) {
        df_hid_replay_output *dst = &b->outs[b->n_outs];
        *dst = *o;
        memcpy(dst->path, d->s->info.path, sizeof dst->path);
        dst->seq = b->n_outs++;
        dst->time_us = d->last_us;
        dst->data = copy;
        copy = NULL;
    }
    pthread_mutex_unlock(&b->mu);
    free(copy);
    return rc;
}

static int rp_write_output(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    rp_dev *d = (rp_dev *)dd;
    if (!d || !data || len == 0 || len > DF_HID_READ_MAX)
        return df_error_set(err, DF_EINVAL, "hid replay: write_output: NULL data or length %zu not "
                            "in 1..%d", len, DF_HID_READ_MAX);
    if (d->s->info.raw_powermate)
        return df_error_set(err, DF_EUNSUPPORTED, "hid replay: %s: a PowerMate takes no output "
                            "reports (its LED is a control transfer)", d->s->info.path);
    df_hid_replay_output o = { .is_control = 0, .len = len };
    return capture(d, &o, data, err);
}

static int rp_control(df_hid_dev *dd, uint8_t request_type, uint8_t request, uint16_t value,
                      uint16_t index, df_error *err)
{
    rp_dev *d = (rp_dev *)dd;
    if (!d) return df_error_set(err, DF_EINVAL, "hid replay: control: NULL device");
    if (!d->s->info.raw_powermate)
        return df_error_set(err, DF_EUNSUPPORTED, "hid replay: %s: a hidraw device takes no USB "
                            "control transfers", d->s->info.path);
    df_hid_replay_output o = { .is_control = 1, .request_type = request_type, .request = request,
                               .value = value, .index = index };
    return capture(d, &o, NULL, err);
}

/* Feature reports sent are captured like output reports (is_feature 1). */
static int rp_send_feature(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    rp_dev *d = (rp_dev *)dd;
    if (!d || !data || len == 0 || len > DF_HID_READ_MAX)
        return df_error_set(err, DF_EINVAL, "hid replay: send_feature: NULL data or length %zu "
                            "not in 1..%d", len, DF_HID_READ_MAX);
    if (d->s->info.raw_powermate)
        return df_error_set(err, DF_EUNSUPPORTED, "hid replay: %s: a PowerMate has no feature "
                            "reports", d->s->info.path);
    df_hid_replay_output o = { .is_feature = 1, .len = len };
    return capture(d, &o, data, err);
}

/* A recording holds no device answers: nothing to read. */
static int rp_get_feature(df_hid_dev *dd, uint8_t *buf, size_t cap, df_error *err)
{
    (void)buf; (void)cap;
    rp_dev *d = (rp_dev *)dd;
    return df_error_set(err, DF_EUNSUPPORTED, "hid replay: %s: a recording answers no feature "
                        "report requests", d ? d->s->info.path : "(null)");
}

static void rp_close(df_hid_dev *dd)
{
    rp_dev *d = (rp_dev *)dd;
    if (!d) return;
    pthread_mutex_lock(&d->b->mu);
    d->s->open = 0;
    pthread_mutex_unlock(&d->b->mu);
    free(d);
}

static void rp_destroy(df_hid_backend *bb)
{
    rp_backend *b = (rp_backend *)bb;
    if (!b) return;
    for (size_t i = 0; i < b->n_slots; i++) free(b->slots[i].ev);
    free(b->slots);
    for (size_t i = 0; i < b->n_files; i++) {
        free(b->files[i].path);
        df_hid_recording_free(&b->files[i].rec);
    }
    free(b->files);
    df_hid_replay_outputs_free(b->outs, b->n_outs);
    pthread_mutex_destroy(&b->mu);
    free(b);
}

int df_hid_backend_replay(const char *const *files, size_t n, const df_hid_replay_opts *opts,
                          df_hid_backend **out, df_error *err)
{
    if (!files || n == 0 || !out)
        return df_error_set(err, DF_EINVAL, "hid replay: no file given");
    df_hid_replay_opts o = opts ? *opts : (df_hid_replay_opts){ 0 };
    if (!(o.speed >= 0.0) || o.speed > 1e6)
        return df_error_set(err, DF_EINVAL, "hid replay: speed %g not in (0, 1e6]", o.speed);
    if (o.speed == 0.0) o.speed = 1.0;
    if (o.at_end < DF_HID_REPLAY_END_UNPLUG || o.at_end > DF_HID_REPLAY_END_HOLD)
        return df_error_set(err, DF_EINVAL, "hid replay: at_end %d unknown", o.at_end);
    if (!o.now_us != !o.sleep_us)
        return df_error_set(err, DF_EINVAL, "hid replay: now_us and sleep_us go together");
    if (!o.now_us) { o.now_us = mono_now_us; o.sleep_us = mono_sleep_us; o.clock_ctx = NULL; }
    for (size_t i = 0; i < n; i++)
        if (!files[i] || !files[i][0])
            return df_error_set(err, DF_EINVAL, "hid replay: file %zu: empty name", i);
    rp_backend *b = calloc(1, sizeof *b);
    if (!b) return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
    if (pthread_mutex_init(&b->mu, NULL) != 0) {
        free(b);
        return df_error_set(err, DF_EINTERNAL, "hid replay: pthread_mutex_init failed");
    }
    b->opts = o;
    b->base = (df_hid_backend){
        .kind = DF_HID_BACKEND_REPLAY, .name = "replay", .enumerate = rp_enumerate,
        .open = rp_open, .read = rp_read, .write_output = rp_write_output, .control = rp_control,
        .close = rp_close, .watch = NULL, .destroy = rp_destroy,
        .send_feature = rp_send_feature, .get_feature = rp_get_feature };
    b->files = calloc(n, sizeof *b->files);
    if (!b->files) {
        rp_destroy(&b->base);
        return df_error_set(err, DF_ENOMEM, "hid replay: out of memory");
    }
    b->n_files = n;
    for (size_t i = 0; i < n; i++) {
        int rc = load_file(b, i, files[i], err);
        if (rc) { rp_destroy(&b->base); return rc; }
    }
    *out = &b->base;
    return DF_OK;
}

int df_hid_replay_outputs(df_hid_backend *bb, size_t from, df_hid_replay_output **out, size_t *n,
                          df_error *err)
{
    if (!bb || !out || !n || bb->kind != DF_HID_BACKEND_REPLAY || bb->destroy != rp_destroy)
        return df_error_set(err, DF_EINVAL, "hid replay outputs: not a replay backend or NULL");
    rp_backend *b = (rp_backend *)bb;
    int rc = DF_OK;
    df_hid_replay_output *list = NULL;
    size_t k = 0;
    pthread_mutex_lock(&b->mu);
    if (from < b->n_outs) {
        list = calloc(b->n_outs - from, sizeof *list);
        if (!list) rc = df_error_set(err, DF_ENOMEM, "hid replay outputs: out of memory");
        for (size_t i = from; rc == DF_OK && i < b->n_outs; i++, k++) {
            list[k] = b->outs[i];
            if (b->outs[i].data) {
                list[k].data = malloc(b->outs[i].len);
                if (!list[k].data) {
                    rc = df_error_set(err, DF_ENOMEM, "hid replay outputs: out of memory");
                    break;
                }
                memcpy(list[k].data, b->outs[i].data, b->outs[i].len);
            }
        }
    }
    pthread_mutex_unlock(&b->mu);
    if (rc != DF_OK) { df_hid_replay_outputs_free(list, k); return rc; }
    *out = list;
    *n = k;
    return DF_OK;
}

int df_hid_replay_start_us(const df_hid_backend *b, const df_hid_dev *d, uint64_t *t0_us,
                           df_error *err)
{
    if (!b || !d || !t0_us || b->kind != DF_HID_BACKEND_REPLAY || b->destroy != rp_destroy)
        return df_error_set(err, DF_EINVAL, "hid replay start: not a replay device or NULL");
    *t0_us = ((const rp_dev *)d)->t0;
    return DF_OK;
}

void df_hid_replay_outputs_free(df_hid_replay_output *list, size_t n)
{
    if (!list) return;
    for (size_t i = 0; i < n; i++) free(list[i].data);
    free(list);
}

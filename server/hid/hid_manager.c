/* hid_manager.c — HID device registry, discovery, reader threads, start and shutdown (see
 * hid_manager.h). The actions of a report are applied in hid_mgr_drive.c; listing, binding and
 * stats are in hid_mgr_query.c. */
#include "server/hid/hid_manager.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/exec/pool.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/session.h"

/* A message from a reader thread (or the libusb hotplug thread) to the loop. */
enum { MSG_REPORT = 0, MSG_GONE = 1, MSG_RESCAN = 2 };
typedef struct hid_msg {
    df_task task;                /* first: the pool hands it back to after() */
    df_hid_manager *mgr;
    df_hid_device *d;            /* NULL for MSG_RESCAN */
    int kind;
    int code;                    /* MSG_GONE: DF_EIO or DF_ENOTFOUND */
    char err[DF_ERROR_MSG_MAX];
    uint64_t time_us;
    size_t len;
    uint8_t data[];
} hid_msg;

static void close_device(df_hid_device *d, int state, const char *why);
static void rescan(df_hid_manager *m);

/* ---------------------------------------------------------------------------------- posting */
/* The loop handled d's posted report: a lock-step reader may read the next. */
static void ack(df_hid_device *d)
{
    pthread_mutex_lock(&d->mu);
    d->unacked = 0;
    pthread_cond_signal(&d->cv);
    pthread_mutex_unlock(&d->mu);
}

static void on_msg(df_task *t)
{
    hid_msg *msg = (hid_msg *)t;
    df_hid_manager *m = msg->mgr;
    atomic_fetch_sub(&m->posted, 1);
    if (!m->stopping) {
        if (msg->kind == MSG_REPORT && msg->d->state == DF_DEVSTATE_OPEN) {
            m->events++;
            msg->d->events++;
            df_hid_drive_report(msg->d, msg->data, msg->len, msg->time_us);
        } else if (msg->kind == MSG_GONE && msg->d->state == DF_DEVSTATE_OPEN) {
            int st = msg->code == DF_ENOTFOUND ? DF_DEVSTATE_UNPLUGGED : DF_DEVSTATE_ERROR;
            close_device(msg->d, st, msg->err);
        } else if (msg->kind == MSG_RESCAN) {
            rescan(m);
        }
    }
    if (msg->kind == MSG_REPORT && msg->d->lockstep) ack(msg->d);
    free(msg);
}

static void post(df_hid_manager *m, hid_msg *msg)
{
    msg->mgr = m;
    msg->task.after = on_msg;
    atomic_fetch_add(&m->posted, 1);
    df_pool_post(m->srv->pool, &msg->task);
}

/* ----------------------------------------------------------------------------- reader thread */
static void *reader_main(void *arg)
{
    df_hid_device *d = arg;
    df_hid_backend *b = d->mgr->be[d->be];
    uint8_t *buf = malloc(DF_HID_READ_MAX);
    df_error err = {0, ""};
    int rc = buf ? 0 : DF_ENOMEM;
    if (!buf) df_error_set(&err, DF_EIO, "%s: out of memory", d->info.path);
    while (buf && !atomic_load(&d->stop)) {
        uint64_t t = 0;
        rc = b->read(d->dev, buf, DF_HID_READ_MAX, DF_HID_READ_TIMEOUT_MS, &t, &err);
        if (rc == 0) continue;
        if (rc < 0) break;
        hid_msg *msg = malloc(sizeof *msg + (size_t)rc);
        if (!msg) continue; /* dropped: the next report carries absolute values again */
        memset(msg, 0, sizeof *msg);
        msg->d = d;
        msg->kind = MSG_REPORT;
        msg->time_us = t;
        msg->len = (size_t)rc;
        memcpy(msg->data, buf, (size_t)rc);
        if (d->lockstep) {
            pthread_mutex_lock(&d->mu);
            d->unacked = 1;
            pthread_mutex_unlock(&d->mu);
        }
        post(d->mgr, msg);
        if (d->lockstep) {
            pthread_mutex_lock(&d->mu);
            while (d->unacked && !atomic_load(&d->stop)) pthread_cond_wait(&d->cv, &d->mu);
            pthread_mutex_unlock(&d->mu);
        }
    }
    free(buf);
    if (rc < 0 && !atomic_load(&d->stop)) {
        hid_msg *msg = calloc(1, sizeof *msg);
        if (msg) {
            msg->d = d;
            msg->kind = MSG_GONE;
            msg->code = rc == DF_ENOTFOUND ? DF_ENOTFOUND : DF_EIO;
            snprintf(msg->err, sizeof msg->err, "%s", err.msg[0] ? err.msg : "read failed");
            post(d->mgr, msg);
        }
    }
    return NULL;
}

/* ------------------------------------------------------------------------------- registry */
df_hid_device *df_hid_find(df_hid_manager *m, uint64_t id)
{
    for (df_hid_device *d = m->devs; d; d = d->next)
        if (d->id == id) return d;
    return NULL;
}

static df_hid_device *find_path(df_hid_manager *m, int be, const char *path)
{
    for (df_hid_device *d = m->devs; d; d = d->next)
        if (d->be == be && strcmp(d->info.path, path) == 0) return d;
    return NULL;
}

void df_hid_device_info(const df_hid_device *d, df_msg_device_info *out)
{
    memset(out, 0, sizeof *out);
    out->device_id = d->id;
    out->dev_class = (uint8_t)d->cls.cls;
    out->backend = (uint8_t)d->info.backend;
    out->state = (uint8_t)d->state;
    out->bus = d->info.bus;
    out->vid = d->info.vid;
    out->pid = d->info.pid;
    out->bound_session = d->bound;
    out->active_session = d->state == DF_DEVSTATE_OPEN ? d->active : 0;
    out->haptics = d->mapper_ok && d->map.hap.present && d->map.p.haptics ? 1 : 0;
    snprintf(out->name, sizeof out->name, "%s", d->info.name);
    snprintf(out->path, sizeof out->path, "%s", d->info.path);
    snprintf(out->error, sizeof out->error, "%s", d->error);
}

void df_hid_device_announce(df_hid_device *d, uint64_t session_id)
{
    df_session *s = session_id ? df_session_find(d->mgr->srv, session_id) : NULL;
    if (!s && !session_id) s = df_hid_drive_session(d); /* the session it would drive */
    if (!s) return;
    df_msg_device_info *info = malloc(sizeof *info);
    if (!info) return;
    df_hid_device_info(d, info);
    df_error err;
    df_sbuf *f = df_out_device_info(DF_MSG_DEVICE_STATE, DF_FLAG_EVENT, 0, info, &err);
    if (f) {
        df_session_broadcast(s, f);
        df_sbuf_unref(f);
    } else {
        df_log(DF_LOG_ERROR, "hid: device_state event of %s: %s", d->info.path, err.msg);
    }
    free(info);
}

/* Parses the descriptor, classifies the device and prepares its mapper. */
static void classify(df_hid_device *d)
{
    df_error err = {0, ""};
    if (d->info.desc && d->info.desc_len) {
        if (df_hid_desc_parse(d->info.desc, d->info.desc_len, &d->desc, &err) == DF_OK)
            d->have_desc = 1;
        else
            df_log(DF_LOG_WARN, "hid: %s (%s): report descriptor refused: %s", d->info.path,
                   d->info.name, err.msg);
    }
    df_hid_classify(d->have_desc ? &d->desc : NULL, d->info.vid, d->info.pid, &d->cls);
    if (d->cls.cls == DF_HID_CLASS_NONE) return;
    if (df_hid_mapper_init(&d->map, &d->cls, d->have_desc ? &d->desc : NULL,
                           &d->mgr->srv->cfg.hid, &err) == DF_OK)
        d->mapper_ok = 1;
    else
        df_log(DF_LOG_WARN, "hid: %s (%s): no mapping: %s", d->info.path, d->info.name, err.msg);
}

static df_hid_device *add_device(df_hid_manager *m, int be, const df_hid_devinfo *info)
{
    if (m->ndev >= DF_MAX_DEVICES) {
        df_log(DF_LOG_WARN, "hid: more than %u devices, %s ignored", DF_MAX_DEVICES, info->path);
        return NULL;
    }
    df_hid_device *d = calloc(1, sizeof *d);
    df_error err;
    if (!d || df_hid_devinfo_copy(&d->info, info, &err) != DF_OK) {
        free(d);
        df_log(DF_LOG_ERROR, "hid: out of memory adding %s", info->path);
        return NULL;
    }
    d->mgr = m;
    d->be = be;
    d->id = DF_HID_ID_BIT | ++m->next_n;
    d->state = DF_DEVSTATE_CLOSED;
    atomic_init(&d->stop, 0);
    d->lockstep = be == DF_HID_BE_REPLAY;
    pthread_mutex_init(&d->mu, NULL);
    pthread_cond_init(&d->cv, NULL);
    classify(d);
    df_hid_device **pp = &m->devs; /* ids grow: append */
    while (*pp) pp = &(*pp)->next;
    *pp = d;
    m->ndev++;
    df_log(DF_LOG_INFO, "hid: device %llu: %s %04x:%04x \"%s\" (%s, %s): %s",
           (unsigned long long)(d->id & ~DF_HID_ID_BIT), df_hid_class_name(d->cls.cls),
           info->vid, info->pid, info->name, info->path, m->be[be]->name, d->cls.reason);
    return d;
}

/* Opens d and starts its reader thread (classified devices only: the others are listed). */
static void open_device(df_hid_device *d)
{
    if (d->state == DF_DEVSTATE_OPEN || !d->mapper_ok) return;
    df_hid_backend *b = d->mgr->be[d->be];
    df_error err = {0, ""};
    int rc = b->open(b, d->info.path, &d->dev, &err);
    if (rc != DF_OK) {
        d->dev = NULL;
        d->state = DF_DEVSTATE_ERROR;
        snprintf(d->error, sizeof d->error, "%s", err.msg);
        if (!d->logged_error++)
            df_log(DF_LOG_WARN, "hid: cannot open %s: %s", d->info.path, err.msg);
        return;
    }
    atomic_store(&d->stop, 0);
    d->unacked = 0;
    d->state = DF_DEVSTATE_OPEN;
    d->error[0] = '\0';
    d->logged_error = 0;
    int e = pthread_create(&d->th, NULL, reader_main, d);
    if (e != 0) {
        b->close(d->dev);
        d->dev = NULL;
        d->state = DF_DEVSTATE_ERROR;
        snprintf(d->error, sizeof d->error, "cannot start a reader thread: %s", strerror(e));
        df_log(DF_LOG_ERROR, "hid: %s: %s", d->info.path, d->error);
        return;
    }
    d->th_running = 1;
    df_log(DF_LOG_INFO, "hid: opened %s (%s)", d->info.path, df_hid_class_name(d->cls.cls));
    df_hid_device_announce(d, d->active ? d->active : d->bound);
}

/* Stops the reader (joined), ends the stroke, closes the handle, reports the new state. */
static void close_device(df_hid_device *d, int state, const char *why)
{
    df_hid_manager *m = d->mgr;
    if (d->th_running) {
        pthread_mutex_lock(&d->mu);
        atomic_store(&d->stop, 1);
        pthread_cond_signal(&d->cv);
        pthread_mutex_unlock(&d->mu);
        pthread_join(d->th, NULL);
        d->th_running = 0;
    }
    int was_open = d->state == DF_DEVSTATE_OPEN;
    uint64_t drove = d->active;
    if (was_open && !m->stopping) df_hid_drive_unplug(d);
    if (d->dev) m->be[d->be]->close(d->dev);
    d->dev = NULL;
    d->state = state;
    snprintf(d->error, sizeof d->error, "%s", why ? why : "");
    if (!was_open) return;
    df_log(state == DF_DEVSTATE_ERROR ? DF_LOG_WARN : DF_LOG_INFO, "hid: %s %s%s%s",
           d->info.path, state == DF_DEVSTATE_UNPLUGGED ? "unplugged"
                         : state == DF_DEVSTATE_ERROR ? "failed" : "closed",
           why && why[0] ? ": " : "", why ? why : "");
    if (!m->stopping) df_hid_device_announce(d, drove ? drove : d->bound);
    d->active = 0;
}

/* Enumerates backend be; new devices are added, known ones that came back are reopened, open
 * ones that vanished are closed as unplugged. Replay devices open only once replay started. */
static void scan_backend(df_hid_manager *m, int be)
{
    df_hid_backend *b = m->be[be];
    if (!b) return;
    df_hid_devinfo *list = NULL;
    size_t n = 0;
    df_error err;
    if (b->enumerate(b, &list, &n, &err) != DF_OK) {
        df_log(DF_LOG_WARN, "hid: %s enumeration failed: %s", b->name, err.msg);
        return;
    }
    for (df_hid_device *d = m->devs; d; d = d->next)
        if (d->be == be) d->present = 0;
    for (size_t i = 0; i < n; i++) {
        df_hid_device *d = find_path(m, be, list[i].path);
        if (!d) d = add_device(m, be, &list[i]);
        if (!d) continue;
        d->present = 1;
        int may_open = be != DF_HID_BE_REPLAY || m->replay_started;
        /* a replay device is opened once: after its end it stays unplugged */
        if (be == DF_HID_BE_REPLAY && d->state != DF_DEVSTATE_CLOSED) may_open = 0;
        if (may_open && d->state != DF_DEVSTATE_OPEN && d->logged_error < 2) open_device(d);
    }
    for (df_hid_device *d = m->devs; d; d = d->next)
        if (d->be == be && !d->present && d->state == DF_DEVSTATE_OPEN && be != DF_HID_BE_REPLAY)
            close_device(d, DF_DEVSTATE_UNPLUGGED, "no longer present");
    df_hid_devinfo_free_list(list, n);
}

static void rescan(df_hid_manager *m)
{
    for (int be = 0; be < DF_HID_BE_COUNT; be++)
        if (be != DF_HID_BE_REPLAY) scan_backend(m, be);
}

static void on_enum_timer(uv_timer_t *t)
{
    df_hid_manager *m = t->data;
    if (!m->stopping) rescan(m);
}

/* libusb's event thread: a device arrived or left; enumerate on the loop thread. */
static void on_hotplug(void *user)
{
    df_hid_manager *m = user;
    hid_msg *msg = calloc(1, sizeof *msg);
    if (!msg) return;
    msg->kind = MSG_RESCAN;
    post(m, msg);
}

/* ---------------------------------------------------------------------------------- start */
static int start_backends(df_hid_manager *m, df_error *err)
{
    const df_server_config *cfg = &m->srv->cfg;
    df_error e;
    if (cfg->hid_on) {
        if (df_hid_backend_hidapi(&m->be[DF_HID_BE_HIDAPI], &e) != DF_OK) {
            m->be[DF_HID_BE_HIDAPI] = NULL;
            df_log(DF_LOG_WARN, "hid: hidapi backend unavailable: %s", e.msg);
        }
        if (df_hid_backend_libusb(&m->be[DF_HID_BE_LIBUSB], &e) != DF_OK) {
            m->be[DF_HID_BE_LIBUSB] = NULL;
            df_log(DF_LOG_WARN, "hid: libusb backend unavailable: %s", e.msg);
        }
    }
    if (cfg->n_hid_replay) {
        const char *files[DF_CONFIG_MAX_HID_REPLAY];
        for (int i = 0; i < cfg->n_hid_replay; i++) files[i] = cfg->hid_replay[i];
        df_hid_replay_opts o;
        memset(&o, 0, sizeof o);
        o.speed = cfg->hid_replay_speed > 0 ? cfg->hid_replay_speed : 1;
        o.no_wait = cfg->hid_replay_speed == 0;
        o.at_end = DF_HID_REPLAY_END_UNPLUG;
        int rc = df_hid_backend_replay(files, (size_t)cfg->n_hid_replay, &o,
                                       &m->be[DF_HID_BE_REPLAY], err);
        if (rc != DF_OK) {
            m->be[DF_HID_BE_REPLAY] = NULL;
            return rc;
        }
    }
    return DF_OK;
}

static void destroy_backends(df_hid_manager *m)
{
    for (int i = 0; i < DF_HID_BE_COUNT; i++) {
        if (m->be[i] && m->be[i]->watch) m->be[i]->watch(m->be[i], NULL, NULL, NULL);
        df_hid_backend_destroy(m->be[i]);
        m->be[i] = NULL;
    }
}

/* The manager m with its backends runs: hotplug watches, the first enumeration, the timer. */
static void run(df_server *srv, df_hid_manager *m)
{
    srv->hid = m;
    df_error e;
    for (int be = 0; be < DF_HID_BE_COUNT; be++)
        if (be != DF_HID_BE_REPLAY && m->be[be] && m->be[be]->watch &&
            m->be[be]->watch(m->be[be], on_hotplug, m, &e) != DF_OK)
            df_log(DF_LOG_INFO, "hid: no %s hotplug (%s): enumerating every %d s",
                   m->be[be]->name, e.msg, srv->cfg.hid_enumerate_s);
    for (int be = 0; be < DF_HID_BE_COUNT; be++) scan_backend(m, be);
    uint32_t open = 0;
    for (df_hid_device *d = m->devs; d; d = d->next) open += d->state == DF_DEVSTATE_OPEN;
    if (m->ndev == 0)
        df_log(DF_LOG_INFO, "hid: no HID devices%s", srv->cfg.hid_on ? " (hidapi, libusb)" : "");
    else
        df_log(DF_LOG_INFO, "hid: %u device(s), %u open", m->ndev, open);
    if ((m->be[DF_HID_BE_HIDAPI] || m->be[DF_HID_BE_LIBUSB]) && srv->cfg.hid_enumerate_s > 0) {
        uv_timer_init(srv->loop, &m->enum_timer);
        m->enum_timer.data = m;
        uint64_t ms = (uint64_t)srv->cfg.hid_enumerate_s * 1000;
        uv_timer_start(&m->enum_timer, on_enum_timer, ms, ms);
        uv_unref((uv_handle_t *)&m->enum_timer);
        m->timer_on = 1;
    }
}

int df_hid_manager_start(df_server *srv, df_error *err)
{
    srv->hid = NULL;
    if (!srv->cfg.hid_on && srv->cfg.n_hid_replay == 0) return DF_OK;
    df_hid_manager *m = calloc(1, sizeof *m);
    if (!m) return df_error_set(err, DF_ENOMEM, "hid: out of memory");
    m->srv = srv;
    atomic_init(&m->posted, 0);
    int rc = start_backends(m, err);
    if (rc != DF_OK) {
        destroy_backends(m);
        free(m);
        return rc;
    }
    run(srv, m);
    return DF_OK;
}

int df_hid_manager_start_with(df_server *srv, df_hid_backend *live, df_hid_backend *usb,
                              df_hid_backend *replay, df_error *err)
{
    srv->hid = NULL;
    df_hid_manager *m = calloc(1, sizeof *m);
    if (!m) {
        df_hid_backend_destroy(live);
        df_hid_backend_destroy(usb);
        df_hid_backend_destroy(replay);
        return df_error_set(err, DF_ENOMEM, "hid: out of memory");
    }
    m->srv = srv;
    atomic_init(&m->posted, 0);
    m->be[DF_HID_BE_HIDAPI] = live;
    m->be[DF_HID_BE_LIBUSB] = usb;
    m->be[DF_HID_BE_REPLAY] = replay;
    run(srv, m);
    return DF_OK;
}

void df_hid_manager_session_active(df_server *srv, df_session *s)
{
    df_hid_manager *m = srv->hid;
    if (!m || m->stopping || !s || m->replay_started || !m->be[DF_HID_BE_REPLAY]) return;
    m->replay_started = 1;
    df_log(DF_LOG_INFO, "hid: session %llu is active: starting the replay devices",
           (unsigned long long)s->id);
    scan_backend(m, DF_HID_BE_REPLAY);
}

void df_hid_manager_session_gone(df_server *srv, df_session *s)
{
    df_hid_manager *m = srv->hid;
    if (!m || !s) return;
    df_hid_drive_pen_forget(m, s->id);
    for (df_hid_device *d = m->devs; d; d = d->next) {
        if (d->stroke && d->stroke_session == s->id) d->stroke = 0; /* gone with the session */
        if (d->bound == s->id) {
            d->bound = 0;
            d->have_view = 0;
        }
        if (d->active == s->id) d->active = 0;
        if (d->cursor_session == s->id) d->cursor_session = 0;
    }
}

void df_hid_manager_stop(df_server *srv)
{
    df_hid_manager *m = srv->hid;
    if (!m || m->stopping) return;
    m->stopping = 1;
    if (m->timer_on) {
        uv_timer_stop(&m->enum_timer);
        uv_close((uv_handle_t *)&m->enum_timer, NULL);
        m->timer_on = 0;
    }
    for (df_hid_device *d = m->devs; d; d = d->next) { /* every reader stops at once ... */
        pthread_mutex_lock(&d->mu);
        atomic_store(&d->stop, 1);
        pthread_cond_signal(&d->cv);
        pthread_mutex_unlock(&d->mu);
    }
    for (df_hid_device *d = m->devs; d; d = d->next) /* ... then each is joined and closed */
        if (d->state == DF_DEVSTATE_OPEN || d->th_running)
            close_device(d, DF_DEVSTATE_CLOSED, "daemon shutting down");
    destroy_backends(m);
}

int df_hid_manager_busy(const df_server *srv)
{
    return srv->hid && atomic_load(&srv->hid->posted) > 0;
}

void df_hid_manager_free(df_server *srv)
{
    df_hid_manager *m = srv->hid;
    if (!m) return;
    df_hid_manager_stop(srv);
    df_hid_drive_pen_forget(m, 0);
    while (m->devs) {
        df_hid_device *d = m->devs;
        m->devs = d->next;
        df_hid_desc_free(&d->desc);
        pthread_mutex_destroy(&d->mu);
        pthread_cond_destroy(&d->cv);
        free(d->info.desc);
        free(d);
    }
    free(m);
    srv->hid = NULL;
}

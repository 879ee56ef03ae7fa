/* hid_libusb.c — the libusb-1.0 backend of the device-source seam (hid_source.h): the Griffin
 * PowerMate 077d:0410, which Linux gives no hidraw node (usbhid ignores it; the `powermate`
 * input driver binds). Open detaches that kernel driver (auto-detach where libusb supports it,
 * else an explicit detach that close undoes), claims interface 0 and reads its 6-byte interrupt
 * IN packets; the LED is a vendor control transfer (`control`, DF_HID_POWERMATE_LED_*).
 *
 * Hotplug: watch() registers a libusb hotplug callback for 077d:0410 (arrived/left) when
 * libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG), and starts this backend's event thread, which
 * runs libusb_handle_events until watch(b, NULL, NULL) or destroy. libusb runs hotplug callbacks
 * in whichever thread handles events (the event thread, or a reader thread inside a synchronous
 * transfer), so the callback calls fn(user) under the backend mutex: once watch(NULL) returns,
 * fn is never called again. fn must be quick and must not call watch or destroy.
 * Without hotplug, the manager enumerates periodically (as for hidapi). libusb itself is
 * thread-safe: enumerate/open/control (loop thread) run alongside the reader threads. */
#include "server/hid/hid_source.h"

#include <limits.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <libusb-1.0/libusb.h>

#define LU_CONTROL_TIMEOUT_MS 1000
#define LU_MAX_PACKET 64          /* full-speed interrupt max packet size */

typedef struct lu_backend {
    df_hid_backend base;          /* first: the vtable the caller holds */
    libusb_context *ctx;
    pthread_mutex_t mu;           /* guards fn/user (held while fn runs) */
    df_hid_change_fn fn;
    void *user;
    int watching;                 /* loop thread only */
    libusb_hotplug_callback_handle hp;
    pthread_t thread;
    atomic_int stop;
} lu_backend;

typedef struct lu_dev {
    lu_backend *b;
    libusb_device_handle *h;
    int iface;
    uint8_t ep_in;
    int reattach;                 /* 1: we detached the kernel driver by hand */
    char path[DF_HID_PATH_MAX];
} lu_dev;

static int is_powermate(const struct libusb_device_descriptor *dd)
{
    return dd->idVendor == DF_HID_POWERMATE_VID && dd->idProduct == DF_HID_POWERMATE_PID;
}

static int lu_code(int r)
{
    return r == LIBUSB_ERROR_NO_DEVICE || r == LIBUSB_ERROR_NOT_FOUND ? DF_ENOTFOUND
         : r == LIBUSB_ERROR_NO_MEM ? DF_ENOMEM : DF_EIO;
}

static int lu_enumerate(df_hid_backend *bb, df_hid_devinfo **out, size_t *n, df_error *err)
{
    lu_backend *b = (lu_backend *)bb;
    if (!b || !out || !n) return df_error_set(err, DF_EINVAL, "libusb: enumerate: NULL argument");
    libusb_device **all;
    ssize_t cnt = libusb_get_device_list(b->ctx, &all);
    if (cnt < 0)
        return df_error_set(err, lu_code((int)cnt) == DF_ENOMEM ? DF_ENOMEM : DF_EIO,
                            "libusb: enumerate failed: %s", libusb_strerror((int)cnt));
    df_hid_devinfo *list = NULL;
    size_t k = 0;
    int rc = DF_OK;
    for (ssize_t i = 0; i < cnt && rc == DF_OK; i++) {
        struct libusb_device_descriptor dd;
        if (libusb_get_device_descriptor(all[i], &dd) != 0 || !is_powermate(&dd)) continue;
        df_hid_devinfo *nl = realloc(list, (k + 1) * sizeof *nl);
        if (!nl) { rc = df_error_set(err, DF_ENOMEM, "libusb: enumerate: out of memory"); break; }
        list = nl;
        df_hid_devinfo *d = &list[k++];
        memset(d, 0, sizeof *d);
        snprintf(d->path, sizeof d->path, "usb:%03u:%03u", libusb_get_bus_number(all[i]),
                 libusb_get_device_address(all[i]));
        snprintf(d->name, sizeof d->name, "Griffin PowerMate");
        d->vid = dd.idVendor;
        d->pid = dd.idProduct;
        d->bus = DF_HID_BUS_USB;
        d->backend = DF_HID_BACKEND_LIBUSB;
        d->raw_powermate = 1;
    }
    libusb_free_device_list(all, 1);
    if (rc != DF_OK) { df_hid_devinfo_free_list(list, k); return rc; }
    *out = list;
    *n = k;
    return DF_OK;
}

/* "usb:BUS:ADDR" (decimal) -> bus, addr; 0 on success. */
static int parse_path(const char *path, unsigned *bus, unsigned *addr)
{
    int used = -1;
    if (sscanf(path, "usb:%3u:%3u%n", bus, addr, &used) != 2 || used < 0 || path[used] != '\0')
        return -1;
    return *bus <= 255 && *addr <= 255 ? 0 : -1;
}

/* The first interrupt IN endpoint of interface 0, alt 0 of the active configuration. */
static int find_ep_in(libusb_device *dev, uint8_t *ep)
{
    struct libusb_config_descriptor *cfg;
    if (libusb_get_active_config_descriptor(dev, &cfg) != 0) return -1;
    int found = -1;
    if (cfg->bNumInterfaces > 0 && cfg->interface[0].num_altsetting > 0) {
        const struct libusb_interface_descriptor *alt = &cfg->interface[0].altsetting[0];
        for (int i = 0; i < alt->bNumEndpoints && found < 0; i++) {
            const struct libusb_endpoint_descriptor *e = &alt->endpoint[i];
            if ((e->bmAttributes & 3) == LIBUSB_TRANSFER_TYPE_INTERRUPT
                && (e->bEndpointAddress & LIBUSB_ENDPOINT_IN)) {
                *ep = e->bEndpointAddress;
                found = 0;
            }
        }
    }
    libusb_free_config_descriptor(cfg);
    return found;
}

static int lu_open(df_hid_backend *bb, const char *path, df_hid_dev **out, df_error *err)
{
    lu_backend *b = (lu_backend *)bb;
    unsigned bus, addr;
    if (!b || !path || !out) return df_error_set(err, DF_EINVAL, "libusb: open: NULL argument");
    if (parse_path(path, &bus, &addr) != 0)
        return df_error_set(err, DF_EINVAL, "libusb: open: '%s' is not a path usb:BUS:ADDR", path);
    libusb_device **all;
    ssize_t cnt = libusb_get_device_list(b->ctx, &all);
    if (cnt < 0)
        return df_error_set(err, DF_EIO, "libusb: open %s: device list: %s", path,
                            libusb_strerror((int)cnt));
    libusb_device *dev = NULL;
    for (ssize_t i = 0; i < cnt && !dev; i++) {
        struct libusb_device_descriptor dd;
        if (libusb_get_bus_number(all[i]) == bus && libusb_get_device_address(all[i]) == addr
            && libusb_get_device_descriptor(all[i], &dd) == 0 && is_powermate(&dd))
            dev = all[i];
    }
    int rc = DF_OK;
    lu_dev *d = NULL;
    uint8_t ep = 0;
    if (!dev)
        rc = df_error_set(err, DF_ENOTFOUND, "libusb: open %s: no PowerMate %04x:%04x there", path,
                          DF_HID_POWERMATE_VID, DF_HID_POWERMATE_PID);
    else if (find_ep_in(dev, &ep) != 0)
        rc = df_error_set(err, DF_EIO, "libusb: open %s: no interrupt IN endpoint on interface 0",
                          path);
    else if (!(d = calloc(1, sizeof *d)))
        rc = df_error_set(err, DF_ENOMEM, "libusb: open: out of memory");
    int r;
    if (rc == DF_OK && (r = libusb_open(dev, &d->h)) != 0)
        rc = df_error_set(err, lu_code(r), "libusb: open %s: %s%s", path, libusb_strerror(r),
                          r == LIBUSB_ERROR_ACCESS ? " (a udev rule must give this user the "
                          "device)" : "");
    libusb_free_device_list(all, 1);
    if (rc != DF_OK) { free(d); return rc; }
    d->b = b;
    d->ep_in = ep;
    d->iface = 0;
    snprintf(d->path, sizeof d->path, "%s", path);
    if (libusb_set_auto_detach_kernel_driver(d->h, 1) != 0
        && libusb_kernel_driver_active(d->h, d->iface) == 1) {
        if ((r = libusb_detach_kernel_driver(d->h, d->iface)) != 0) {
            libusb_close(d->h);
            free(d);
            return df_error_set(err, lu_code(r), "libusb: open %s: cannot detach the kernel driver: "
                                "%s", path, libusb_strerror(r));
        }
        d->reattach = 1;
    }
    if ((r = libusb_claim_interface(d->h, d->iface)) != 0) {
        if (d->reattach) libusb_attach_kernel_driver(d->h, d->iface);
        libusb_close(d->h);
        free(d);
        return df_error_set(err, lu_code(r), "libusb: open %s: cannot claim interface 0: %s%s", path,
                            libusb_strerror(r), r == LIBUSB_ERROR_BUSY ? " (another program has it)"
                            : "");
    }
    *out = (df_hid_dev *)d;
    return DF_OK;
}

static int lu_read(df_hid_dev *dd, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                   df_error *err)
{
    lu_dev *d = (lu_dev *)dd;
    if (!d || !buf || !time_us || cap == 0 || timeout_ms < 0)
        return df_error_set(err, DF_EINVAL, "libusb: read: NULL buffer, cap 0 or timeout < 0");
    int got = 0;
    /* a short caller buffer gets the packet truncated (the seam's rule), not LIBUSB_ERROR_OVERFLOW */
    uint8_t small[LU_MAX_PACKET];
    uint8_t *dst = cap < LU_MAX_PACKET ? small : buf;
    int len = cap < LU_MAX_PACKET ? LU_MAX_PACKET : cap > INT_MAX ? INT_MAX : (int)cap;
    /* libusb takes timeout 0 as "forever": a poll waits 1 ms */
    int r = libusb_interrupt_transfer(d->h, d->ep_in, dst, len, &got,
                                      timeout_ms > 0 ? (unsigned)timeout_ms : 1u);
    if ((r == 0 || r == LIBUSB_ERROR_TIMEOUT) && got > 0) {
        if (dst == small) {
            if ((size_t)got > cap) got = (int)cap;
            memcpy(buf, small, (size_t)got);
        }
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        *time_us = (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
        return got;
    }
    if (r == 0 || r == LIBUSB_ERROR_TIMEOUT) return 0;
    return df_error_set(err, lu_code(r), "libusb: read %s: %s", d->path,
                        r == LIBUSB_ERROR_NO_DEVICE ? "device unplugged" : libusb_strerror(r));
}

static int lu_write_output(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    (void)data; (void)len;
    lu_dev *d = (lu_dev *)dd;
    return df_error_set(err, DF_EUNSUPPORTED, "libusb: %s: a PowerMate takes no output reports "
                        "(its LED is a control transfer)", d ? d->path : "(null)");
}

static int lu_send_feature(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    (void)data; (void)len;
    lu_dev *d = (lu_dev *)dd;
    return df_error_set(err, DF_EUNSUPPORTED, "libusb: %s: a PowerMate has no feature reports",
                        d ? d->path : "(null)");
}

static int lu_get_feature(df_hid_dev *dd, uint8_t *buf, size_t cap, df_error *err)
{
    (void)buf; (void)cap;
    return lu_send_feature(dd, NULL, 0, err);
}

static int lu_control(df_hid_dev *dd, uint8_t request_type, uint8_t request, uint16_t value,
                      uint16_t index, df_error *err)
{
    lu_dev *d = (lu_dev *)dd;
    if (!d) return df_error_set(err, DF_EINVAL, "libusb: control: NULL device");
    if (request_type & LIBUSB_ENDPOINT_IN)
        return df_error_set(err, DF_EINVAL, "libusb: control %s: bmRequestType 0x%02x is "
                            "device-to-host; only host-to-device without data is sent", d->path,
                            request_type);
    int r = libusb_control_transfer(d->h, request_type, request, value, index, NULL, 0,
                                    LU_CONTROL_TIMEOUT_MS);
    if (r < 0)
        return df_error_set(err, lu_code(r), "libusb: control %s (0x%02x 0x%02x 0x%04x 0x%04x): %s",
                            d->path, request_type, request, value, index, libusb_strerror(r));
    return DF_OK;
}

static void lu_close(df_hid_dev *dd)
{
    lu_dev *d = (lu_dev *)dd;
    if (!d) return;
    libusb_release_interface(d->h, d->iface); /* auto-detach reattaches the driver here */
    if (d->reattach) libusb_attach_kernel_driver(d->h, d->iface);
    libusb_close(d->h);
    free(d);
}

static int hotplug_cb(libusb_context *ctx, libusb_device *dev, libusb_hotplug_event ev, void *user)
{
    (void)ctx; (void)dev; (void)ev;
    lu_backend *b = user;
    pthread_mutex_lock(&b->mu);
    if (b->fn) b->fn(b->user);
    pthread_mutex_unlock(&b->mu);
    return 0; /* stay registered */
}

static void *event_thread(void *arg)
{
    lu_backend *b = arg;
    while (!atomic_load(&b->stop)) {
        struct timeval tv = { 1, 0 }; /* watch(NULL) interrupts it at once */
        libusb_handle_events_timeout_completed(b->ctx, &tv, NULL);
    }
    return NULL;
}

static void unwatch(lu_backend *b)
{
    if (!b->watching) return;
    pthread_mutex_lock(&b->mu);
    b->fn = NULL;
    b->user = NULL;
    pthread_mutex_unlock(&b->mu);
    libusb_hotplug_deregister_callback(b->ctx, b->hp);
    atomic_store(&b->stop, 1);
    libusb_interrupt_event_handler(b->ctx);
    pthread_join(b->thread, NULL);
    b->watching = 0;
}

static int lu_watch(df_hid_backend *bb, df_hid_change_fn fn, void *user, df_error *err)
{
    lu_backend *b = (lu_backend *)bb;
    if (!b) return df_error_set(err, DF_EINVAL, "libusb: watch: NULL backend");
    if (!fn) { unwatch(b); return DF_OK; }
    if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG))
        return df_error_set(err, DF_EUNSUPPORTED, "libusb: this system has no USB hotplug "
                            "notification; enumerate periodically");
    pthread_mutex_lock(&b->mu);
    b->fn = fn;
    b->user = user;
    pthread_mutex_unlock(&b->mu);
    if (b->watching) return DF_OK;
    int r = libusb_hotplug_register_callback(
        b->ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, 0,
        DF_HID_POWERMATE_VID, DF_HID_POWERMATE_PID, LIBUSB_HOTPLUG_MATCH_ANY, hotplug_cb, b, &b->hp);
    if (r != LIBUSB_SUCCESS) {
        pthread_mutex_lock(&b->mu);
        b->fn = NULL;
        pthread_mutex_unlock(&b->mu);
        return df_error_set(err, DF_EINTERNAL, "libusb: hotplug registration failed: %s",
                            libusb_strerror(r));
    }
    atomic_store(&b->stop, 0);
    if (pthread_create(&b->thread, NULL, event_thread, b) != 0) {
        libusb_hotplug_deregister_callback(b->ctx, b->hp);
        pthread_mutex_lock(&b->mu);
        b->fn = NULL;
        pthread_mutex_unlock(&b->mu);
        return df_error_set(err, DF_EINTERNAL, "libusb: cannot start the hotplug event thread");
    }
    b->watching = 1;
    return DF_OK;
}

static void lu_destroy(df_hid_backend *bb)
{
    lu_backend *b = (lu_backend *)bb;
    if (!b) return;
    unwatch(b);
    libusb_exit(b->ctx);
    pthread_mutex_destroy(&b->mu);
    free(b);
}

int df_hid_backend_libusb(df_hid_backend **out, df_error *err)
{
    if (!out) return df_error_set(err, DF_EINVAL, "libusb: NULL out");
    lu_backend *b = calloc(1, sizeof *b);
    if (!b) return df_error_set(err, DF_ENOMEM, "libusb: out of memory");
    int r = libusb_init(&b->ctx);
    if (r != 0) {
        free(b);
        return df_error_set(err, DF_EINTERNAL, "libusb: libusb_init failed: %s", libusb_strerror(r));
    }
    if (pthread_mutex_init(&b->mu, NULL) != 0) {
        libusb_exit(b->ctx);
        free(b);
        return df_error_set(err, DF_EINTERNAL, "libusb: pthread_mutex_init failed");
    }
    atomic_init(&b->stop, 0);
    b->base = (df_hid_backend){
        .kind = DF_HID_BACKEND_LIBUSB, .name = "libusb", .enumerate = lu_enumerate,
        .open = lu_open, .read = lu_read, .write_output = lu_write_output, .control = lu_control,
        .close = lu_close, .watch = lu_watch, .destroy = lu_destroy,
        .send_feature = lu_send_feature, .get_feature = lu_get_feature };
    *out = &b->base;
    return DF_OK;
}

/* hid_hidapi.c — the hidraw backend of the device-source seam (hid_source.h), through hidapi
 * (hidapi-hidraw, 0.13 on Debian 12).
 *
 * Enumeration: hid_enumerate lists every hidraw node (0.13 lists one entry per top-level usage:
 * entries are merged by path); hidapi 0.13 has no hid_get_report_descriptor, so the descriptor is
 * read from /sys/class/hidraw/<node>/device/report_descriptor (NULL when unreadable). No hotplug
 * (watch is NULL): the manager enumerates periodically (config hid_enumerate_s).
 *
 * Threads: hid_init runs once per process (pthread_once) and hid_exit never (other backends or a
 * second instance may still use hidapi). hidapi handles are not thread-safe (each keeps an error
 * string that hid_read_timeout and hid_write both replace), so the reader thread alone uses the
 * hidapi handle (hid_read_timeout) and output reports go through a second descriptor of the same
 * node opened write-only: write(2) of the report is exactly what hid_write does on hidraw, and
 * feature reports are the HIDIOCSFEATURE / HIDIOCGFEATURE ioctls on that descriptor, exactly
 * what hid_send_feature_report / hid_get_feature_report do on hidraw.
 * hid_error(NULL) is process-global: enumerate/open run on one thread (the seam's rule). */
#include "server/hid/hid_source.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <linux/hidraw.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <time.h>
#include <unistd.h>
#include <wchar.h>

#include <hidapi/hidapi.h>

#define HA_MAX_DESC 4096 /* HID_MAX_DESCRIPTOR_SIZE of the kernel */

typedef struct ha_dev {
    hid_device *h;               /* reader thread only */
    int wfd;                     /* write-only fd for output reports */
    char path[DF_HID_PATH_MAX];
} ha_dev;

static pthread_once_t ha_once = PTHREAD_ONCE_INIT;
static int ha_init_rc = -1;

static void ha_init(void)
{
    ha_init_rc = hid_init();
}

/* UTF-8 of a hidapi wide string (NULL -> ""), truncated to fit. */
static void wide_to_utf8(const wchar_t *w, char *out, size_t cap)
{
    size_t k = 0;
    for (; w && *w; w++) {
        uint32_t c = (uint32_t)*w;
        char tmp[4];
        size_t n;
        if (c < 0x80) { tmp[0] = (char)c; n = 1; }
        else if (c < 0x800) { tmp[0] = (char)(0xc0 | c >> 6); tmp[1] = (char)(0x80 | (c & 0x3f)); n = 2; }
        else if (c < 0x10000) {
            tmp[0] = (char)(0xe0 | c >> 12); tmp[1] = (char)(0x80 | ((c >> 6) & 0x3f));
            tmp[2] = (char)(0x80 | (c & 0x3f)); n = 3;
        } else if (c < 0x110000) {
            tmp[0] = (char)(0xf0 | c >> 18); tmp[1] = (char)(0x80 | ((c >> 12) & 0x3f));
            tmp[2] = (char)(0x80 | ((c >> 6) & 0x3f)); tmp[3] = (char)(0x80 | (c & 0x3f)); n = 4;
        } else continue;
        if (k + n >= cap) break;
        memcpy(out + k, tmp, n);
        k += n;
    }
    out[k] = '\0';
}

static uint8_t linux_bus(hid_bus_type t)
{
    switch (t) {
    case HID_API_BUS_USB: return DF_HID_BUS_USB;
    case HID_API_BUS_BLUETOOTH: return DF_HID_BUS_BLUETOOTH;
    case HID_API_BUS_I2C: return DF_HID_BUS_I2C;
    case HID_API_BUS_SPI: return 0x1c; /* BUS_SPI */
    default: return 0;
    }
}

/* The report descriptor of hidraw node `path` from sysfs (malloc'd), or NULL (n = 0). */
static uint8_t *sysfs_descriptor(const char *path, size_t *n)
{
    *n = 0;
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (strncmp(base, "hidraw", 6) != 0) return NULL;
    char sys[DF_HID_PATH_MAX + 64];
    snprintf(sys, sizeof sys, "/sys/class/hidraw/%s/device/report_descriptor", base);
    FILE *f = fopen(sys, "rb");
    if (!f) return NULL;
    uint8_t *buf = malloc(HA_MAX_DESC);
    size_t got = buf ? fread(buf, 1, HA_MAX_DESC, f) : 0;
    fclose(f);
    if (got == 0) { free(buf); return NULL; }
    *n = got;
    return buf;
}

static int ha_enumerate(df_hid_backend *b, df_hid_devinfo **out, size_t *n, df_error *err)
{
    if (!b || !out || !n) return df_error_set(err, DF_EINVAL, "hidapi: enumerate: NULL argument");
    struct hid_device_info *all = hid_enumerate(0, 0);
    if (!all) {
        char msg[200];
        wide_to_utf8(hid_error(NULL), msg, sizeof msg);
        /* 0.13 says "No HID devices found in the system." for an empty list */
        if (msg[0] && !strstr(msg, "No HID devices"))
            return df_error_set(err, DF_EIO, "hidapi: enumerate failed: %s", msg);
        *out = NULL;
        *n = 0;
        return DF_OK;
    }
    size_t cap = 0;
    for (struct hid_device_info *i = all; i; i = i->next) cap++;
    df_hid_devinfo *list = calloc(cap, sizeof *list);
    if (!list) {
        hid_free_enumeration(all);
        return df_error_set(err, DF_ENOMEM, "hidapi: enumerate: out of memory");
    }
    size_t k = 0;
    for (struct hid_device_info *i = all; i; i = i->next) {
        if (!i->path || strlen(i->path) >= DF_HID_PATH_MAX) continue;
        int dup = 0;
        for (size_t j = 0; j < k && !dup; j++) dup = strcmp(list[j].path, i->path) == 0;
        if (dup) continue;
        df_hid_devinfo *d = &list[k++];
        snprintf(d->path, sizeof d->path, "%s", i->path);
        wide_to_utf8(i->product_string, d->name, sizeof d->name);
        d->vid = i->vendor_id;
        d->pid = i->product_id;
        d->bus = linux_bus(i->bus_type);
        d->backend = DF_HID_BACKEND_HIDAPI;
        d->desc = sysfs_descriptor(i->path, &d->desc_len);
    }
    hid_free_enumeration(all);
    if (k == 0) { free(list); list = NULL; }
    *out = list;
    *n = k;
    return DF_OK;
}

/* 1 when the character device st is a hidraw node (its sysfs subsystem is "hidraw"). hidapi 0.13
 * crashes (frees garbage) when hid_open_path is given another character device (/dev/null), so
 * nothing else reaches it. */
static int is_hidraw(const struct stat *st)
{
    char link[128], target[DF_HID_PATH_MAX];
    snprintf(link, sizeof link, "/sys/dev/char/%u:%u/subsystem", major(st->st_rdev),
             minor(st->st_rdev));
    ssize_t k = readlink(link, target, sizeof target - 1);
    if (k <= 0) return 0;
    target[k] = '\0';
    const char *base = strrchr(target, '/');
    return strcmp(base ? base + 1 : target, "hidraw") == 0;
}

static int ha_open(df_hid_backend *b, const char *path, df_hid_dev **out, df_error *err)
{
    if (!b || !path || !out || !path[0])
        return df_error_set(err, DF_EINVAL, "hidapi: open: NULL or empty path");
    if (strlen(path) >= DF_HID_PATH_MAX)
        return df_error_set(err, DF_EINVAL, "hidapi: open: path longer than %d bytes",
                            DF_HID_PATH_MAX - 1);
    struct stat st;
    if (stat(path, &st) != 0)
        return df_error_set(err, errno == ENOENT ? DF_ENOTFOUND : DF_EIO, "hidapi: open %s: %s",
                            path, strerror(errno));
    if (!S_ISCHR(st.st_mode) || !is_hidraw(&st))
        return df_error_set(err, DF_EINVAL, "hidapi: open %s: not a hidraw character device", path);
    ha_dev *d = calloc(1, sizeof *d);
    if (!d) return df_error_set(err, DF_ENOMEM, "hidapi: open: out of memory");
    snprintf(d->path, sizeof d->path, "%s", path);
    d->h = hid_open_path(path);
    if (!d->h) {
        int e = errno;
        char msg[200];
        wide_to_utf8(hid_error(NULL), msg, sizeof msg);
        free(d);
        return df_error_set(err, e == ENOENT || e == ENODEV ? DF_ENOTFOUND : DF_EIO,
                            "hidapi: open %s: %s", path, msg[0] ? msg : strerror(e));
    }
    d->wfd = open(path, O_WRONLY | O_CLOEXEC);
    if (d->wfd < 0) {
        int e = errno;
        hid_close(d->h);
        free(d);
        return df_error_set(err, e == ENOENT || e == ENODEV ? DF_ENOTFOUND : DF_EIO,
                            "hidapi: open %s for output reports: %s", path, strerror(e));
    }
    *out = (df_hid_dev *)d;
    return DF_OK;
}

static uint64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static int ha_read(df_hid_dev *dd, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                   df_error *err)
{
    ha_dev *d = (ha_dev *)dd;
    if (!d || !buf || !time_us || cap == 0 || timeout_ms < 0)
        return df_error_set(err, DF_EINVAL, "hidapi: read: NULL buffer, cap 0 or timeout < 0");
    int r = hid_read_timeout(d->h, buf, cap, timeout_ms);
    if (r > 0) {
        *time_us = mono_us();
        return r;
    }
    if (r == 0) return 0;
    int e = errno;
    char msg[200];
    wide_to_utf8(hid_error(d->h), msg, sizeof msg);
    struct stat st;
    int gone = strstr(msg, "disconnected") || e == ENODEV || stat(d->path, &st) != 0;
    return df_error_set(err, gone ? DF_ENOTFOUND : DF_EIO, "hidapi: read %s: %s", d->path,
                        gone ? "device unplugged" : (msg[0] ? msg : strerror(e)));
}

static int ha_write_output(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    ha_dev *d = (ha_dev *)dd;
    if (!d || !data || len == 0 || len > DF_HID_READ_MAX)
        return df_error_set(err, DF_EINVAL, "hidapi: write_output: NULL data or length %zu not in "
                            "1..%d", len, DF_HID_READ_MAX);
    ssize_t w;
    do w = write(d->wfd, data, len); while (w < 0 && errno == EINTR);
    if (w < 0)
        return df_error_set(err, errno == ENODEV || errno == ENOENT ? DF_ENOTFOUND : DF_EIO,
                            "hidapi: output report to %s: %s", d->path, strerror(errno));
    if ((size_t)w != len)
        return df_error_set(err, DF_EIO, "hidapi: output report to %s: %zd of %zu bytes written",
                            d->path, w, len);
    return DF_OK;
}

static int ha_control(df_hid_dev *dd, uint8_t request_type, uint8_t request, uint16_t value,
                      uint16_t index, df_error *err)
{
    (void)request_type; (void)request; (void)value; (void)index;
    ha_dev *d = (ha_dev *)dd;
    return df_error_set(err, DF_EUNSUPPORTED, "hidapi: %s: hidraw sends no USB control transfers",
                        d ? d->path : "(null)");
}

static int ha_send_feature(df_hid_dev *dd, const uint8_t *data, size_t len, df_error *err)
{
    ha_dev *d = (ha_dev *)dd;
    if (!d || !data || len == 0 || len > DF_HID_READ_MAX)
        return df_error_set(err, DF_EINVAL, "hidapi: send_feature: NULL data or length %zu not "
                            "in 1..%d", len, DF_HID_READ_MAX);
    int r;
    do r = ioctl(d->wfd, HIDIOCSFEATURE(len), data); while (r < 0 && errno == EINTR);
    if (r < 0)
        return df_error_set(err, errno == ENODEV || errno == ENOENT ? DF_ENOTFOUND : DF_EIO,
                            "hidapi: feature report %u to %s: %s", data[0], d->path,
                            strerror(errno));
    return DF_OK;
}

static int ha_get_feature(df_hid_dev *dd, uint8_t *buf, size_t cap, df_error *err)
{
    ha_dev *d = (ha_dev *)dd;
    if (!d || !buf || cap == 0 || cap > DF_HID_READ_MAX)
        return df_error_set(err, DF_EINVAL, "hidapi: get_feature: NULL buffer or cap %zu not in "
                            "1..%d", cap, DF_HID_READ_MAX);
    int r;
    do r = ioctl(d->wfd, HIDIOCGFEATURE(cap), buf); while (r < 0 && errno == EINTR);
    if (r < 0)
        return df_error_set(err, errno == ENODEV || errno == ENOENT ? DF_ENOTFOUND : DF_EIO,
                            "hidapi: feature report %u from %s: %s", buf[0], d->path,
                            strerror(errno));
    return r;
}

static void ha_close(df_hid_dev *dd)
{
    ha_dev *d = (ha_dev *)dd;
    if (!d) return;
    hid_close(d->h);
    close(d->wfd);
    free(d);
}

static void ha_destroy(df_hid_backend *b)
{
    free(b);
}

int df_hid_backend_hidapi(df_hid_backend **out, df_error *err)
{
    if (!out) return df_error_set(err, DF_EINVAL, "hidapi: NULL out");
    pthread_once(&ha_once, ha_init);
    if (ha_init_rc != 0)
        return df_error_set(err, DF_EINTERNAL, "hidapi: hid_init failed (%d)", ha_init_rc);
    df_hid_backend *b = calloc(1, sizeof *b);
    if (!b) return df_error_set(err, DF_ENOMEM, "hidapi: out of memory");
    *b = (df_hid_backend){
        .kind = DF_HID_BACKEND_HIDAPI, .name = "hidapi", .enumerate = ha_enumerate,
        .open = ha_open, .read = ha_read, .write_output = ha_write_output, .control = ha_control,
        .close = ha_close, .watch = NULL, .destroy = ha_destroy,
        .send_feature = ha_send_feature, .get_feature = ha_get_feature };
    *out = b;
    return DF_OK;
}

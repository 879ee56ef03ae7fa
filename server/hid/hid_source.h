/* hid_source.h — the device-source seam of the HID subsystem (issue 11, Devices).
 *
 * A backend lists the HID devices present now and opens them; an open device delivers input
 * reports (blocking read with a timeout) and accepts output reports and USB control transfers.
 * Three backends share this one interface, so everything above the seam (server/hid/hid_manager)
 * is one code path:
 *   df_hid_backend_hidapi()  hidraw nodes through hidapi (hidapi-hidraw),
 *   df_hid_backend_libusb()  the Griffin PowerMate 077d:0410 through libusb-1.0 (Linux gives it
 *                            no hidraw node), with USB hotplug,
 *   df_hid_backend_replay()  hid-recorder files and the PowerMate raw file, delivered at their
 *                            recorded timestamps; every output/control/feature report sent
 *                            is captured.
 *
 * Threads: a backend's enumerate/open/watch/destroy are called from one thread at a time (the
 * manager's loop thread). Each open device is used by one reader thread (read) while the loop
 * thread may call write_output/control on it concurrently; close is called once no read is
 * running on the device (the reader thread has been joined). A backend outlives its devices:
 * close every device before destroy.
 *
 * Errors follow core/common/df_error.h: every vtable call that can fail returns DF_OK / a byte
 * count, or a negative DF_E* code and fills err (may be NULL) with a message naming the device. */
#ifndef DF_SERVER_HID_SOURCE_H
#define DF_SERVER_HID_SOURCE_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

/* Backend kinds = the wire values DF_DEVBACKEND_* of DEVICE_LIST. */
enum { DF_HID_BACKEND_HIDAPI = 1, DF_HID_BACKEND_LIBUSB = 2, DF_HID_BACKEND_REPLAY = 3 };

/* Bus values of linux/input.h. */
enum { DF_HID_BUS_USB = 0x03, DF_HID_BUS_BLUETOOTH = 0x05, DF_HID_BUS_I2C = 0x18 };

/* Griffin PowerMate: USB ids and its LED vendor control transfer (bmRequestType 0x41 = vendor,
 * host-to-device, interface; bRequest 0x01; wValue 0x01 = static brightness, wIndex = 0..255). */
#define DF_HID_POWERMATE_VID 0x077du
#define DF_HID_POWERMATE_PID 0x0410u
#define DF_HID_POWERMATE_REPORT_BYTES 6
#define DF_HID_POWERMATE_LED_REQTYPE 0x41u
#define DF_HID_POWERMATE_LED_REQUEST 0x01u
#define DF_HID_POWERMATE_LED_STATIC 0x01u

#define DF_HID_PATH_MAX 256
#define DF_HID_NAME_MAX 256
#define DF_HID_READ_MAX 8192 /* a read buffer this size holds any input report */

typedef struct df_hid_devinfo {
    char path[DF_HID_PATH_MAX];  /* backend path: "replay:FILE#n", "/dev/hidrawN", "usb:BUS:ADDR" */
    char name[DF_HID_NAME_MAX];  /* product name, "" when unknown */
    uint16_t vid, pid;
    uint8_t bus;                 /* DF_HID_BUS_* (linux/input.h values), 0 unknown */
    int backend;                 /* DF_HID_BACKEND_* */
    uint8_t *desc;               /* report descriptor (malloc'd), NULL for raw devices */
    size_t desc_len;
    int raw_powermate;           /* 1: PowerMate 6-byte interrupt packets, no descriptor */
} df_hid_devinfo;

typedef struct df_hid_dev df_hid_dev;          /* an open device of some backend */
typedef struct df_hid_backend df_hid_backend;  /* vtable + backend state */

/* Called by a backend's own thread (libusb's event thread, or a reader thread inside a libusb
 * transfer) when devices arrived or left; the callee should only note it (e.g. post to the loop)
 * and re-enumerate on its own thread. It must not call watch or destroy (it runs under the
 * backend's lock). */
typedef void (*df_hid_change_fn)(void *user);

struct df_hid_backend {
    int kind;                    /* DF_HID_BACKEND_* */
    const char *name;            /* "hidapi", "libusb", "replay" (static) */

    /* The devices present now. On DF_OK *out is a malloc'd array of *n entries (NULL when
     * *n == 0; no device is not an error), freed with df_hid_devinfo_free_list. Errors: DF_EIO
     * (the system listing failed), DF_ENOMEM. */
    int (*enumerate)(df_hid_backend *b, df_hid_devinfo **out, size_t *n, df_error *err);

    /* Opens the device at path (a devinfo path from enumerate). On DF_OK *out is the open device
     * (release with close). Errors: DF_ENOTFOUND (no such device now), DF_EIO (present but cannot
     * be opened: permissions, busy, kernel driver), DF_EINVAL (NULL / malformed path),
     * DF_ENOMEM. */
    int (*open)(df_hid_backend *b, const char *path, df_hid_dev **out, df_error *err);

    /* Blocks up to timeout_ms (>= 0; 0 polls) for one input report into buf[0..cap).
     * Returns > 0: the report's byte count (report-id byte first when the descriptor uses ids;
     * PowerMate: the 6 raw bytes), *time_us = the event's time in microseconds (replay: the
     * recorded time; live: CLOCK_MONOTONIC at read); 0: timeout, nothing read; < 0: DF_EIO
     * (device error), DF_ENOTFOUND (unplugged / end of a replay: the device is gone, close it),
     * DF_EINVAL (NULL buf/time_us, cap 0). A report longer than cap is truncated to cap. */
    int (*read)(df_hid_dev *d, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                df_error *err);

    /* Sends one output report of len bytes (report-id byte first when the descriptor uses ids,
     * else the report alone). DF_OK, or DF_EIO / DF_ENOTFOUND (gone) / DF_EINVAL (len 0) /
     * DF_EUNSUPPORTED (the device takes no output reports: PowerMate). */
    int (*write_output)(df_hid_dev *d, const uint8_t *data, size_t len, df_error *err);

    /* A USB control transfer without data stage (wLength 0), e.g. the PowerMate LED
     * (DF_HID_POWERMATE_LED_*). DF_OK, or DF_EIO / DF_ENOTFOUND / DF_EUNSUPPORTED (hidraw
     * devices: the backend cannot send one). */
    int (*control)(df_hid_dev *d, uint8_t request_type, uint8_t request, uint16_t value,
                   uint16_t index, df_error *err);

    /* Closes and frees d (NULL is fine). No read may be running on d. */
    void (*close)(df_hid_dev *d);

    /* Optional, may be NULL (no hotplug notification: the caller enumerates periodically).
     * Registers fn(user) to be called from the backend's own thread whenever devices arrive or
     * leave; fn NULL unregisters. DF_OK, or DF_EUNSUPPORTED (this system has no hotplug) /
     * DF_EINTERNAL. The callback is never running once watch(b, NULL, NULL) or destroy returns. */
    int (*watch)(df_hid_backend *b, df_hid_change_fn fn, void *user, df_error *err);

    /* Frees the backend (NULL-safe through df_hid_backend_destroy); every device closed. */
    void (*destroy)(df_hid_backend *b);

    /* Feature reports (PID force feedback: Create New Effect, Block Load). Optional: NULL means
     * DF_EUNSUPPORTED (df_hid_send_feature / df_hid_get_feature check it). Loop thread, like
     * write_output. send_feature: SET_REPORT(Feature) of data[0..len) (report-id byte first,
     * 0 when the descriptor uses no ids); DF_OK, or DF_EIO / DF_ENOTFOUND / DF_EINVAL (len 0)
     * / DF_EUNSUPPORTED. get_feature: GET_REPORT(Feature) with buf[0] = the report id on entry;
     * returns the byte count read into buf[0..cap) (report id first), or DF_EIO /
     * DF_ENOTFOUND / DF_EINVAL / DF_EUNSUPPORTED (the replay backend: no device to answer). */
    int (*send_feature)(df_hid_dev *d, const uint8_t *data, size_t len, df_error *err);
    int (*get_feature)(df_hid_dev *d, uint8_t *buf, size_t cap, df_error *err);
};

/* b->send_feature / b->get_feature, or DF_EUNSUPPORTED when the backend has none. */
int df_hid_send_feature(df_hid_backend *b, df_hid_dev *d, const uint8_t *data, size_t len,
                        df_error *err);
int df_hid_get_feature(df_hid_backend *b, df_hid_dev *d, uint8_t *buf, size_t cap,
                       df_error *err);

/* Frees a list from enumerate: each desc, then the array (NULL is fine). */
void df_hid_devinfo_free_list(df_hid_devinfo *list, size_t n);

/* Copies src into *dst (desc duplicated). DF_OK or DF_ENOMEM (dst untouched). */
int df_hid_devinfo_copy(df_hid_devinfo *dst, const df_hid_devinfo *src, df_error *err);

/* b->destroy(b) when b is not NULL. */
void df_hid_backend_destroy(df_hid_backend *b);

/* hidapi (hidraw) backend: every /dev/hidraw* node hidapi lists (the report descriptor read from
 * sysfs). Calls hid_init once per process. On DF_OK *out is the backend. Errors: DF_EINTERNAL
 * (hid_init failed), DF_ENOMEM. */
int df_hid_backend_hidapi(df_hid_backend **out, df_error *err);

/* libusb backend: USB devices 077d:0410 (PowerMate), paths "usb:BUS:ADDR". Owns a libusb
 * context; watch() uses libusb hotplug when libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG), with
 * its own event thread. Errors: DF_EINTERNAL (libusb_init failed), DF_ENOMEM. */
int df_hid_backend_libusb(df_hid_backend **out, df_error *err);

/* Replay backend options (zero-initialised = real time, speed 1, unplug at the end). */
typedef struct df_hid_replay_opts {
    double speed;        /* > 0: recorded gaps are divided by it; 0 means 1 */
    int no_wait;         /* 1: deliver every report at once (tests); timestamps still recorded */
    int at_end;          /* DF_HID_REPLAY_END_UNPLUG (default), _LOOP, _HOLD */
    /* Optional clock for tests (both or neither): now_us returns a monotonic time in us and
     * sleep_us waits (the fake advances its time). NULL: CLOCK_MONOTONIC and nanosleep. */
    uint64_t (*now_us)(void *ctx);
    void (*sleep_us)(void *ctx, uint64_t us);
    void *clock_ctx;
} df_hid_replay_opts;

enum {
    DF_HID_REPLAY_END_UNPLUG = 0, /* read returns DF_ENOTFOUND after the last report; the device
                                     then no longer enumerates */
    DF_HID_REPLAY_END_LOOP = 1,   /* starts again; times continue (+ span + 10 ms per pass) */
    DF_HID_REPLAY_END_HOLD = 2    /* stays open and silent: read times out */
};

/* Replay backend over n files (paths), each a hid-recorder file (one device per D: node that has
 * an R: descriptor; path "replay:FILE#n") or a PowerMate raw file (a file with E: lines and no
 * R: line: one raw_powermate device 077d:0410 named "Griffin PowerMate", path "replay:FILE#0").
 * read() delivers the device's E: reports in file order, each at open time + recorded time /
 * speed, with *time_us = the recorded time. opts NULL = defaults. Errors: DF_EINVAL (n == 0,
 * NULL, bad opts), DF_EIO (a file cannot be read), DF_EFORMAT / DF_ELIMIT (a file does not parse:
 * the message names it and the line), DF_ENOMEM. */
int df_hid_backend_replay(const char *const *files, size_t n, const df_hid_replay_opts *opts,
                          df_hid_backend **out, df_error *err);

/* One captured write_output / control call of a replay device. */
typedef struct df_hid_replay_output {
    char path[DF_HID_PATH_MAX];  /* the device's path */
    uint64_t seq;                /* 0, 1, 2... over the whole backend, in call order */
    uint64_t time_us;            /* the device's replay time then: recorded time of the last
                                    report delivered (0 before the first) */
    int is_control;              /* 0: output report (data/len), 1: control transfer */
    int is_feature;              /* 1: a feature report sent (SET_REPORT Feature, data/len) */
    uint8_t request_type, request;
    uint16_t value, index;       /* control only */
    uint8_t *data;               /* output report bytes (malloc'd), NULL for control */
    size_t len;
} df_hid_replay_output;

/* Copies the captured calls of backend b (a replay backend) made so far, in call order, from
 * index `from` on (0 = all): *out malloc'd array of *n (NULL when none), free with
 * df_hid_replay_outputs_free. Thread-safe against concurrent write_output/control. Errors:
 * DF_EINVAL (b not a replay backend, NULL out/n), DF_ENOMEM. */
int df_hid_replay_outputs(df_hid_backend *b, size_t from, df_hid_replay_output **out, size_t *n,
                          df_error *err);
void df_hid_replay_outputs_free(df_hid_replay_output *list, size_t n);

/* The start of replay device d of backend b on the backend's clock (CLOCK_MONOTONIC in us unless
 * opts gave now_us): the clock time at open, so d's report recorded at r is due at
 * *t0_us + r / speed (the HID latency bench compares event receipt with it). Set by open, constant
 * until close: any thread may call this while d is open. Errors: DF_EINVAL (NULL arguments, b not
 * a replay backend). */
int df_hid_replay_start_us(const df_hid_backend *b, const df_hid_dev *d, uint64_t *t0_us,
                           df_error *err);

#endif

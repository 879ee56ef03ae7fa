/* Unit tests for the live device sources, server/hid/hid_hidapi.c and hid_libusb.c, against the
 * true state of this machine: what they enumerate must equal what the test finds itself in /dev
 * and sysfs (hidraw nodes and their report descriptors; USB devices 077d:0410 with their bus and
 * address). On a machine without HID devices both lists are empty, and that is checked, not
 * skipped. Opening bogus paths fails with the right code and a message naming the path. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <dirent.h>
#include <glob.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include <libusb-1.0/libusb.h>

#include "server/hid/hid_source.h"

#define MAX_DEV 256

/* The bus of hidraw node /dev/<name> from its sysfs uevent (HID_ID=BBBB:VVVVVVVV:PPPPPPPP), or
 * -1 when unreadable. */
static int hidraw_bus(const char *devpath)
{
    char p[512], line[256];
    snprintf(p, sizeof p, "/sys/class/hidraw/%s/device/uevent", strrchr(devpath, '/') + 1);
    FILE *f = fopen(p, "r");
    if (!f) return -1;
    int bus = -1;
    unsigned b;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "HID_ID=%x:", &b) == 1) bus = (int)b;
    fclose(f);
    return bus;
}

/* The /dev/hidraw* nodes hidapi 0.13 lists: those on a bus it handles (USB, Bluetooth, I2C, SPI;
 * it skips others, e.g. BUS_VIRTUAL uhid devices). */
static size_t dev_hidraw(char out[][DF_HID_PATH_MAX])
{
    glob_t g;
    size_t n = 0;
    if (glob("/dev/hidraw*", 0, NULL, &g) == 0) {
        for (size_t i = 0; i < g.gl_pathc && n < MAX_DEV; i++) {
            int bus = hidraw_bus(g.gl_pathv[i]);
            if (bus == 0x03 || bus == 0x05 || bus == 0x18 || bus == 0x1c)
                snprintf(out[n++], DF_HID_PATH_MAX, "%s", g.gl_pathv[i]);
        }
        globfree(&g);
    }
    return n;
}

/* The whole sysfs file at path (malloc'd, *n) or NULL. */
static uint8_t *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    uint8_t *b = malloc(65536);
    *n = fread(b, 1, 65536, f);
    fclose(f);
    return b;
}

static void test_hidapi_matches_machine(void **state)
{
    (void)state;
    static char nodes[MAX_DEV][DF_HID_PATH_MAX];
    size_t want = dev_hidraw(nodes);
    df_hid_backend *b = NULL;
    df_error e;
    if (df_hid_backend_hidapi(&b, &e) != DF_OK) fail_msg("%s", e.msg);
    assert_int_equal(b->kind, DF_HID_BACKEND_HIDAPI);
    assert_string_equal(b->name, "hidapi");
    assert_null(b->watch); /* no hotplug: the manager enumerates periodically */
    df_hid_devinfo *list = NULL;
    size_t n = 99;
    if (b->enumerate(b, &list, &n, &e) != DF_OK) fail_msg("%s", e.msg);
    printf("hidapi: %zu hidraw device(s) listed, %zu /dev/hidraw* node(s) here%s\n", n, want,
           want == 0 ? " (no HID devices on this machine)" : "");
    assert_int_equal(n, want);
    if (n == 0) assert_null(list);
    for (size_t i = 0; i < n; i++) {
        int found = 0;
        for (size_t k = 0; k < want && !found; k++) found = strcmp(nodes[k], list[i].path) == 0;
        assert_true(found);
        for (size_t k = 0; k < i; k++) assert_string_not_equal(list[k].path, list[i].path);
        assert_int_equal(list[i].backend, DF_HID_BACKEND_HIDAPI);
        assert_int_equal(list[i].raw_powermate, 0);
        assert_int_equal(list[i].bus, hidraw_bus(list[i].path));
        char sys[512];
        snprintf(sys, sizeof sys, "/sys/class/hidraw/%s/device/report_descriptor",
                 strrchr(list[i].path, '/') + 1);
        size_t dn = 0;
        uint8_t *desc = slurp(sys, &dn);
        if (desc && dn) {
            assert_int_equal(list[i].desc_len, dn);
            assert_memory_equal(list[i].desc, desc, dn);
        } else {
            assert_null(list[i].desc);
        }
        free(desc);
    }
    df_hid_devinfo_free_list(list, n);

    /* a second instance shares the one hid_init */
    df_hid_backend *b2 = NULL;
    assert_int_equal(df_hid_backend_hidapi(&b2, &e), DF_OK);
    df_hid_backend_destroy(b2);
    /* not a replay backend */
    df_hid_replay_output *out;
    size_t on;
    assert_int_equal(df_hid_replay_outputs(b, 0, &out, &on, &e), DF_EINVAL);
    df_hid_backend_destroy(b);
}

static void test_hidapi_bogus_paths(void **state)
{
    (void)state;
    df_hid_backend *b = NULL;
    df_error e;
    assert_int_equal(df_hid_backend_hidapi(&b, &e), DF_OK);
    df_hid_dev *d = NULL;
    const char *missing = "/dev/hidraw-no-such-node";
    assert_int_equal(b->open(b, missing, &d, &e), DF_ENOTFOUND);
    assert_non_null(strstr(e.msg, missing));
    assert_int_equal(b->open(b, "/etc/passwd", &d, &e), DF_EINVAL); /* a regular file */
    assert_non_null(strstr(e.msg, "not a hidraw"));
    assert_int_equal(b->open(b, "/dev/null", &d, &e), DF_EINVAL); /* a character device, not hidraw */
    assert_non_null(strstr(e.msg, "/dev/null"));
    assert_non_null(strstr(e.msg, "not a hidraw"));
    assert_int_equal(b->open(b, "", &d, &e), DF_EINVAL);
    assert_int_equal(b->open(b, NULL, &d, &e), DF_EINVAL);
    assert_null(d);
    df_hid_backend_destroy(b);
}

/* "usb:BUS:ADDR" of every USB device 077d:0410 sysfs lists. */
static size_t sysfs_powermates(char out[][DF_HID_PATH_MAX])
{
    size_t n = 0;
    DIR *dir = opendir("/sys/bus/usb/devices");
    if (!dir) return 0;
    for (struct dirent *de; (de = readdir(dir)) && n < MAX_DEV;) {
        char p[512];
        unsigned v = 0, pid = 0, bus = 0, dev = 0;
        FILE *f;
#define READ_ATTR(name, fmt, var)                                                       \
        snprintf(p, sizeof p, "/sys/bus/usb/devices/%s/" name, de->d_name);            \
        if (!(f = fopen(p, "r"))) continue;                                            \
        if (fscanf(f, fmt, &var) != 1) var = 0;                                        \
        fclose(f);
        READ_ATTR("idVendor", "%x", v)
        READ_ATTR("idProduct", "%x", pid)
        READ_ATTR("busnum", "%u", bus)
        READ_ATTR("devnum", "%u", dev)
#undef READ_ATTR
        if (v == DF_HID_POWERMATE_VID && pid == DF_HID_POWERMATE_PID)
            snprintf(out[n++], DF_HID_PATH_MAX, "usb:%03u:%03u", bus, dev);
    }
    closedir(dir);
    return n;
}

static void on_change(void *user)
{
    atomic_fetch_add((atomic_int *)user, 1);
}

static void test_libusb_matches_machine(void **state)
{
    (void)state;
    static char pms[MAX_DEV][DF_HID_PATH_MAX];
    size_t want = sysfs_powermates(pms);
    df_hid_backend *b = NULL;
    df_error e;
    if (df_hid_backend_libusb(&b, &e) != DF_OK) fail_msg("%s", e.msg);
    assert_int_equal(b->kind, DF_HID_BACKEND_LIBUSB);
    assert_string_equal(b->name, "libusb");
    df_hid_devinfo *list = NULL;
    size_t n = 99;
    if (b->enumerate(b, &list, &n, &e) != DF_OK) fail_msg("%s", e.msg);
    printf("libusb: %zu PowerMate(s) listed, %zu in sysfs%s\n", n, want,
           want == 0 ? " (no PowerMate on this machine)" : "");
    assert_int_equal(n, want);
    for (size_t i = 0; i < n; i++) {
        int found = 0;
        for (size_t k = 0; k < want && !found; k++) found = strcmp(pms[k], list[i].path) == 0;
        assert_true(found);
        assert_int_equal(list[i].vid, DF_HID_POWERMATE_VID);
        assert_int_equal(list[i].pid, DF_HID_POWERMATE_PID);
        assert_int_equal(list[i].raw_powermate, 1);
        assert_null(list[i].desc);
    }
    df_hid_devinfo_free_list(list, n);

    /* hotplug: a watch exactly when libusb has the capability here; unwatch, rewatch, destroy
     * while watching (destroy stops the event thread) */
    int cap = libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) != 0;
    atomic_int calls;
    atomic_init(&calls, 0);
    assert_int_equal(b->watch(b, on_change, &calls, &e), cap ? DF_OK : DF_EUNSUPPORTED);
    assert_int_equal(b->watch(b, NULL, NULL, &e), DF_OK);
    assert_int_equal(b->watch(b, NULL, NULL, &e), DF_OK);
    if (cap) {
        assert_int_equal(b->watch(b, on_change, &calls, &e), DF_OK);
        assert_int_equal(b->watch(b, on_change, &calls, &e), DF_OK);
    }
    df_hid_backend_destroy(b);
}

static void test_libusb_bogus_paths(void **state)
{
    (void)state;
    static char pms[MAX_DEV][DF_HID_PATH_MAX];
    size_t have = sysfs_powermates(pms);
    df_hid_backend *b = NULL;
    df_error e;
    assert_int_equal(df_hid_backend_libusb(&b, &e), DF_OK);
    df_hid_dev *d = NULL;
    const char *bad[] = { "usb:1", "usb:001:001x", "usb:999:001", "/dev/hidraw0", "usb:-1:2", "" };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        assert_int_equal(b->open(b, bad[i], &d, &e), DF_EINVAL);
        assert_non_null(strstr(e.msg, "usb:BUS:ADDR"));
    }
    /* a well-formed address where sysfs has no PowerMate */
    const char *none = "usb:255:255";
    for (size_t k = 0; k < have; k++) assert_string_not_equal(pms[k], none);
    assert_int_equal(b->open(b, none, &d, &e), DF_ENOTFOUND);
    assert_non_null(strstr(e.msg, none));
    assert_null(d);
    df_hid_backend_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hidapi_matches_machine),
        cmocka_unit_test(test_hidapi_bogus_paths),
        cmocka_unit_test(test_libusb_matches_machine),
        cmocka_unit_test(test_libusb_bogus_paths),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Unit tests for server/config.c and server/log.c: defaults, the key = value parser (comments,
 * whitespace, sizes with suffixes, every bad value, all-or-nothing on error), the command line
 * (--config then overrides, --opt=value, --help, unknown options), allow_paths matching and the
 * hid.* keys handed to server/hid/hid_config.c. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/config.h"
#include "server/session/membudget.h"
#include "server/session/stream_lag.h"
#include "server/log.h"

static void test_defaults(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, "/run/user/1000");
    assert_string_equal(c.socket_path, "/run/user/1000/deformd.sock");
    df_config_defaults(&c, NULL);
    assert_string_equal(c.socket_path, "/run/deformd/deformd.sock");
    df_config_defaults(&c, "");
    assert_string_equal(c.socket_path, "/run/deformd/deformd.sock");
    assert_string_equal(c.tcp_host, "");
    assert_int_equal(c.n_allow, 0);
    assert_int_equal(c.max_clients, DF_CONFIG_DEFAULT_MAX_CLIENTS);
    assert_true(c.output_queue_limit == DF_CONFIG_DEFAULT_QUEUE_LIMIT);
    assert_int_equal(c.log_level, DF_LOG_INFO);
    assert_int_equal(c.foreground, 0);
    assert_int_equal(c.spin_us, DF_CONFIG_DEFAULT_SPIN_US);
    assert_int_equal(c.inline_us, DF_CONFIG_DEFAULT_INLINE_US);
    assert_int_equal(c.cursor_hz, 120);
    assert_true(c.shm_ring_bytes == (uint64_t)64 << 20);
    /* memory limits (issue 9, items 10-13): sized from the machine's RAM where it matters */
    assert_true(c.shm_total_bytes == DF_CONFIG_DEFAULT_SHM_TOTAL);
    assert_int_equal(c.max_upload_mb, 1024);
    assert_int_equal(c.uploads_max_mb, DF_CONFIG_DEFAULT_UPLOADS_MB);
    assert_in_range(c.history_max_mb, DF_CONFIG_HISTORY_MIN_DEFAULT_MB,
                    DF_CONFIG_HISTORY_MAX_DEFAULT_MB);
    assert_int_equal(c.resync_ring_mb, 32); /* issue 12: resync ring per session */
    assert_true(c.memory_max_mb >= DF_CONFIG_MEMORY_MIN_DEFAULT_MB);
    assert_true((uint64_t)c.memory_max_mb << 20 <= df_mem_physical_bytes() ||
                c.memory_max_mb == DF_CONFIG_MEMORY_MIN_DEFAULT_MB);
    /* An XDG dir too long for sun_path falls back to /run/deformd. */
    char longdir[200];
    memset(longdir, 'a', sizeof longdir - 1);
    longdir[0] = '/';
    longdir[sizeof longdir - 1] = '\0';
    df_config_defaults(&c, longdir);
    assert_string_equal(c.socket_path, "/run/deformd/deformd.sock");
}

static void test_parse_file_text(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, NULL);
    const char *text = "# deformd test config\n"
                       "\n"
                       "socket = /tmp/x.sock   # trailing comment\n"
                       "  tcp=127.0.0.1:7878\n"
                       "allow_paths = /tmp, /\n"
                       "max_clients = 12\n"
                       "output_queue_limit = 8m\n"
                       "stream_coalesce_start = 2m\n"
                       "stream_coalesce_resume = 512k\n"
                       "cache_memory_mb = 64\n"
                       "log_level = debug\n"
                       "max_mesh_vertices = 2000\n"
                       "max_sessions = 3\n"
                       "threads = 2\r\n"
                       "spin_us = 30\n"
                       "inline_us = 0\n"
                       "cursor_hz = 0\n"
                       "shm_ring_bytes = 64k\n";
    df_error e;
    assert_int_equal(df_config_parse(&c, text, strlen(text), "t.conf", &e), DF_OK);
    assert_string_equal(c.socket_path, "/tmp/x.sock");
    assert_string_equal(c.tcp_host, "127.0.0.1");
    assert_int_equal(c.tcp_port, 7878);
    assert_int_equal(c.n_allow, 2);
    assert_string_equal(c.allow_paths[1], "/");
    assert_int_equal(c.max_clients, 12);
    assert_true(c.output_queue_limit == (size_t)8 << 20);
    assert_int_equal(c.stream_coalesce_start, 2 << 20);
    assert_int_equal(c.stream_coalesce_resume, 512 << 10);
    assert_true(c.cache_memory_mb == 64);
    assert_int_equal(c.log_level, DF_LOG_DEBUG);
    assert_int_equal(c.max_mesh_vertices, 2000);
    assert_int_equal(c.max_sessions, 3);
    assert_int_equal(c.threads, 2);
    assert_int_equal(c.spin_us, 30);
    assert_int_equal(c.inline_us, 0);
    assert_int_equal(c.cursor_hz, 0); /* unlimited */
    assert_int_equal(df_config_set(&c, "cursor_hz", "240", &e), DF_OK);
    assert_int_equal(c.cursor_hz, 240);
    assert_true(c.shm_ring_bytes == 65536);
    assert_int_equal(df_config_set(&c, "shm_ring_bytes", "0", &e), DF_OK); /* disabled */
    assert_true(c.shm_ring_bytes == 0);
    assert_int_equal(df_config_set(&c, "shm_ring_bytes", "4g", &e), DF_OK);
    assert_true(c.shm_ring_bytes == (uint64_t)4 << 30);
    const char mem[] = "max_upload_mb = 8\nuploads_max_mb = 16\nhistory_max_mb = 0\n"
                       "memory_max_mb = 512\nshm_total_bytes = 3m\nresync_ring_mb = 0\n";
    assert_int_equal(df_config_parse(&c, mem, sizeof mem - 1, "mem.conf", &e), DF_OK);
    assert_int_equal(c.max_upload_mb, 8);
    assert_int_equal(c.uploads_max_mb, 16);
    assert_int_equal(c.history_max_mb, 0);
    assert_int_equal(c.resync_ring_mb, 0);
    assert_int_equal(c.memory_max_mb, 512);
    assert_true(c.shm_total_bytes == (uint64_t)3 << 20);
    /* IPv6 brackets and disabling. */
    assert_int_equal(df_config_set(&c, "tcp", "[::1]:0", &e), DF_OK);
    assert_string_equal(c.tcp_host, "::1");
    assert_int_equal(c.tcp_port, 0);
    assert_int_equal(df_config_set(&c, "tcp", "none", &e), DF_OK);
    assert_string_equal(c.tcp_host, "");
    assert_int_equal(df_config_set(&c, "socket", "none", &e), DF_OK);
    assert_string_equal(c.socket_path, "");
}

/* stream_coalesce_start / _resume: 0 = output_queue_limit / 8 and / 16; start capped at the
 * limit, resume at the start */
static void test_stream_coalesce_thresholds(void **state)
{
    (void)state;
    size_t hi, lo, limit = (size_t)4 << 20;
    df_stream_lag_thresholds(limit, 0, 0, &hi, &lo);
    assert_true(hi == limit / 8 && lo == limit / 16);
    df_stream_lag_thresholds(limit, 1 << 20, 1000, &hi, &lo);
    assert_true(hi == (size_t)1 << 20 && lo == 1000);
    df_stream_lag_thresholds(limit, 64 << 20, 0, &hi, &lo);   /* above the limit: the limit */
    assert_true(hi == limit && lo == limit / 16);
    df_stream_lag_thresholds(limit, 4096, 8192, &hi, &lo);    /* resume above start: start */
    assert_true(hi == 4096 && lo == 4096);
}

/* admm_active: 0 full solve (default), 1 active set, 2 active set with the tail test; anything
 * else is refused and leaves the value */
static void test_admm_active_modes(void **state)
{
    (void)state;
    df_server_config c;
    df_error e;
    df_config_defaults(&c, NULL);
    assert_int_equal(c.admm_active, 0);
    for (int v = 0; v <= 2; v++) {
        char txt[16];
        snprintf(txt, sizeof txt, "%d", v);
        assert_int_equal(df_config_set(&c, "admm_active", txt, &e), DF_OK);
        assert_int_equal(c.admm_active, v);
    }
    static const char *bad[] = {"3", "-1", "tail", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_not_equal(df_config_set(&c, "admm_active", bad[i], &e), DF_OK);
        assert_non_null(strstr(e.msg, "admm_active"));
        assert_int_equal(c.admm_active, 2);
    }
}

static void test_parse_errors_leave_config_untouched(void **state)
{
    (void)state;
    static const char *const bad[] = {
        "max_clients = 0\n",          "max_clients = -3\n",       "max_clients = 12x\n",
        "output_queue_limit = 10\n",  "output_queue_limit = 2t\n", "log_level = loud\n",
        "tcp = 127.0.0.1\n",          "tcp = :80\n",              "tcp = host:65536\n",
        "tcp = host:8k\n",            "allow_paths = relative/dir\n",
        "no_such_key = 1\n",          "just words\n",             " = 5\n",
        "threads = 0\n",              "threads = 65\n",           "max_mesh_vertices = 0\n",
        "max_sessions = 99999999\n",  "cache_memory_mb = lots\n",
        "spin_us = 1001\n",           "inline_us = 1001\n",       "inline_us = -1\n",
        "inline_us = fast\n",       "shm_ring_bytes = 65535\n", "shm_ring_bytes = 5g\n",
        "shm_ring_bytes = -1\n",     "shm_ring_bytes = big\n",
        "max_upload_mb = 0\n",       "max_upload_mb = 1025\n",   "uploads_max_mb = 0\n",
        "history_max_mb = -1\n",     "history_max_mb = 2000000\n", "memory_max_mb = 15\n",
        "resync_ring_mb = -1\n",     "resync_ring_mb = 2000000\n", "resync_ring_mb = 32m\n",
        "memory_max_mb = lots\n",    "shm_total_bytes = 1k\n",   "shm_total_bytes = 2t\n",
        "tcp_insecure = maybe\n",    "tcp_insecure =\n",         "socket_mode = 0778\n",
        "socket_mode = 1777\n",      "socket_mode = rw\n",       "socket_mode = -1\n",
        "socket_group = a b\n",      "socket_group = /etc\n",
        "handshake_timeout_s = -1\n", "handshake_timeout_s = 86401\n",
        "idle_timeout_s = soon\n",   "idle_timeout_s = 1e3\n",
        "cursor_hz = -1\n",          "cursor_hz = 10001\n",      "cursor_hz = fast\n",
        "stream_coalesce_start = -1\n", "stream_coalesce_start = 2g\n",
        "stream_coalesce_resume = lots\n",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        df_server_config c, before;
        df_config_defaults(&c, "/x");
        /* a good line first: must not be applied either (all-or-nothing) */
        char text[256];
        snprintf(text, sizeof text, "max_clients = 7\n%s", bad[i]);
        before = c;
        df_error e;
        df_error_clear(&e);
        int rc = df_config_parse(&c, text, strlen(text), "bad.conf", &e);
        if (rc == DF_OK) fail_msg("accepted: %s", bad[i]);
        assert_true(rc == DF_EINVAL || rc == DF_EFORMAT || rc == DF_ELIMIT);
        assert_non_null(strstr(e.msg, "bad.conf:2:"));
        assert_memory_equal(&c, &before, sizeof c);
    }
    /* NUL byte inside a line, over-long line. */
    df_server_config c;
    df_config_defaults(&c, NULL);
    df_error e;
    const char nul[] = "log_level = info\0x\n";
    assert_int_equal(df_config_parse(&c, nul, sizeof nul - 1, "n", &e), DF_EFORMAT);
    size_t big = DF_CONFIG_LINE_MAX + 10;
    char *line = malloc(big);
    assert_non_null(line);
    memset(line, 'a', big);
    assert_int_equal(df_config_parse(&c, line, big, "n", &e), DF_EFORMAT);
    free(line);
}

/* Issue 9 items 3, 4, 9: the keys of network exposure and connection admission. */
static void test_network_and_admission_keys(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, NULL);
    assert_int_equal(c.tcp_insecure, 0);
    assert_int_equal(c.socket_mode, 0660);
    assert_string_equal(c.socket_group, "");
    assert_int_equal(c.handshake_timeout_s, DF_CONFIG_DEFAULT_HANDSHAKE_TIMEOUT_S);
    assert_int_equal(c.idle_timeout_s, DF_CONFIG_DEFAULT_IDLE_TIMEOUT_S);
    const char *text = "tcp_insecure = yes\nsocket_mode = 600\nsocket_group = deformd\n"
                       "handshake_timeout_s = 3\nidle_timeout_s = 0\n";
    df_error e;
    assert_int_equal(df_config_parse(&c, text, strlen(text), "t.conf", &e), DF_OK);
    assert_int_equal(c.tcp_insecure, 1);
    assert_int_equal(c.socket_mode, 0600);
    assert_string_equal(c.socket_group, "deformd");
    assert_int_equal(c.handshake_timeout_s, 3);
    assert_int_equal(c.idle_timeout_s, 0);
    assert_int_equal(df_config_set(&c, "tcp_insecure", "No", &e), DF_OK);
    assert_int_equal(c.tcp_insecure, 0);
    assert_int_equal(df_config_set(&c, "socket_mode", "0777", &e), DF_OK);
    assert_int_equal(c.socket_mode, 0777);
    assert_int_equal(df_config_set(&c, "socket_group", "", &e), DF_OK);
    assert_string_equal(c.socket_group, "");
    /* --tcp-insecure on the command line */
    df_cli_action act;
    char *argv[] = {"deformd", "--tcp", "0.0.0.0:7878", "--tcp-insecure", NULL};
    assert_int_equal(df_config_from_args(&c, 4, argv, NULL, &act, &e), DF_OK);
    assert_int_equal(c.tcp_insecure, 1);
    assert_string_equal(c.tcp_host, "0.0.0.0");
    assert_non_null(strstr(df_config_usage(), "--tcp-insecure"));
}

static void test_cluster_keys(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, NULL);
    assert_string_equal(c.cluster, "");
    assert_string_equal(c.advertise, "");
    assert_int_equal(c.cluster_lease_ms, 3000);
    const char *text = "cluster = redis://10.0.0.5:6379\nadvertise = host-a:7878\n"
                       "cluster_lease_ms = 1500\n";
    df_error e;
    assert_int_equal(df_config_parse(&c, text, strlen(text), "t.conf", &e), DF_OK);
    assert_string_equal(c.cluster, "redis://10.0.0.5:6379");
    assert_string_equal(c.advertise, "host-a:7878");
    assert_int_equal(c.cluster_lease_ms, 1500);
    /* a Redis Cluster: seed nodes, comma-separated (a repeated redis:// and spaces allowed) */
    const char *seeds = "redis://10.0.0.5:7000,10.0.0.6:7001, redis://10.0.0.7:7002";
    assert_int_equal(df_config_set(&c, "cluster", seeds, &e), DF_OK);
    assert_string_equal(c.cluster, seeds);
    assert_int_equal(df_config_set(&c, "cluster", "redis://10.0.0.5:6379", &e), DF_OK);
    /* bad values: a clear error naming the key, nothing changed */
    const char *bad[][2] = {{"cluster", "10.0.0.5:6379"}, {"cluster", "redis://nohost"},
                            {"cluster", "redis://a:1,"}, {"cluster", "redis://a:1,,b:2"},
                            {"cluster", "redis://a:1,b"}, {"cluster", "redis://a:1,b:70000"},
                            {"cluster", "redis://a:1,:2"}, {"cluster", "redis://a:0"},
                            {"advertise", "nohost"}, {"advertise", ":7878"},
                            {"advertise", "h:"}, {"cluster_lease_ms", "299"},
                            {"cluster_lease_ms", "600001"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(df_config_set(&c, bad[i][0], bad[i][1], &e), DF_EINVAL);
        assert_non_null(strstr(e.msg, bad[i][0]));
    }
    assert_string_equal(c.cluster, "redis://10.0.0.5:6379");
    assert_string_equal(c.advertise, "host-a:7878");
    assert_int_equal(c.cluster_lease_ms, 1500);
    char longer[300];
    memset(longer, 'a', sizeof longer);
    memcpy(longer + 280, ":1", 3);
    assert_int_equal(df_config_set(&c, "advertise", longer, &e), DF_EINVAL);
    assert_int_equal(df_config_set(&c, "cluster", "", &e), DF_OK); /* off again */
    assert_string_equal(c.cluster, "");
}

static void test_load_file_and_cli(void **state)
{
    (void)state;
    char path[] = "/tmp/deformd_test_conf_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    const char *text = "socket = /tmp/from_file.sock\nmax_clients = 5\nlog_level = warn\n";
    assert_int_equal(write(fd, text, strlen(text)), (int)strlen(text));
    close(fd);
    df_server_config c;
    df_cli_action act;
    df_error e;
    char *argv1[] = {"deformd", "--config", path, "--log-level=debug", "--tcp", "127.0.0.1:0",
                     "--foreground", "--inline-us", "120", "--spin-us=5", NULL};
    assert_int_equal(df_config_from_args(&c, 10, argv1, "/run/user/7", &act, &e), DF_OK);
    assert_int_equal(c.inline_us, 120);
    assert_int_equal(c.spin_us, 5);
    assert_int_equal(act, DF_CLI_RUN);
    assert_string_equal(c.socket_path, "/tmp/from_file.sock");
    assert_int_equal(c.max_clients, 5);
    assert_int_equal(c.log_level, DF_LOG_DEBUG); /* command line wins over the file */
    assert_string_equal(c.tcp_host, "127.0.0.1");
    assert_int_equal(c.foreground, 1);
    assert_string_equal(c.config_path, path);
    /* --socket after --config overrides the file's socket, whatever the order on the line. */
    char *argv2[] = {"deformd", "--socket", "/tmp/cli.sock", "--config", path, NULL};
    assert_int_equal(df_config_from_args(&c, 5, argv2, NULL, &act, &e), DF_OK);
    assert_string_equal(c.socket_path, "/tmp/cli.sock");
    unlink(path);
    /* Errors: missing file, unknown option, missing value. --help wins. */
    df_server_config keep = c;
    char *argv3[] = {"deformd", "--config", path, NULL};
    assert_int_equal(df_config_from_args(&c, 3, argv3, NULL, &act, &e), DF_EIO);
    char *argv4[] = {"deformd", "--bogus", NULL};
    assert_int_equal(df_config_from_args(&c, 2, argv4, NULL, &act, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "--bogus"));
    char *argv5[] = {"deformd", "--socket", NULL};
    assert_int_equal(df_config_from_args(&c, 2, argv5, NULL, &act, &e), DF_EINVAL);
    char *argv6[] = {"deformd", "--log-level", "chatty", NULL};
    assert_int_equal(df_config_from_args(&c, 3, argv6, NULL, &act, &e), DF_EINVAL);
    char *argv8[] = {"deformd", "--inline-us", "5000", NULL};
    assert_int_equal(df_config_from_args(&c, 3, argv8, NULL, &act, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "--inline-us"));
    assert_memory_equal(&c, &keep, sizeof c);
    char *argv7[] = {"deformd", "--bogus", "--help", NULL};
    assert_int_equal(df_config_from_args(&c, 3, argv7, NULL, &act, &e), DF_OK);
    assert_int_equal(act, DF_CLI_HELP);
    assert_non_null(strstr(df_config_usage(), "--foreground"));
    assert_non_null(strstr(df_config_usage(), "--inline-us"));
}

static void test_allowed_paths(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, NULL);
    df_error e;
    assert_int_equal(df_config_set(&c, "allow_paths", "/srv/meshes/:/data", &e), DF_OK);
    assert_int_equal(df_config_set(&c, "allow_paths", "/opt/x", &e), DF_OK); /* appends */
    assert_int_equal(c.n_allow, 3);
    assert_int_equal(df_config_path_allowed(&c, "/srv/meshes/a.obj"), 1);
    assert_int_equal(df_config_path_allowed(&c, "/srv/meshes/sub/a.obj"), 1);
    assert_int_equal(df_config_path_allowed(&c, "/srv/meshesX/a.obj"), 0);
    assert_int_equal(df_config_path_allowed(&c, "/srv/meshes"), 0);
    assert_int_equal(df_config_path_allowed(&c, "/data/b.off"), 1);
    assert_int_equal(df_config_path_allowed(&c, "/opt/x/y.mesh"), 1);
    assert_int_equal(df_config_path_allowed(&c, "/etc/passwd"), 0);
    assert_int_equal(df_config_path_allowed(&c, "relative/a.obj"), 0);
    assert_int_equal(df_config_path_allowed(&c, NULL), 0);
}

static void test_log_levels(void **state)
{
    (void)state;
    int l = -1;
    assert_int_equal(df_log_parse_level("ERROR", &l), DF_OK);
    assert_int_equal(l, DF_LOG_ERROR);
    assert_int_equal(df_log_parse_level("warning", &l), DF_OK);
    assert_int_equal(l, DF_LOG_WARN);
    assert_int_equal(df_log_parse_level("3", &l), DF_OK);
    assert_int_equal(l, DF_LOG_DEBUG);
    assert_int_equal(df_log_parse_level("4", &l), DF_EINVAL);
    assert_int_equal(l, DF_LOG_DEBUG);
    assert_int_equal(df_log_parse_level("", &l), DF_EINVAL);
    df_log_set_level(99);
    assert_int_equal(df_log_get_level(), DF_LOG_DEBUG);
    df_log_set_level(-5);
    assert_int_equal(df_log_get_level(), DF_LOG_ERROR);
    df_log_set_level(DF_LOG_INFO);
}

/* hid.* keys (issue 11): routed to server/hid/hid_config.c; an unknown hid key or bad value names
 * file:line, the cross-key check after the file names the file, nothing changes on error. */
static void test_hid_keys(void **state)
{
    (void)state;
    df_server_config c;
    df_config_defaults(&c, NULL);
    const char *good = "threads = 2\n"
                       "hid.knob.radius_step = 1.25\n"
                       "hid.046d:c626.deadzone = 0.2   # SpaceNavigator\n"
                       "hid.3d-mouse.sensitivity = 3\n";
    df_error e;
    assert_int_equal(df_config_parse(&c, good, strlen(good), "h.conf", &e), DF_OK);
    df_hid_params p;
    assert_int_equal(df_hid_config_resolve(&c.hid, DF_HID_CLASS_KNOB, 0x045e, 0x091b, &p, &e), DF_OK);
    assert_true(p.radius_step == 1.25);
    assert_int_equal(df_hid_config_resolve(&c.hid, DF_HID_CLASS_MOUSE3D, 0x046d, 0xc626, &p, &e),
                     DF_OK);
    assert_true(p.deadzone == 0.2 && p.sensitivity == 3.0);

    df_server_config before = c;
    const char *unknown = "threads = 3\n"
                          "\n"
                          "hid.knob.radius_stepp = 1.1\n";
    assert_int_equal(df_config_parse(&c, unknown, strlen(unknown), "h.conf", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "h.conf:3: "));
    assert_non_null(strstr(e.msg, "radius_stepp"));
    assert_memory_equal(&before, &c, sizeof c);
    const char *bad = "hid.pen.pressure_gamma = 0\n";
    assert_int_equal(df_config_parse(&c, bad, strlen(bad), "h.conf", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "h.conf:1: hid.pen.pressure_gamma"));
    const char *cls = "hid.pen.deadzone = 0.1\n";
    assert_int_equal(df_config_parse(&c, cls, strlen(cls), "h.conf", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "h.conf:1: "));
    assert_non_null(strstr(e.msg, "not a pen key"));
    /* a cross-key inconsistency names the line from which the file stays inconsistent */
    const char *cross = "hid.knob.nu_min = 0.4\n# x\nhid.knob.nu_max = 0.3\n";
    assert_int_equal(df_config_parse(&c, cross, strlen(cross), "h.conf", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "h.conf:3: hid.knob: nu_min 0.4 above nu_max 0.3"));
    assert_memory_equal(&before, &c, sizeof c);
    const char *cross2 = "hid.knob.nu_max = 0.3\nlog_level = info\nhid.knob.nu_min = 0.4\n"
                         "hid.knob.radius_step = 1.2\n";
    assert_int_equal(df_config_parse(&c, cross2, strlen(cross2), "h.conf", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "h.conf:3: hid.knob: nu_min 0.4 above nu_max 0.3"));
    /* inconsistent only half-way (led_min above the default led_max until the next line): fine */
    const char *mid = "hid.knob.led_min_radius = 2\nhid.knob.led_max_radius = 5\n";
    assert_int_equal(df_config_parse(&c, mid, strlen(mid), "h.conf", &e), DF_OK);
    c = before;
    /* the plain df_config_set path too */
    assert_int_equal(df_config_set(&c, "hid.knob.falloff_max", "5", &e), DF_OK);
    assert_int_equal(df_config_set(&c, "hid.knob.falloff_max", "0", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "falloff_max"));
}

/* The daemon-integration keys (issue 11): hid, hid_replay (comma lists appended, each file must
 * be readable, at most DF_CONFIG_MAX_HID_REPLAY), hid_replay_speed, hid_enumerate_s and the
 * --hid-replay option; a bad value names the key and changes nothing. */
static void test_hid_daemon_keys(void **state)
{
    (void)state;
    char f1[] = "/tmp/df-cfg-hid-XXXXXX", f2[] = "/tmp/df-cfg-hid-XXXXXX";
    int fd1 = mkstemp(f1), fd2 = mkstemp(f2);
    assert_true(fd1 >= 0 && fd2 >= 0);
    close(fd1);
    close(fd2);
    df_server_config c;
    df_config_defaults(&c, NULL);
    assert_int_equal(c.hid_on, 1);
    assert_int_equal(c.hid_enumerate_s, DF_CONFIG_DEFAULT_HID_ENUMERATE_S);
    assert_true(c.hid_replay_speed == 1.0 && c.n_hid_replay == 0);
    df_error e;
    char text[512];
    snprintf(text, sizeof text, "hid = off\nhid_replay = %s , %s\nhid_replay = %s\n"
             "hid_replay_speed = 0\nhid_enumerate_s = 0\n", f1, f2, f1);
    assert_int_equal(df_config_parse(&c, text, strlen(text), "h.conf", &e), DF_OK);
    assert_int_equal(c.hid_on, 0);
    assert_int_equal(c.n_hid_replay, 3);
    assert_string_equal(c.hid_replay[1], f2);
    assert_true(c.hid_replay_speed == 0.0 && c.hid_enumerate_s == 0);
    df_server_config before = c;
    static const char *const bad[][2] = {
        {"hid = maybe\n", "hid: 'maybe'"},
        {"hid_replay = /nonexistent/x.hid\n", "cannot read '/nonexistent/x.hid'"},
        {"hid_replay = ,\n", "no file"},
        {"hid_replay_speed = -1\n", "hid_replay_speed"},
        {"hid_replay_speed = fast\n", "hid_replay_speed"},
        {"hid_enumerate_s = 3601\n", "hid_enumerate_s"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(df_config_parse(&c, bad[i][0], strlen(bad[i][0]), "h.conf", &e),
                         DF_EINVAL);
        assert_non_null(strstr(e.msg, "h.conf:1: "));
        assert_non_null(strstr(e.msg, bad[i][1]));
        assert_memory_equal(&before, &c, sizeof c);
    }
    char many[20 * 40] = "hid_replay = ";
    for (int i = 0; i <= DF_CONFIG_MAX_HID_REPLAY; i++) {
        strcat(many, f1);
        strcat(many, ",");
    }
    df_config_defaults(&c, NULL);
    assert_int_equal(df_config_set(&c, "hid_replay", many + strlen("hid_replay = "), &e),
                     DF_EINVAL);
    assert_non_null(strstr(e.msg, "more than"));
    assert_int_equal(c.n_hid_replay, 0);
    char *argv[] = {"deformd", "--hid-replay", f2, NULL};
    df_cli_action act;
    assert_int_equal(df_config_from_args(&c, 3, argv, NULL, &act, &e), DF_OK);
    assert_int_equal(c.n_hid_replay, 1);
    assert_string_equal(c.hid_replay[0], f2);
    assert_non_null(strstr(df_config_usage(), "--hid-replay"));
    /* --hid-replay overrides the file's hid_replay (as every option overrides the file); two
     * --hid-replay options add up */
    char conf[] = "/tmp/df-cfg-hid-conf-XXXXXX";
    int fdc = mkstemp(conf);
    assert_true(fdc >= 0);
    snprintf(text, sizeof text, "hid_replay = %s\n", f1);
    assert_int_equal(write(fdc, text, strlen(text)), (ssize_t)strlen(text));
    close(fdc);
    char *argv2[] = {"deformd", "--config", conf, "--hid-replay", f2, "--hid-replay", f2, NULL};
    assert_int_equal(df_config_from_args(&c, 7, argv2, NULL, &act, &e), DF_OK);
    assert_int_equal(c.n_hid_replay, 2);
    assert_string_equal(c.hid_replay[0], f2);
    assert_string_equal(c.hid_replay[1], f2);
    char *argv3[] = {"deformd", "--config", conf, NULL};
    assert_int_equal(df_config_from_args(&c, 3, argv3, NULL, &act, &e), DF_OK);
    assert_int_equal(c.n_hid_replay, 1);
    assert_string_equal(c.hid_replay[0], f1);
    unlink(conf);
    unlink(f1);
    unlink(f2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_parse_file_text),
        cmocka_unit_test(test_parse_errors_leave_config_untouched),
        cmocka_unit_test(test_stream_coalesce_thresholds),
        cmocka_unit_test(test_admm_active_modes),
        cmocka_unit_test(test_network_and_admission_keys),
        cmocka_unit_test(test_cluster_keys),
        cmocka_unit_test(test_load_file_and_cli),
        cmocka_unit_test(test_allowed_paths),
        cmocka_unit_test(test_log_levels),
        cmocka_unit_test(test_hid_keys),
        cmocka_unit_test(test_hid_daemon_keys),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Unit tests for server/net/sd.c (sd_notify datagrams, LISTEN_FDS parsing) and server/session/cache.c (LRU
 * eviction of cached Kelvinlet pin solvers under the memory cap, sessions with a running job are
 * never evicted, accounting back to zero). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/session/cache.h"
#include "server/net/sd.h"

static void test_sd_notify(void **state)
{
    (void)state;
    unsetenv("NOTIFY_SOCKET");
    assert_int_equal(df_sd_notify("READY=1"), 0); /* not under systemd */
    char path[108];
    snprintf(path, sizeof path, "/tmp/deformd_notify_%d.sock", (int)getpid());
    unlink(path);
    int fd = socket(AF_UNIX, SOCK_DGRAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", path);
    assert_int_equal(bind(fd, (struct sockaddr *)&sa, sizeof sa), 0);
    setenv("NOTIFY_SOCKET", path, 1);
    assert_int_equal(df_sd_notify("READY=1"), 1);
    char buf[64];
    ssize_t n = recv(fd, buf, sizeof buf, 0);
    assert_int_equal(n, 7);
    assert_memory_equal(buf, "READY=1", 7);
    assert_int_equal(df_sd_notify("STOPPING=1"), 1);
    n = recv(fd, buf, sizeof buf, 0);
    assert_int_equal(n, 10);
    assert_memory_equal(buf, "STOPPING=1", 10);
    setenv("NOTIFY_SOCKET", "relative/path", 1);
    assert_int_equal(df_sd_notify("READY=1"), DF_EINVAL);
    setenv("NOTIFY_SOCKET", "/tmp/deformd_no_such_socket_here", 1);
    assert_int_equal(df_sd_notify("READY=1"), DF_EIO);
    unsetenv("NOTIFY_SOCKET");
    close(fd);
    unlink(path);
}

static void test_sd_listen_fds(void **state)
{
    (void)state;
    int fds[4] = {-1, -1, -1, -1};
    unsetenv("LISTEN_PID");
    unsetenv("LISTEN_FDS");
    assert_int_equal(df_sd_listen_fds(fds, 4), 0);
    setenv("LISTEN_PID", "1", 1); /* someone else's */
    setenv("LISTEN_FDS", "1", 1);
    assert_int_equal(df_sd_listen_fds(fds, 4), 0);
    setenv("LISTEN_PID", "12abc", 1);
    assert_int_equal(df_sd_listen_fds(fds, 4), DF_EINVAL);
    /* ours: put a socket on fd 3 as systemd would */
    int s = socket(AF_UNIX, SOCK_STREAM, 0);
    assert_true(s >= 0);
    int saved3 = dup(3); /* may fail when fd 3 is closed; restored below */
    assert_int_equal(dup2(s, 3), 3);
    char pid[32];
    snprintf(pid, sizeof pid, "%d", (int)getpid());
    setenv("LISTEN_PID", pid, 1);
    setenv("LISTEN_FDS", "1", 1);
    assert_int_equal(df_sd_listen_fds(fds, 4), 1);
    assert_int_equal(fds[0], 3);
    assert_null(getenv("LISTEN_PID")); /* consumed */
    assert_null(getenv("LISTEN_FDS"));
    setenv("LISTEN_PID", pid, 1);
    setenv("LISTEN_FDS", "9", 1); /* more than we accept */
    assert_int_equal(df_sd_listen_fds(fds, 4), DF_EINVAL);
    if (saved3 >= 0) {
        dup2(saved3, 3);
        close(saved3);
    } else {
        close(3);
    }
    close(s);
}

static df_kelvinlet_constraints *make_kc(double x)
{
    double pt[3] = {x, 0, 0};
    df_kelvinlet_pins pins = {.n = 1, .points = pt, .flags = DF_KELVINLET_PIN_DISPLACEMENT,
                              .radius = 1, .ratio = 1.1, .nu = 0.4, .order = 1};
    df_kelvinlet_constraints *kc = NULL;
    df_error e;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &kc, &e), DF_OK);
    return kc;
}

static void test_cache_lru_eviction(void **state)
{
    (void)state;
    static df_server srv; /* zeroed */
    static df_session s[3];
    memset(&srv, 0, sizeof srv);
    memset(s, 0, sizeof s);
    srv.cfg.cache_memory_mb = 1;
    for (int i = 0; i < 3; i++) {
        s[i].srv = &srv;
        s[i].id = (uint64_t)i + 1;
        s[i].next = i < 2 ? &s[i + 1] : NULL;
    }
    srv.sessions = &s[0];
    size_t each = 600u << 10;
    s[0].kc = make_kc(0);
    df_cache_install_kelvinlet(&srv, &s[0], each);
    s[1].kc = make_kc(1);
    df_cache_install_kelvinlet(&srv, &s[1], each);
    assert_int_equal(srv.cache_bytes, 2 * each);
    df_cache_touch_kelvinlet(&srv, &s[0]); /* s[1] is now the least recently used */
    assert_int_equal(df_cache_enforce(&srv), 1);
    assert_non_null(s[0].kc);
    assert_null(s[1].kc);
    assert_int_equal(srv.cache_bytes, each);
    assert_true(srv.stats.lru_evictions == 1);
    /* a session with a running job is never evicted, even when it is the oldest */
    s[2].kc = make_kc(2);
    df_cache_install_kelvinlet(&srv, &s[2], each);
    s[0].running = (struct df_job *)&srv; /* any non-NULL marker */
    assert_int_equal(df_cache_enforce(&srv), 1);
    assert_non_null(s[0].kc);
    assert_null(s[2].kc);
    /* nothing evictable: stays over the cap */
    s[2].kc = make_kc(3);
    df_cache_install_kelvinlet(&srv, &s[2], each);
    s[2].running = s[0].running;
    assert_int_equal(df_cache_enforce(&srv), 0);
    assert_int_equal(srv.cache_bytes, 2 * each);
    s[0].running = s[2].running = NULL;
    df_cache_drop_kelvinlet(&srv, &s[0]);
    df_cache_drop_kelvinlet(&srv, &s[2]);
    df_cache_drop_kelvinlet(&srv, &s[1]); /* absent: no-op */
    assert_int_equal(srv.cache_bytes, 0);
    /* estimates grow with the problem */
    assert_true(df_cache_estimate_admm(1000, 2000) < df_cache_estimate_admm(10000, 20000));
    assert_true(df_cache_estimate_kelvinlet(10) < df_cache_estimate_kelvinlet(100));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sd_notify),
        cmocka_unit_test(test_sd_listen_fds),
        cmocka_unit_test(test_cache_lru_eviction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

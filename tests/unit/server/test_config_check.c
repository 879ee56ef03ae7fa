/* Unit tests for server/config_check.c (deformd --check-config) and the --check-config option of
 * server/config.c: a clean configuration has no problem; each problem (socket directory, socket
 * group, non-loopback tcp, allow_paths entry, unparsable hid_replay file, no listener) is counted
 * once and named by the config line that set the value in use, or "command line" when an
 * option overrode the file. */
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
#include "server/config_check.h"

static char g_dir[256];

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/df-cfgcheck-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void write_file(const char *name, const char *text, char *path, size_t cap)
{
    snprintf(path, cap, "%s/%s", g_dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Parses argv (NULL-terminated) and checks; returns the number of problems, report in out. */
static int run(const char *const *args, char *out, size_t cap, df_cli_action *action)
{
    char *argv[16];
    int argc = 0;
    argv[argc++] = (char *)"deformd";
    for (; *args; args++) argv[argc++] = (char *)*args;
    df_server_config cfg;
    df_error err;
    assert_int_equal(df_config_from_args(&cfg, argc, argv, NULL, action, &err), DF_OK);
    return df_config_check(&cfg, out, cap);
}

static void test_clean_configuration(void **state)
{
    (void)state;
    char conf[512], sock[512], out[4096];
    snprintf(sock, sizeof sock, "--socket=%s/s.sock", g_dir);
    write_file("ok.conf", "log_level = debug\nallow_paths = /tmp\ntcp = 127.0.0.1:0\n", conf,
               sizeof conf);
    df_cli_action action = DF_CLI_RUN;
    const char *args[] = {"--check-config", "--config", conf, sock, NULL};
    assert_int_equal(run(args, out, sizeof out, &action), 0);
    assert_int_equal(action, DF_CLI_CHECK);
    assert_string_equal(out, "");
    const char *args2[] = {"--config", conf, sock, NULL}; /* without the option: a run */
    assert_int_equal(run(args2, out, sizeof out, &action), 0);
    assert_int_equal(action, DF_CLI_RUN);
}

static void test_each_problem_names_its_line(void **state)
{
    (void)state;
    char conf[512], bad[512], out[8192], text[2048], want[1024];
    write_file("bad.hid", "not a recording\n", bad, sizeof bad);
    snprintf(text, sizeof text,
             "# line 1\n"
             "socket = %s/no-such-dir/s.sock\n"          /* 2 */
             "socket_group = df-no-such-group-xyz\n"      /* 3 */
             "tcp = 10.1.2.3:7878\n"                      /* 4 */
             "allow_paths = /tmp\n"                       /* 5: fine */
             "allow_paths = /df-no-such-dir-xyz\n"        /* 6 */
             "hid = off\n"
             "hid_replay = %s\n",                         /* 8 */
             g_dir, bad);
    write_file("bad.conf", text, conf, sizeof conf);
    df_cli_action action;
    const char *args[] = {"--config", conf, NULL};
    assert_int_equal(run(args, out, sizeof out, &action), 5);
    const int lines[] = {2, 3, 4, 6, 8};
    const char *keys[] = {"socket ", "socket_group:", "tcp ", "allow_paths:", "hid_replay:"};
    for (int i = 0; i < 5; i++) {
        snprintf(want, sizeof want, "%s:%d: %s", conf, lines[i], keys[i]);
        assert_non_null(strstr(out, want));
    }
    assert_null(strstr(out, ":5: "));
    /* an option overriding the file is named as the command line; the file's line is not */
    char sock[512];
    snprintf(sock, sizeof sock, "--socket=%s/other-missing/s.sock", g_dir);
    const char *args2[] = {"--config", conf, sock, "--tcp-insecure", NULL};
    assert_int_equal(run(args2, out, sizeof out, &action), 4);
    assert_non_null(strstr(out, "command line: socket "));
    snprintf(want, sizeof want, "%s:2:", conf);
    assert_null(strstr(out, want));
    assert_null(strstr(out, "tcp ")); /* --tcp-insecure allows the address */
}

static void test_no_listener_and_truncation(void **state)
{
    (void)state;
    char out[4096];
    df_cli_action action;
    const char *args[] = {"--socket", "none", NULL};
    unsetenv("LISTEN_FDS");
    assert_int_equal(run(args, out, sizeof out, &action), 1);
    assert_non_null(strstr(out, "command line: no listener"));
    char tiny[8];
    assert_int_equal(run(args, tiny, sizeof tiny, &action), 1); /* counted, text cut short */
    assert_int_equal(strlen(tiny), sizeof tiny - 1);
    assert_int_equal(run(args, NULL, 0, &action), 1);
}

static void test_cluster_needs_store_and_address(void **state)
{
    (void)state;
    char conf[512], sock[512], out[4096];
    df_cli_action action;
    snprintf(sock, sizeof sock, "--socket=%s/s.sock", g_dir);
    write_file("cl.conf", "cluster = redis://127.0.0.1:6379\nstore = none\n", conf, sizeof conf);
    const char *args[] = {"--config", conf, sock, NULL};
    assert_int_equal(run(args, out, sizeof out, &action), 2);
    assert_non_null(strstr(out, "cl.conf:1: cluster: needs a local store"));
    assert_non_null(strstr(out, "cl.conf:1: cluster: needs advertise"));
    write_file("cl2.conf", "cluster = redis://127.0.0.1:6379\nadvertise = h:1\n", conf,
               sizeof conf);
    assert_int_equal(run(args, out, sizeof out, &action), 0);
    assert_string_equal(out, "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean_configuration),
        cmocka_unit_test(test_each_problem_names_its_line),
        cmocka_unit_test(test_no_listener_and_truncation),
        cmocka_unit_test(test_cluster_needs_store_and_address),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

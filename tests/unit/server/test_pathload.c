/* Unit tests for server/session/pathload.c (issue 9, items 1 and 2): every file read for a client, both
 * halves of a TetGen pair included, is checked on its resolved path against allow_paths; a symlink
 * out of the allowed folder, a missing file and a disallowed file all give the same "not allowed
 * or not found" without the resolved path; FIFOs and devices are refused at once; the size cap
 * holds before reading; parse errors never quote file content; T1.NODE finds T1.ELE; an unknown
 * extension names the formats. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/session/pathload.h"

static const char *SECRET = "root:*:19000:0:99999:7:::\n";
static const char *NODE = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
static const char *ELE = "1 4 0\n1 1 2 3 4\n";

typedef struct fixture {
    char allowed[64], outside[64];
    df_server_config cfg;
} fixture;

static void put(const char *dir, const char *name, const char *text)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void link_to(const char *dir, const char *name, const char *target)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    assert_int_equal(symlink(target, p), 0);
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    snprintf(f->allowed, sizeof f->allowed, "/tmp/df_pl_allowed_XXXXXX");
    snprintf(f->outside, sizeof f->outside, "/tmp/df_pl_outside_XXXXXX");
    assert_non_null(mkdtemp(f->allowed));
    assert_non_null(mkdtemp(f->outside));
    df_config_defaults(&f->cfg, NULL);
    char *real = realpath(f->allowed, NULL);
    f->cfg.n_allow = 1;
    snprintf(f->cfg.allow_paths[0], sizeof f->cfg.allow_paths[0], "%s", real);
    free(real);
    put(f->outside, "shadow", SECRET);
    put(f->outside, "x.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    char cmd[200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' '%s'", f->allowed, f->outside);
    assert_int_equal(system(cmd), 0);
    free(f);
    return 0;
}

static int load(fixture *f, const char *name, df_mesh *m, df_error *e)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", f->allowed, name);
    df_mesh_init(m);
    memset(e, 0, sizeof *e);
    return df_pathload_mesh(&f->cfg, p, 0, 1000, 0, m, NULL, NULL, e);
}

static void test_tetgen_halves_are_both_checked(void **state)
{
    fixture *f = *state;
    char target[128];
    snprintf(target, sizeof target, "%s/shadow", f->outside);
    put(f->allowed, "X.node", NODE);
    link_to(f->allowed, "X.ele", target); /* the reported attack: content leaked before */
    df_mesh m;
    df_error e;
    assert_int_equal(load(f, "X.node", &m, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "not allowed or not found"));
    assert_null(strstr(e.msg, "root"));
    assert_null(strstr(e.msg, f->outside));
    assert_null(m.V);
    /* the .ele given, the .node a symlink out */
    put(f->allowed, "Y.ele", ELE);
    snprintf(target, sizeof target, "%s/x.obj", f->outside);
    link_to(f->allowed, "Y.node", target);
    assert_int_equal(load(f, "Y.ele", &m, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "not allowed or not found"));
    /* and a plain file outside, reached by a symlink named .obj */
    link_to(f->allowed, "out.obj", target);
    assert_int_equal(load(f, "out.obj", &m, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "not allowed or not found"));
}

static void test_missing_and_disallowed_read_the_same(void **state)
{
    fixture *f = *state;
    df_mesh m;
    df_error missing, outside, proc;
    assert_int_equal(load(f, "nothing.obj", &m, &missing), DF_EIO);
    char p[256];
    snprintf(p, sizeof p, "%s/x.obj", f->outside);
    df_mesh_init(&m);
    assert_int_equal(df_pathload_mesh(&f->cfg, p, 0, 1000, 0, &m, NULL, NULL, &outside), DF_EIO);
    assert_int_equal(df_pathload_mesh(&f->cfg, "/proc/self/cwd/x.obj", 0, 1000, 0, &m, NULL, NULL, &proc),
                     DF_EIO);
    assert_int_equal(missing.code, outside.code);
    assert_non_null(strstr(missing.msg, "not allowed or not found"));
    assert_non_null(strstr(outside.msg, "not allowed or not found"));
    assert_string_equal(proc.msg,
                        "load_mesh: /proc/self/cwd/x.obj: not allowed or not found (config "
                        "allow_paths)");
    char *cwd = getcwd(NULL, 0);
    assert_null(strstr(proc.msg, cwd)); /* no resolved path */
    free(cwd);
}

static void test_fifo_device_and_size_cap(void **state)
{
    fixture *f = *state;
    char p[256];
    snprintf(p, sizeof p, "%s/F.obj", f->allowed);
    assert_int_equal(mkfifo(p, 0600), 0);
    df_mesh m;
    df_error e;
    assert_int_equal(load(f, "F.obj", &m, &e), DF_EIO); /* blocked a worker forever before */
    assert_non_null(strstr(e.msg, "not a regular file"));
    snprintf(p, sizeof p, "%s/zero.obj", f->allowed);
    assert_int_equal(symlink("/dev/zero", p), 0);
    assert_int_equal(load(f, "zero.obj", &m, &e), DF_EIO); /* outside the allowed folder */
    /* a device inside an allowed folder: allow /dev for this check */
    df_server_config dev = f->cfg;
    snprintf(dev.allow_paths[0], sizeof dev.allow_paths[0], "/dev");
    assert_int_equal(df_pathload_mesh(&dev, "/dev/zero", DF_FMT_OBJ, 1000, 0, &m, NULL, NULL, &e),
                     DF_EIO);
    assert_non_null(strstr(e.msg, "not a regular file"));
    put(f->allowed, "big.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    snprintf(p, sizeof p, "%s/big.obj", f->allowed);
    char *buf = NULL;
    size_t len = 0;
    assert_int_equal(df_pathload_read(&f->cfg, p, 10, &buf, &len, &e), DF_ELIMIT);
    assert_null(buf);
    assert_int_equal(df_pathload_read(&f->cfg, p, 1000, &buf, &len, &e), DF_OK);
    assert_int_equal(len, 32);
    free(buf);
    df_server_config none = f->cfg;
    none.n_allow = 0;
    assert_int_equal(df_pathload_read(&none, p, 1000, &buf, &len, &e), DF_EUNSUPPORTED);
}

static void test_parse_errors_do_not_quote_the_file(void **state)
{
    fixture *f = *state;
    put(f->allowed, "S.node", NODE);
    put(f->allowed, "S.ele", SECRET);
    put(f->allowed, "s.obj", "v root:*:19000 0 0\n");
    put(f->allowed, "s.off", SECRET);
    df_mesh m;
    df_error e;
    const char *names[] = {"S.node", "s.obj", "s.off"};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(load(f, names[i], &m, &e), DF_EFORMAT);
        if (strstr(e.msg, "root"))
            fail_msg("%s: quoted: %s", names[i], e.msg);
    }
}

static void test_case_kept_and_unknown_extension(void **state)
{
    fixture *f = *state;
    put(f->allowed, "T1.NODE", NODE);
    put(f->allowed, "T1.ELE", ELE);
    df_mesh m;
    df_mesh_report r;
    df_error e;
    char p[256];
    snprintf(p, sizeof p, "%s/T1.NODE", f->allowed);
    df_mesh_init(&m);
    int rc = df_pathload_mesh(&f->cfg, p, 0, 1000, 0, &m, &r, NULL, &e);
    if (rc)
        fail_msg("%s", e.msg);
    assert_int_equal(m.kind, DF_MESH_TET);
    assert_int_equal(r.format, DF_FMT_TETGEN);
    df_mesh_free(&m);
    put(f->allowed, "m.stl", "solid x\n");
    assert_int_equal(load(f, "m.stl", &m, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "not recognised"));
    assert_non_null(strstr(e.msg, ".obj"));
    assert_non_null(strstr(e.msg, ".node + .ele"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_tetgen_halves_are_both_checked, setup, teardown),
        cmocka_unit_test_setup_teardown(test_missing_and_disallowed_read_the_same, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_fifo_device_and_size_cap, setup, teardown),
        cmocka_unit_test_setup_teardown(test_parse_errors_do_not_quote_the_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_case_kept_and_unknown_extension, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

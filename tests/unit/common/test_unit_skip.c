/* Unit tests of the unit tests' skip helper (tests/unit/unit_skip.c): outside CI a missing
 * prerequisite skips the test; with CI=true the same call fails it, so CI runs are never thinned
 * out silently. Each case runs a one-test cmocka group in a forked child (its output captured, so
 * the child's PASSED/FAILED/SKIPPED lines do not reach tests/run_tests.sh's counts). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "tests/unit/unit_skip.h"

static void child_skips(void **state)
{
    (void)state;
    unit_skip("prerequisite %s missing", "/nonexistent/meshes");
}

static void child_needs_mesh(void **state)
{
    (void)state;
    char p[256];
    unit_mesh_or_skip("bunny.off", p, sizeof p);
    fail_msg("unit_mesh_or_skip returned for a missing file");
}

/* Runs `fn` as a one-test group in a child with CI=`ci` (NULL: unset) and MESHES pointing nowhere;
 * returns the child's exit status (cmocka: number of failed tests) and its output in `out`. */
static int run_child(void (*fn)(void **), const char *ci, char *out, size_t cap)
{
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        dup2(fds[1], 1);
        dup2(fds[1], 2);
        close(fds[0]);
        if (ci) setenv("CI", ci, 1);
        else unsetenv("CI");
        setenv("MESHES", "/nonexistent/deformd-meshes", 1);
        const struct CMUnitTest one[] = {cmocka_unit_test(fn)};
        int failed = cmocka_run_group_tests_name("child", one, NULL, NULL);
        fflush(stdout);
        _exit(failed > 100 ? 100 : failed);
    }
    close(fds[1]);
    size_t n = 0;
    ssize_t r;
    while (n + 1 < cap && (r = read(fds[0], out + n, cap - 1 - n)) > 0) n += (size_t)r;
    out[n] = '\0';
    close(fds[0]);
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    assert_true(WIFEXITED(st));
    return WEXITSTATUS(st);
}

static void test_skip_outside_ci(void **state)
{
    (void)state;
    static char out[8192];
    assert_int_equal(run_child(child_skips, NULL, out, sizeof out), 0);
    assert_non_null(strstr(out, "skipping: prerequisite /nonexistent/meshes missing"));
    assert_non_null(strstr(out, "SKIPPED"));
    assert_null(strstr(out, "FAILED"));
    assert_int_equal(run_child(child_skips, "false", out, sizeof out), 0);
    assert_non_null(strstr(out, "SKIPPED"));
}

static void test_skip_is_failure_under_ci(void **state)
{
    (void)state;
    static char out[8192];
    assert_int_equal(run_child(child_skips, "true", out, sizeof out), 1);
    assert_non_null(strstr(out, "CI=true"));
    assert_non_null(strstr(out, "prerequisite /nonexistent/meshes missing"));
    assert_non_null(strstr(out, "FAILED"));
}

static void test_missing_mesh_file(void **state)
{
    (void)state;
    static char out[8192];
    assert_int_equal(run_child(child_needs_mesh, NULL, out, sizeof out), 0);
    assert_non_null(strstr(out, "/nonexistent/deformd-meshes/bunny.off not found"));
    assert_int_equal(run_child(child_needs_mesh, "true", out, sizeof out), 1);
    assert_non_null(strstr(out, "/nonexistent/deformd-meshes/bunny.off not found"));
}

static void test_ci_flag(void **state)
{
    (void)state;
    const char *old = getenv("CI");
    char *keep = old ? strdup(old) : NULL;
    setenv("CI", "true", 1);
    assert_int_equal(unit_ci(), 1);
    setenv("CI", "1", 1);
    assert_int_equal(unit_ci(), 0);
    unsetenv("CI");
    assert_int_equal(unit_ci(), 0);
    if (keep) setenv("CI", keep, 1);
    free(keep);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_skip_outside_ci),
        cmocka_unit_test(test_skip_is_failure_under_ci),
        cmocka_unit_test(test_missing_mesh_file),
        cmocka_unit_test(test_ci_flag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

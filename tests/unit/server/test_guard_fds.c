/* Unit tests of df_guard_fd_limit (server/net/guard.c): the daemon raises its soft
 * RLIMIT_NOFILE to what max_clients needs, never above the hard limit and never downwards.
 * Each test sets this process's limits first and computes what to expect from them. The last
 * test lowers the hard limit, which cannot be undone: it runs last. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <cmocka.h>

#include "server/net/guard.h"
#include "tests/unit/unit_skip.h"

static struct rlimit limits(void)
{
    struct rlimit rl;
    assert_int_equal(getrlimit(RLIMIT_NOFILE, &rl), 0);
    return rl;
}

static void set_soft(rlim_t soft)
{
    struct rlimit rl = limits();
    rl.rlim_cur = soft;
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &rl), 0);
}

static void test_raises_the_soft_limit_to_what_max_clients_needs(void **state)
{
    (void)state;
    struct rlimit rl = limits();
    rlim_t need = 300 + DF_GUARD_FD_RESERVE;
    if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < need)
        unit_skip("hard RLIMIT_NOFILE %llu is below %llu", (unsigned long long)rl.rlim_max,
                  (unsigned long long)need);
    set_soft(100);
    assert_int_equal(df_guard_fd_limit(300), (long)need);
    assert_int_equal(limits().rlim_cur, need);
    assert_int_equal(limits().rlim_max, rl.rlim_max); /* the hard limit is left alone */
}

static void test_never_lowers_the_soft_limit(void **state)
{
    (void)state;
    struct rlimit rl = limits();
    if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < 1000)
        unit_skip("hard RLIMIT_NOFILE %llu is below 1000", (unsigned long long)rl.rlim_max);
    set_soft(1000);
    assert_int_equal(df_guard_fd_limit(10), 1000);
    assert_int_equal(limits().rlim_cur, 1000);
    assert_int_equal(df_guard_fd_limit(1000 - DF_GUARD_FD_RESERVE), 1000); /* exactly enough */
}

static void test_stops_at_the_hard_limit(void **state)
{
    (void)state;
    struct rlimit rl = limits();
    if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < 200)
        unit_skip("hard RLIMIT_NOFILE %llu is below 200", (unsigned long long)rl.rlim_max);
    rl.rlim_cur = 100;
    rl.rlim_max = 200; /* irreversible without privileges: this test runs last */
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &rl), 0);
    assert_int_equal(df_guard_fd_limit(5000), 200); /* as far as it goes (a warning is logged) */
    assert_int_equal(limits().rlim_cur, 200);
    assert_int_equal(limits().rlim_max, 200);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_raises_the_soft_limit_to_what_max_clients_needs),
        cmocka_unit_test(test_never_lowers_the_soft_limit),
        cmocka_unit_test(test_stops_at_the_hard_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

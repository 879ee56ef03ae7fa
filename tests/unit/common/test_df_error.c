/* Unit tests for core/common/df_error: codes, messages, truncation, NULL tolerance. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "core/common/df_error.h"

static void test_set_formats_and_returns_code(void **state)
{
    (void)state;
    df_error e;
    df_error_clear(&e);
    int rc = df_error_set(&e, DF_EINVAL, "radius %g <= 0", -1.5);
    assert_int_equal(rc, DF_EINVAL);
    assert_int_equal(e.code, DF_EINVAL);
    assert_string_equal(e.msg, "radius -1.5 <= 0");
    assert_string_equal(df_error_name(e.code), "EINVAL");
}

static void test_null_error_is_tolerated(void **state)
{
    (void)state;
    assert_int_equal(df_error_set(NULL, DF_EIO, "x"), DF_EIO);
    df_error_clear(NULL);
}

static void test_long_message_is_truncated(void **state)
{
    (void)state;
    df_error e;
    char big[1000];
    memset(big, 'a', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    df_error_set(&e, DF_EFORMAT, "%s", big);
    assert_int_equal(strlen(e.msg), DF_ERROR_MSG_MAX - 1);
    assert_string_equal(df_error_name(12345), "EUNKNOWN");
    assert_string_equal(df_error_name(DF_EEXIST), "EEXIST");
    assert_string_equal(df_error_name(DF_EPERM), "EPERM");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_set_formats_and_returns_code),
        cmocka_unit_test(test_null_error_is_tolerated),
        cmocka_unit_test(test_long_message_is_truncated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Unit tests for server/text.c: UTF-8 validation, name checks and log escaping (issue 9 item 5),
 * and that df_log writes one escaped line. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/log.h"
#include "server/text.h"

static void test_utf8_validation(void **state)
{
    (void)state;
    assert_true(df_text_utf8_valid("", 0));
    assert_true(df_text_utf8_valid("plain", 5));
    assert_true(df_text_utf8_valid("\xc3\xa9\xe2\x9c\x93\xf0\x9f\x98\x80", 9)); /* é ✓ 😀 */
    assert_false(df_text_utf8_valid("\xff", 1));
    assert_false(df_text_utf8_valid("\xc3", 1));             /* truncated */
    assert_false(df_text_utf8_valid("\xc0\xaf", 2));         /* overlong '/' */
    assert_false(df_text_utf8_valid("\xed\xa0\x80", 3));     /* surrogate */
    assert_false(df_text_utf8_valid("\xf4\x90\x80\x80", 4)); /* > U+10FFFF */
    assert_false(df_text_utf8_valid("a\x80", 2));            /* stray continuation */
}

static void test_name_check(void **state)
{
    (void)state;
    df_error e;
    assert_int_equal(df_text_check_name("name", "grille-\xc3\xa9", &e), DF_OK);
    assert_int_equal(df_text_check_name("name", "", &e), DF_OK);
    assert_int_equal(df_text_check_name("load_mesh: name", "a\xff", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "load_mesh: name is not valid UTF-8"));
    assert_int_equal(df_text_check_name("name", "a\nb", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "U+000A"));
    assert_int_equal(df_text_check_name("name", "\x7f", &e), DF_EINVAL);
    assert_int_equal(df_text_check_name("name", "\xc2\x9b", &e), DF_EINVAL); /* C1 CSI */
}

static void test_escape(void **state)
{
    (void)state;
    char out[64];
    assert_int_equal(df_text_escape(out, sizeof out, "ok \xc3\xa9"), 5);
    assert_string_equal(out, "ok \xc3\xa9");
    df_text_escape(out, sizeof out, "a\nb\x1b[2J\r\x7f");
    assert_string_equal(out, "a\\x0ab\\x1b[2J\\x0d\\x7f");
    df_text_escape(out, sizeof out, "x\xff\xc2\x9by");
    assert_string_equal(out, "x\\xff\\xc2\\x9by");
    /* truncation never splits a character or an escape */
    char small[6];
    df_text_escape(small, sizeof small, "ab\n\n");
    assert_string_equal(small, "ab");
    df_text_escape(small, sizeof small, "a\xe2\x9c\x93\xe2\x9c\x93");
    assert_string_equal(small, "a\xe2\x9c\x93");
    df_text_escape(small, 1, "abc");
    assert_string_equal(small, "");
}

static void test_log_line_is_escaped(void **state)
{
    (void)state;
    FILE *tmp = tmpfile();
    assert_non_null(tmp);
    fflush(stderr);
    int saved = dup(2);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(tmp), 2) >= 0);
    df_log(DF_LOG_WARN, "client 'x\ndeformd[error]: forged\x1b[31m'");
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    char buf[256] = {0};
    rewind(tmp);
    size_t n = fread(buf, 1, sizeof buf - 1, tmp);
    fclose(tmp);
    assert_true(n > 0);
    assert_string_equal(buf, "deformd[warn]: client 'x\\x0adeformd[error]: forged\\x1b[31m'\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_utf8_validation),
        cmocka_unit_test(test_name_check),
        cmocka_unit_test(test_escape),
        cmocka_unit_test(test_log_line_is_escaped),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Unit tests for client/dc_cli: option table parsing, typed values, HOST:PORT, default socket. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "client/dc_cli.h"

static const dc_cli_opt OPTS[] = {
    {"type", 1, "--type grab|twist"},
    {"center", 1, "--center X,Y,Z"},
    {"json", 0, "--json"},
    {"nu", 1, "--nu NU"},
};
#define NOPTS ((int)(sizeof OPTS / sizeof OPTS[0]))

static void test_parse_values_flags_positionals(void **state)
{
    (void)state;
    char *argv[] = {"s1", "--type", "grab", "--center=-1,0.5,2", "--json", "--nu", "-0.25"};
    dc_cli_args a;
    df_error e;
    assert_int_equal(dc_cli_parse(7, argv, OPTS, NOPTS, 1, &a, &e), DF_OK);
    assert_int_equal(a.npos, 1);
    assert_string_equal(a.pos[0], "s1");
    assert_string_equal(a.val[0], "grab");
    assert_string_equal(a.val[1], "-1,0.5,2");
    assert_string_equal(a.val[2], "");
    assert_string_equal(a.val[3], "-0.25");
    assert_int_equal(a.help, 0);
}

static void test_parse_errors(void **state)
{
    (void)state;
    dc_cli_args a;
    df_error e;
    char *unknown[] = {"--typo", "x"};
    assert_int_equal(dc_cli_parse(2, unknown, OPTS, NOPTS, 2, &a, &e), DF_EINVAL);
    assert_string_equal(e.msg, "unknown option '--typo'");
    char *missing[] = {"--type"};
    assert_int_equal(dc_cli_parse(1, missing, OPTS, NOPTS, 0, &a, &e), DF_EINVAL);
    assert_string_equal(e.msg, "option '--type' needs a value");
    char *twice[] = {"--json", "--json"};
    assert_int_equal(dc_cli_parse(2, twice, OPTS, NOPTS, 0, &a, &e), DF_EINVAL);
    assert_string_equal(e.msg, "option '--json' given twice");
    char *flagval[] = {"--json=1"};
    assert_int_equal(dc_cli_parse(1, flagval, OPTS, NOPTS, 0, &a, &e), DF_EINVAL);
    char *toomany[] = {"a", "b"};
    assert_int_equal(dc_cli_parse(2, toomany, OPTS, NOPTS, 1, &a, &e), DF_EINVAL);
    assert_string_equal(e.msg, "unexpected argument 'b'");
    char *shortopt[] = {"-x"};
    assert_int_equal(dc_cli_parse(1, shortopt, OPTS, NOPTS, 1, &a, &e), DF_EINVAL);
}

static void test_help_wins_and_double_dash(void **state)
{
    (void)state;
    dc_cli_args a;
    df_error e;
    char *h[] = {"--bogus", "--help"};
    assert_int_equal(dc_cli_parse(2, h, OPTS, NOPTS, 0, &a, &e), DF_OK);
    assert_int_equal(a.help, 1);
    char *dd[] = {"--", "--help"};
    assert_int_equal(dc_cli_parse(2, dd, OPTS, NOPTS, 1, &a, &e), DF_OK);
    assert_int_equal(a.help, 0);
    assert_int_equal(a.npos, 1);
    assert_string_equal(a.pos[0], "--help");
}

static void test_numbers(void **state)
{
    (void)state;
    df_error e;
    double d = 0;
    assert_int_equal(dc_cli_double("2.5e-1", "--nu", 0, &d, &e), DF_OK);
    assert_true(d == 0.25);
    assert_int_equal(dc_cli_double("inf", "--nu", 1, &d, &e), DF_OK);
    assert_true(isinf(d) && d > 0);
    assert_int_equal(dc_cli_double("Infinity", "--nu", 1, &d, &e), DF_OK);
    assert_true(isinf(d) && d > 0);
    assert_int_equal(dc_cli_double("+inf", "--nu", 1, &d, &e), DF_OK);
    assert_true(isinf(d) && d > 0);
    assert_int_equal(dc_cli_double("-inf", "--nu", 1, &d, &e), DF_OK);
    assert_true(isinf(d) && d < 0);
    assert_int_equal(dc_cli_double("-Infinity", "--nu", 1, &d, &e), DF_OK);
    assert_true(isinf(d) && d < 0);
    d = 7;
    assert_int_equal(dc_cli_double("-inf", "--radius", 0, &d, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--radius: '-inf' must be finite");
    assert_true(d == 7);
    d = 7;
    assert_int_equal(dc_cli_double("inf", "--radius", 0, &d, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--radius: 'inf' must be finite");
    assert_true(d == 7);
    assert_int_equal(dc_cli_double("nan", "--radius", 1, &d, &e), DF_EINVAL);
    assert_int_equal(dc_cli_double("1.5x", "--radius", 1, &d, &e), DF_EINVAL);
    assert_int_equal(dc_cli_double("1e999", "--radius", 1, &d, &e), DF_EINVAL);
    assert_int_equal(dc_cli_double("", "--radius", 1, &d, &e), DF_EINVAL);
    long long i = 0;
    assert_int_equal(dc_cli_int("42", "--steps", 1, 100, &i, &e), DF_OK);
    assert_int_equal(i, 42);
    assert_int_equal(dc_cli_int("0", "--steps", 1, 100, &i, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--steps: 0 out of range 1..100");
    assert_int_equal(dc_cli_int("4.0", "--steps", 1, 100, &i, &e), DF_EINVAL);
    assert_int_equal(dc_cli_int("99999999999999999999", "--steps", 1, 100, &i, &e), DF_EINVAL);
    assert_int_equal(i, 42);
}

static void test_vectors(void **state)
{
    (void)state;
    df_error e;
    double v[9];
    assert_int_equal(dc_cli_vec("1,-2.5,3e2", "--center", 3, v, &e), DF_OK);
    assert_true(v[0] == 1 && v[1] == -2.5 && v[2] == 300);
    assert_int_equal(dc_cli_vec("1,0,0,0,1,0,0,0,1", "--matrix", 9, v, &e), DF_OK);
    assert_true(v[0] == 1 && v[4] == 1 && v[8] == 1 && v[1] == 0);
    v[0] = 5;
    assert_int_equal(dc_cli_vec("1,2", "--center", 3, v, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--center: '1,2' has 2 numbers, expected 3");
    assert_int_equal(dc_cli_vec("1,2,3,4", "--center", 3, v, &e), DF_EINVAL);
    assert_int_equal(dc_cli_vec("1,,3", "--center", 3, v, &e), DF_EINVAL);
    assert_int_equal(dc_cli_vec("1,2,", "--center", 3, v, &e), DF_EINVAL);
    assert_int_equal(dc_cli_vec("1,inf,3", "--center", 3, v, &e), DF_EINVAL);
    assert_int_equal(dc_cli_vec("1,nan,3", "--center", 3, v, &e), DF_EINVAL);
    assert_true(v[0] == 5);
}

static void test_choice_and_hostport(void **state)
{
    (void)state;
    df_error e;
    static const char *const types[] = {"grab", "twist", "scale", "pinch", "affine", NULL};
    assert_int_equal(dc_cli_choice("pinch", "--type", types, &e), 3);
    assert_int_equal(dc_cli_choice("grip", "--type", types, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--type: 'grip' is not one of grab|twist|scale|pinch|affine");
    char host[64];
    int port = 0;
    assert_int_equal(dc_cli_hostport("127.0.0.1:7000", host, sizeof host, &port, &e), DF_OK);
    assert_string_equal(host, "127.0.0.1");
    assert_int_equal(port, 7000);
    assert_int_equal(dc_cli_hostport("[::1]:65535", host, sizeof host, &port, &e), DF_OK);
    assert_string_equal(host, "::1");
    assert_int_equal(port, 65535);
    assert_int_equal(dc_cli_hostport("localhost", host, sizeof host, &port, &e), DF_EINVAL);
    assert_int_equal(dc_cli_hostport(":80", host, sizeof host, &port, &e), DF_EINVAL);
    assert_int_equal(dc_cli_hostport("h:0", host, sizeof host, &port, &e), DF_EINVAL);
    assert_int_equal(dc_cli_hostport("h:65536", host, sizeof host, &port, &e), DF_EINVAL);
    assert_int_equal(dc_cli_hostport("[::1]80", host, sizeof host, &port, &e), DF_EINVAL);
    /* the messages name --tcp and the value */
    assert_int_equal(dc_cli_hostport("127.0.0.1", host, sizeof host, &port, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--tcp: '127.0.0.1' is not HOST:PORT");
    assert_int_equal(dc_cli_hostport(":99999", host, sizeof host, &port, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "':99999' has no host"));
    assert_int_equal(dc_cli_hostport("h:abc", host, sizeof host, &port, &e), DF_EINVAL);
    assert_string_equal(e.msg, "--tcp port: 'abc' is not an integer");
}

static void test_socket_path(void **state)
{
    (void)state;
    df_error e;
    char longp[200];
    memset(longp, 'a', sizeof longp - 1);
    longp[sizeof longp - 1] = '\0';
    assert_int_equal(dc_cli_socket_path("/tmp/d.sock", &e), DF_OK);
    assert_int_equal(dc_cli_socket_path("", &e), DF_EINVAL);
    assert_string_equal(e.msg, "--socket: empty path");
    assert_int_equal(dc_cli_socket_path(NULL, &e), DF_EINVAL);
    assert_int_equal(dc_cli_socket_path(longp, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "--socket: path of 199 bytes is too long"));
}

static void test_default_socket(void **state)
{
    (void)state;
    df_error e;
    char buf[128];
    setenv("DEFORMD_SOCKET", "/tmp/x.sock", 1);
    assert_int_equal(dc_cli_default_socket(buf, sizeof buf, &e), DF_OK);
    assert_string_equal(buf, "/tmp/x.sock");
    unsetenv("DEFORMD_SOCKET");
    setenv("XDG_RUNTIME_DIR", "/run/user/1000", 1);
    assert_int_equal(dc_cli_default_socket(buf, sizeof buf, &e), DF_OK);
    assert_string_equal(buf, "/run/user/1000/deformd.sock");
    assert_int_equal(dc_cli_default_socket(buf, 10, &e), DF_ELIMIT);
    unsetenv("XDG_RUNTIME_DIR");
    assert_int_equal(dc_cli_default_socket(buf, sizeof buf, &e), DF_OK);
    assert_string_equal(buf, "/run/deformd/deformd.sock");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_values_flags_positionals),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_help_wins_and_double_dash),
        cmocka_unit_test(test_numbers),
        cmocka_unit_test(test_vectors),
        cmocka_unit_test(test_choice_and_hostport),
        cmocka_unit_test(test_default_socket),
        cmocka_unit_test(test_socket_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

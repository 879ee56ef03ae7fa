/* Unit tests of proto/auth_mac.c (AUTH, PROTOCOL.md 4.3): the HMAC-SHA256 wrapper against the
 * RFC 4231 test vectors, df_auth_mac as HMAC over Ns || Nc || context (composed here with the
 * wrapper), the constant-time comparison, nonces, and the key file rules (mode, length, trailing
 * newline; an error leaves the outputs untouched). */
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

#include "proto/auth_mac.h"

static void unhex(const char *s, uint8_t *out, size_t n)
{
    assert_int_equal(strlen(s), 2 * n);
    for (size_t i = 0; i < n; i++) {
        unsigned v;
        assert_int_equal(sscanf(s + 2 * i, "%2x", &v), 1);
        out[i] = (uint8_t)v;
    }
}

/* RFC 4231 section 4: HMAC-SHA-256 of test cases 1..7 (case 5 compares the first 128 bits). */
static void test_rfc4231_vectors(void **state)
{
    (void)state;
    uint8_t k0b[20], kaa20[20], k0c[20], k25[25], kaa131[131], ddd[50], cdd[50];
    memset(k0b, 0x0b, sizeof k0b);
    memset(kaa20, 0xaa, sizeof kaa20);
    memset(k0c, 0x0c, sizeof k0c);
    for (int i = 0; i < 25; i++) k25[i] = (uint8_t)(i + 1);
    memset(kaa131, 0xaa, sizeof kaa131);
    memset(ddd, 0xdd, sizeof ddd);
    memset(cdd, 0xcd, sizeof cdd);
    static const char t6[] = "Test Using Larger Than Block-Size Key - Hash Key First";
    static const char t7[] = "This is a test using a larger than block-size key and a larger than "
                             "block-size data. The key needs to be hashed before being used by "
                             "the HMAC algorithm.";
    const struct {
        const uint8_t *key;
        size_t klen;
        const uint8_t *msg;
        size_t mlen;
        const char *mac;
        size_t cmp;
    } v[] = {
        {k0b, 20, (const uint8_t *)"Hi There", 8,
         "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7", 32},
        {(const uint8_t *)"Jefe", 4, (const uint8_t *)"what do ya want for nothing?", 28,
         "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843", 32},
        {kaa20, 20, ddd, 50, "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe",
         32},
        {k25, 25, cdd, 50, "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b",
         32},
        {k0c, 20, (const uint8_t *)"Test With Truncation", 20, "a3b6167473100ee06e0c796c2955552b",
         16},
        {kaa131, 131, (const uint8_t *)t6, sizeof t6 - 1,
         "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54", 32},
        {kaa131, 131, (const uint8_t *)t7, sizeof t7 - 1,
         "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2", 32},
    };
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        uint8_t want[32], got[32];
        df_error e;
        unhex(v[i].mac, want, v[i].cmp);
        assert_int_equal(df_auth_hmac_sha256(v[i].key, v[i].klen, v[i].msg, v[i].mlen, got, &e),
                         DF_OK);
        assert_memory_equal(got, want, v[i].cmp);
        assert_true(df_auth_equal(got, want, v[i].cmp)); /* the server's comparison path */
    }
}

static void test_mac_is_hmac_of_nonces_and_context(void **state)
{
    (void)state;
    const uint8_t key[] = "a key of at least thirty-two bytes, for the test";
    uint8_t ns[32], nc[32], msg[64 + 64], want[32], got[32], other[32];
    for (int i = 0; i < 32; i++) ns[i] = (uint8_t)(0x40 + i), nc[i] = (uint8_t)(0x20 + i);
    df_error e;
    const char *ctx[2] = {"deformd-auth-v1 client", "deformd-auth-v1 server"};
    for (int role = 0; role < 2; role++) {
        size_t cl = strlen(ctx[role]);
        memcpy(msg, ns, 32);
        memcpy(msg + 32, nc, 32);
        memcpy(msg + 64, ctx[role], cl);
        assert_int_equal(df_auth_hmac_sha256(key, sizeof key - 1, msg, 64 + cl, want, &e), DF_OK);
        assert_int_equal(df_auth_mac(key, sizeof key - 1, ns, nc, (df_auth_role)role, got, &e),
                         DF_OK);
        assert_memory_equal(got, want, 32);
    }
    /* the two roles differ, and swapping the nonces changes the MAC (no reflection) */
    assert_int_equal(df_auth_mac(key, sizeof key - 1, ns, nc, DF_AUTH_ROLE_CLIENT, got, &e), DF_OK);
    assert_int_equal(df_auth_mac(key, sizeof key - 1, ns, nc, DF_AUTH_ROLE_SERVER, other, &e),
                     DF_OK);
    assert_false(df_auth_equal(got, other, 32));
    assert_int_equal(df_auth_mac(key, sizeof key - 1, nc, ns, DF_AUTH_ROLE_CLIENT, other, &e),
                     DF_OK);
    assert_false(df_auth_equal(got, other, 32));
    assert_int_equal(df_auth_mac(key, sizeof key - 1, ns, nc, (df_auth_role)7, got, &e), DF_EINVAL);
    assert_int_equal(df_auth_hmac_sha256(NULL, 3, msg, 1, got, &e), DF_EINVAL);
}

static void test_equal_compares_every_byte(void **state)
{
    (void)state;
    uint8_t a[32], b[32];
    for (int i = 0; i < 32; i++) a[i] = b[i] = (uint8_t)(i * 7);
    assert_true(df_auth_equal(a, b, 32));
    assert_true(df_auth_equal(a, b, 0));
    for (int i = 0; i < 32; i++) { /* a difference at any position, first and last included */
        b[i] ^= 0x80;
        assert_false(df_auth_equal(a, b, 32));
        b[i] ^= 0x80;
    }
}

static void test_random_nonces_differ(void **state)
{
    (void)state;
    uint8_t a[32], b[32];
    df_error e;
    assert_int_equal(df_auth_random(a, sizeof a, &e), DF_OK);
    assert_int_equal(df_auth_random(b, sizeof b, &e), DF_OK);
    assert_false(df_auth_equal(a, b, 32)); /* 2^-256 */
}

/* Writes `text` to a fresh temp file with `mode`; returns its path in buf. */
static void key_file(char *buf, size_t cap, const char *text, size_t len, mode_t mode)
{
    snprintf(buf, cap, "/tmp/df_test_key_XXXXXX");
    int fd = mkstemp(buf);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, text, len), (ssize_t)len);
    close(fd);
    assert_int_equal(chmod(buf, mode), 0);
}

static void test_key_file_rules(void **state)
{
    (void)state;
    char path[64];
    uint8_t key[DF_AUTH_KEY_CAP_BYTES];
    size_t len = 12345;
    df_error e;
    const char hex[] = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
    /* trailing CR LF, blanks removed; group-readable is fine */
    char text[128];
    snprintf(text, sizeof text, "%s \r\n", hex);
    key_file(path, sizeof path, text, strlen(text), 0640);
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_OK);
    assert_int_equal(len, 64);
    assert_memory_equal(key, hex, 64);
    /* readable by others: refused, outputs untouched */
    memset(key, 0x5a, sizeof key);
    len = 12345;
    assert_int_equal(chmod(path, 0644), 0);
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "readable or writable by others"));
    assert_non_null(strstr(e.msg, path));
    assert_int_equal(len, 12345);
    assert_int_equal(key[0], 0x5a);
    assert_int_equal(chmod(path, 0602), 0); /* writable by others */
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_EINVAL);
    unlink(path);
    /* 31 bytes (after the newline is stripped): too short; 32 fine */
    key_file(path, sizeof path, "0123456789abcdef0123456789abcde\n", 32, 0600);
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "31 bytes is too short"));
    unlink(path);
    key_file(path, sizeof path, "0123456789abcdef0123456789abcdef", 32, 0600);
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_OK);
    assert_int_equal(len, 32);
    unlink(path);
    /* too long */
    static char big[DF_AUTH_KEY_CAP_BYTES + 2];
    memset(big, 'k', sizeof big);
    key_file(path, sizeof path, big, sizeof big, 0600);
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "longer than"));
    unlink(path);
    /* missing file, a directory */
    assert_int_equal(df_auth_key_load(path, key, sizeof key, &len, &e), DF_EIO);
    assert_non_null(strstr(e.msg, path));
    assert_int_equal(df_auth_key_load("/tmp", key, sizeof key, &len, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "not a regular file"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rfc4231_vectors),
        cmocka_unit_test(test_mac_is_hmac_of_nonces_and_context),
        cmocka_unit_test(test_equal_compares_every_byte),
        cmocka_unit_test(test_random_nonces_differ),
        cmocka_unit_test(test_key_file_rules),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* test_codec_delta — the store's packed change deltas (server/store/codec.h): a bit-exact round
 * trip on random and adversarial bit patterns (NaN payloads, -0.0, denormals, infinities), a
 * corrupt or truncated packed blob refused with nothing written, and the packed layout's size
 * against the raw one on a fixed brush workload (the ratio computed from the data). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"
#include "server/store/codec.h"

static uint64_t rng(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static double from_bits(uint64_t u)
{
    double d;
    memcpy(&d, &u, 8);
    return d;
}

/* Changed vertices of old -> now, counted independently of the codec. */
static uint32_t changed(const double *a, const double *b, int32_t nv)
{
    uint32_t c = 0;
    for (int32_t i = 0; i < nv; i++) c += memcmp(a + 3 * i, b + 3 * i, 24) != 0;
    return c;
}

static uint32_t first_u32(const uint8_t *b)
{
    uint32_t u;
    memcpy(&u, b, 4);
    return u;
}

/* Encodes old -> now, applies to a copy of old: must give now bit for bit. Returns the blob. */
static uint8_t *round_trip(const double *old, const double *now, int32_t nv, size_t *len)
{
    uint8_t *d;
    df_error e;
    assert_int_equal(df_codec_delta_encode(old, now, nv, &d, len, &e), DF_OK);
    double *c = malloc(24 * (size_t)nv);
    assert_non_null(c);
    memcpy(c, old, 24 * (size_t)nv);
    uint32_t n = 0;
    assert_int_equal(df_codec_delta_apply(d, *len, c, nv, &n, &e), DF_OK);
    assert_int_equal(n, changed(old, now, nv));
    assert_memory_equal(c, now, 24 * (size_t)nv);
    free(c);
    return d;
}

static const uint64_t special[] = {
    0x7ff8000000000000ull, /* quiet NaN */
    0x7ff0000000000001ull, /* signalling NaN */
    0xfff8dead0000beefull, /* negative NaN with a payload */
    0x7fffffffffffffffull, /* NaN, every payload bit */
    0x8000000000000000ull, /* -0.0 */
    0x0000000000000000ull, /* +0.0 */
    0x0000000000000001ull, /* smallest denormal */
    0x000fffffffffffffull, /* largest denormal */
    0x800fffffffffffffull, /* negative denormal */
    0x7ff0000000000000ull, /* +inf */
    0xfff0000000000000ull, /* -inf */
    0x7fefffffffffffffull, /* DBL_MAX */
};
#define NSPECIAL (sizeof special / sizeof special[0])

static void test_round_trip_random_and_adversarial(void **state)
{
    (void)state;
    const int32_t nv = 2000;
    double *old = malloc(24 * (size_t)nv), *now = malloc(24 * (size_t)nv);
    assert_non_null(old);
    assert_non_null(now);
    uint64_t s = 0x1234567u;
    for (int pass = 0; pass < 6; pass++) {
        for (size_t i = 0; i < 3 * (size_t)nv; i++) /* random bits: any pattern at all */
            old[i] = pass % 2 ? from_bits(rng(&s)) : from_bits(special[rng(&s) % NSPECIAL]);
        memcpy(now, old, 24 * (size_t)nv);
        for (size_t i = 0; i < 3 * (size_t)nv; i++) {
            uint64_t r = rng(&s) % 8, u;
            memcpy(&u, now + i, 8);
            if (pass >= 4) r = 1 + r % 3; /* every value changes: dense */
            if (r == 1) u ^= 1ull << (rng(&s) % 30 + 29);    /* a float32 mantissa bit */
            else if (r == 2) u = special[rng(&s) % NSPECIAL]; /* to a special pattern */
            else if (r == 3) u = rng(&s);                      /* to anything */
            else if (r == 4) u ^= 0x8000000000000000ull;       /* sign flip: -0.0 <-> +0.0 */
            now[i] = from_bits(u);
        }
        size_t len;
        uint8_t *d = round_trip(old, now, nv, &len);
        free(d);
        d = round_trip(now, old, nv, &len); /* and back */
        free(d);
    }
    /* a change of special patterns only, every vertex: small, so packed */
    for (size_t i = 0; i < 3 * (size_t)nv; i++) {
        old[i] = from_bits(special[i % NSPECIAL]);
        now[i] = from_bits(special[(i + 1) % NSPECIAL]);
    }
    size_t len;
    uint8_t *d = round_trip(old, now, nv, &len);
    assert_int_equal(first_u32(d), DF_CODEC_PACKED_MARKER);
    free(d);
    memcpy(now, old, 24 * (size_t)nv); /* no change: a raw header only */
    d = round_trip(old, now, nv, &len);
    assert_int_equal(len, 8);
    free(d);
    free(old);
    free(now);
}

static void test_corrupt_packed_blob_is_refused(void **state)
{
    (void)state;
    const int32_t nv = 500;
    double *old = malloc(24 * (size_t)nv), *now = malloc(24 * (size_t)nv);
    double *c = malloc(24 * (size_t)nv);
    assert_true(old && now && c);
    for (int32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            old[3 * i + k] = (double)(float)(0.001 * i + k);
            now[3 * i + k] = (double)(float)(old[3 * i + k] + 1e-6 * (i % 7));
        }
    size_t len;
    uint8_t *d = round_trip(old, now, nv, &len);
    assert_int_equal(first_u32(d), DF_CODEC_PACKED_MARKER);
    df_error e;
    for (size_t at = 0; at < len; at++) { /* every byte inverted in turn */
        d[at] ^= 0xff;
        memcpy(c, old, 24 * (size_t)nv);
        int rc = df_codec_delta_apply(d, len, c, nv, NULL, &e);
        if (rc != DF_EFORMAT) fail_msg("byte %zu of %zu inverted: rc %d", at, len, rc);
        assert_true(strstr(e.msg, "store: ") != NULL);
        assert_memory_equal(c, old, 24 * (size_t)nv); /* nothing written */
        d[at] ^= 0xff;
    }
    for (size_t cut = 0; cut < len; cut++) { /* every truncation */
        memcpy(c, old, 24 * (size_t)nv);
        assert_int_equal(df_codec_delta_apply(d, cut, c, nv, NULL, &e), DF_EFORMAT);
        assert_memory_equal(c, old, 24 * (size_t)nv);
    }
    memcpy(c, old, 24 * (size_t)nv);
    assert_int_equal(df_codec_delta_apply(d, len, c, nv + 1, NULL, &e), DF_EFORMAT); /* nv */
    free(d);
    free(old);
    free(now);
    free(c);
}

/* Fixed workload: 5 tri-scale local grab strokes on a 100 x 100 grid, each as the server
 * computes a brush version (float32 motion of the float32 start added to the doubles). */
static void test_packed_is_smaller_on_local_strokes(void **state)
{
    (void)state;
    const int n = 100;
    const int32_t nv = n * n;
    size_t nd = 3 * (size_t)nv;
    double *cur = malloc(nd * 8), *pos = malloc(nd * 8);
    float *x0 = malloc(nd * 4), *disp = malloc(nd * 4);
    assert_true(cur && pos && x0 && disp);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double *p = cur + 3 * ((size_t)j * n + i);
            p[0] = (float)i / (float)(n - 1);
            p[1] = (float)j / (float)(n - 1);
            p[2] = 0;
        }
    double raw = 0, packed = 0;
    for (int s = 0; s < 5; s++) {
        df_kelvinlet_brush b;
        df_kelvinlet_brush_defaults(&b);
        b.order = 3;
        b.radius = 0.03;
        b.centre[0] = 0.2 + 0.15 * s;
        b.centre[1] = 0.3 + 0.1 * s;
        b.tip[2] = 0.01;
        df_kelvinlet_prepared prep;
        df_error e;
        for (size_t i = 0; i < nd; i++) x0[i] = (float)cur[i];
        assert_int_equal(df_kelvinlet_prepare(&b, &prep, &e), DF_OK);
        prep.threads = 1;
        assert_int_equal(df_kelvinlet_displacements(&prep, x0, (size_t)nv, disp, &e), DF_OK);
        for (size_t i = 0; i < nd; i++) pos[i] = cur[i] + (double)((x0[i] + disp[i]) - x0[i]);
        uint32_t count = changed(cur, pos, nv);
        assert_true(count > (uint32_t)nv / 10); /* the workload is not trivially sparse */
        raw += 8.0 + (count == (uint32_t)nv ? 0 : 4.0 * count) + 24.0 * count;
        size_t len;
        uint8_t *d = round_trip(cur, pos, nv, &len);
        packed += (double)len;
        free(d);
        memcpy(cur, pos, nd * 8);
    }
    double ratio = raw / packed;
    print_message("raw %.0f B, packed %.0f B per change: %.1fx\n", raw / 5, packed / 5, ratio);
    assert_true(ratio >= 4.0);
    free(cur);
    free(pos);
    free(x0);
    free(disp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_random_and_adversarial),
        cmocka_unit_test(test_corrupt_packed_blob_is_refused),
        cmocka_unit_test(test_packed_is_smaller_on_local_strokes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

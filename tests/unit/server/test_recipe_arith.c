/* test_recipe_arith — stroke recipes recorded by a build before arithmetic version 2 replay bit
 * for bit (issue 14 item 6: the 2D grab of orders 1-3 moved from double sums to float32,
 * core/kelvinlet/kelvinlet_simd2d.h, which changes the bits of those strokes). The fixture
 * (fixtures/recipe_arith1.h) holds six 2D recipes — grab orders 1, 2, 3 at close and wide
 * radius ratios, a moving RK4 order-3 grab, a twist — as that build encoded them ('DSR2') and
 * the checksums of its replays from fixtures/recipe_arith1_from.h. Here: each blob decodes as
 * arithmetic 1 and its replay (1 and 2 threads) reproduces the old checksum; the same recipe
 * under the current arithmetic gives other bits for the grabs (so the check above could fail)
 * yet the same mesh to float rounding (within 2e-6 of the stroke's largest motion plus one
 * float ulp of the positions), and the
 * twist, whose arithmetic did not change, the same bits; a current recipe records its version
 * and replays to the live result's checksum. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/stroke_recipe.h"
#include "tests/unit/server/fixtures/recipe_arith1_from.h"
#include "tests/unit/server/fixtures/recipe_arith1.h"

#define TWIST 5 /* the fixture's affine recipe */

static void replay(const df_stroke_recipe *r, const double *from, int threads, double *to)
{
    df_error e;
    if (df_stroke_recipe_replay(r, from, FIX_NV, 1, threads, to, &e) != DF_OK)
        fail_msg("replay: %s", e.msg);
}

static void test_old_records_replay_bit_exact(void **st)
{
    (void)st;
    double *from = fixture_from(), *to = malloc(3 * FIX_NV * sizeof *to);
    assert_non_null(from);
    assert_non_null(to);
    for (int k = 0; k < FIX_N; k++) {
        df_stroke_recipe r;
        df_error e;
        assert_int_equal(df_stroke_recipe_decode(FIX_BLOB[k], FIX_BLOB_LEN, &r, &e), DF_OK);
        assert_int_equal(r.brush.arith, DF_KELVINLET_ARITH_1);
        assert_int_equal(r.brush.dim, 2);
        for (int threads = 1; threads <= 2; threads++) {
            replay(&r, from, threads, to);
            if (df_positions_checksum(to, 3 * FIX_NV) != FIX_SUM[k])
                fail_msg("recipe %d (order %d) on %d threads: checksum %016llx, recorded %016llx",
                         k, r.brush.order, threads,
                         (unsigned long long)df_positions_checksum(to, 3 * FIX_NV),
                         (unsigned long long)FIX_SUM[k]);
        }
        df_stroke_recipe_free(&r);
    }
    free(from);
    free(to);
}

static void test_current_arith_differs_by_rounding_only(void **st)
{
    (void)st;
    double *from = fixture_from(), *old = malloc(3 * FIX_NV * sizeof *old);
    double *cur = malloc(3 * FIX_NV * sizeof *cur);
    assert_non_null(from);
    assert_non_null(old);
    assert_non_null(cur);
    for (int k = 0; k < FIX_N; k++) {
        df_stroke_recipe r;
        assert_int_equal(df_stroke_recipe_decode(FIX_BLOB[k], FIX_BLOB_LEN, &r, NULL), DF_OK);
        replay(&r, from, 1, old);
        r.brush.arith = DF_KELVINLET_ARITH_CURRENT;
        replay(&r, from, 1, cur);
        double dmax = 0.0, umax = 0.0, pmax = 0.0;
        for (size_t i = 0; i < 3 * FIX_NV; i++) {
            dmax = fmax(dmax, fabs(cur[i] - old[i]));
            umax = fmax(umax, fabs(old[i] - from[i]));
            pmax = fmax(pmax, fabs(from[i]));
        }
        /* the motion is fl32(x0 + d) - x0: a field difference of float rounding may flip the
         * last bit of a float position (FLT_EPSILON pmax) on top of 2e-6 of the motion */
        print_message("# recipe %d (order %d): max |current - arith 1| %.2e = %.2f float ulps "
                      "of the positions, %.2e of max motion %.2e\n", k, r.brush.order, dmax,
                      dmax / (FLT_EPSILON * pmax), dmax / umax, umax);
        assert_true(umax > 1e-3);
        if (k == TWIST)
            assert_true(dmax == 0.0);
        else
            assert_true(dmax > 0.0 && dmax <= 2e-6 * umax + FLT_EPSILON * pmax);
        /* a recipe of the current build records its version and replays to its own bits */
        uint8_t *blob;
        size_t len;
        df_stroke_recipe back;
        assert_int_equal(df_stroke_recipe_encode(&r, &blob, &len, NULL), DF_OK);
        assert_int_equal(df_stroke_recipe_decode(blob, len, &back, NULL), DF_OK);
        assert_int_equal(back.brush.arith, DF_KELVINLET_ARITH_CURRENT);
        replay(&back, from, 2, old);
        assert_true(df_positions_checksum(old, 3 * FIX_NV) ==
                    df_positions_checksum(cur, 3 * FIX_NV));
        free(blob);
        df_stroke_recipe_free(&back);
        df_stroke_recipe_free(&r);
    }
    free(from);
    free(old);
    free(cur);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_old_records_replay_bit_exact),
        cmocka_unit_test(test_current_arith_differs_by_rounding_only),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Unit tests for the pin system's blocked LU (core/kelvinlet/kelvinlet_lu.c, issue 14 item 6):
 * on random matrices of sizes around the block and chunk widths (and one above the size where
 * the trailing updates are threaded) it solves A x = b to a small
 * backward error through LAPACK's dgetrs (so its factors are in dgetrf's layout), gives the
 * same bits on 1, 2 and 3 threads, restores OpenBLAS's thread count, and reports an exactly
 * singular column like dgetrf. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <cblas.h>
#include <lapacke.h>

#include "core/kelvinlet/kelvinlet_internal.h"

static double *random_matrix(int m, uint64_t seed)
{
    double *a = malloc((size_t)m * m * sizeof *a);
    assert_non_null(a);
    for (size_t i = 0; i < (size_t)m * m; i++) {
        seed ^= seed << 13; seed ^= seed >> 7; seed ^= seed << 17;
        a[i] = (double)(seed >> 11) * 0x1.0p-53 - 0.5;
    }
    return a;
}

static void test_solves_and_same_bits(void **state)
{
    (void)state;
    const int sizes[] = {1, 7, 64, 65, 130, 300, 481, 1100};   /* 1100: the threaded path */
    openblas_set_num_threads(2);
    int nb = openblas_get_num_threads();
    for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
        int m = sizes[z];
        double *a = random_matrix(m, 88172645463325252ull + (uint64_t)m);
        double *lu[3];
        int *piv[3];
        for (int t = 0; t < 3; t++) {
            lu[t] = malloc((size_t)m * m * sizeof *lu[t]);
            piv[t] = malloc((size_t)m * sizeof *piv[t]);
            memcpy(lu[t], a, (size_t)m * m * sizeof *a);
            assert_int_equal(dfk_lu_factor(m, lu[t], piv[t], t + 1), 0);
            assert_int_equal(openblas_get_num_threads(), nb);
            if (t > 0) {
                assert_memory_equal(lu[t], lu[0], (size_t)m * m * sizeof *a);
                assert_memory_equal(piv[t], piv[0], (size_t)m * sizeof *piv[0]);
            }
        }
        /* solve A x = b with dgetrs on our factors; residual |A x - b| / (|A| |x|) */
        double *x = malloc((size_t)m * sizeof *x), *b = malloc((size_t)m * sizeof *b);
        for (int i = 0; i < m; i++)
            x[i] = b[i] = sin(1.0 + i);
        assert_int_equal(LAPACKE_dgetrs(LAPACK_COL_MAJOR, 'N', m, 1, lu[0], m, piv[0], x, m), 0);
        double rmax = 0.0, amax = 0.0, xmax = 0.0;
        for (int i = 0; i < m; i++) {
            double r = -b[i];
            for (int k = 0; k < m; k++) {
                r += a[(size_t)k * m + i] * x[k];
                amax = fmax(amax, fabs(a[(size_t)k * m + i]));
            }
            rmax = fmax(rmax, fabs(r));
            xmax = fmax(xmax, fabs(x[i]));
        }
        double be = rmax / (amax * xmax * m);
        if (!(be < 1e-13))
            fail_msg("m %d: backward error %.2e", m, be);
        for (int t = 0; t < 3; t++) {
            free(lu[t]);
            free(piv[t]);
        }
        free(a);
        free(x);
        free(b);
    }
}

/* A zero column: U(j, j) = 0 exactly, reported as j + 1 (dgetrf's info). */
static void test_singular_column(void **state)
{
    (void)state;
    int m = 150, j = 97;
    double *a = random_matrix(m, 12345);
    for (int i = 0; i < m; i++)
        a[(size_t)j * m + i] = 0.0;
    int *piv = malloc((size_t)m * sizeof *piv);
    assert_int_equal(dfk_lu_factor(m, a, piv, 2), j + 1);
    free(a);
    free(piv);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solves_and_same_bits),
        cmocka_unit_test(test_singular_column),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

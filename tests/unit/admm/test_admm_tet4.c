/* Unit tests of the 4-lane tet kernels (core/admm/admm_tet4.c) against the scalar per-element
 * code they replace, bit for bit: local step 1 (ARAP, ACAP) against admm_local_x_one_G, the
 * dual update against the per-element formula, the energies against admm_element_energy_F and
 * the certificate's force norm against the per-element sum, on a tet bar with random positions (some
 * elements inverted or flattened, so both the closed-form lanes and the scalar SVD fallback
 * run inside one block), random duals, a shuffled element order and a count that is not a
 * multiple of 4 (the block tail); each kernel as the library has it (the clone the CPU picks) and
 * compiled here for the portable target. White-box: the solver's state through admm_internal.h. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/admm_internal.h"
#include "core/admm/svd3.h"
#include "tests/unit/admm/admm_test_util.h"

/* The kernels once more, compiled here for the portable target only (no target_clones: the
 * build's baseline, x86-64-v2 SSE), under other names, so that the clone the running CPU picks
 * in the library and the portable lowering are both held to the scalar bits */
#define DF_NO_TARGET_CLONES
#define admm_local_tet4 portable_local_tet4
#define admm_dual_tet4 portable_dual_tet4
#define admm_energy_tet4 portable_energy_tet4
#define admm_force_tet4 portable_force_tet4
void portable_local_tet4(df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *s2, double *z2);
void portable_dual_tet4(df_admm *s, const int32_t *ae, double *fb, int32_t n, int lazy, double *t);
void portable_energy_tet4(const df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *out);
double portable_force_tet4(const df_admm *s, const double *V, int32_t i);
#include "core/admm/admm_tet4.c"
#undef admm_local_tet4
#undef admm_dual_tet4
#undef admm_energy_tet4
#undef admm_force_tet4

static double urand(unsigned *seed) { return 2.0 * rand_r(seed) / (double)RAND_MAX - 1.0; }

typedef struct fixture {
    df_mesh m;
    df_admm *s;
    int32_t n, *ae;
    double *fb;
} fixture;

/* a 3 x 3 x 3 tet bar (162 elements) with the given energy, positions scrambled (every 5th
 * vertex thrown far: inverted and flattened elements), W and R X random, ae a shuffled subset of
 * n elements, fb their F_e(V) rows */
static void setup(fixture *f, df_admm_energy en, int32_t n)
{
    memset(f, 0, sizeof(*f));
    f->m = tu_bar3d(3, 3, 3, 1.0, 1.0, 1.0);
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1;
    int32_t h[2] = {0, f->m.nv - 1};
    df_error err;
    assert_int_equal(df_admm_create(&f->m, &p, h, 2, NULL, 0, &f->s, &err), DF_OK);
    df_admm *s = f->s;
    assert_int_equal(s->esz, 4);
    assert_int_equal(s->q, 3);
    unsigned seed = 7;
    for (int32_t i = 0; i < s->nv; i++)
        for (int c = 0; c < 3; c++)
            s->V[3 * (size_t)i + c] = s->Vrest[3 * (size_t)i + c] + (i % 5 == 0 ? 0.6 : 0.05) * urand(&seed);
    for (int64_t k = 0; k < 9 * (int64_t)s->ne; k++) {
        s->W[k] = 0.1 * urand(&seed);
        s->RX[k] = (k % 4 == 0) + 0.2 * urand(&seed);
    }
    f->n = n;
    f->ae = malloc((size_t)s->ne * sizeof(int32_t));
    f->fb = malloc((size_t)n * 9 * sizeof(double));
    for (int32_t e = 0; e < s->ne; e++) f->ae[e] = e;
    for (int32_t e = s->ne - 1; e > 0; e--) {
        int32_t j = rand_r(&seed) % (e + 1), t = f->ae[e];
        f->ae[e] = f->ae[j];
        f->ae[j] = t;
    }
    for (int32_t k = 0; k < n; k++) admm_element_F(s, s->V, f->ae[k], f->fb + 9 * (size_t)k);
}

static void teardown(fixture *f)
{
    df_admm_free(f->s);
    free(f->ae);
    free(f->fb);
    tu_free(&f->m);
}

static double *dup(const double *x, size_t n)
{
    double *y = malloc(n * sizeof(double));
    memcpy(y, x, n * sizeof(double));
    return y;
}

static void local_matches(df_admm_energy en)
{
    fixture f;
    setup(&f, en, 158); /* 39 blocks and a tail of 2 */
    df_admm *s = f.s;
    size_t nrx = 9 * (size_t)s->ne, nce = 12 * (size_t)s->ne;
    double *rx0 = dup(s->RX, nrx), *ce0 = dup(s->Ce, nce);
    /* the scalar reference, summed in ae order */
    double s2 = 0, z2 = 0;
    int inverted = 0;
    for (int32_t k = 0; k < f.n; k++) {
        int32_t e = f.ae[k];
        double G[9], old[9], ds = 0, dz = 0;
        for (int c = 0; c < 9; c++) G[c] = f.fb[9 * (size_t)k + c] + s->W[9 * (size_t)e + c];
        inverted += !(admm_det3(G) > 0);
        memcpy(old, s->RX + 9 * (size_t)e, sizeof(old));
        admm_local_x_one_G(s, e, G);
        for (int c = 0; c < 9; c++) {
            double d = s->RX[9 * (size_t)e + c] - old[c];
            ds += d * d;
            dz += s->RX[9 * (size_t)e + c] * s->RX[9 * (size_t)e + c];
        }
        s2 += s->gam[e] * ds;
        z2 += s->gam[e] * dz;
    }
    assert_true(inverted > 0 && inverted < f.n / 2); /* both paths inside the blocks */
    double *rx1 = dup(s->RX, nrx), *ce1 = dup(s->Ce, nce);
    for (int pass = 0; pass < 2; pass++) { /* the library's clone, then the portable build */
        memcpy(s->RX, rx0, nrx * sizeof(double));
        memcpy(s->Ce, ce0, nce * sizeof(double));
        double s2v = 0, z2v = 0;
        (pass ? portable_local_tet4 : admm_local_tet4)(s, f.ae, f.fb, f.n, &s2v, &z2v);
        assert_memory_equal(s->RX, rx1, nrx * sizeof(double));
        assert_memory_equal(s->Ce, ce1, nce * sizeof(double));
        assert_memory_equal(&s2v, &s2, sizeof(double));
        assert_memory_equal(&z2v, &z2, sizeof(double));
    }
    free(rx0); free(ce0); free(rx1); free(ce1);
    teardown(&f);
}

static void test_local_arap(void **st) { (void)st; local_matches(DF_ADMM_ARAP); }
static void test_local_acap(void **st) { (void)st; local_matches(DF_ADMM_ACAP); }

/* the dual update: W, the F rows and the four terms per element (energy on and lazy) */
static void test_dual(void **st)
{
    (void)st;
    for (int lazy = 0; lazy < 2; lazy++) {
        fixture f;
        setup(&f, DF_ADMM_ARAP, 161);
        df_admm *s = f.s;
        size_t nw = 9 * (size_t)s->ne;
        double *w0 = dup(s->W, nw), *fr = malloc((size_t)f.n * 9 * sizeof(double));
        double *tr = malloc((size_t)f.n * 4 * sizeof(double)), *tv = malloc((size_t)f.n * 4 * sizeof(double));
        for (int32_t k = 0; k < f.n; k++) {
            int32_t e = f.ae[k];
            double F[9], er = 0, ea = 0, ey = 0, *W = s->W + 9 * (size_t)e;
            admm_element_F(s, s->V, e, F);
            for (int c = 0; c < 9; c++) {
                double dw = F[c] - s->RX[9 * (size_t)e + c];
                W[c] += dw;
                er += dw * dw; ea += F[c] * F[c]; ey += W[c] * W[c];
            }
            memcpy(fr + 9 * (size_t)k, F, sizeof(F));
            double *t = tr + 4 * (size_t)k;
            t[0] = s->gam[e] * er; t[1] = s->gam[e] * ea; t[2] = s->gam[e] * ey;
            t[3] = lazy ? 0.0 : admm_element_energy_F(s, e, F);
        }
        double *w1 = dup(s->W, nw);
        for (int pass = 0; pass < 2; pass++) {
            memcpy(s->W, w0, nw * sizeof(double));
            memset(f.fb, 0, (size_t)f.n * 9 * sizeof(double));
            (pass ? portable_dual_tet4 : admm_dual_tet4)(s, f.ae, f.fb, f.n, lazy, tv);
            assert_memory_equal(s->W, w1, nw * sizeof(double));
            assert_memory_equal(f.fb, fr, (size_t)f.n * 9 * sizeof(double));
            assert_memory_equal(tv, tr, (size_t)f.n * 4 * sizeof(double));
        }
        free(w0); free(w1); free(fr); free(tr); free(tv);
        teardown(&f);
    }
}

/* the elastic energies from F rows against admm_element_energy_F (ARAP, ACAP) */
static void test_energy(void **st)
{
    (void)st;
    static const df_admm_energy en[2] = {DF_ADMM_ARAP, DF_ADMM_ACAP};
    for (int k = 0; k < 2; k++) {
        fixture f;
        setup(&f, en[k], 157);
        double *ref = malloc((size_t)f.n * sizeof(double)), *vec = malloc((size_t)f.n * sizeof(double));
        int fallback = 0;
        for (int32_t i = 0; i < f.n; i++) {
            ref[i] = admm_element_energy_F(f.s, f.ae[i], f.fb + 9 * (size_t)i);
            fallback += !(admm_det3(f.fb + 9 * (size_t)i) > 0);
        }
        assert_true(fallback > 0);
        admm_energy_tet4(f.s, f.ae, f.fb, f.n, vec);
        assert_memory_equal(vec, ref, (size_t)f.n * sizeof(double));
        portable_energy_tet4(f.s, f.ae, f.fb, f.n, vec);
        assert_memory_equal(vec, ref, (size_t)f.n * sizeof(double));
        free(ref); free(vec);
        teardown(&f);
    }
}

/* the certificate's force norm: the per-element sum of admm_active.c (vol_e (F - sc R) g_corner
 * over the moved elements around i) against admm_force_tet4, every vertex, with a third of the
 * vertices put back exactly at rest (unmoved elements skipped) */
static double force_ref(const df_admm *s, const double *V, int32_t i)
{
    double f[3] = {0, 0, 0};
    for (int32_t p = s->ve_ptr[i]; p < s->ve_ptr[i + 1]; p++) {
        int32_t e = s->ve_ent[p] / 4, corner = s->ve_ent[p] % 4;
        const int32_t *el = s->E + 4 * (size_t)e;
        int moved = 0;
        for (int c = 0; c < 4; c++) moved |= memcmp(V + 3 * (size_t)el[c], s->Vrest + 3 * (size_t)el[c], 3 * sizeof(double)) != 0;
        if (!moved) continue;
        double F[9], R[9], P[9], sc = 1.0;
        admm_element_F(s, V, e, F);
        if (df_admm_polar3(F, R) != 0) {
            double U[9], sg[3], Vm[9];
            df_admm_svd3(F, U, sg, Vm);
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++)
                    R[3 * r + c] = U[3 * r] * Vm[3 * c] + U[3 * r + 1] * Vm[3 * c + 1] + U[3 * r + 2] * Vm[3 * c + 2];
        }
        if (s->p.energy == DF_ADMM_ACAP) {
            double tS = 0;
            for (int k = 0; k < 9; k++) tS += R[k] * F[k];
            sc = tS / 3.0;
        }
        for (int k = 0; k < 9; k++) P[k] = F[k] - sc * R[k];
        const double *gc = s->grad + (size_t)e * 12 + 3 * corner;
        for (int r = 0; r < 3; r++) f[r] += s->vol[e] * (P[3 * r] * gc[0] + P[3 * r + 1] * gc[1] + P[3 * r + 2] * gc[2]);
    }
    return sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}

static void test_force(void **st)
{
    (void)st;
    static const df_admm_energy en[2] = {DF_ADMM_ARAP, DF_ADMM_ACAP};
    for (int k = 0; k < 2; k++) {
        fixture f;
        setup(&f, en[k], 4);
        df_admm *s = f.s;
        for (int32_t i = 0; i < s->nv; i += 3) memcpy(s->V + 3 * (size_t)i, s->Vrest + 3 * (size_t)i, 3 * sizeof(double));
        int zero = 0;
        for (int32_t i = 0; i < s->nv; i++) {
            double a = force_ref(s, s->V, i), b = admm_force_tet4(s, s->V, i), c = portable_force_tet4(s, s->V, i);
            assert_memory_equal(&a, &b, sizeof(double));
            assert_memory_equal(&a, &c, sizeof(double));
            zero += a == 0.0;
        }
        assert_true(zero < s->nv / 4);
        teardown(&f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_local_arap),
        cmocka_unit_test(test_local_acap),
        cmocka_unit_test(test_dual),
        cmocka_unit_test(test_energy),
        cmocka_unit_test(test_force),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

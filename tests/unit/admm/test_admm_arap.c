/* Unit tests of the ARAP paths of the SC-L1 ADMM on synthetic meshes: with w = 0 it reaches the
 * energy of an independent, straightforward local-global ARAP written here (2D spokes-and-rims
 * with cotangent weights; per-element tets), handles land exactly on their targets, the objective
 * never increases by more than 1e-9 (relative) between iterations, one analysis/factorization per
 * solver and none per target, warm starts converge faster than cold starts, the progress callback
 * and the time budget stop a run, and reset_rest makes the current shape the rest. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/svd3.h"
#include "tests/unit/admm/admm_test_util.h"

/* ---------- independent reference ARAP (dense, handles eliminated) ---------- */

/* 2D spokes-and-rims: cells = all edges of the triangles around each vertex, half-cot weights */
static double ref_cot(const double *V, int a, int b, int c) /* half cot of angle at a */
{
    double u[2] = {V[3 * b] - V[3 * a], V[3 * b + 1] - V[3 * a + 1]};
    double v[2] = {V[3 * c] - V[3 * a], V[3 * c + 1] - V[3 * a + 1]};
    return 0.5 * (u[0] * v[0] + u[1] * v[1]) / fabs(u[0] * v[1] - u[1] * v[0]);
}

static double ref_arap2d(const df_mesh *m, const int32_t *h, int nh, const double *tg, double *V, int iters)
{
    int n = m->nv;
    char *isH = calloc((size_t)n, 1);
    for (int k = 0; k < nh; k++) isH[h[k]] = 1;
    double *K = calloc((size_t)n * n, sizeof(double));
    double *R = calloc((size_t)n * 4, sizeof(double));
    double *B = calloc((size_t)2 * n, sizeof(double));
    double *A = malloc((size_t)n * n * sizeof(double));
    const double *X = m->V;
    /* K */
    for (int e = 0; e < m->ne; e++)
        for (int c = 0; c < 3; c++) {
            int i = m->E[3 * e + (c + 1) % 3], j = m->E[3 * e + (c + 2) % 3];
            double w = 3 * ref_cot(X, m->E[3 * e + c], i, j); /* each triangle edge is in 3 cells */
            K[i * n + i] += w; K[j * n + j] += w; K[i * n + j] -= w; K[j * n + i] -= w;
        }
    for (int k = 0; k < nh; k++) { V[3 * h[k]] = tg[3 * k]; V[3 * h[k] + 1] = tg[3 * k + 1]; }
    double E = 0;
    for (int it = 0; it < iters; it++) {
        /* local: per-vertex rotation */
        memset(R, 0, (size_t)n * 4 * sizeof(double));
        double *M = calloc((size_t)n * 4, sizeof(double));
        for (int e = 0; e < m->ne; e++)
            for (int c = 0; c < 3; c++) {
                int i = m->E[3 * e + (c + 1) % 3], j = m->E[3 * e + (c + 2) % 3];
                double w = ref_cot(X, m->E[3 * e + c], i, j);
                double d[2] = {V[3 * j] - V[3 * i], V[3 * j + 1] - V[3 * i + 1]};
                double r[2] = {X[3 * j] - X[3 * i], X[3 * j + 1] - X[3 * i + 1]};
                for (int q = 0; q < 3; q++) {
                    int o = m->E[3 * e + q];
                    M[4 * o] += w * d[0] * r[0]; M[4 * o + 1] += w * d[0] * r[1];
                    M[4 * o + 2] += w * d[1] * r[0]; M[4 * o + 3] += w * d[1] * r[1];
                }
            }
        for (int o = 0; o < n; o++) {
            double a = M[4 * o] + M[4 * o + 3], b = M[4 * o + 2] - M[4 * o + 1], nn = sqrt(a * a + b * b);
            double cs = a / nn, sn = b / nn;
            R[4 * o] = cs; R[4 * o + 1] = -sn; R[4 * o + 2] = sn; R[4 * o + 3] = cs;
        }
        free(M);
        /* energy at V with these (optimal) rotations */
        E = 0;
        for (int e = 0; e < m->ne; e++)
            for (int c = 0; c < 3; c++) {
                int i = m->E[3 * e + (c + 1) % 3], j = m->E[3 * e + (c + 2) % 3];
                double w = ref_cot(X, m->E[3 * e + c], i, j);
                double d[2] = {V[3 * j] - V[3 * i], V[3 * j + 1] - V[3 * i + 1]};
                double r[2] = {X[3 * j] - X[3 * i], X[3 * j + 1] - X[3 * i + 1]};
                for (int q = 0; q < 3; q++) {
                    const double *Ro = R + 4 * m->E[3 * e + q];
                    double ex = Ro[0] * r[0] + Ro[1] * r[1] - d[0], ey = Ro[2] * r[0] + Ro[3] * r[1] - d[1];
                    E += 0.5 * w * (ex * ex + ey * ey);
                }
            }
        /* global */
        memset(B, 0, (size_t)2 * n * sizeof(double));
        for (int e = 0; e < m->ne; e++)
            for (int c = 0; c < 3; c++) {
                int i = m->E[3 * e + (c + 1) % 3], j = m->E[3 * e + (c + 2) % 3];
                double w = ref_cot(X, m->E[3 * e + c], i, j);
                double r[2] = {X[3 * j] - X[3 * i], X[3 * j + 1] - X[3 * i + 1]};
                for (int q = 0; q < 3; q++) {
                    const double *Ro = R + 4 * m->E[3 * e + q];
                    double b0 = w * (Ro[0] * r[0] + Ro[1] * r[1]), b1 = w * (Ro[2] * r[0] + Ro[3] * r[1]);
                    B[j] += b0; B[n + j] += b1; B[i] -= b0; B[n + i] -= b1;
                }
            }
        /* eliminate handles: rows/cols of handles -> identity, rhs -> target */
        memcpy(A, K, (size_t)n * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            if (isH[i]) continue;
            for (int j = 0; j < n; j++)
                if (isH[j]) { B[i] -= K[i * n + j] * V[3 * j]; B[n + i] -= K[i * n + j] * V[3 * j + 1]; }
        }
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++)
                if (isH[i] || isH[j]) A[i * n + j] = (i == j) ? 1.0 : 0.0;
        for (int i = 0; i < n; i++) if (isH[i]) { B[i] = V[3 * i]; B[n + i] = V[3 * i + 1]; }
        assert_int_equal(tu_chol_solve(A, B, n, 2), 0);
        for (int i = 0; i < n; i++) { V[3 * i] = B[i]; V[3 * i + 1] = B[n + i]; V[3 * i + 2] = 0; }
    }
    free(isH); free(K); free(R); free(B); free(A);
    return E;
}

/* 3D per-element ARAP, E = sum vol / 2 |F - R|^2 with R the polar rotation of F */
static double ref_arap_tet(const df_mesh *m, const int32_t *h, int nh, const double *tg, double *V, int iters)
{
    int n = m->nv;
    char *isH = calloc((size_t)n, 1);
    for (int k = 0; k < nh; k++) isH[h[k]] = 1;
    double *G = malloc((size_t)m->ne * 12 * sizeof(double)), *vol = malloc((size_t)m->ne * sizeof(double));
    double *K = calloc((size_t)n * n, sizeof(double)), *A = malloc((size_t)n * n * sizeof(double));
    double *B = malloc((size_t)3 * n * sizeof(double));
    for (int e = 0; e < m->ne; e++) {
        const int32_t *el = m->E + 4 * e;
        double D[9];
        for (int a = 1; a <= 3; a++)
            for (int k = 0; k < 3; k++) D[3 * k + a - 1] = m->V[3 * el[a] + k] - m->V[3 * el[0] + k];
        double det = D[0] * (D[4] * D[8] - D[5] * D[7]) - D[1] * (D[3] * D[8] - D[5] * D[6]) + D[2] * (D[3] * D[7] - D[4] * D[6]);
        vol[e] = det / 6;
        /* inverse by Gauss-Jordan */
        double M[18];
        for (int i = 0; i < 3; i++) for (int j = 0; j < 6; j++) M[6 * i + j] = j < 3 ? D[3 * i + j] : (j - 3 == i);
        for (int c = 0; c < 3; c++) {
            int p = c;
            for (int r = c + 1; r < 3; r++) if (fabs(M[6 * r + c]) > fabs(M[6 * p + c])) p = r;
            for (int j = 0; j < 6; j++) { double t = M[6 * c + j]; M[6 * c + j] = M[6 * p + j]; M[6 * p + j] = t; }
            double d = M[6 * c + c];
            for (int j = 0; j < 6; j++) M[6 * c + j] /= d;
            for (int r = 0; r < 3; r++) if (r != c) { double f = M[6 * r + c]; for (int j = 0; j < 6; j++) M[6 * r + j] -= f * M[6 * c + j]; }
        }
        double *g = G + 12 * e;
        for (int k = 0; k < 3; k++) { g[k] = 0; }
        for (int a = 1; a <= 3; a++)
            for (int k = 0; k < 3; k++) { g[3 * a + k] = M[6 * (a - 1) + 3 + k]; g[k] -= g[3 * a + k]; }
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++)
                K[el[a] * n + el[b]] += vol[e] * (g[3 * a] * g[3 * b] + g[3 * a + 1] * g[3 * b + 1] + g[3 * a + 2] * g[3 * b + 2]);
    }
    for (int k = 0; k < nh; k++) memcpy(V + 3 * h[k], tg + 3 * k, 3 * sizeof(double));
    double E = 0;
    for (int it = 0; it < iters; it++) {
        memset(B, 0, (size_t)3 * n * sizeof(double));
        E = 0;
        for (int e = 0; e < m->ne; e++) {
            const int32_t *el = m->E + 4 * e;
            const double *g = G + 12 * e;
            double F[9] = {0}, U[9], sg[3], Vm[9], R[9];
            for (int a = 0; a < 4; a++)
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 3; c++) F[3 * r + c] += V[3 * el[a] + r] * g[3 * a + c];
            df_admm_svd3(F, U, sg, Vm);
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) R[3 * r + c] = U[3 * r] * Vm[3 * c] + U[3 * r + 1] * Vm[3 * c + 1] + U[3 * r + 2] * Vm[3 * c + 2];
            for (int k = 0; k < 9; k++) E += 0.5 * vol[e] * (F[k] - R[k]) * (F[k] - R[k]);
            for (int a = 0; a < 4; a++)
                for (int r = 0; r < 3; r++)
                    B[(size_t)r * n + el[a]] += vol[e] * (R[3 * r] * g[3 * a] + R[3 * r + 1] * g[3 * a + 1] + R[3 * r + 2] * g[3 * a + 2]);
        }
        memcpy(A, K, (size_t)n * n * sizeof(double));
        for (int i = 0; i < n; i++) {
            if (isH[i]) continue;
            for (int j = 0; j < n; j++)
                if (isH[j]) for (int r = 0; r < 3; r++) B[(size_t)r * n + i] -= K[i * n + j] * V[3 * j + r];
        }
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++)
                if (isH[i] || isH[j]) A[i * n + j] = (i == j) ? 1.0 : 0.0;
        for (int i = 0; i < n; i++) if (isH[i]) for (int r = 0; r < 3; r++) B[(size_t)r * n + i] = V[3 * i + r];
        assert_int_equal(tu_chol_solve(A, B, n, 3), 0);
        for (int i = 0; i < n; i++) for (int r = 0; r < 3; r++) V[3 * i + r] = B[(size_t)r * n + i];
    }
    free(isH); free(G); free(vol); free(K); free(A); free(B);
    return E;
}

/* ---------- scenarios ---------- */

/* 2D strip [0,2]x[0,0.5]: left column fixed, right column lifted by 0.6 */
static void strip2d(df_mesh *m, int32_t **h, int *nh, double **tg)
{
    *m = tu_grid2d(12, 3, 2.0, 0.5);
    *nh = 0;
    *h = malloc(8 * sizeof(int32_t));
    *tg = malloc(8 * 3 * sizeof(double));
    for (int j = 0; j <= 3; j++) {
        int32_t l = j * 13, r = j * 13 + 12;
        (*h)[*nh] = l; memcpy(*tg + 3 * *nh, m->V + 3 * l, 24); (*nh)++;
        (*h)[*nh] = r; memcpy(*tg + 3 * *nh, m->V + 3 * r, 24); (*tg)[3 * *nh + 1] += 0.6; (*nh)++;
    }
}

/* Runs plain ADMM (w = 0, one thread, to tol 1e-14) on m with handles h at targets tg and checks it
 * against the reference local-global ARAP result Vr of energy Eref: the solver's evaluation of Vr
 * equals Eref (same energy definition), its objective equals Eref (same minimum) and its positions
 * are within 1e-4 of Vr. */
static void expect_reference_arap(const char *label, df_mesh *m, const int32_t *h, int nh,
                                  const double *tg, const double *Vr, double Eref)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 0.0;
    p.rho = 1e-3;
    p.tol = 1e-14;
    p.max_iters = 3000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    double Eours;
    assert_int_equal(df_admm_evaluate(s, Vr, &Eours, NULL, &err), DF_OK);
    double maxd = 0;
    for (int i = 0; i < m->nv; i++) maxd = fmax(maxd, tu_dist(df_admm_positions(s) + 3 * i, Vr + 3 * i));
    printf("%s ARAP: ADMM (w = 0) E = %.10g in %d its, reference local-global E = %.10g (our evaluation %.10g), max |dV| %.2e\n",
           label, r.objective, r.iterations, Eref, Eours, maxd);
    assert_true(Eref > 1e-3);
    assert_true(fabs(Eours - Eref) < 1e-9 * Eref);         /* same energy definition */
    assert_true(fabs(r.objective - Eref) < 1e-6 * Eref);   /* same minimum */
    assert_true(maxd < 1e-4);
    df_admm_free(s);
}

static void test_plain_arap_2d_matches_reference(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    strip2d(&m, &h, &nh, &tg);
    double *Vr = malloc((size_t)m.nv * 3 * sizeof(double));
    memcpy(Vr, m.V, (size_t)m.nv * 3 * sizeof(double));
    double Eref = ref_arap2d(&m, h, nh, tg, Vr, 400);
    expect_reference_arap("2D", &m, h, nh, tg, Vr, Eref);
    free(Vr); free(h); free(tg); tu_free(&m);
}

static void test_plain_arap_tet_matches_reference(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    double *Vr = malloc((size_t)m.nv * 3 * sizeof(double));
    memcpy(Vr, m.V, (size_t)m.nv * 3 * sizeof(double));
    double Eref = ref_arap_tet(&m, h, nh, tg, Vr, 300);
    expect_reference_arap("tet", &m, h, nh, tg, Vr, Eref);
    free(Vr); free(h); free(tg); tu_free(&m);
}

typedef struct mono {
    double prev, worst;
    int calls;
} mono;

static int mono_cb(void *user, const df_admm_progress *pr)
{
    mono *mo = user;
    if (mo->calls > 0) {
        double inc = (pr->objective - mo->prev) / fabs(mo->prev);
        if (inc > mo->worst) mo->worst = inc;
    }
    mo->prev = pr->objective;
    mo->calls++;
    return 0;
}

static void check_monotone(df_mesh *m, int32_t *h, int nh, double *tg, df_admm_energy en, double w, double sth, double rho, int its)
{
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = w; p.s = sth; p.rho = rho; p.max_iters = its; p.tol = 0;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    mono mo = {0, -INFINITY, 0};
    df_admm_budget b = {its, 0, 1, mono_cb, &mo};
    df_admm_result r;
    assert_int_equal(df_admm_run(s, &b, &r, &err), DF_OK);
    printf("monotone (%s, w %g s %g rho %g): %d its, E %.8g (elastic %.4g, locality %.4g), worst relative increase %.2e\n",
           m->kind == DF_MESH_TET ? "tet" : "2D", w, sth, rho, r.iterations, r.objective, r.elastic, r.locality, mo.worst);
    assert_int_equal(mo.calls, its);
    assert_true(r.locality > 0);
    assert_true(mo.worst <= 1e-9);
    /* handles exactly at their targets */
    const double *V = df_admm_positions(s);
    for (int k = 0; k < nh; k++)
        for (int d = 0; d < 3; d++) assert_true(V[3 * h[k] + d] == tg[3 * k + d]);
    df_admm_free(s);
}

static void test_objective_monotone_and_handles_exact(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    strip2d(&m, &h, &nh, &tg);
    check_monotone(&m, h, nh, tg, DF_ADMM_ARAP, 1e-3, 0.05, 0.1, 300);
    free(h); free(tg); tu_free(&m);
    tu_bar3d_handles(&m, &h, &nh, &tg);
    check_monotone(&m, h, nh, tg, DF_ADMM_ARAP, 1e-3, 0.05, 0.1, 300);
    free(h); free(tg); tu_free(&m);
}

static void test_stats_and_warm_start(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-3; p.s = 0.05; p.rho = 0.1; p.tol = 1e-10; p.max_iters = 20000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    df_admm_stats stt;
    df_admm_get_stats(s, &stt);
    assert_true(stt.analyses == 1 && stt.factorizations == 1 && stt.solves == 0 && stt.iterations == 0);
    /* target 1, from rest */
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r1, r2, r3;
    assert_int_equal(df_admm_run(s, NULL, &r1, &err), DF_OK);
    assert_true(r1.converged);
    /* target 2, 2% further: warm start */
    double *tg2 = malloc((size_t)nh * 3 * sizeof(double));
    for (int k = 0; k < nh; k++)
        for (int d = 0; d < 3; d++) tg2[3 * k + d] = m.V[3 * h[k] + d] + 1.02 * (tg[3 * k + d] - m.V[3 * h[k] + d]);
    assert_int_equal(df_admm_set_targets(s, tg2, &err), DF_OK);
    assert_int_equal(df_admm_run(s, NULL, &r2, &err), DF_OK);
    assert_true(r2.converged);
    df_admm_get_stats(s, &stt);
    assert_true(stt.analyses == 1 && stt.factorizations == 1);
    assert_true(stt.solves == r1.iterations + r2.iterations);
    assert_true(stt.iterations == r1.iterations + r2.iterations);
    /* target 2 from rest in a fresh solver */
    df_admm *c = NULL;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &c, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(c, tg2, &err), DF_OK);
    assert_int_equal(df_admm_run(c, NULL, &r3, &err), DF_OK);
    assert_true(r3.converged);
    printf("warm start: target 1 from rest %d its; target 2 warm %d its vs from rest %d its (E %.8g vs %.8g)\n",
           r1.iterations, r2.iterations, r3.iterations, r2.objective, r3.objective);
    assert_true(r2.iterations < r3.iterations);
    assert_true(fabs(r2.objective - r3.objective) < 1e-3 * r3.objective);
    printf("phase times target 1: local1 %.4f s, local2 %.4f s, global %.4f s, total %.4f s\n",
           r1.t_local1, r1.t_local2, r1.t_global, r1.t_total);
    assert_true(r1.t_local1 > 0 && r1.t_local2 > 0 && r1.t_global > 0);
    assert_true(r1.t_local1 + r1.t_local2 + r1.t_global <= r1.t_total);
    df_admm_free(c);
    df_admm_free(s);
    free(tg2); free(h); free(tg); tu_free(&m);
}

static int stop_at_7(void *user, const df_admm_progress *pr)
{
    int *n = user;
    (*n)++;
    assert_true(pr->nv > 0 && pr->V != NULL && isfinite(pr->objective));
    return pr->iteration >= 7;
}

static void test_callback_budget_and_reset_rest(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-3; p.s = 0.05; p.rho = 0.1;
    p.tol = 0; /* never converges: only the callback and the budget stop these runs */
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    int calls = 0;
    df_admm_budget b = {100, 0, 1, stop_at_7, &calls};
    df_admm_result r;
    assert_int_equal(df_admm_run(s, &b, &r, &err), DF_OK);
    assert_int_equal(r.iterations, 7);
    assert_int_equal(calls, 7);
    assert_int_equal(r.stop, DF_ADMM_STOP_CALLBACK);
    /* time budget: 30 ms with an iteration cap far away */
    df_admm_budget tb = {100000, 30.0, 0, NULL, NULL};
    assert_int_equal(df_admm_run(s, &tb, &r, &err), DF_OK);
    printf("time budget 30 ms: %d iterations in %.1f ms\n", r.iterations, 1e3 * r.t_total);
    assert_int_equal(r.stop, DF_ADMM_STOP_TIME);
    assert_true(r.iterations >= 1 && r.t_total < 0.06);
    /* reset rest: the current shape becomes the rest; running again keeps it (E = 0) */
    double *Vb = malloc((size_t)m.nv * 3 * sizeof(double));
    assert_int_equal(df_admm_get_positions(s, Vb, &err), DF_OK);
    assert_int_equal(df_admm_reset_rest(s, &err), DF_OK);
    df_admm_stats stt;
    df_admm_get_stats(s, &stt);
    assert_true(stt.analyses == 2 && stt.factorizations == 2);
    double el, lo;
    assert_int_equal(df_admm_evaluate(s, Vb, &el, &lo, &err), DF_OK);
    printf("after reset_rest: E(rest) = %.2e\n", el);
    assert_true(el < 1e-14 && lo == 0.0);
    assert_int_equal(df_admm_run(s, &(df_admm_budget){20, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    double maxd = 0;
    for (int i = 0; i < m.nv; i++) maxd = fmax(maxd, tu_dist(df_admm_positions(s) + 3 * i, Vb + 3 * i));
    printf("after reset_rest: 20 its move the shape by at most %.2e, E = %.3e\n", maxd, r.objective);
    assert_true(maxd < 1e-12);
    df_admm_free(s);
    free(Vb); free(h); free(tg); tu_free(&m);
}

/* Anderson-accelerated ADMM converges to the same objective as plain ADMM, keeps the handles
 * exact and really takes accelerated steps */
static void test_anderson(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    double E[2];
    int its[2], acc = 0;
    for (int a = 0; a < 2; a++) {
        df_admm_params p;
        df_admm_params_default(&p, DF_ADMM_ARAP);
        p.threads = 1;
        p.w = 1e-3; p.s = 0.05; p.rho = 0.1; p.tol = 1e-12; p.max_iters = 20000;
        p.accelerate = a;
        df_admm *s = NULL;
        df_error err;
        assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
        assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
        df_admm_result r;
        assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
        assert_true(r.converged);
        E[a] = r.objective;
        its[a] = r.iterations;
        if (a) acc = r.anderson_accepted;
        const double *V = df_admm_positions(s);
        for (int k = 0; k < nh; k++)
            for (int d = 0; d < 3; d++) assert_true(V[3 * h[k] + d] == tg[3 * k + d]);
        df_admm_free(s);
    }
    printf("Anderson: plain %d its E %.10g, accelerated %d its (%d accepted steps) E %.10g\n", its[0], E[0], its[1], acc, E[1]);
    assert_true(acc > 0);
    assert_true(fabs(E[1] - E[0]) < 1e-6 * E[0]);
    free(h); free(tg); tu_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_arap_2d_matches_reference),
        cmocka_unit_test(test_plain_arap_tet_matches_reference),
        cmocka_unit_test(test_objective_monotone_and_handles_exact),
        cmocka_unit_test(test_stats_and_warm_start),
        cmocka_unit_test(test_callback_budget_and_reset_rest),
        cmocka_unit_test(test_anderson),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

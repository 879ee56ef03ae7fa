/* Unit tests of the ADMM's constraints and input checking: affine constraints on vertex sets
 * (plane, line, point) hold to 1e-9 after a run while handles pull the mesh; bad input (rho <=
 * w max(a_i)/s, NaN targets, handle out of range or repeated, empty handle set, inverted
 * elements (degenerate ones are excluded and counted instead), energy/mesh mismatch, affine vertex that is a handle, dependent affine
 * rows, NaN coordinates, bad parameters) gives a clear error and changes nothing. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

static void test_affine_constraints(void **st)
{
    (void)st;
    df_mesh m = tu_bar3d(6, 2, 2, 3.0, 1.0, 1.0);
    /* handles: x = 0 face fixed, one vertex at x = 3 pulled up */
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    int32_t plane[64], line[64];
    int npl = 0, nli = 0;
    int32_t pull = -1;
    for (int32_t i = 0; i < m.nv; i++) {
        const double *x = m.V + 3 * i;
        if (x[0] == 0.0) { h[nh] = i; memcpy(tg + 3 * nh, x, 24); nh++; }
        else if (x[0] == 3.0 && x[1] == 1.0 && x[2] == 1.0) pull = i;
        else if (x[0] == 3.0) plane[npl++] = i;              /* rest of the end face: stay on x = 3 */
        else if (x[1] == 0.0 && x[2] == 0.0) line[nli++] = i; /* bottom edge: stay on the line y = z = 0 */
    }
    h[nh] = pull;
    tg[3 * nh] = 3.4; tg[3 * nh + 1] = 1.6; tg[3 * nh + 2] = 1.2;
    nh++;
    df_admm_affine aff[3] = {
        {npl, plane, 1, {1, 0, 0, 0, 0, 0, 0, 0, 0}, {3.0, 0, 0}},
        {nli, line, 2, {0, 1, 0, 0, 0, 1, 0, 0, 0}, {0.0, 0.0, 0}},
    };
    /* a point constraint: the middle vertex of the top edge stays exactly where it is */
    int32_t pt = -1;
    for (int32_t i = 0; i < m.nv; i++)
        if (m.V[3 * i] == 1.5 && m.V[3 * i + 1] == 1.0 && m.V[3 * i + 2] == 1.0) pt = i;
    assert_true(pt >= 0);
    aff[2] = (df_admm_affine){1, &pt, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {1.5, 1.0, 1.0}};
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-3; p.s = 0.1; p.rho = 0.1;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, aff, 3, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){200, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    const double *V = df_admm_positions(s);
    double worst = 0, moved = 0;
    for (int k = 0; k < npl; k++) {
        worst = fmax(worst, fabs(V[3 * plane[k]] - 3.0));
        moved = fmax(moved, tu_dist(V + 3 * plane[k], m.V + 3 * plane[k]));
    }
    for (int k = 0; k < nli; k++) worst = fmax(worst, fmax(fabs(V[3 * line[k] + 1]), fabs(V[3 * line[k] + 2])));
    worst = fmax(worst, tu_dist(V + 3 * pt, m.V + 3 * pt));
    printf("affine: %d plane + %d line + 1 point vertices, worst violation %.2e, plane vertices moved up to %.3f, E %.6g\n",
           npl, nli, worst, moved, r.objective);
    assert_true(worst < 1e-9);
    assert_true(moved > 0.05); /* the constraint is not trivially satisfied by not moving */
    df_admm_stats stt;
    df_admm_get_stats(s, &stt);
    printf("stats: %ld analyses, %ld factorizations, %ld solves for %d iterations (+1 affine setup solve)\n",
           stt.analyses, stt.factorizations, stt.solves, r.iterations);
    assert_true(stt.analyses == 1 && stt.factorizations == 1 && stt.solves == r.iterations + 1);
    df_admm_free(s);
    /* dependent rows: the same plane twice on one vertex */
    df_admm_affine dup[2] = {{1, &pt, 1, {1, 0, 0}, {1.5}}, {1, &pt, 1, {2, 0, 0}, {3.0}}};
    s = (df_admm *)0x1;
    assert_int_equal(df_admm_create(&m, &p, h, nh, dup, 2, &s, &err), DF_ESINGULAR);
    assert_true(s == (df_admm *)0x1);
    printf("dependent affine rows: %s\n", err.msg);
    /* affine vertex that is a handle */
    df_admm_affine bad = {1, &h[0], 1, {1, 0, 0}, {0}};
    assert_int_equal(df_admm_create(&m, &p, h, nh, &bad, 1, &s, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "handle"));
    tu_free(&m);
}

static void expect_create_error(const df_mesh *m, const df_admm_params *p, const int32_t *h, int nh, int code, const char *needle)
{
    df_admm *s = (df_admm *)0x1;
    df_error err;
    df_error_clear(&err);
    int rc = df_admm_create(m, p, h, nh, NULL, 0, &s, &err);
    printf("  -> %s: %s\n", df_error_name(rc), err.msg);
    assert_int_equal(rc, code);
    assert_true(s == (df_admm *)0x1);
    assert_true(strlen(err.msg) > 0);
    if (needle) assert_non_null(strstr(err.msg, needle));
}

static void test_bad_input(void **st)
{
    (void)st;
    df_mesh m = tu_bar3d(3, 1, 1, 3.0, 1.0, 1.0);
    int32_t h[2] = {0, m.nv - 1};
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-3; p.s = 0.01; p.rho = 0.1; /* rho = w/s exactly: refused */
    expect_create_error(&m, &p, h, 2, DF_EINVAL, "rho");
    p.rho = 0.10001; /* just above: accepted */
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, 2, NULL, 0, &s, &err), DF_OK);
    /* area weighting: max a_i enters the bound */
    p.area_weighting = 1; p.rho = 0.1;
    df_admm *aw = NULL;
    assert_int_equal(df_admm_create(&m, &p, h, 2, NULL, 0, &aw, &err), DF_OK); /* a_i < 1 here */
    df_admm_free(aw);
    p.area_weighting = 0; p.rho = 0.10001;
    expect_create_error(&m, &p, h, 0, DF_EINVAL, "empty handle");
    int32_t hbad[2] = {0, m.nv};
    expect_create_error(&m, &p, hbad, 2, DF_EINVAL, "out of range");
    int32_t hneg[2] = {-1, 3};
    expect_create_error(&m, &p, hneg, 2, DF_EINVAL, "out of range");
    int32_t hrep[2] = {3, 3};
    expect_create_error(&m, &p, hrep, 2, DF_EINVAL, "twice");
    df_admm_params q = p;
    q.energy = DF_ADMM_CLOTH;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "triangle");
    /* energy / mesh mismatches name both by their wire names and the energy to use */
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "energy cloth needs triangles; this mesh is a "
                        "tet mesh: use energy arap, acap or neohookean");
    double pv[12] = {0, 0, 0, 1, 0, 0, 2, 0.5, 0, 3, 0, 0};
    int32_t pe[6] = {0, 1, 1, 2, 2, 3}, ph[2] = {0, 3};
    df_mesh poly = {DF_MESH_POLYLINE, 0, 4, pv, 3, pe, 0, NULL};
    q = p; q.energy = DF_ADMM_ARAP;
    expect_create_error(&poly, &q, ph, 2, DF_EINVAL, "energy arap needs triangles or tets; this "
                        "mesh is a polyline: use energy polyline (deformctl --energy polyline)");
    q = p; q.energy = DF_ADMM_POLYLINE;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "energy polyline needs a polyline");
    q = p; q.energy = (df_admm_energy)99;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "energy");
    q = p; q.s = 0;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "s =");
    q = p; q.w = NAN;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "w =");
    q = p; q.max_iters = 0;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "max_iters");
    q = p; q.accelerate = 1; q.anderson_m = 0;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "anderson_m");
    q = p; q.threads = -2;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "threads");
    q = p; q.energy = DF_ADMM_NEOHOOKEAN; q.poisson = 0.5;
    expect_create_error(&m, &q, h, 2, DF_EINVAL, "Poisson");
    /* inverted tet */
    int32_t t0 = m.E[0];
    m.E[0] = m.E[1]; m.E[1] = t0;
    expect_create_error(&m, &p, h, 2, DF_EINVAL, "inverted");
    m.E[1] = m.E[0]; m.E[0] = t0;
    /* degenerate tets (a vertex collapsed onto another) are no longer refused: excluded from the
     * energy and counted (test_admm_degenerate.c); only a mesh of nothing else is refused */
    double keep[3];
    memcpy(keep, m.V + 3 * m.E[4 * 5 + 3], 24);
    memcpy(m.V + 3 * m.E[4 * 5 + 3], m.V + 3 * m.E[4 * 5 + 2], 24);
    df_admm_degenerate dg;
    assert_int_equal(df_admm_find_degenerate(&m, NULL, &dg, &err), DF_OK);
    assert_true(dg.elements >= 1);
    df_admm *sd = NULL;
    assert_int_equal(df_admm_create(&m, &p, h, 2, NULL, 0, &sd, &err), DF_OK);
    df_admm_degenerate dgs;
    df_admm_get_degenerate(sd, &dgs);
    assert_int_equal(dgs.elements, dg.elements);
    df_admm_free(sd);
    memcpy(m.V + 3 * m.E[4 * 5 + 3], keep, 24);
    /* NaN coordinate, bad element index */
    m.V[7] = NAN;
    expect_create_error(&m, &p, h, 2, DF_EINVAL, "non-finite");
    m.V[7] = keep[0] * 0 + m.V[4]; /* restore something finite */
    df_mesh m2 = tu_bar3d(3, 1, 1, 3.0, 1.0, 1.0);
    m2.E[9] = m2.nv + 5;
    expect_create_error(&m2, &p, h, 2, DF_EINVAL, "references");
    tu_free(&m2);
    expect_create_error(NULL, &p, h, 2, DF_EINVAL, "NULL");

    /* set_targets with NaN: error, nothing changed */
    double tg[6] = {0, 0, 0, 3.5, 1, 1};
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){10, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    double *before = malloc((size_t)m.nv * 3 * sizeof(double));
    assert_int_equal(df_admm_get_positions(s, before, &err), DF_OK);
    double bad[6] = {0, 0, 0, NAN, 1, 1};
    assert_int_equal(df_admm_set_targets(s, bad, &err), DF_EINVAL);
    printf("  -> NaN target: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "handle 1"));
    /* continuing with the old targets gives exactly what an uninterrupted solver gives */
    df_admm *ref = NULL;
    assert_int_equal(df_admm_create(&m, &p, h, 2, NULL, 0, &ref, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(ref, tg, &err), DF_OK);
    assert_int_equal(df_admm_run(ref, &(df_admm_budget){15, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    assert_int_equal(df_admm_run(s, &(df_admm_budget){5, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    assert_memory_equal(df_admm_positions(s), df_admm_positions(ref), (size_t)m.nv * 3 * sizeof(double));
    assert_int_equal(df_admm_set_targets(s, NULL, &err), DF_EINVAL);
    assert_int_equal(df_admm_run(NULL, NULL, &r, &err), DF_EINVAL);
    assert_int_equal(df_admm_get_positions(s, NULL, &err), DF_EINVAL);
    double el;
    assert_int_equal(df_admm_evaluate(s, bad, &el, NULL, &err), DF_EINVAL);
    df_admm_stats stt;
    df_admm_get_stats(NULL, &stt);
    assert_true(stt.analyses == 0 && stt.solves == 0);
    df_admm_free(ref);
    df_admm_free(s);
    df_admm_free(NULL);
    free(before);
    tu_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_affine_constraints),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

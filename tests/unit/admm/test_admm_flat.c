/* Unit tests for flat meshes in ADMM (issue 9 item 16): a flat 3D triangle mesh (every z = 0,
 * not declared 2D) deforms in 3D: handles pulled out of the plane reach their targets and drag
 * the region around them along under ARAP, ACAP and cloth (and ARAP and ACAP differ); a 2D mesh
 * (planar) refuses targets with z != 0 instead of dropping z. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "admm_test_util.h"
#include "core/admm/admm.h"

/* 16 x 16 cells: the boundary fixed, the centre vertex pulled to z = 0.3. */
static int setup_handles(const df_mesh *m, int32_t *h, double *tg, int32_t *centre)
{
    int nh = 0;
    for (int32_t i = 0; i < m->nv; i++) {
        double x = m->V[3 * i], y = m->V[3 * i + 1];
        if (x == 0 || y == 0 || x == 1.0 || y == 1.0) {
            h[nh] = i;
            memcpy(tg + 3 * nh, m->V + 3 * i, 24);
            nh++;
        }
    }
    *centre = 8 * 17 + 8;
    h[nh] = *centre;
    memcpy(tg + 3 * nh, m->V + 3 * *centre, 24);
    tg[3 * nh + 2] = 0.3;
    return nh + 1;
}

static double pull(df_admm_energy en, double *zc, double *znear, double *zh)
{
    df_mesh m = tu_grid2d(16, 16, 1.0, 1.0);
    m.planar = 0;                      /* what a `v x y 0` OBJ now loads as */
    int32_t h[128], c;
    double tg[128 * 3];
    int nh = setup_handles(&m, h, tg, &c);
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1;
    p.max_iters = 3000;
    if (en == DF_ADMM_CLOTH) {
        p.w = 1e-4; p.s = 0.05; p.rho = 5e-3;
        p.strain_min = 0.5; p.strain_max = 10.0; p.bending = 1e-4;
    }
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    const double *V = df_admm_positions(s);
    *zh = V[3 * c + 2];
    *zc = V[3 * (c + 1) + 2];            /* a neighbour of the pulled vertex */
    *znear = V[3 * (c + 17 + 1) + 2];    /* a diagonal neighbour */
    printf("# energy %d: handle z %.6f, neighbours z %.4f %.4f, objective %.6g\n", (int)en, *zh,
           *zc, *znear, r.objective);
    df_admm_free(s);
    tu_free(&m);
    return r.objective;
}

static void test_flat_3d_mesh_moves_out_of_plane(void **st)
{
    (void)st;
    double zc, zn, zh;
    double ea = pull(DF_ADMM_ARAP, &zc, &zn, &zh);
    assert_true(zh == 0.3);            /* the handle is at its target */
    assert_true(zc > 0.01 && zn > 0.01);
    double eb = pull(DF_ADMM_ACAP, &zc, &zn, &zh);
    assert_true(zh == 0.3);
    assert_true(zc > 0.01 && zn > 0.01);
    assert_true(fabs(ea - eb) > 1e-6 * fabs(ea));   /* two different energies, two objectives */
    pull(DF_ADMM_CLOTH, &zc, &zn, &zh);
    assert_true(zh == 0.3);
    assert_true(zc > 0.01 && zn > 0.01);
}

static void test_2d_mesh_refuses_targets_off_the_plane(void **st)
{
    (void)st;
    df_mesh m = tu_grid2d(16, 16, 1.0, 1.0);   /* planar = 1: a declared 2D mesh */
    int32_t h[128], c;
    double tg[128 * 3];
    int nh = setup_handles(&m, h, tg, &c);
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "2D"));
    assert_non_null(strstr(err.msg, "z = 0.3"));
    tg[3 * (nh - 1) + 2] = 0.0;
    tg[3 * (nh - 1)] += 0.1;                   /* in the plane: fine */
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_free(s);
    tu_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_3d_mesh_moves_out_of_plane),
        cmocka_unit_test(test_2d_mesh_refuses_targets_off_the_plane),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

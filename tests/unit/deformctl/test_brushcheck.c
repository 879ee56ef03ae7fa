/* Unit tests for client/deformctl/dc_brush (the local Kelvinlet pre-flight check of deformctl
 * brush, linked into deformctl only) and
 * client/dc_meshout's tet -> boundary-surface fallback. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformctl/dc_brush.h"
#include "client/dc_meshout.h"

static void grab(df_msg_brush *b, df_msg_brush_update *u)
{
    df_msg_brush_defaults(b);
    memset(u, 0, sizeof *u);
    b->session_id = u->session_id = 1;
    b->type = DF_BRUSH_GRAB;
    b->radius = 0.5;
    b->nu = 0.4;
    u->move[2] = 0.1;
}

static void test_conversion_mirrors_the_daemon(void **state)
{
    (void)state;
    df_msg_brush b;
    df_msg_brush_update u;
    grab(&b, &u);
    b.type = DF_BRUSH_AFFINE;
    b.strength = 2;
    b.falloff = 3;
    b.ratio = 1.3;
    b.integrator = DF_INTEG_RK4;
    b.steps = 7;
    b.moving = 1;
    b.dim = 2;
    b.center[1] = 0.25;
    for (int i = 0; i < 9; i++)
        u.matrix[i] = 0.01 * (i + 1);
    u.move[0] = 0.5;
    u.twist[1] = 0.3;
    u.scale = 0.125;
    df_kelvinlet_brush k;
    dc_brush_to_kelvinlet(&b, &u, &k);
    assert_int_equal(k.type, DF_KELVINLET_AFFINE);
    assert_int_equal(k.order, 3);
    assert_int_equal(k.dim, 2);
    assert_int_equal(k.integrator, DF_KELVINLET_RK4);
    assert_int_equal(k.steps, 7);
    assert_int_equal(k.moving, 1);
    assert_true(k.ratio == 1.3 && k.radius == 0.5 && k.nu == 0.4 && k.centre[1] == 0.25);
    assert_true(fabs(k.grad[8] - 0.18) < 1e-15 && k.grad[0] == 0.02); /* loads x strength */
    assert_true(k.tip[0] == 1.0 && k.tip[2] == 0.2 && k.omega[1] == 0.6 && k.s == 0.25);
    static const df_brush_type wire[5] = {DF_BRUSH_GRAB, DF_BRUSH_TWIST, DF_BRUSH_SCALE,
                                          DF_BRUSH_PINCH, DF_BRUSH_AFFINE};
    static const df_kelvinlet_type eng[5] = {DF_KELVINLET_GRAB, DF_KELVINLET_TWIST,
                                             DF_KELVINLET_SCALE, DF_KELVINLET_PINCH,
                                             DF_KELVINLET_AFFINE};
    for (int t = 0; t < 5; t++) {
        b.type = (uint8_t)wire[t];
        dc_brush_to_kelvinlet(&b, &u, &k);
        assert_int_equal(k.type, eng[t]);
    }
}

static void test_check_rejects_what_the_engine_rejects(void **state)
{
    (void)state;
    df_msg_brush b;
    df_msg_brush_update u;
    df_error e;
    grab(&b, &u);
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_OK);
    b.nu = -INFINITY;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_OK);
    b.nu = 0.7;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "nu 0.7"));
    grab(&b, &u);
    b.type = DF_BRUSH_PINCH;
    u.matrix[1] = 0.2; /* not symmetric */
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "symmetric and traceless"));
    u.matrix[3] = 0.2; /* symmetric, traceless */
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_OK);
    grab(&b, &u);
    b.type = DF_BRUSH_SCALE;
    b.nu = 0.5;
    u.scale = 0.1;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_ESINGULAR);
    grab(&b, &u);
    b.radius = 1e-9; /* below DF_KELVINLET_MIN_RADIUS */
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_EINVAL);
}

static void test_check_pins(void **state)
{
    (void)state;
    df_msg_brush b;
    df_msg_brush_update u;
    df_error e;
    grab(&b, &u);
    double pins[6] = {1, 0, 0, 0, 1, 0};
    b.n_pinned = 2;
    b.pinned = pins;
    b.pin_flags = DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_OK);
    pins[3] = 1, pins[4] = 0; /* identical pins */
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_ESINGULAR);
    assert_non_null(strstr(e.msg, "coincide"));
    pins[4] = 1;
    b.has_mirror = 1;
    b.mirror_normal[0] = 1;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_EUNSUPPORTED);
    /* beyond the local limit the pin part is left to the daemon: duplicates pass here */
    size_t n = DC_BRUSH_LOCAL_PIN_CHECK_MAX + 1;
    double *many = calloc(3 * n, sizeof *many);
    b.has_mirror = 0;
    b.n_pinned = (uint32_t)n;
    b.pinned = many;
    assert_int_equal(dc_brush_check(&b, &u, &e), DF_OK);
    free(many);
}

static void test_tet_mesh_written_as_its_boundary(void **state)
{
    (void)state;
    /* two positive tets sharing face (1,2,3): 5 vertices, 6 boundary triangles */
    const float xyz[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const int32_t E[8] = {0, 1, 2, 3, 4, 1, 3, 2};
    char path[64];
    snprintf(path, sizeof path, "/tmp/dc-meshout-%d.obj", (int)getpid());
    df_error e;
    int32_t nb = 99;
    assert_int_equal(dc_meshout_write(path, 3, 0, 5, xyz, 2, E, 0, NULL, &nb, &e), DF_OK);
    assert_int_equal(nb, 6);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[256];
    int nv = 0, nf = 0, shared = 0;
    while (fgets(line, sizeof line, f)) {
        int a, b, c;
        if (line[0] == 'v' && line[1] == ' ')
            nv++;
        if (line[0] == 'f' && sscanf(line + 1, "%d %d %d", &a, &b, &c) == 3) {
            nf++;
            int s = (a == 2 || b == 2 || c == 2) + (a == 3 || b == 3 || c == 3) +
                    (a == 4 || b == 4 || c == 4);
            shared += s == 3; /* the interior face must not be written */
        }
    }
    fclose(f);
    unlink(path);
    assert_int_equal(nv, 5);
    assert_int_equal(nf, 6);
    assert_int_equal(shared, 0);
    /* volumetric formats keep the tets; nb reports -1 */
    snprintf(path, sizeof path, "/tmp/dc-meshout-%d.mesh", (int)getpid());
    assert_int_equal(dc_meshout_write(path, 3, 0, 5, xyz, 2, E, 0, NULL, &nb, &e), DF_OK);
    assert_int_equal(nb, -1);
    unlink(path);
    /* an invalid tet (index out of range) is an error, not a crash */
    const int32_t bad[8] = {0, 1, 2, 3, 4, 1, 3, 9};
    snprintf(path, sizeof path, "/tmp/dc-meshout-%d.off", (int)getpid());
    nb = 99;
    assert_true(dc_meshout_write(path, 3, 0, 5, xyz, 2, bad, 0, NULL, &nb, &e) < 0);
    assert_int_equal(nb, 99);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conversion_mirrors_the_daemon),
        cmocka_unit_test(test_check_rejects_what_the_engine_rejects),
        cmocka_unit_test(test_check_pins),
        cmocka_unit_test(test_tet_mesh_written_as_its_boundary),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

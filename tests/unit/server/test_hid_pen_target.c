/* Unit tests of server/hid/hid_pen_target: the pen's normalized position through a published view
 * onto a session's surface. Expected centres come from the camera frame the test builds the view
 * from (gluLookAt / gluPerspective formulas) intersected with the known face plane, not from the
 * code under test. Covers a triangle mesh (3D and 2D), a tet mesh's boundary, hits and misses, the
 * version cache (same version: positions not re-read; new version: refit), and refusals. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"
#include "server/hid/hid_pen_target.h"
#include "tests/unit/server/tiny_mesh.h"

typedef struct cam { double eye[3], f[3], s[3], u[3], th, aspect; double vp[16]; } cam;
static const double VIEWPORT[4] = {0, 0, 640, 480};

static void normalize(double *v)
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= n, v[1] /= n, v[2] /= n;
}
static void cross(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* view_proj = perspective(fovy, aspect of VIEWPORT, 0.1, 100) * look_at(eye, at, up). */
static cam camera(const double eye[3], const double at[3], const double up[3], double fovy)
{
    cam c;
    memcpy(c.eye, eye, sizeof c.eye);
    for (int k = 0; k < 3; k++)
        c.f[k] = at[k] - eye[k];
    normalize(c.f);
    cross(c.f, up, c.s);
    normalize(c.s);
    cross(c.s, c.f, c.u);
    c.th = tan(fovy / 2);
    c.aspect = VIEWPORT[2] / VIEWPORT[3];
    double n = 0.1, fa = 100, g = 1 / c.th;
    double view[16] = {c.s[0], c.s[1], c.s[2], -dot(c.s, eye), c.u[0], c.u[1], c.u[2],
                       -dot(c.u, eye), -c.f[0], -c.f[1], -c.f[2], dot(c.f, eye), 0, 0, 0, 1};
    double proj[16] = {g / c.aspect, 0, 0, 0, 0, g, 0, 0, 0, 0, (fa + n) / (n - fa),
                       2 * fa * n / (n - fa), 0, 0, -1, 0};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += proj[4 * i + k] * view[4 * k + j];
            c.vp[4 * i + j] = s;
        }
    return c;
}

/* The pen ray's point on the plane dot(normal, x) = offset, from the camera frame. */
static void expected_on_plane(const cam *c, double nx, double ny, const double normal[3],
                              double offset, double p[3])
{
    double d[3];
    for (int k = 0; k < 3; k++)
        d[k] = c->f[k] + (2 * nx - 1) * c->th * c->aspect * c->s[k]
               + (1 - 2 * ny) * c->th * c->u[k];
    double t = (offset - dot(normal, c->eye)) / dot(normal, d);
    for (int k = 0; k < 3; k++)
        p[k] = c->eye[k] + t * d[k];
}

static void run_triangle(int planar)
{
    df_mesh m = tiny_mesh();
    assert_non_null(m.V);
    assert_non_null(m.E);
    m.planar = planar;
    df_pen_cache *pc = NULL;
    df_error e;
    assert_int_equal(df_pen_cache_create(&m, &pc, &e), DF_OK);
    double eye[3] = {0.3, 0.2, 2}, at[3] = {0.3, 0.3, 0}, up[3] = {0, 1, 0};
    cam c = camera(eye, at, up, 1.0);
    double z0[3] = {0, 0, 1};
    int hits = 0, misses = 0;
    for (int j = 0; j <= 20; j++)
        for (int i = 0; i <= 20; i++) {
            double nx = i / 20.0, ny = j / 20.0, p[3], center[3] = {-9, -9, -9};
            expected_on_plane(&c, nx, ny, z0, 0, p);
            double margin = fmin(fmin(p[0], p[1]), 1 - p[0] - p[1]);
            if (fabs(margin) < 1e-6)
                continue;   /* on an edge: either answer is right */
            int r = df_pen_target(pc, m.V, 1, c.vp, VIEWPORT, nx, ny, center, &e);
            if (margin > 0) {
                assert_int_equal(r, 1);
                for (int k = 0; k < 3; k++)
                    assert_true(fabs(center[k] - p[k]) <= 1e-9);
                hits++;
            } else {
                assert_int_equal(r, 0);
                assert_true(center[0] == -9 && center[1] == -9 && center[2] == -9);
                misses++;
            }
        }
    assert_true(hits >= 20 && misses >= 20);
    df_pen_cache_free(pc);
    df_mesh_free(&m);
}

static void test_triangle_hits_and_misses(void **state)
{
    (void)state;
    run_triangle(0);
}

static void test_planar_mesh(void **state)
{
    (void)state;
    run_triangle(1);
}

static void test_version_cache_and_refit(void **state)
{
    (void)state;
    df_mesh m = tiny_mesh();
    assert_non_null(m.V);
    df_pen_cache *pc = NULL;
    df_error e;
    assert_int_equal(df_pen_cache_create(&m, &pc, &e), DF_OK);
    double eye[3] = {0.25, 0.25, 3}, at[3] = {0.25, 0.25, 0}, up[3] = {0, 1, 0};
    cam c = camera(eye, at, up, 0.8);
    double cur[9], center[3], z[3] = {0, 0, 1}, p[3];
    memcpy(cur, m.V, sizeof cur);
    assert_int_equal(df_pen_target(pc, cur, 7, c.vp, VIEWPORT, 0.5, 0.5, center, &e), 1);
    assert_true(fabs(center[0] - 0.25) <= 1e-9 && fabs(center[1] - 0.25) <= 1e-9
                && fabs(center[2]) <= 1e-12);
    /* The session moves the triangle up by 0.5 but reports the same version: the cache keeps the
     * positions it fitted (they are not re-read). */
    for (int i = 0; i < 3; i++)
        cur[3 * i + 2] = 0.5;
    assert_int_equal(df_pen_target(pc, cur, 7, c.vp, VIEWPORT, 0.5, 0.5, center, &e), 1);
    assert_true(fabs(center[2]) <= 1e-12);
    /* A new version refits. */
    assert_int_equal(df_pen_target(pc, cur, 8, c.vp, VIEWPORT, 0.52, 0.45, center, &e), 1);
    expected_on_plane(&c, 0.52, 0.45, z, 0.5, p);
    assert_true(p[0] > 0 && p[1] > 0 && p[0] + p[1] < 1);   /* inside the triangle */
    for (int k = 0; k < 3; k++)
        assert_true(fabs(center[k] - p[k]) <= 1e-9);
    /* A bad position at a new version is refused; the fitted scene stays (version 8). */
    double bad[9];
    memcpy(bad, cur, sizeof bad);
    bad[4] = NAN;
    double keep[3] = {1, 2, 3};
    assert_int_equal(df_pen_target(pc, bad, 9, c.vp, VIEWPORT, 0.5, 0.5, keep, &e), DF_EINVAL);
    assert_true(keep[0] == 1 && keep[1] == 2 && keep[2] == 3);
    assert_int_equal(df_pen_target(pc, bad, 8, c.vp, VIEWPORT, 0.5, 0.5, center, &e), 1);
    assert_true(fabs(center[2] - 0.5) <= 1e-12);
    /* Then good positions at version 9: a tilted triangle (z = x). */
    cur[2] = 0, cur[5] = 1, cur[8] = 0;   /* (0,0,0) (1,0,1) (0,1,0) */
    assert_int_equal(df_pen_target(pc, cur, 9, c.vp, VIEWPORT, 0.45, 0.5, center, &e), 1);
    double tilt[3] = {1, 0, -1};   /* x - z = 0 */
    expected_on_plane(&c, 0.45, 0.5, tilt, 0, p);
    assert_true(p[0] > 0 && p[1] > 0 && p[0] + p[1] < 1);
    for (int k = 0; k < 3; k++)
        assert_true(fabs(center[k] - p[k]) <= 1e-9);
    df_pen_cache_free(pc);
    df_mesh_free(&m);
}

static void test_tet_boundary(void **state)
{
    (void)state;
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TET;
    m.nv = 4;
    m.ne = 1;
    m.V = calloc(12, sizeof(double));
    m.E = malloc(4 * sizeof(int32_t));
    assert_non_null(m.V);
    assert_non_null(m.E);
    m.V[3] = m.V[7] = m.V[11] = 1;   /* (0,0,0) (1,0,0) (0,1,0) (0,0,1) */
    for (int i = 0; i < 4; i++)
        m.E[i] = i;
    df_pen_cache *pc = NULL;
    df_error e;
    assert_int_equal(df_pen_cache_create(&m, &pc, &e), DF_OK);
    double eye[3] = {2, 2, 2.5}, at[3] = {0.25, 0.25, 0.25}, up[3] = {0, 0, 1};
    cam c = camera(eye, at, up, 0.6);
    double slanted[3] = {1, 1, 1}, center[3], p[3];
    const double pens[][2] = {{0.5, 0.5}, {0.45, 0.55}, {0.55, 0.48}};
    for (size_t i = 0; i < sizeof pens / sizeof pens[0]; i++) {
        assert_int_equal(df_pen_target(pc, m.V, 1, c.vp, VIEWPORT, pens[i][0], pens[i][1], center,
                                       &e), 1);
        expected_on_plane(&c, pens[i][0], pens[i][1], slanted, 1, p);
        assert_true(p[0] > 0 && p[1] > 0 && p[2] > 0);   /* inside the slanted face */
        for (int k = 0; k < 3; k++)
            assert_true(fabs(center[k] - p[k]) <= 1e-9);
    }
    /* Far off to the side: a miss. */
    assert_int_equal(df_pen_target(pc, m.V, 1, c.vp, VIEWPORT, 0.0, 0.0, center, &e), 0);
    df_pen_cache_free(pc);
    df_mesh_free(&m);
}

static void test_refusals(void **state)
{
    (void)state;
    df_pen_cache *pc = (df_pen_cache *)&pc;
    df_error e;
    df_mesh line;
    memset(&line, 0, sizeof line);
    line.kind = DF_MESH_POLYLINE;
    line.nv = 2;
    line.ne = 1;
    int32_t seg[2] = {0, 1};
    double lv[6] = {0, 0, 0, 1, 0, 0};
    line.E = seg;
    line.V = lv;
    assert_int_equal(df_pen_cache_create(&line, &pc, &e), DF_EUNSUPPORTED);
    assert_non_null(strstr(e.msg, "polyline"));
    assert_int_equal(df_pen_cache_create(NULL, &pc, &e), DF_EINVAL);
    df_mesh m = tiny_mesh();
    assert_non_null(m.E);
    m.E[2] = 5;
    assert_int_equal(df_pen_cache_create(&m, &pc, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "out of range"));
    assert_ptr_equal(pc, (df_pen_cache *)&pc);
    m.E[2] = 2;
    assert_int_equal(df_pen_cache_create(&m, &pc, &e), DF_OK);
    double eye[3] = {0.25, 0.25, 3}, at[3] = {0.25, 0.25, 0}, up[3] = {0, 1, 0};
    cam c = camera(eye, at, up, 0.8);
    double center[3] = {4, 5, 6};
    double zero[16] = {0};
    assert_int_equal(df_pen_target(pc, m.V, 1, zero, VIEWPORT, 0.5, 0.5, center, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "singular"));
    assert_int_equal(df_pen_target(pc, m.V, 1, c.vp, VIEWPORT, NAN, 0.5, center, &e), DF_EINVAL);
    double flat[4] = {0, 0, 640, 0};
    assert_int_equal(df_pen_target(pc, m.V, 1, c.vp, flat, 0.5, 0.5, center, &e), DF_EINVAL);
    assert_int_equal(df_pen_target(pc, NULL, 1, c.vp, VIEWPORT, 0.5, 0.5, center, &e), DF_EINVAL);
    assert_int_equal(df_pen_target(NULL, m.V, 1, c.vp, VIEWPORT, 0.5, 0.5, center, &e),
                     DF_EINVAL);
    double bad[9];
    memcpy(bad, m.V, sizeof bad);
    bad[0] = INFINITY;   /* the first query builds the scene: refused, nothing built */
    assert_int_equal(df_pen_target(pc, bad, 1, c.vp, VIEWPORT, 0.5, 0.5, center, &e), DF_EINVAL);
    assert_true(center[0] == 4 && center[1] == 5 && center[2] == 6);
    /* The cache is still usable after every refusal. */
    assert_int_equal(df_pen_target(pc, m.V, 1, c.vp, VIEWPORT, 0.5, 0.5, center, &e), 1);
    assert_true(fabs(center[0] - 0.25) <= 1e-9 && fabs(center[1] - 0.25) <= 1e-9);
    df_pen_cache_free(pc);
    df_pen_cache_free(NULL);
    df_mesh_free(&m);
}

/* DEVICE_VIEW's check: an invertible view passes; a singular one, a non-finite entry, an empty
 * viewport or NULL are DF_EINVAL with a reason. */
static void test_view_check(void **state)
{
    (void)state;
    double vp[16] = {0}, port[4] = {0, 0, 960, 720};
    for (int i = 0; i < 4; i++) vp[5 * i] = 1;
    df_error e;
    assert_int_equal(df_pen_view_check(vp, port, &e), DF_OK);
    double sing[16];
    memcpy(sing, vp, sizeof sing);
    sing[10] = 0; /* z row zero: no inverse */
    assert_int_equal(df_pen_view_check(sing, port, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "singular"));
    double nan_vp[16];
    memcpy(nan_vp, vp, sizeof nan_vp);
    nan_vp[3] = NAN;
    assert_int_equal(df_pen_view_check(nan_vp, port, &e), DF_EINVAL);
    double empty[4] = {0, 0, 0, 720};
    assert_int_equal(df_pen_view_check(vp, empty, &e), DF_EINVAL);
    assert_int_equal(df_pen_view_check(NULL, port, &e), DF_EINVAL);
    assert_int_equal(df_pen_view_check(vp, NULL, &e), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_hits_and_misses),
        cmocka_unit_test(test_planar_mesh),
        cmocka_unit_test(test_version_cache_and_refit),
        cmocka_unit_test(test_tet_boundary),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_view_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

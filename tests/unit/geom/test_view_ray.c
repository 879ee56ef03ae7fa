/* Unit tests of core/geom/view_ray: pixel -> ray through perspective and orthographic
 * view-projection matrices built here (gluLookAt / gluPerspective / glOrtho formulas), compared
 * with the ray computed directly from the camera frame; the round trip pixel -> ray -> hit on a
 * mesh (df_raycast) -> view_proj -> pixel; the 4x4 inverse; the pen's normalized position onto
 * the viewport; singular and non-finite input refused. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/geom/raycast.h"
#include "core/geom/view_ray.h"

/* Camera frame of gluLookAt: f forward, s right, u up (unit, orthonormal). */
typedef struct cam { double eye[3], f[3], s[3], u[3]; } cam;

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

static cam look_at(const double eye[3], const double at[3], const double up[3], double view[16])
{
    cam c;
    memcpy(c.eye, eye, sizeof c.eye);
    for (int k = 0; k < 3; k++)
        c.f[k] = at[k] - eye[k];
    normalize(c.f);
    cross(c.f, up, c.s);
    normalize(c.s);
    cross(c.s, c.f, c.u);
    double m[16] = {c.s[0], c.s[1], c.s[2], -dot(c.s, eye),
                    c.u[0], c.u[1], c.u[2], -dot(c.u, eye),
                    -c.f[0], -c.f[1], -c.f[2], dot(c.f, eye),
                    0, 0, 0, 1};
    memcpy(view, m, sizeof m);
    return c;
}

static void perspective(double fovy, double aspect, double n, double f, double p[16])
{
    double g = 1 / tan(fovy / 2);
    double m[16] = {g / aspect, 0, 0, 0, 0, g, 0, 0, 0, 0, (f + n) / (n - f), 2 * f * n / (n - f),
                    0, 0, -1, 0};
    memcpy(p, m, sizeof m);
}

static void ortho(double l, double r, double b, double t, double n, double f, double p[16])
{
    double m[16] = {2 / (r - l), 0, 0, -(r + l) / (r - l), 0, 2 / (t - b), 0, -(t + b) / (t - b),
                    0, 0, -2 / (f - n), -(f + n) / (f - n), 0, 0, 0, 1};
    memcpy(p, m, sizeof m);
}

static void mul4(const double *a, const double *b, double *o)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += a[4 * i + k] * b[4 * k + j];
            o[4 * i + j] = s;
        }
}

/* Mesh point -> window pixel (y down) through vp and the viewport. */
static void project(const double vp[16], const double view[4], const double x[3], double *px,
                    double *py)
{
    double c[4];
    for (int r = 0; r < 4; r++)
        c[r] = vp[4 * r] * x[0] + vp[4 * r + 1] * x[1] + vp[4 * r + 2] * x[2] + vp[4 * r + 3];
    *px = view[0] + (c[0] / c[3] + 1) / 2 * view[2];
    *py = view[1] + (1 - c[1] / c[3]) / 2 * view[3];
}

static void assert_vec_near(const double *a, const double *b, double tol)
{
    for (int k = 0; k < 3; k++)
        if (fabs(a[k] - b[k]) > tol) {
            print_error("component %d: %.17g vs %.17g (tol %g)\n", k, a[k], b[k], tol);
            fail();
        }
}

static const double EYE[3] = {3, 2, 5}, AT[3] = {0.2, -0.1, 0.3}, UP[3] = {0, 1, 0};
static const double VIEWPORT[4] = {10, 20, 800, 600};

static void test_perspective_known_rays(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16];
    cam c = look_at(EYE, AT, UP, view);
    double fovy = 50 * M_PI / 180, aspect = VIEWPORT[2] / VIEWPORT[3], n = 0.1, f = 100;
    perspective(fovy, aspect, n, f, proj);
    mul4(proj, view, vp);
    /* Pixels as fractions of the viewport (0..1, y down): the ray's camera-frame direction is
     * f + (2 fx - 1) tan(fovy/2) aspect s + (1 - 2 fy) tan(fovy/2) u, its origin eye + n dir. */
    const double fr[][2] = {{0.5, 0.5}, {0, 0}, {1, 1}, {0.25, 0.8}, {0.9, 0.1}, {-0.2, 1.3}};
    double th = tan(fovy / 2);
    for (size_t i = 0; i < sizeof fr / sizeof fr[0]; i++) {
        double px = VIEWPORT[0] + fr[i][0] * VIEWPORT[2], py = VIEWPORT[1] + fr[i][1] * VIEWPORT[3];
        double d[3], o[3], org[3], dir[3];
        for (int k = 0; k < 3; k++) {
            d[k] = c.f[k] + (2 * fr[i][0] - 1) * th * aspect * c.s[k]
                   + (1 - 2 * fr[i][1]) * th * c.u[k];
            o[k] = c.eye[k] + n * d[k];
        }
        normalize(d);
        df_error e;
        assert_int_equal(df_view_ray(vp, VIEWPORT, px, py, org, dir, &e), DF_OK);
        assert_vec_near(org, o, 1e-9);
        assert_vec_near(dir, d, 1e-9);
        assert_true(fabs(dot(dir, dir) - 1) <= 1e-12);
    }
}

static void test_orthographic_known_rays(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16];
    cam c = look_at(EYE, AT, UP, view);
    double l = -2, r = 3, b = -1.5, t = 2, n = 0.5, f = 20;
    ortho(l, r, b, t, n, f, proj);
    mul4(proj, view, vp);
    const double fr[][2] = {{0.5, 0.5}, {0, 0}, {1, 1}, {0.3, 0.7}};
    for (size_t i = 0; i < sizeof fr / sizeof fr[0]; i++) {
        double px = VIEWPORT[0] + fr[i][0] * VIEWPORT[2], py = VIEWPORT[1] + fr[i][1] * VIEWPORT[3];
        double o[3], org[3], dir[3];
        double x = l + fr[i][0] * (r - l), y = t - fr[i][1] * (t - b);
        for (int k = 0; k < 3; k++)
            o[k] = c.eye[k] + x * c.s[k] + y * c.u[k] + n * c.f[k];
        assert_int_equal(df_view_ray(vp, VIEWPORT, px, py, org, dir, NULL), DF_OK);
        assert_vec_near(org, o, 1e-9);
        assert_vec_near(dir, c.f, 1e-12);
    }
}

static void test_infinite_far_plane(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16];
    cam c = look_at(EYE, AT, UP, view);
    double fovy = 1.0, n = 0.2, g = 1 / tan(fovy / 2);
    /* The limit far -> infinity of gluPerspective (aspect 1). */
    double m[16] = {g, 0, 0, 0, 0, g, 0, 0, 0, 0, -1, -2 * n, 0, 0, -1, 0};
    memcpy(proj, m, sizeof m);
    mul4(proj, view, vp);
    double sq[4] = {0, 0, 100, 100}, org[3], dir[3], o[3];
    assert_int_equal(df_view_ray(vp, sq, 50, 50, org, dir, NULL), DF_OK);
    for (int k = 0; k < 3; k++)
        o[k] = c.eye[k] + n * c.f[k];
    assert_vec_near(org, o, 1e-9);
    assert_vec_near(dir, c.f, 1e-9);
}

/* pixel -> ray -> hit on a tilted quad -> projected back -> the same pixel. */
static void test_round_trip_through_a_hit(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16];
    look_at(EYE, AT, UP, view);
    perspective(60 * M_PI / 180, VIEWPORT[2] / VIEWPORT[3], 0.05, 50, proj);
    mul4(proj, view, vp);
    double V[12] = {-4, -3, -1, 4, -3, 0, 4, 3, 1, -4, 3, 0.5};
    int32_t F[6] = {0, 1, 2, 0, 2, 3};
    df_raycast *rc = NULL;
    assert_int_equal(df_raycast_create(V, 4, F, 2, &rc, NULL), DF_OK);
    int hits = 0;
    for (int j = 0; j < 12; j++)
        for (int i = 0; i < 16; i++) {
            double px = VIEWPORT[0] + (i + 0.5) * VIEWPORT[2] / 16;
            double py = VIEWPORT[1] + (j + 0.5) * VIEWPORT[3] / 12;
            double org[3], dir[3], qx, qy;
            assert_int_equal(df_view_ray(vp, VIEWPORT, px, py, org, dir, NULL), DF_OK);
            project(vp, VIEWPORT, org, &qx, &qy);   /* the origin itself projects there */
            assert_true(fabs(qx - px) <= 1e-6 && fabs(qy - py) <= 1e-6);
            df_ray_hit h;
            if (!df_raycast_hit(rc, org, dir, &h))
                continue;
            hits++;
            project(vp, VIEWPORT, h.point, &qx, &qy);
            assert_true(fabs(qx - px) <= 1e-6 && fabs(qy - py) <= 1e-6);
        }
    assert_true(hits >= 100);   /* the quad fills most of the view */
    df_raycast_free(rc);
}

static void test_inverse(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16], inv[16], id[16];
    look_at(EYE, AT, UP, view);
    perspective(1.2, 1.5, 0.01, 1000, proj);
    mul4(proj, view, vp);
    const double *ms[] = {view, proj, vp};
    for (int m = 0; m < 3; m++) {
        assert_int_equal(df_mat4_inverse(ms[m], inv), DF_OK);
        mul4(ms[m], inv, id);
        for (int i = 0; i < 16; i++)
            assert_true(fabs(id[i] - (i % 5 == 0)) <= 1e-9);
    }
}

static void test_refused(void **state)
{
    (void)state;
    double view[16], proj[16], vp[16];
    look_at(EYE, AT, UP, view);
    perspective(1.0, 1.0, 0.1, 10, proj);
    mul4(proj, view, vp);
    double org[3] = {7, 7, 7}, dir[3] = {7, 7, 7};
    df_error e;
    double zero[16] = {0};
    assert_int_equal(df_view_ray(zero, VIEWPORT, 1, 1, org, dir, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "singular"));
    double rank3[16];
    memcpy(rank3, vp, sizeof rank3);
    for (int c = 0; c < 4; c++)   /* row 3 = row 0 + 2 row 1 */
        rank3[12 + c] = vp[c] + 2 * vp[4 + c];
    assert_int_equal(df_view_ray(rank3, VIEWPORT, 1, 1, org, dir, &e), DF_EINVAL);
    double nan_m[16];
    memcpy(nan_m, vp, sizeof nan_m);
    nan_m[6] = NAN;
    assert_int_equal(df_view_ray(nan_m, VIEWPORT, 1, 1, org, dir, &e), DF_EINVAL);
    double bad_vp[4] = {0, 0, 0, 600};
    assert_int_equal(df_view_ray(vp, bad_vp, 1, 1, org, dir, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "viewport"));
    bad_vp[2] = INFINITY;
    assert_int_equal(df_view_ray(vp, bad_vp, 1, 1, org, dir, &e), DF_EINVAL);
    assert_int_equal(df_view_ray(vp, VIEWPORT, NAN, 1, org, dir, &e), DF_EINVAL);
    assert_int_equal(df_view_ray(NULL, VIEWPORT, 1, 1, org, dir, &e), DF_EINVAL);
    assert_int_equal(df_view_ray(vp, VIEWPORT, 1, 1, NULL, dir, &e), DF_EINVAL);
    /* An affine (w = 1 everywhere) matrix whose inverse exists but maps NDC z = -1 and 0 to the
     * same point cannot happen; a matrix taking every point to w = 0 at the pixel can: rows
     * x and w equal, so NDC x = 1 is the plane at infinity in the unprojection. */
    double wx[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1};
    double sq[4] = {0, 0, 2, 2};   /* pixel x = 2 (the right edge) is NDC x = 1 */
    int rc = df_view_ray(wx, sq, 2, 1, org, dir, &e);
    assert_int_equal(rc, DF_EINVAL);
    assert_non_null(strstr(e.msg, "infinity"));
    for (int k = 0; k < 3; k++)
        assert_true(org[k] == 7 && dir[k] == 7);   /* untouched by every refusal */
    double inv[16];
    assert_int_equal(df_mat4_inverse(zero, inv), DF_EINVAL);
    /* Ill-conditioned: row 3 = row 0 + 1e-14 e_w (det ~1e-14, rows' norm product ~30). */
    double near_sing[16] = {1, 2, 3, 4, 0, 1, 0, 0, 0, 0, 1, 0, 1, 2, 3, 4 + 1e-14};
    assert_int_equal(df_mat4_inverse(near_sing, inv), DF_EINVAL);
    /* A uniformly tiny but well-conditioned matrix is fine (the test is relative). */
    double tiny[16] = {1e-30, 0, 0, 0, 0, 1e-30, 0, 0, 0, 0, 1e-30, 0, 0, 0, 0, 1e-30};
    assert_int_equal(df_mat4_inverse(tiny, inv), DF_OK);
    assert_true(fabs(inv[0] - 1e30) <= 1e16);
}

static void test_pen_pixel(void **state)
{
    (void)state;
    double px = -1, py = -1;
    df_error e;
    assert_int_equal(df_view_pen_pixel(VIEWPORT, 0, 0, &px, &py, &e), DF_OK);
    assert_true(px == VIEWPORT[0] && py == VIEWPORT[1]);
    assert_int_equal(df_view_pen_pixel(VIEWPORT, 1, 1, &px, &py, &e), DF_OK);
    assert_true(px == VIEWPORT[0] + VIEWPORT[2] && py == VIEWPORT[1] + VIEWPORT[3]);
    assert_int_equal(df_view_pen_pixel(VIEWPORT, 0.25, 0.75, &px, &py, &e), DF_OK);
    assert_true(fabs(px - (10 + 200)) <= 1e-12 && fabs(py - (20 + 450)) <= 1e-12);
    assert_int_equal(df_view_pen_pixel(VIEWPORT, NAN, 0, &px, &py, &e), DF_EINVAL);
    double flat[4] = {0, 0, 100, -1};
    assert_int_equal(df_view_pen_pixel(flat, 0, 0, &px, &py, &e), DF_EINVAL);
    assert_int_equal(df_view_pen_pixel(NULL, 0, 0, &px, &py, &e), DF_EINVAL);
    assert_true(fabs(px - 210) <= 1e-12 && fabs(py - 470) <= 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_perspective_known_rays),
        cmocka_unit_test(test_orthographic_known_rays),
        cmocka_unit_test(test_infinite_far_plane),
        cmocka_unit_test(test_round_trip_through_a_hit),
        cmocka_unit_test(test_inverse),
        cmocka_unit_test(test_refused),
        cmocka_unit_test(test_pen_pixel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

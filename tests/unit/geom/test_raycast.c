/* Unit tests of core/geom/raycast (Embree): analytic hits on a triangle and a quad (t, point,
 * face, barycentrics), misses, the nearest of stacked layers, refit after moving vertices, bad
 * input refused, real meshes from $MESHES (a surface and a tet boundary) against a brute-force
 * double-precision Möller-Trumbore over every face for many random rays, and no thread started
 * by a build or refit of a mesh big enough for Embree to build in parallel by default. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/geom/raycast.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/operators.h"
#include "tests/unit/unit_skip.h"

static void lerp_tri(const double *a, const double *b, const double *c, double u, double v,
                     double *p)
{
    for (int k = 0; k < 3; k++)
        p[k] = (1 - u - v) * a[k] + u * b[k] + v * c[k];
}

static void test_triangle_analytic(void **state)
{
    (void)state;
    double V[9] = {1, 2, 3, 4, 2, 3, 1, 5, 4};
    int32_t F[3] = {0, 1, 2};
    df_raycast *rc = NULL;
    df_error e;
    assert_int_equal(df_raycast_create(V, 3, F, 1, &rc, &e), DF_OK);
    assert_int_equal(df_raycast_nv(rc), 3);
    assert_int_equal(df_raycast_nf(rc), 1);
    const double bary[][2] = {{0.25, 0.35}, {0.1, 0.1}, {0.6, 0.3}, {0.05, 0.9}};
    const double dirs[][3] = {{0.3, -0.2, -1.0}, {-0.1, 0.4, 2.0}, {1.0, 1.0, 0.5}};
    for (size_t i = 0; i < sizeof bary / sizeof bary[0]; i++)
        for (size_t j = 0; j < sizeof dirs / sizeof dirs[0]; j++) {
            double P[3], org[3], t0 = 2.5 + (double)i;
            lerp_tri(V, V + 3, V + 6, bary[i][0], bary[i][1], P);
            for (int k = 0; k < 3; k++)
                org[k] = P[k] - t0 * dirs[j][k];
            df_ray_hit h;
            assert_int_equal(df_raycast_hit(rc, org, dirs[j], &h), 1);
            assert_int_equal(h.face, 0);
            assert_true(fabs(h.t - t0) <= 1e-12 * t0);
            assert_true(fabs(h.u - bary[i][0]) <= 1e-12);
            assert_true(fabs(h.v - bary[i][1]) <= 1e-12);
            for (int k = 0; k < 3; k++)
                assert_true(fabs(h.point[k] - P[k]) <= 1e-12);
        }
    df_raycast_free(rc);
}

static void test_quad_faces_and_misses(void **state)
{
    (void)state;
    /* Unit square in the plane z = 1, split along the diagonal (0,0)-(1,1). */
    double V[12] = {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
    int32_t F[6] = {0, 1, 2, 0, 2, 3};
    df_raycast *rc = NULL;
    assert_int_equal(df_raycast_create(V, 4, F, 2, &rc, NULL), DF_OK);
    df_ray_hit h;
    double down[3] = {0, 0, -1}, up[3] = {0, 0, 1};
    double o1[3] = {0.7, 0.2, 3}, o2[3] = {0.2, 0.7, 3};
    assert_int_equal(df_raycast_hit(rc, o1, down, &h), 1);
    assert_int_equal(h.face, 0);   /* below the diagonal: (0,0),(1,0),(1,1) */
    /* x = 0.7, y = 0.2 = (1-u-v)(0,0) + u(1,0) + v(1,1): v = 0.2, u = 0.5 */
    assert_true(fabs(h.u - 0.5) <= 1e-12 && fabs(h.v - 0.2) <= 1e-12);
    assert_true(fabs(h.t - 2) <= 1e-12);
    assert_int_equal(df_raycast_hit(rc, o2, down, &h), 1);
    assert_int_equal(h.face, 1);   /* (0,0),(1,1),(0,1): x = u, y = u + v */
    assert_true(fabs(h.u - 0.2) <= 1e-12 && fabs(h.v - 0.5) <= 1e-12);
    /* From below, pointing up: the back side is hit too. */
    double o3[3] = {0.7, 0.2, -1};
    assert_int_equal(df_raycast_hit(rc, o3, up, &h), 1);
    assert_true(fabs(h.t - 2) <= 1e-12 && h.face == 0);
    /* Misses: pointing away, beside the quad, parallel to it, degenerate rays. */
    h.face = -7;
    assert_int_equal(df_raycast_hit(rc, o1, up, &h), 0);
    double beside[3] = {1.5, 0.5, 3};
    assert_int_equal(df_raycast_hit(rc, beside, down, &h), 0);
    double par_d[3] = {1, 0, 0}, par_o2[3] = {-1, 0.5, 1.5};
    assert_int_equal(df_raycast_hit(rc, par_o2, par_d, &h), 0);
    double zero[3] = {0, 0, 0}, nan_d[3] = {NAN, 0, -1}, inf_o[3] = {INFINITY, 0, 0};
    assert_int_equal(df_raycast_hit(rc, o1, zero, &h), 0);
    assert_int_equal(df_raycast_hit(rc, o1, nan_d, &h), 0);
    assert_int_equal(df_raycast_hit(rc, inf_o, down, &h), 0);
    assert_int_equal(df_raycast_hit(NULL, o1, down, &h), 0);
    assert_int_equal(df_raycast_hit(rc, o1, down, NULL), 0);
    assert_int_equal(h.face, -7);  /* untouched by every miss */
    df_raycast_free(rc);
    df_raycast_free(NULL);
}

/* n stacked unit squares at z = 0 .. n-1, listed in a scrambled order (face order must not
 * matter). Layer of face f: LAYER_OF[f / 2]. */
#define NL 5
static const int LAYER_ORDER[NL] = {3, 0, 4, 1, 2};

static void layers(double *V, int32_t *F, double shift_top_x)
{
    for (int i = 0; i < NL; i++) {
        double z = LAYER_ORDER[i], dx = LAYER_ORDER[i] == NL - 1 ? shift_top_x : 0;
        double q[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int c = 0; c < 4; c++) {
            V[12 * i + 3 * c] = q[c][0] + dx;
            V[12 * i + 3 * c + 1] = q[c][1];
            V[12 * i + 3 * c + 2] = z;
        }
        int32_t b = 4 * i, t[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(F + 6 * i, t, sizeof t);
    }
}

static void test_nearest_layer_and_refit(void **state)
{
    (void)state;
    double V[NL * 12], V2[NL * 12];
    int32_t F[NL * 6];
    layers(V, F, 0);
    df_raycast *rc = NULL;
    assert_int_equal(df_raycast_create(V, NL * 4, F, NL * 2, &rc, NULL), DF_OK);
    double down[3] = {0, 0, -1}, up[3] = {0, 0, 1};
    df_ray_hit h;
    for (int i = 0; i <= NL; i++) {   /* start above layer i - 0.5 ... */
        double o[3] = {0.3, 0.6, i - 0.5};
        if (i == 0) {
            assert_int_equal(df_raycast_hit(rc, o, down, &h), 0);
            assert_int_equal(df_raycast_hit(rc, o, up, &h), 1);
            assert_int_equal(LAYER_ORDER[h.face / 2], 0);
            assert_true(fabs(h.t - 0.5) <= 1e-12);
            continue;
        }
        assert_int_equal(df_raycast_hit(rc, o, down, &h), 1);
        assert_int_equal(LAYER_ORDER[h.face / 2], i - 1);
        assert_true(fabs(h.t - 0.5) <= 1e-12);
        assert_true(fabs(h.point[2] - (i - 1)) <= 1e-12);
    }
    /* Move the top layer away in x: a ray from above now reaches layer NL - 2. */
    layers(V2, F, 10);
    df_error e;
    assert_int_equal(df_raycast_refit(rc, V2, &e), DF_OK);
    double top[3] = {0.3, 0.6, NL + 1.0};
    assert_int_equal(df_raycast_hit(rc, top, down, &h), 1);
    assert_int_equal(LAYER_ORDER[h.face / 2], NL - 2);
    assert_true(fabs(h.t - 3) <= 1e-12);
    double top_moved[3] = {10.3, 0.6, NL + 1.0};
    assert_int_equal(df_raycast_hit(rc, top_moved, down, &h), 1);
    assert_int_equal(LAYER_ORDER[h.face / 2], NL - 1);
    assert_true(fabs(h.point[0] - 10.3) <= 1e-12 && fabs(h.t - 2) <= 1e-12);
    /* A bad refit changes nothing: NaN and beyond-float coordinates are refused. */
    double bad[NL * 12];
    memcpy(bad, V, sizeof bad);
    bad[7] = NAN;
    assert_int_equal(df_raycast_refit(rc, bad, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "vertex 2"));
    bad[7] = 1e39;
    assert_int_equal(df_raycast_refit(rc, bad, &e), DF_EINVAL);
    assert_int_equal(df_raycast_refit(NULL, V, &e), DF_EINVAL);
    assert_int_equal(df_raycast_hit(rc, top_moved, down, &h), 1);
    assert_int_equal(LAYER_ORDER[h.face / 2], NL - 1);
    /* Back to the original positions. */
    assert_int_equal(df_raycast_refit(rc, V, &e), DF_OK);
    assert_int_equal(df_raycast_hit(rc, top, down, &h), 1);
    assert_int_equal(LAYER_ORDER[h.face / 2], NL - 1);
    assert_int_equal(df_raycast_hit(rc, top_moved, down, &h), 0);
    df_raycast_free(rc);
}

static void test_create_refuses_bad_input(void **state)
{
    (void)state;
    double V[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    int32_t F[3] = {0, 1, 2}, Fbad[3] = {0, 1, 3}, Fneg[3] = {0, -1, 2};
    df_raycast *rc = (df_raycast *)&V;  /* must stay untouched */
    df_error e;
    assert_int_equal(df_raycast_create(V, 3, Fbad, 1, &rc, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "index 3 out of range"));
    assert_int_equal(df_raycast_create(V, 3, Fneg, 1, &rc, &e), DF_EINVAL);
    assert_int_equal(df_raycast_create(V, 0, F, 1, &rc, &e), DF_EINVAL);
    assert_int_equal(df_raycast_create(V, 3, F, 0, &rc, &e), DF_EINVAL);
    assert_int_equal(df_raycast_create(NULL, 3, F, 1, &rc, &e), DF_EINVAL);
    assert_int_equal(df_raycast_create(V, 3, NULL, 1, &rc, &e), DF_EINVAL);
    assert_int_equal(df_raycast_create(V, 3, F, 1, NULL, &e), DF_EINVAL);
    V[4] = INFINITY;
    assert_int_equal(df_raycast_create(V, 3, F, 1, &rc, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "vertex 1 coordinate 1"));
    V[4] = -3.5e38;
    assert_int_equal(df_raycast_create(V, 3, F, 1, &rc, &e), DF_EINVAL);
    assert_ptr_equal(rc, (df_raycast *)&V);
    /* A degenerate face is accepted and never hit. */
    double D[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    assert_int_equal(df_raycast_create(D, 3, F, 1, &rc, &e), DF_OK);
    double o[3] = {0.5, 0, 1}, d[3] = {0, 0, -1};
    df_ray_hit h;
    assert_int_equal(df_raycast_hit(rc, o, d, &h), 0);
    df_raycast_free(rc);
}

/* ---- real meshes against brute force ---- */

/* Möller-Trumbore in double: 1 with t > 0, barycentrics, for the ray against one triangle. */
static int mt(const double *o, const double *d, const double *a, const double *b, const double *c,
              double *t, double *u, double *v)
{
    double e1[3], e2[3], p[3], s[3], q[3];
    for (int k = 0; k < 3; k++)
        e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], s[k] = o[k] - a[k];
    p[0] = d[1] * e2[2] - d[2] * e2[1];
    p[1] = d[2] * e2[0] - d[0] * e2[2];
    p[2] = d[0] * e2[1] - d[1] * e2[0];
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0)
        return 0;
    double uu = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    q[0] = s[1] * e1[2] - s[2] * e1[1];
    q[1] = s[2] * e1[0] - s[0] * e1[2];
    q[2] = s[0] * e1[1] - s[1] * e1[0];
    double vv = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    if (uu < 0 || vv < 0 || uu + vv > 1 || !(tt > 0))
        return 0;
    *t = tt, *u = uu, *v = vv;
    return 1;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * 0x1.0p-53;
}

static int threads_at_start;   /* the process's thread count before any test (main) */

static int nthreads(void)
{
    DIR *d = opendir("/proc/self/task");
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

/* Casts nrays random rays (from a sphere around the mesh towards random points of its box) with
 * Embree and by brute force. Embree must give the brute-force nearest face and t (float
 * tolerance) unless the ray is ambiguous there: it grazes an edge (a barycentric below 1e-4) or
 * another face is hit within the t tolerance (then Embree's face must be one of those). */
static void compare_brute(const double *V, int32_t nv, const int32_t *F, int32_t nf, int nrays)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], V[3 * i + k]), hi[k] = fmax(hi[k], V[3 * i + k]);
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1])
                       + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    int threads0 = threads_at_start;
    df_raycast *rc = NULL;
    df_error e;
    assert_int_equal(df_raycast_create(V, nv, F, nf, &rc, &e), DF_OK);
    assert_int_equal(nthreads(), threads0);   /* the build started no thread */
    int hits = 0, agree = 0, ambiguous = 0;
    double tol = 1e-5 * diag;
    for (int r = 0; r < nrays; r++) {
        double o[3], d[3], target[3], z = 2 * rnd() - 1, ph = 2 * M_PI * rnd();
        double s = sqrt(1 - z * z), dn = 0;
        double dirs[3] = {s * cos(ph), s * sin(ph), z};
        for (int k = 0; k < 3; k++) {
            double c = 0.5 * (lo[k] + hi[k]);
            o[k] = c + 1.5 * diag * dirs[k];
            target[k] = lo[k] + rnd() * (hi[k] - lo[k]);
            d[k] = target[k] - o[k];
            dn += d[k] * d[k];
        }
        if (r % 2)   /* half the rays with a unit direction, half not */
            for (int k = 0; k < 3; k++)
                d[k] /= sqrt(dn);
        double bt = INFINITY, bu = 0, bv = 0;
        int32_t bf = -1;
        for (int32_t f = 0; f < nf; f++) {
            double t, u, v;
            if (mt(o, d, V + 3 * F[3 * f], V + 3 * F[3 * f + 1], V + 3 * F[3 * f + 2], &t, &u,
                   &v) && t < bt)
                bt = t, bu = u, bv = v, bf = f;
        }
        df_ray_hit h;
        int got = df_raycast_hit(rc, o, d, &h);
        double tl = tol / sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (bf < 0 && !got) {
            agree++;
            continue;
        }
        hits += bf >= 0;
        int edge = bf >= 0 && fmin(fmin(bu, bv), 1 - bu - bv) < 1e-4;
        if (bf >= 0 && got && h.face == bf && fabs(h.t - bt) <= tl) {
            agree++;
            double q[3];
            for (int k = 0; k < 3; k++)
                q[k] = o[k] + h.t * d[k];
            for (int k = 0; k < 3; k++)
                assert_true(fabs(q[k] - h.point[k]) <= tol);
            assert_true(fabs(h.u - bu) <= 1e-4 && fabs(h.v - bv) <= 1e-4);
            continue;
        }
        /* Disagreement: only allowed when ambiguous. */
        int ok = edge;
        if (got && bf >= 0 && fabs(h.t - bt) <= tl) {
            double t, u, v;   /* Embree's face is hit by brute force at (nearly) the same t */
            const int32_t *g = F + 3 * h.face;
            if (mt(o, d, V + 3 * g[0], V + 3 * g[1], V + 3 * g[2], &t, &u, &v)
                && fabs(t - bt) <= tl)
                ok = 1;
            if (fmin(fmin(h.u, h.v), 1 - h.u - h.v) < 1e-4)
                ok = 1;   /* Embree's hit itself is on an edge shared with the brute face */
        }
        if (!ok)
            print_error("ray %d: embree %s face %d t %.9g, brute face %d t %.9g (u %g v %g)\n", r,
                        got ? "hit" : "missed", got ? h.face : -1, got ? h.t : 0.0, bf, bt, bu,
                        bv);
        assert_true(ok);
        ambiguous++;
    }
    printf("  %d rays: %d hit the mesh, %d agree exactly, %d ambiguous (edge or tie)\n", nrays,
           hits, agree, ambiguous);
    assert_true(hits >= nrays / 5);        /* the rays do reach the mesh */
    assert_true(ambiguous <= nrays / 50);  /* ties are rare */
    /* Refit to a deformed copy (a twist about z) and compare again on a few rays. */
    double *W = malloc(3 * (size_t)nv * sizeof *W);
    assert_non_null(W);
    for (int32_t i = 0; i < nv; i++) {
        double a = 0.5 * (V[3 * i + 2] - lo[2]) / diag;
        W[3 * i] = cos(a) * V[3 * i] - sin(a) * V[3 * i + 1];
        W[3 * i + 1] = sin(a) * V[3 * i] + cos(a) * V[3 * i + 1];
        W[3 * i + 2] = V[3 * i + 2];
    }
    assert_int_equal(df_raycast_refit(rc, W, &e), DF_OK);
    assert_int_equal(nthreads(), threads0);   /* nor did the refit */
    df_raycast_free(rc);
    if (nrays > 0) {
        /* The twisted mesh gives the same answers as a fresh build on it (the refit is exact). */
        df_raycast *fresh = NULL;
        assert_int_equal(df_raycast_create(W, nv, F, nf, &fresh, &e), DF_OK);
        assert_int_equal(df_raycast_create(V, nv, F, nf, &rc, &e), DF_OK);
        assert_int_equal(df_raycast_refit(rc, W, &e), DF_OK);
        int same = 0, n = 0;
        for (int r = 0; r < 500; r++) {
            double o[3], d[3];
            for (int k = 0; k < 3; k++) {
                o[k] = 0.5 * (lo[k] + hi[k]) + diag * (2 * rnd() - 1);
                d[k] = lo[k] + rnd() * (hi[k] - lo[k]) - o[k];
            }
            df_ray_hit h1, h2;
            int g1 = df_raycast_hit(rc, o, d, &h1), g2 = df_raycast_hit(fresh, o, d, &h2);
            n += g1 || g2;
            same += g1 == g2 && (!g1 || (h1.face == h2.face && h1.t == h2.t));
        }
        printf("  refit vs fresh build on the twisted mesh: %d of 500 rays identical (%d hit)\n",
               same, n);
        assert_true(same >= 495 && n >= 100);
        df_raycast_free(rc);
        df_raycast_free(fresh);
    }
    free(W);
}

static void test_real_surface_vs_brute_force(void **state)
{
    (void)state;
    char path[1024];
    unit_mesh_or_skip("bunny.off", path, sizeof path);
    df_mesh m;
    memset(&m, 0, sizeof m);
    df_error e;
    assert_int_equal(df_mesh_read_file(path, NULL, &m, NULL, &e), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    compare_brute(m.V, m.nv, m.E, m.ne, 2000);
    df_mesh_free(&m);
}

static void test_real_tet_boundary_vs_brute_force(void **state)
{
    (void)state;
    char path[1024];
    unit_mesh_or_skip("octopus-low.mesh", path, sizeof path);
    df_mesh m;
    memset(&m, 0, sizeof m);
    df_error e;
    assert_int_equal(df_mesh_read_file(path, NULL, &m, NULL, &e), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TET);
    int32_t *B = NULL, nb = 0;
    assert_int_equal(df_mesh_boundary_faces(&m, &B, &nb, &e), DF_OK);
    assert_true(nb > 0);
    compare_brute(m.V, m.nv, B, nb, 2000);
    free(B);
    df_mesh_free(&m);
}

/* A 300 x 300 grid (178k faces): big enough that Embree's default configuration builds it in
 * parallel (on this 2-core machine a default device starts a TBB worker during the build); the
 * configured device must not start any thread, neither for the build nor for a refit. */
static void test_no_threads_started(void **state)
{
    (void)state;
    enum { N = 300 };
    double *V = malloc(3 * (size_t)N * N * sizeof *V);
    int32_t *F = malloc(6 * (size_t)(N - 1) * (N - 1) * sizeof *F);
    assert_non_null(V);
    assert_non_null(F);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            double *p = V + 3 * (size_t)(j * N + i);
            p[0] = i, p[1] = j, p[2] = sin(0.1 * i) * cos(0.07 * j);
        }
    size_t f = 0;
    for (int j = 0; j + 1 < N; j++)
        for (int i = 0; i + 1 < N; i++) {
            int32_t a = j * N + i, t[6] = {a, a + 1, a + N + 1, a, a + N + 1, a + N};
            memcpy(F + 3 * f, t, sizeof t);
            f += 2;
        }
    int before = threads_at_start;
    assert_true(before >= 1);
    df_raycast *rc = NULL;
    df_error e;
    assert_int_equal(df_raycast_create(V, N * N, F, (int32_t)f, &rc, &e), DF_OK);
    assert_int_equal(nthreads(), before);
    for (int i = 0; i < N * N; i++)
        V[3 * i + 2] += 0.5;
    assert_int_equal(df_raycast_refit(rc, V, &e), DF_OK);
    assert_int_equal(nthreads(), before);
    double o[3] = {150.25, 150.5, 10}, d[3] = {0, 0, -1};
    df_ray_hit h;
    assert_int_equal(df_raycast_hit(rc, o, d, &h), 1);
    /* (150.25, 150.5) lies in the upper triangle (a, a+N+1, a+N) of cell (150, 150) with
     * u = 0.25, v = 0.25 (x = i + u, y = j + u + v). */
    const double *za = V + 3 * (150 * N + 150), *zb = za + 3 * (N + 1), *zc = za + 3 * N;
    double z = 0.5 * za[2] + 0.25 * zb[2] + 0.25 * zc[2];
    assert_int_equal(h.face, 2 * (150 * (N - 1) + 150) + 1);
    assert_true(fabs(h.point[2] - z) <= 1e-12 && fabs(h.t - (10 - z)) <= 1e-12);
    df_raycast_free(rc);
    assert_int_equal(nthreads(), before);   /* releasing an Embree device would start one */
    free(V);
    free(F);
}

int main(void)
{
    threads_at_start = nthreads();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_analytic),
        cmocka_unit_test(test_quad_faces_and_misses),
        cmocka_unit_test(test_nearest_layer_and_refit),
        cmocka_unit_test(test_create_refuses_bad_input),
        cmocka_unit_test(test_real_surface_vs_brute_force),
        cmocka_unit_test(test_real_tet_boundary_vs_brute_force),
        cmocka_unit_test(test_no_threads_started),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

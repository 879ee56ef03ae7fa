/* Unit tests for surface-aware brushes (issue 14 item 7): edge-graph geodesics (Dijkstra)
 * against distances computed independently on a grid, and the attenuation on two close,
 * disconnected parts (two parallel sheets 0.05 apart, a grab of radius 0.25 on one): with the
 * mask the untouched sheet stays exactly at rest (every displacement bit +0) while the grabbed
 * one moves as without the mask near the centre; without the mask the other sheet moves. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"
#include "core/kelvinlet/kelvinlet_surface.h"
#include "core/mesh/geodesic.h"
#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"

#define G 21   /* grid vertices per side */

/* Two G x G triangulated sheets over [0, 1]^2: z = 0 and z = gap (sheet 1 when two). */
static void sheets(df_mesh *m, int two, double gap)
{
    int ns = two ? 2 : 1;
    memset(m, 0, sizeof *m);
    m->kind = DF_MESH_TRIANGLE;
    m->nv = ns * G * G;
    m->ne = ns * 2 * (G - 1) * (G - 1);
    m->V = malloc(3 * (size_t)m->nv * sizeof *m->V);
    m->E = malloc(3 * (size_t)m->ne * sizeof *m->E);
    assert_non_null(m->V);
    assert_non_null(m->E);
    int32_t t = 0;
    for (int s = 0; s < ns; s++) {
        int32_t o = s * G * G;
        for (int j = 0; j < G; j++)
            for (int i = 0; i < G; i++) {
                double *p = m->V + 3 * (size_t)(o + j * G + i);
                p[0] = (double)i / (G - 1);
                p[1] = (double)j / (G - 1);
                p[2] = s * gap;
            }
        for (int j = 0; j + 1 < G; j++)
            for (int i = 0; i + 1 < G; i++) {
                int32_t a = o + j * G + i, b = a + 1, c = a + G, d = c + 1;
                int32_t tri[6] = {a, b, d, a, d, c};
                memcpy(m->E + 3 * (size_t)t, tri, sizeof tri);
                t += 2;
            }
    }
}

static void mesh_free(df_mesh *m)
{
    free(m->V);
    free(m->E);
}

/* Along a grid row the edge path is the straight line: dist = |x - x_src| exactly (up to the
 * rounding of the sums); across the diagonal it is the staircase/diagonal mix the
 * triangulation allows: checked against an independent closed form, the grid's chamfer
 * distance for the a-b-d triangles (diagonal steps along (1,1) only). */
static void test_dijkstra_on_grid(void **state)
{
    (void)state;
    df_mesh m;
    sheets(&m, 0, 0.0);
    df_mesh_sparse A;
    assert_int_equal(df_mesh_vertex_adjacency(&m, &A, NULL), DF_OK);
    double *dist = malloc((size_t)m.nv * sizeof *dist);
    assert_non_null(dist);
    assert_int_equal(df_mesh_geodesic_from(&A, m.V, 0, dist, NULL), DF_OK);
    double h = 1.0 / (G - 1);
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            int lo = i < j ? i : j, hi = i < j ? j : i;
            double want = lo * h * sqrt(2.0) + (hi - lo) * h;
            assert_true(fabs(dist[j * G + i] - want) < 1e-12);
        }
    assert_int_equal(df_mesh_geodesic_from(&A, m.V, m.nv, dist, NULL), DF_EINVAL);
    free(dist);
    df_mesh_sparse_free(&A);
    mesh_free(&m);
}

/* Displacements of a grab at the middle of sheet 0, masked (surface = 1) or not. */
static void grab_on_sheets(const df_mesh *m, int surface, float *d)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.radius = 0.25;
    b.nu = 0.45;
    b.order = 2;
    b.centre[0] = 0.5;
    b.centre[1] = 0.5;
    b.tip[2] = 0.1;
    df_kelvinlet_prepared p;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
    float *x = malloc(3 * (size_t)m->nv * sizeof *x);
    assert_non_null(x);
    for (size_t i = 0; i < 3 * (size_t)m->nv; i++)
        x[i] = (float)m->V[i];
    assert_int_equal(df_kelvinlet_displacements(&p, x, (size_t)m->nv, d, NULL), DF_OK);
    if (surface) {
        df_mesh_sparse A;
        assert_int_equal(df_mesh_vertex_adjacency(m, &A, NULL), DF_OK);
        double *dist = malloc((size_t)m->nv * sizeof *dist);
        float *w = malloc((size_t)m->nv * sizeof *w);
        assert_non_null(dist);
        assert_non_null(w);
        int32_t src = df_mesh_nearest_vertex(m->V, m->nv, b.centre);
        assert_int_equal(src, (G / 2) * G + G / 2);
        assert_int_equal(df_mesh_geodesic_from(&A, m->V, src, dist, NULL), DF_OK);
        assert_int_equal(df_kelvinlet_surface_weights(m->V, m->nv, dist, src, b.centre,
                                                      b.radius, b.order, w, NULL), DF_OK);
        df_kelvinlet_surface_mask(d, w, (size_t)m->nv);
        free(dist);
        free(w);
        df_mesh_sparse_free(&A);
    }
    free(x);
}

static void test_disconnected_part_stays_at_rest(void **state)
{
    (void)state;
    df_mesh m;
    sheets(&m, 1, 0.05);
    size_t n = 3 * (size_t)m.nv, half = n / 2;
    float *plain = malloc(n * sizeof *plain), *masked = malloc(n * sizeof *masked);
    assert_non_null(plain);
    assert_non_null(masked);
    grab_on_sheets(&m, 0, plain);
    grab_on_sheets(&m, 1, masked);
    double moved_plain = 0.0;
    for (size_t i = half; i < n; i++) {
        moved_plain = fmax(moved_plain, fabs(plain[i]));
        uint32_t bits;
        memcpy(&bits, &masked[i], sizeof bits);
        assert_int_equal(bits, 0u);                     /* exactly +0: at rest */
    }
    printf("# other sheet: max |u| %.3g without the mask, 0 with it\n", moved_plain);
    assert_true(moved_plain > 0.05);                    /* the grab's tip is 0.1 */
    /* on the grabbed (flat) sheet the edge path is within the slack of the straight line:
     * weight 1, the very same bits */
    assert_memory_equal(plain, masked, half * sizeof *plain);
    free(plain);
    free(masked);
    mesh_free(&m);
}

/* A sheet folded into a U (the "next finger"): vertices close in space but far along the
 * surface are attenuated, monotonically in the detour; weights stay in [0, 1]. */
static void test_detour_attenuates(void **state)
{
    (void)state;
    df_mesh m;
    sheets(&m, 0, 0.0);
    for (int j = 0; j < G; j++)          /* fold: x > 0.5 goes back over the sheet at z = 0.1 */
        for (int i = 0; i < G; i++) {
            double *p = m.V + 3 * (size_t)(j * G + i);
            if (p[0] > 0.5) {
                p[2] = 0.1;
                p[0] = 1.0 - p[0];
            }
        }
    df_mesh_sparse A;
    assert_int_equal(df_mesh_vertex_adjacency(&m, &A, NULL), DF_OK);
    double *dist = malloc((size_t)m.nv * sizeof *dist);
    float *w = malloc((size_t)m.nv * sizeof *w);
    assert_non_null(dist);
    assert_non_null(w);
    double c[3] = {0.1, 0.5, 0.0};
    int32_t src = df_mesh_nearest_vertex(m.V, m.nv, c);
    assert_int_equal(df_mesh_geodesic_from(&A, m.V, src, dist, NULL), DF_OK);
    assert_int_equal(df_kelvinlet_surface_weights(m.V, m.nv, dist, src, c, 0.05, 1, w, NULL),
                     DF_OK);
    int j = G / 2, below = j * G + 2, above = j * G + (G - 1 - 2);  /* both at x = 0.1 */
    assert_true(fabs(m.V[3 * below] - m.V[3 * above]) < 1e-12);
    assert_true(w[below] == 1.0f);
    printf("# folded sheet: weight %.3g 0.1 above the centre, across the fold\n", w[above]);
    assert_true(w[above] < 0.25f && w[above] > 0.0f);
    for (int32_t v = 0; v < m.nv; v++)
        assert_true(w[v] >= 0.0f && w[v] <= 1.0f);
    assert_int_equal(df_kelvinlet_surface_weights(m.V, m.nv, dist, src, c, -1.0, 1, w, NULL),
                     DF_EINVAL);
    free(dist);
    free(w);
    df_mesh_sparse_free(&A);
    mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dijkstra_on_grid),
        cmocka_unit_test(test_disconnected_part_stays_at_rest),
        cmocka_unit_test(test_detour_attenuates),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* test_surface_cache — the per-session cache of surface-brush distances
 * (server/session/surface_cache.h): a second stroke near the same centre vertex is answered
 * from the cache with the very distances a fresh df_stroke_surface_dist computes (over the
 * rest positions, whatever the current ones), another vertex misses, and bad arguments are
 * refused with the cache unchanged. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/mesh/operators.h"
#include "server/session/stroke_recipe.h"
#include "server/session/surface_cache.h"

#define G 12

static df_mesh grid(void)
{
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = G * G;
    m.ne = 2 * (G - 1) * (G - 1);
    m.V = malloc(3 * (size_t)m.nv * sizeof *m.V);
    m.E = malloc(3 * (size_t)m.ne * sizeof *m.E);
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double *p = m.V + 3 * (j * G + i);
            p[0] = i / (double)(G - 1);
            p[1] = j / (double)(G - 1);
            p[2] = 0.05 * sin(4.0 * p[0]);
        }
    int32_t t = 0;
    for (int j = 0; j + 1 < G; j++)
        for (int i = 0; i + 1 < G; i++) {
            int32_t a = j * G + i, tri[6] = {a, a + 1, a + G + 1, a, a + G + 1, a + G};
            memcpy(m.E + 3 * (size_t)t, tri, sizeof tri);
            t += 2;
        }
    return m;
}

static void test_hits_and_misses(void **state)
{
    (void)state;
    df_mesh m = grid();
    float *x0 = malloc(3 * (size_t)m.nv * sizeof *x0);
    for (size_t i = 0; i < 3 * (size_t)m.nv; i++) /* deformed: current != rest */
        x0[i] = (float)(m.V[i] + (i % 3 == 2 ? 0.02 * m.V[i - 2] : 0.0));
    df_mesh_sparse A;
    assert_int_equal(df_mesh_vertex_adjacency(&m, &A, NULL), DF_OK);
    double c[3] = {0.31, 0.52, 0.0}, *want = malloc((size_t)m.nv * sizeof *want);
    int32_t wsrc;
    assert_int_equal(df_stroke_surface_dist(&A, m.V, x0, m.nv, c, &wsrc, want, NULL), DF_OK);
    df_surface_cache *sc = NULL;
    double *d = NULL;
    int32_t src = -1;
    for (int k = 0; k < 2; k++) {
        assert_int_equal(df_surface_cache_dist(&sc, &m, x0, m.nv, c, &src, &d, NULL), DF_OK);
        assert_int_equal(src, wsrc);
        assert_memory_equal(d, want, (size_t)m.nv * sizeof *d);
        assert_int_equal(df_surface_cache_hits(sc), (unsigned long)k);
        free(d);
    }
    c[0] = 0.9;                                       /* another vertex: a miss */
    assert_int_equal(df_surface_cache_dist(&sc, &m, x0, m.nv, c, &src, &d, NULL), DF_OK);
    assert_true(src != wsrc);
    assert_int_equal(df_surface_cache_hits(sc), 1);
    free(d);
    d = NULL;
    assert_int_equal(df_surface_cache_dist(&sc, &m, x0, m.nv - 1, c, &src, &d, NULL), DF_EINVAL);
    assert_null(d);
    assert_int_equal(df_surface_cache_hits(sc), 1);
    df_surface_cache_free(sc);
    df_mesh_sparse_free(&A);
    free(want);
    free(x0);
    free(m.V);
    free(m.E);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hits_and_misses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

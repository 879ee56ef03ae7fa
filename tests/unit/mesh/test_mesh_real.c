/* Unit tests on the real meshes of $MESHES (default ../shared/meshes; skipped with a message when
 * absent): every file reads with the vertex/element counts of its README, write -> read round trips
 * are bit-exact in every format that can hold the mesh kind, the paper's *_init*.node files differ
 * from the rest positions only at handle rows, operators hold on real data (Laplacian rows sum to 0
 * and are symmetric, the tet boundary encloses the tet volume), and the big files parse fast. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"
#include "core/mesh/operators.h"
#include "tests/unit/unit_skip.h"

static const char *meshes_dir(void)
{
    const char *d = getenv("MESHES");
    return d && *d ? d : "../shared/meshes";
}

/* Returns 1 when the mesh folder is there; otherwise skips the test (fails it under CI=true). */
static int have_meshes(void)
{
    struct stat st;
    char p[1024];
    snprintf(p, sizeof p, "%s/README.md", meshes_dir());
    if (stat(p, &st) != 0)
        unit_skip("mesh folder %s not found (set MESHES)", meshes_dir());
    return 1;
}

static void path_of(char *out, size_t n, const char *file)
{
    snprintf(out, n, "%s/%s", meshes_dir(), file);
}

typedef struct {
    const char *file;
    df_mesh_kind kind;
    int32_t nv, polygons, ne;  /* polygons as in the README; ne after triangulation */
    int planar;
} expect_t;

static const expect_t EXPECT[] = {
    {"bunny.off", DF_MESH_TRIANGLE, 3485, 6966, 6966, 0},
    {"stanford-bunny.obj", DF_MESH_TRIANGLE, 35947, 69451, 69451, 0},
    {"spot.obj", DF_MESH_TRIANGLE, 2930, 5856, 5856, 0},
    {"suzanne.obj", DF_MESH_TRIANGLE, 507, 500, 968, 0},
    {"decimated-knight.off", DF_MESH_TRIANGLE, 502, 1000, 1000, 0},
    {"woody.obj", DF_MESH_TRIANGLE, 694, 1267, 1267, 0},   /* `v x y 0`: flat 3D */
    {"bunny.mesh", DF_MESH_TET, 5433, 0, 34055, 0},
    {"octopus-low.mesh", DF_MESH_TET, 452, 0, 1140, 0},
    {"pig_rest.node", DF_MESH_TET, 10416, 0, 43749, 0},
    {"bar3_rest.ele", DF_MESH_TET, 7011, 0, 34557, 0},
    {"teaser_apple_rest.node", DF_MESH_TET, 1088, 0, 4072, 0},
};
#define N_EXPECT (sizeof EXPECT / sizeof EXPECT[0])

static void read_expect(const expect_t *x, df_mesh *m, df_mesh_report *r)
{
    char p[1024];
    df_error err;
    path_of(p, sizeof p, x->file);
    df_mesh_init(m);
    int rc = df_mesh_read_file(p, NULL, m, r, &err);
    if (rc)
        fail_msg("%s: %s", x->file, err.msg);
    assert_int_equal(m->kind, x->kind);
    assert_int_equal(m->nv, x->nv);
    assert_int_equal(m->ne, x->ne);
    assert_int_equal(m->planar, x->planar);
    if (x->kind == DF_MESH_TRIANGLE)
        assert_int_equal(r->input_polygons, x->polygons);
}

static void test_counts_match_readme(void **state)
{
    (void)state;
    have_meshes();
    for (size_t i = 0; i < N_EXPECT; i++) {
        df_mesh m;
        df_mesh_report r;
        read_expect(&EXPECT[i], &m, &r);
        printf("  %-24s nv %6d ne %6d inverted %d degenerate %d nonmanifold edges %d\n",
               EXPECT[i].file, (int)m.nv, (int)m.ne, (int)r.inverted_elements,
               (int)r.degenerate_elements, (int)r.nonmanifold_edges);
        assert_int_equal(r.inverted_elements, 0);
        assert_int_equal(r.degenerate_elements, 0);
        if (m.kind == DF_MESH_TET)
            assert_int_equal(r.index_base, 1);
        df_mesh_free(&m);
    }
}

static void same(const df_mesh *a, const df_mesh *b, int with_F, const char *what)
{
    if (a->kind != b->kind || a->nv != b->nv || a->ne != b->ne || a->planar != b->planar ||
        memcmp(a->V, b->V, (size_t)a->nv * 3 * sizeof(double)) ||
        memcmp(a->E, b->E, (size_t)a->ne * df_mesh_elem_size(a->kind) * sizeof(int32_t)))
        fail_msg("round trip %s differs", what);
    if (with_F && (a->nf != b->nf || (a->nf && memcmp(a->F, b->F, (size_t)a->nf * 12))))
        fail_msg("round trip %s: boundary faces differ", what);
}

static void test_roundtrips_exact(void **state)
{
    (void)state;
    have_meshes();
    static const df_mesh_format tri_fmts[] = {DF_FMT_OBJ, DF_FMT_OFF, DF_FMT_PLY,
                                              DF_FMT_PLY_BINARY, DF_FMT_MEDIT, DF_FMT_TETGEN};
    int trips = 0;
    for (size_t i = 0; i < N_EXPECT; i++) {
        df_mesh m;
        df_mesh_report r;
        read_expect(&EXPECT[i], &m, &r);
        for (size_t f = 0; f < sizeof tri_fmts / sizeof tri_fmts[0]; f++) {
            df_mesh_format fmt = tri_fmts[f];
            if (m.kind == DF_MESH_TET && fmt != DF_FMT_MEDIT && fmt != DF_FMT_TETGEN)
                continue;
            char what[128];
            snprintf(what, sizeof what, "%s as %s", EXPECT[i].file, df_mesh_format_name(fmt));
            df_mesh back;
            df_mesh_init(&back);
            df_error err;
            char *b1 = NULL, *b2 = NULL;
            size_t l1 = 0, l2 = 0;
            int rc;
            if (fmt == DF_FMT_TETGEN) {
                assert_int_equal(df_mesh_write_tetgen_memory(&m, &b1, &l1, &b2, &l2, &err), DF_OK);
                rc = df_mesh_read_tetgen_memory(b1, l1, b2, l2, what, NULL, &back, NULL, &err);
            } else {
                assert_int_equal(df_mesh_write_memory(&m, fmt, &b1, &l1, &err), DF_OK);
                rc = df_mesh_read_memory(b1, l1, DF_FMT_AUTO, what, NULL, &back, NULL, &err);
            }
            if (rc)
                fail_msg("%s: %s", what, err.msg);
            same(&m, &back, fmt == DF_FMT_MEDIT, what);
            trips++;
            df_mesh_free(&back);
            free(b1);
            free(b2);
        }
        df_mesh_free(&m);
    }
    assert_int_equal(trips, 6 * 6 + 5 * 2);
}

static void test_init_nodes_differ_only_at_handles(void **state)
{
    (void)state;
    have_meshes();
    static const char *sets[][3] = {{"pig_rest.node", "pig_init0.4.node", "pig_handles.txt"},
                                    {"pig_rest.node", "pig_init_teaser.node", "pig_handles.txt"},
                                    {"bar3_rest.node", "bar3_init1.node", "bar3_handles.txt"},
                                    {"teaser_apple_rest.node", "teaser_apple_init1.node",
                                     "teaser_apple_handles.txt"}};
    for (size_t s = 0; s < 4; s++) {
        char p[1024];
        double *R, *T;
        int32_t nr, nt;
        df_error err;
        path_of(p, sizeof p, sets[s][0]);
        assert_int_equal(df_mesh_read_tetgen_nodes(p, &R, &nr, &err), DF_OK);
        path_of(p, sizeof p, sets[s][1]);
        assert_int_equal(df_mesh_read_tetgen_nodes(p, &T, &nt, &err), DF_OK);
        df_mesh alone; /* a .node without its .ele is not a mesh */
        df_mesh_init(&alone);
        assert_int_equal(df_mesh_read_file(p, NULL, &alone, NULL, &err), DF_EIO);
        assert_non_null(strstr(err.msg, "init"));
        assert_non_null(strstr(err.msg, ".ele: cannot open"));
        assert_null(alone.V);
        assert_int_equal(nr, nt);
        char *is_handle = calloc((size_t)nr, 1);
        path_of(p, sizeof p, sets[s][2]);
        FILE *f = fopen(p, "r");
        assert_non_null(f);
        int h, nh = 0;
        while (fscanf(f, "%d", &h) == 1) {
            assert_true(h >= 0 && h < nr);
            is_handle[h] = 1;
            nh++;
        }
        fclose(f);
        int moved = 0;
        for (int32_t i = 0; i < nr; i++)
            if (memcmp(R + 3 * i, T + 3 * i, 3 * sizeof(double))) {
                assert_true(is_handle[i]);
                moved++;
            }
        printf("  %-24s %d handles, %d moved\n", sets[s][1], nh, moved);
        assert_true(moved > 0 && moved <= nh);
        free(is_handle);
        free(R);
        free(T);
    }
}

static void test_operators_on_real_meshes(void **state)
{
    (void)state;
    have_meshes();
    df_mesh m;
    df_mesh_report r;
    read_expect(&EXPECT[0], &m, &r); /* bunny.off, closed surface */
    df_mesh_sparse L;
    assert_int_equal(df_mesh_cotan_laplacian(&m, &L, NULL), DF_OK);
    double maxrow = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        double s = 0;
        for (int32_t t = L.ptr[i]; t < L.ptr[i + 1]; t++)
            s += L.val[t];
        if (fabs(s) > maxrow)
            maxrow = fabs(s);
    }
    assert_true(maxrow < 1e-9);
    df_mesh_sparse_free(&L);
    double *area = malloc((size_t)m.ne * sizeof(double)), *mass = malloc((size_t)m.nv * sizeof(double));
    assert_int_equal(df_mesh_element_volumes(&m, area, NULL), DF_OK);
    assert_int_equal(df_mesh_vertex_areas(&m, mass, NULL), DF_OK);
    double sa = 0, sm = 0;
    for (int32_t e = 0; e < m.ne; e++)
        sa += area[e];
    for (int32_t i = 0; i < m.nv; i++)
        sm += mass[i];
    assert_true(fabs(sa - sm) < 1e-12 * sa);
    free(area);
    free(mass);
    df_mesh_free(&m);

    read_expect(&EXPECT[8], &m, &r); /* pig tets */
    assert_int_equal(df_mesh_check_for_solver(&m, &r, NULL), DF_OK);
    double *vol = malloc((size_t)m.ne * sizeof(double)), total = 0;
    assert_int_equal(df_mesh_element_volumes(&m, vol, NULL), DF_OK);
    for (int32_t e = 0; e < m.ne; e++)
        total += vol[e];
    free(vol);
    int32_t *F, nf;
    assert_int_equal(df_mesh_boundary_faces(&m, &F, &nf, NULL), DF_OK);
    assert_int_equal(nf, r.boundary_faces);
    double div = 0;
    for (int32_t t = 0; t < nf; t++) {
        const double *a = m.V + 3 * F[3 * t], *b = m.V + 3 * F[3 * t + 1], *c = m.V + 3 * F[3 * t + 2];
        div += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    free(F);
    printf("  pig: volume %.9g, boundary-enclosed %.9g, %d boundary faces\n", total, div, (int)nf);
    assert_true(total > 0 && fabs(div - total) < 1e-9 * total);
    df_mesh_rest rest;
    assert_int_equal(df_mesh_rest_shapes(&m, &rest, NULL), DF_OK);
    df_mesh_rest_free(&rest);
    df_mesh_spokes S;
    assert_int_equal(df_mesh_spokes_rims(&m, &S, NULL), DF_OK);
    assert_int_equal(S.ptr[m.nv], m.ne * 4 * 6);
    df_mesh_spokes_free(&S);
    df_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counts_match_readme),
        cmocka_unit_test(test_roundtrips_exact),
        cmocka_unit_test(test_init_nodes_differ_only_at_handles),
        cmocka_unit_test(test_operators_on_real_meshes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

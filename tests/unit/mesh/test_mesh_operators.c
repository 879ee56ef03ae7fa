/* Unit tests for core/mesh/operators.h against closed-form values: a right triangle, a regular
 * tet, a unit cube split into tets (Freudenthal grid), planar and 3D-embedded triangle grids and a
 * polyline: measures, barycentric masses, cotangent weights and Laplacian (annihilates constants,
 * reproduces linear functions at interior vertices), rest shapes, adjacency, spokes-and-rims and
 * boundary faces. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"
#include "core/mesh/operators.h"

#define TOL 1e-12

/* Mesh over caller-owned static arrays (never freed). */
static df_mesh make(df_mesh_kind kind, int planar, double *V, int32_t nv, int32_t *E, int32_t ne)
{
    df_mesh m;
    df_mesh_init(&m);
    m.kind = kind;
    m.planar = planar;
    m.V = V;
    m.nv = nv;
    m.E = E;
    m.ne = ne;
    return m;
}

/* Unit cube [0,1]^3 split into n^3 cells of 6 Freudenthal tets, all positively oriented. */
static df_mesh cube_grid(int n)
{
    int nv = (n + 1) * (n + 1) * (n + 1);
    df_mesh m;
    df_mesh_init(&m);
    m.kind = DF_MESH_TET;
    m.nv = nv;
    m.ne = 6 * n * n * n;
    m.V = malloc((size_t)nv * 3 * sizeof(double));
    m.E = malloc((size_t)m.ne * 4 * sizeof(int32_t));
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                double *v = m.V + 3 * (i + (n + 1) * (j + (n + 1) * k));
                v[0] = (double)i / n;
                v[1] = (double)j / n;
                v[2] = (double)k / n;
            }
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int t = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k};
                    int32_t *e = m.E + 4 * t++;
                    e[0] = c[0] + (n + 1) * (c[1] + (n + 1) * c[2]);
                    for (int s = 0; s < 3; s++) {
                        c[perm[p][s]]++;
                        e[s + 1] = c[0] + (n + 1) * (c[1] + (n + 1) * c[2]);
                    }
                    if (p == 1 || p == 2 || p == 5) { /* odd permutations: swap to orient */
                        int32_t tmp = e[2];
                        e[2] = e[3];
                        e[3] = tmp;
                    }
                }
    return m;
}

/* n x n grid of unit-square cells split into triangles (CCW), optionally rotated into 3D. */
static df_mesh tri_grid(int n, int rotate)
{
    df_mesh m;
    df_mesh_init(&m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = (n + 1) * (n + 1);
    m.ne = 2 * n * n;
    m.planar = !rotate;
    m.V = malloc((size_t)m.nv * 3 * sizeof(double));
    m.E = malloc((size_t)m.ne * 3 * sizeof(int32_t));
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            double x = i + 0.3 * (i % 2) * (j > 0 && j < n), y = j * 1.5; /* irregular spacing */
            double *v = m.V + 3 * (i + (n + 1) * j);
            if (!rotate) {
                v[0] = x;
                v[1] = y;
                v[2] = 0.0;
            } else { /* plane spanned by (1,2,2)/3 and (2,1,-2)/3 */
                v[0] = (x + 2 * y) / 3;
                v[1] = (2 * x + y) / 3;
                v[2] = (2 * x - 2 * y) / 3;
            }
        }
    int t = 0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int32_t a = i + (n + 1) * j, b = a + 1, c = a + n + 1, d = c + 1;
            int32_t *e = m.E + 3 * t;
            e[0] = a; e[1] = b; e[2] = d;
            e[3] = a; e[4] = d; e[5] = c;
            t += 2;
        }
    return m;
}

/* y = L x for CSR L. */
static void spmv(const df_mesh_sparse *L, const double *x, double *y)
{
    for (int32_t i = 0; i < L->n_rows; i++) {
        double s = 0;
        for (int32_t t = L->ptr[i]; t < L->ptr[i + 1]; t++)
            s += L->val[t] * x[L->idx[t]];
        y[i] = s;
    }
}

static int on_boundary_cube(const double *v)
{
    for (int k = 0; k < 3; k++)
        if (v[k] == 0.0 || v[k] == 1.0)
            return 1;
    return 0;
}

static void test_right_triangle(void **state)
{
    (void)state;
    double V[] = {0, 0, 0, 3, 0, 0, 0, 4, 0};
    int32_t E[] = {0, 1, 2};
    df_mesh m = make(DF_MESH_TRIANGLE, 1, V, 3, E, 1);
    df_error err;
    double vol, mass[3], W[3];
    assert_int_equal(df_mesh_element_volumes(&m, &vol, &err), DF_OK);
    assert_true(fabs(vol - 6.0) < TOL);
    assert_int_equal(df_mesh_vertex_areas(&m, mass, &err), DF_OK);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(mass[i] - 2.0) < TOL);
    assert_int_equal(df_mesh_cotan_weights(&m, W, &err), DF_OK);
    assert_true(fabs(W[0]) < TOL);              /* right angle at corner 0 */
    assert_true(fabs(W[1] - 0.375) < TOL);      /* cot(angle at (3,0)) = 3/4 */
    assert_true(fabs(W[2] - 2.0 / 3.0) < TOL);  /* cot(angle at (0,4)) = 4/3 */
    df_mesh_rest r;
    assert_int_equal(df_mesh_rest_shapes(&m, &r, &err), DF_OK);
    assert_int_equal(r.dim, 2);
    const double Dm[9] = {3, 0, 0, 0, 4, 0, 0, 0, 0}, Di[9] = {1.0 / 3, 0, 0, 0, 0.25, 0, 0, 0, 0};
    for (int i = 0; i < 9; i++) {
        assert_true(fabs(r.Dm[i] - Dm[i]) < TOL);
        assert_true(fabs(r.Dm_inv[i] - Di[i]) < TOL);
    }
    assert_true(fabs(r.vol[0] - 6.0) < TOL);
    df_mesh_rest_free(&r);
    /* Clockwise order: signed area -6; a consistently clockwise mesh is not inverted ... */
    int32_t Ecw[] = {0, 2, 1};
    df_mesh cw = make(DF_MESH_TRIANGLE, 1, V, 3, Ecw, 1);
    assert_int_equal(df_mesh_element_volumes(&cw, &vol, &err), DF_OK);
    assert_true(fabs(vol + 6.0) < TOL);
    df_mesh_report rep;
    assert_int_equal(df_mesh_check_for_solver(&cw, &rep, &err), DF_OK);
    assert_int_equal(rep.inverted_elements, 0);
    /* ... but one triangle against the majority is: square fan, last triangle flipped */
    double Q[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0};
    int32_t EQ[] = {4, 0, 1, 4, 1, 2, 4, 2, 3, 4, 0, 3};
    df_mesh mixed = make(DF_MESH_TRIANGLE, 1, Q, 5, EQ, 4);
    assert_int_equal(df_mesh_check_for_solver(&mixed, &rep, &err), DF_EINVAL);
    assert_int_equal(rep.inverted_elements, 1);
    assert_int_equal(rep.first_inverted, 3);
    assert_true(fabs(rep.min_signed_volume + 0.25) < TOL);
    assert_non_null(strstr(err.msg, "1 inverted element(s) (first: element 3"));
    for (int t = 0; t < 4; t++) { /* reversing every triangle keeps exactly one odd one out */
        int32_t tmp = EQ[3 * t + 1];
        EQ[3 * t + 1] = EQ[3 * t + 2];
        EQ[3 * t + 2] = tmp;
    }
    mixed.E = EQ;
    assert_int_equal(df_mesh_analyze(&mixed, &rep, &err), DF_OK);
    assert_int_equal(rep.inverted_elements, 1);
    assert_int_equal(rep.first_inverted, 3);
}

static void test_regular_tet(void **state)
{
    (void)state;
    double V[] = {1, 1, 1, -1, 1, -1, 1, -1, -1, -1, -1, 1}; /* edge 2 sqrt(2), volume 8/3 */
    int32_t E[] = {0, 1, 2, 3};
    df_mesh m = make(DF_MESH_TET, 0, V, 4, E, 1);
    df_error err;
    double vol, mass[4], W[6];
    assert_int_equal(df_mesh_element_volumes(&m, &vol, &err), DF_OK);
    assert_true(fabs(vol - 8.0 / 3.0) < TOL);
    assert_int_equal(df_mesh_vertex_areas(&m, mass, &err), DF_OK);
    for (int i = 0; i < 4; i++)
        assert_true(fabs(mass[i] - 2.0 / 3.0) < TOL);
    /* w = l cot(theta) / 6 with l = 2 sqrt 2, cot(acos(1/3)) = 1 / (2 sqrt 2): 1/6 on every edge. */
    assert_int_equal(df_mesh_cotan_weights(&m, W, &err), DF_OK);
    for (int i = 0; i < 6; i++)
        assert_true(fabs(W[i] - 1.0 / 6.0) < TOL);
    df_mesh_sparse L;
    assert_int_equal(df_mesh_cotan_laplacian(&m, &L, &err), DF_OK);
    assert_int_equal(L.ptr[4], 16);
    for (int i = 0; i < 4; i++)
        for (int t = L.ptr[i]; t < L.ptr[i + 1]; t++)
            assert_true(fabs(L.val[t] - (L.idx[t] == i ? -0.5 : 1.0 / 6.0)) < TOL);
    df_mesh_sparse_free(&L);
    df_mesh_rest r;
    assert_int_equal(df_mesh_rest_shapes(&m, &r, &err), DF_OK);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += r.Dm_inv[3 * i + k] * r.Dm[3 * k + j];
            assert_true(fabs(s - (i == j)) < TOL);
        }
    df_mesh_rest_free(&r);
    int32_t *F, nf;
    assert_int_equal(df_mesh_boundary_faces(&m, &F, &nf, &err), DF_OK);
    assert_int_equal(nf, 4);
    for (int f = 0; f < 4; f++) { /* outward: normal points away from the centroid (origin) */
        const double *a = V + 3 * F[3 * f], *b = V + 3 * F[3 * f + 1], *c = V + 3 * F[3 * f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        assert_true(n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0.0);
    }
    free(F);
    df_mesh_report rep;
    assert_int_equal(df_mesh_check_for_solver(&m, &rep, &err), DF_OK);
    assert_int_equal(rep.boundary_faces, 4);
}

/* Tet cotan weights against an independent dihedral-angle computation on a scalene tet. */
static void test_tet_cotan_matches_dihedral(void **state)
{
    (void)state;
    double V[] = {0.1, -0.2, 0.05, 1.3, 0.1, -0.2, 0.2, 0.9, 0.3, 0.4, 0.35, 1.1};
    int32_t E[] = {0, 1, 2, 3};
    df_mesh m = make(DF_MESH_TET, 0, V, 4, E, 1);
    double W[6];
    assert_int_equal(df_mesh_cotan_weights(&m, W, NULL), DF_OK);
    const int (*pairs)[2];
    assert_int_equal(df_mesh_local_edges(DF_MESH_TET, &pairs), 6);
    for (int e = 0; e < 6; e++) {
        int i = pairs[e][0], j = pairs[e][1], k = -1, l = -1;
        for (int c = 0; c < 4; c++)
            if (c != i && c != j) {
                if (k < 0) k = c; else l = c;
            }
        const double *xk = V + 3 * k, *xl = V + 3 * l;
        double d[3] = {xl[0] - xk[0], xl[1] - xk[1], xl[2] - xk[2]};
        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double u[3], v[3];
        for (int r = 0; r < 3; r++) {
            u[r] = V[3 * i + r] - xk[r];
            v[r] = V[3 * j + r] - xk[r];
        }
        double pu = (u[0] * d[0] + u[1] * d[1] + u[2] * d[2]) / (len * len);
        double pv = (v[0] * d[0] + v[1] * d[1] + v[2] * d[2]) / (len * len);
        for (int r = 0; r < 3; r++) {
            u[r] -= pu * d[r];
            v[r] -= pv * d[r];
        }
        double cs = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
        double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double sn = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        double expect = len * (cs / sn) / 6.0;
        assert_true(fabs(W[e] - expect) < 1e-12 * (1 + fabs(expect)));
    }
}

static void test_cube_grid_volumes_laplacian_adjacency(void **state)
{
    (void)state;
    df_mesh m = cube_grid(2);
    df_error err;
    assert_int_equal(m.nv, 27);
    assert_int_equal(m.ne, 48);
    double vol[48], mass[27], sum = 0, msum = 0;
    assert_int_equal(df_mesh_element_volumes(&m, vol, &err), DF_OK);
    for (int e = 0; e < 48; e++) {
        assert_true(fabs(vol[e] - 1.0 / 48.0) < TOL);
        sum += vol[e];
    }
    assert_true(fabs(sum - 1.0) < TOL);
    assert_int_equal(df_mesh_vertex_areas(&m, mass, &err), DF_OK);
    for (int i = 0; i < 27; i++)
        msum += mass[i];
    assert_true(fabs(msum - 1.0) < TOL);
    df_mesh_sparse L;
    assert_int_equal(df_mesh_cotan_laplacian(&m, &L, &err), DF_OK);
    double ones[27], f[27], y[27];
    for (int i = 0; i < 27; i++) {
        const double *v = m.V + 3 * i;
        ones[i] = 1.0;
        f[i] = 2.0 * v[0] - 3.0 * v[1] + 0.5 * v[2] + 1.0;
    }
    spmv(&L, ones, y);
    for (int i = 0; i < 27; i++)
        assert_true(fabs(y[i]) < TOL);
    spmv(&L, f, y);
    int interior = 0;
    for (int i = 0; i < 27; i++)
        if (!on_boundary_cube(m.V + 3 * i)) {
            assert_true(fabs(y[i]) < TOL);
            interior++;
        }
    assert_int_equal(interior, 1);
    for (int i = 0; i < 27; i++) /* symmetric */
        for (int t = L.ptr[i]; t < L.ptr[i + 1]; t++) {
            int j = L.idx[t], s = L.ptr[j];
            while (L.idx[s] != i)
                s++;
            assert_true(fabs(L.val[t] - L.val[s]) < TOL);
        }
    df_mesh_sparse_free(&L);
    /* Edges: 54 axis edges, 36 face diagonals, 8 body diagonals. */
    int32_t *edges, ned;
    assert_int_equal(df_mesh_edges(&m, &edges, &ned, &err), DF_OK);
    assert_int_equal(ned, 98);
    for (int i = 0; i + 1 < ned; i++) {
        assert_true(edges[2 * i] < edges[2 * i + 1]);
        assert_true(edges[2 * i] < edges[2 * i + 2] ||
                    (edges[2 * i] == edges[2 * i + 2] && edges[2 * i + 1] < edges[2 * i + 3]));
    }
    free(edges);
    df_mesh_sparse A;
    assert_int_equal(df_mesh_vertex_adjacency(&m, &A, &err), DF_OK);
    assert_int_equal(A.ptr[27], 2 * 98);
    assert_int_equal(A.ptr[14] - A.ptr[13], 14); /* centre: 6 axis + 6 diagonals + 2 body */
    df_mesh_sparse_free(&A);
    df_mesh_sparse VE;
    assert_int_equal(df_mesh_vertex_elements(&m, &VE, &err), DF_OK);
    assert_int_equal(VE.ptr[27], 4 * 48);
    assert_int_equal(VE.ptr[14] - VE.ptr[13], 24); /* centre vertex is in all 8 cells' ... 24 tets */
    df_mesh_sparse_free(&VE);
    df_mesh_spokes S;
    assert_int_equal(df_mesh_spokes_rims(&m, &S, &err), DF_OK);
    assert_int_equal(S.ptr[27], 4 * 48 * 6);
    assert_int_equal(S.ptr[14] - S.ptr[13], 24 * 6);
    df_mesh_spokes_free(&S);
    int32_t *F, nf;
    assert_int_equal(df_mesh_boundary_faces(&m, &F, &nf, &err), DF_OK);
    assert_int_equal(nf, 6 * 2 * 4);
    double div = 0; /* divergence theorem: sum a . (b x c) / 6 over outward faces = volume */
    for (int t = 0; t < nf; t++) {
        const double *a = m.V + 3 * F[3 * t], *b = m.V + 3 * F[3 * t + 1], *c = m.V + 3 * F[3 * t + 2];
        div += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    assert_true(fabs(div - 1.0) < TOL);
    free(F);
    df_mesh_report rep;
    assert_int_equal(df_mesh_check_for_solver(&m, &rep, &err), DF_OK);
    assert_int_equal(rep.boundary_faces, 48);
    assert_int_equal(rep.nonmanifold_edges, 0);
    df_mesh_free(&m);
}

static void test_single_cube_six_tets(void **state)
{
    (void)state;
    df_mesh m = cube_grid(1);
    double vol[6], sum = 0;
    assert_int_equal(df_mesh_element_volumes(&m, vol, NULL), DF_OK);
    for (int e = 0; e < 6; e++)
        sum += vol[e];
    assert_true(fabs(sum - 1.0) < TOL);
    df_mesh_free(&m);
}

static void check_grid_laplacian(df_mesh *m, int n)
{
    df_mesh_sparse L;
    df_error err;
    assert_int_equal(df_mesh_cotan_laplacian(m, &L, &err), DF_OK);
    size_t nv = (size_t)m->nv;
    double *one = calloc(nv, sizeof(double)), *f = calloc(nv, sizeof(double)),
           *y = calloc(nv, sizeof(double));
    assert_non_null(one);
    assert_non_null(f);
    assert_non_null(y);
    for (int i = 0; i < m->nv; i++) {
        const double *v = m->V + 3 * i;
        one[i] = 1.0;
        f[i] = 0.7 * v[0] - 1.1 * v[1] + 2.0 * v[2] - 3.0;
    }
    spmv(&L, one, y);
    for (int i = 0; i < m->nv; i++)
        assert_true(fabs(y[i]) < 1e-12);
    spmv(&L, f, y);
    int interior = 0;
    for (int j = 1; j < n; j++)
        for (int i = 1; i < n; i++) {
            assert_true(fabs(y[i + (n + 1) * j]) < 1e-12);
            interior++;
        }
    assert_int_equal(interior, (n - 1) * (n - 1));
    /* and not trivially: a boundary corner row is non-zero */
    assert_true(fabs(y[0]) > 1e-3);
    free(one);
    free(f);
    free(y);
    df_mesh_sparse_free(&L);
}

static void test_triangle_grids_2d_and_3d(void **state)
{
    (void)state;
    df_mesh p = tri_grid(4, 0), s = tri_grid(4, 1);
    check_grid_laplacian(&p, 4);
    check_grid_laplacian(&s, 4);
    /* Same intrinsic geometry: identical cotan weights and masses (up to rounding). */
    double Wp[96], Ws[96], mp[25], ms[25], total = 0;
    assert_int_equal(df_mesh_cotan_weights(&p, Wp, NULL), DF_OK);
    assert_int_equal(df_mesh_cotan_weights(&s, Ws, NULL), DF_OK);
    for (int i = 0; i < 96; i++)
        assert_true(fabs(Wp[i] - Ws[i]) < 1e-12);
    assert_int_equal(df_mesh_vertex_areas(&p, mp, NULL), DF_OK);
    assert_int_equal(df_mesh_vertex_areas(&s, ms, NULL), DF_OK);
    for (int i = 0; i < 25; i++) {
        assert_true(fabs(mp[i] - ms[i]) < 1e-12);
        total += mp[i];
    }
    assert_true(fabs(total - 4 * 6.0) < 1e-12); /* 4 x 6 rectangle */
    df_mesh_rest r;
    assert_int_equal(df_mesh_rest_shapes(&s, &r, NULL), DF_OK);
    for (int e = 0; e < s.ne; e++) /* pseudo-inverse: Dm_inv (2x3) * Dm (3x2) = I2 */
        for (int i = 0; i < 2; i++)
            for (int j = 0; j < 2; j++) {
                double acc = 0;
                for (int k = 0; k < 3; k++)
                    acc += r.Dm_inv[9 * e + 3 * i + k] * r.Dm[9 * e + 3 * k + j];
                assert_true(fabs(acc - (i == j)) < 1e-12);
            }
    df_mesh_rest_free(&r);
    df_mesh_report rep;
    assert_int_equal(df_mesh_analyze(&p, &rep, NULL), DF_OK);
    assert_int_equal(rep.boundary_edges, 16);
    assert_int_equal(rep.inverted_elements, 0);
    df_mesh_spokes S;
    assert_int_equal(df_mesh_spokes_rims(&p, &S, NULL), DF_OK);
    assert_int_equal(S.ptr[25], 32 * 3 * 3);
    for (int t = S.ptr[6]; t < S.ptr[7]; t++) { /* entries of vertex 6 come from its triangles */
        const int32_t *c = p.E + 3 * S.elem[t];
        assert_true(c[0] == 6 || c[1] == 6 || c[2] == 6);
        assert_true(fabs(S.w[t] - Wp[3 * S.elem[t] + (t - S.ptr[6]) % 3]) < 1e-15);
    }
    df_mesh_spokes_free(&S);
    df_mesh_free(&p);
    df_mesh_free(&s);
}

static void test_polyline(void **state)
{
    (void)state;
    double V[] = {0, 0, 0, 1, 2, 2, 1.5, 3, 3, 4, 8, 8}; /* on a line, spacing 3, 1.5, 7.5 */
    int32_t E[] = {0, 1, 1, 2, 2, 3};
    df_mesh m = make(DF_MESH_POLYLINE, 0, V, 4, E, 3);
    double vol[3], W[3], mass[4];
    assert_int_equal(df_mesh_element_volumes(&m, vol, NULL), DF_OK);
    assert_true(fabs(vol[0] - 3.0) < TOL && fabs(vol[1] - 1.5) < TOL && fabs(vol[2] - 7.5) < TOL);
    assert_int_equal(df_mesh_cotan_weights(&m, W, NULL), DF_OK);
    assert_true(fabs(W[0] - 1.0 / 3.0) < TOL && fabs(W[2] - 1.0 / 7.5) < TOL);
    assert_int_equal(df_mesh_vertex_areas(&m, mass, NULL), DF_OK);
    assert_true(fabs(mass[1] - 2.25) < TOL && fabs(mass[3] - 3.75) < TOL);
    df_mesh_sparse L;
    assert_int_equal(df_mesh_cotan_laplacian(&m, &L, NULL), DF_OK);
    double x[4] = {0, 1, 1.5, 4}, y[4];
    spmv(&L, x, y);
    assert_true(fabs(y[1]) < TOL && fabs(y[2]) < TOL && fabs(y[0] - 1.0 / 3.0) < TOL);
    df_mesh_sparse_free(&L);
    df_mesh_rest r;
    assert_int_equal(df_mesh_rest_shapes(&m, &r, NULL), DF_OK);
    assert_int_equal(r.dim, 1);
    assert_true(fabs(r.Dm_inv[9] * r.Dm[9] + r.Dm_inv[10] * r.Dm[12] + r.Dm_inv[11] * r.Dm[15] - 1.0) < TOL);
    df_mesh_rest_free(&r);
}

static void test_degenerate_and_bad_inputs(void **state)
{
    (void)state;
    double V[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}; /* four coplanar points */
    int32_t E[] = {0, 1, 2, 3};
    df_mesh m = make(DF_MESH_TET, 0, V, 4, E, 1);
    df_error err;
    df_mesh_rest r = {0};
    assert_int_equal(df_mesh_rest_shapes(&m, &r, &err), DF_ESINGULAR);
    assert_non_null(strstr(err.msg, "element 0"));
    assert_null(r.Dm);
    double W[6];
    assert_int_equal(df_mesh_cotan_weights(&m, W, &err), DF_OK);
    for (int i = 0; i < 6; i++)
        assert_true(W[i] == 0.0);
    df_mesh_report rep;
    assert_int_equal(df_mesh_check_for_solver(&m, &rep, &err), DF_EINVAL);
    assert_int_equal(rep.degenerate_elements, 1);
    assert_non_null(strstr(err.msg, "degenerate"));
    int32_t Ebad[] = {0, 1, 2, 4};
    df_mesh b = make(DF_MESH_TET, 0, V, 4, Ebad, 1);
    double vol = 42;
    assert_int_equal(df_mesh_element_volumes(&b, &vol, &err), DF_EINVAL);
    assert_true(vol == 42);
    assert_non_null(strstr(err.msg, "out of range"));
    V[4] = NAN;
    assert_int_equal(df_mesh_element_volumes(&m, &vol, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "non-finite"));
    df_mesh tri = make(DF_MESH_TRIANGLE, 0, V, 4, E, 1);
    int32_t *F = NULL, nf = 0;
    assert_int_equal(df_mesh_boundary_faces(&tri, &F, &nf, &err), DF_EINVAL);
    assert_int_equal(df_mesh_cotan_laplacian(NULL, NULL, &err), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_right_triangle),
        cmocka_unit_test(test_regular_tet),
        cmocka_unit_test(test_tet_cotan_matches_dihedral),
        cmocka_unit_test(test_cube_grid_volumes_laplacian_adjacency),
        cmocka_unit_test(test_single_cube_six_tets),
        cmocka_unit_test(test_triangle_grids_2d_and_3d),
        cmocka_unit_test(test_polyline),
        cmocka_unit_test(test_degenerate_and_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

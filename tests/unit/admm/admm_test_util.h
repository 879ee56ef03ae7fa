/* admm_test_util.h — small synthetic meshes and helpers shared by the ADMM unit tests
 * (header-only, static inline). */
#ifndef ADMM_TEST_UTIL_H
#define ADMM_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh.h"
#include "tests/unit/unit_skip.h"

/* planar triangle grid, (nx+1) x (ny+1) vertices spanning [0, lx] x [0, ly], counter-clockwise */
static inline df_mesh tu_grid2d(int nx, int ny, double lx, double ly)
{
    df_mesh m;
    memset(&m, 0, sizeof(m));
    m.kind = DF_MESH_TRIANGLE;
    m.planar = 1;
    m.nv = (nx + 1) * (ny + 1);
    m.ne = 2 * nx * ny;
    m.V = calloc((size_t)m.nv * 3, sizeof(double));
    m.E = malloc((size_t)m.ne * 3 * sizeof(int32_t));
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++) {
            m.V[3 * (j * (nx + 1) + i)] = lx * i / nx;
            m.V[3 * (j * (nx + 1) + i) + 1] = ly * j / ny;
        }
    int e = 0;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            int32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            m.E[3 * e] = a; m.E[3 * e + 1] = b; m.E[3 * e + 2] = d; e++;
            m.E[3 * e] = a; m.E[3 * e + 1] = d; m.E[3 * e + 2] = c; e++;
        }
    return m;
}

/* tet bar of nx x ny x nz cubes (6 positive tets each) spanning [0,lx] x [0,ly] x [0,lz] */
static inline df_mesh tu_bar3d(int nx, int ny, int nz, double lx, double ly, double lz)
{
    df_mesh m;
    memset(&m, 0, sizeof(m));
    m.kind = DF_MESH_TET;
    m.nv = (nx + 1) * (ny + 1) * (nz + 1);
    m.ne = 6 * nx * ny * nz;
    m.V = malloc((size_t)m.nv * 3 * sizeof(double));
    m.E = malloc((size_t)m.ne * 4 * sizeof(int32_t));
#define TU_ID(i, j, k) ((int32_t)(((k) * (ny + 1) + (j)) * (nx + 1) + (i)))
    for (int k = 0; k <= nz; k++)
        for (int j = 0; j <= ny; j++)
            for (int i = 0; i <= nx; i++) {
                double *p = m.V + 3 * TU_ID(i, j, k);
                p[0] = lx * i / nx; p[1] = ly * j / ny; p[2] = lz * k / nz;
            }
    static const int cube6[6][4] = {{0, 1, 3, 7}, {0, 1, 7, 5}, {0, 5, 7, 4}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}};
    int e = 0;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                int32_t c[8];
                for (int b = 0; b < 8; b++) c[b] = TU_ID(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                for (int t = 0; t < 6; t++) {
                    int32_t *el = m.E + 4 * e;
                    for (int q = 0; q < 4; q++) el[q] = c[cube6[t][q]];
                    const double *x0 = m.V + 3 * el[0], *x1 = m.V + 3 * el[1], *x2 = m.V + 3 * el[2], *x3 = m.V + 3 * el[3];
                    double u[3], v[3], w[3];
                    for (int d = 0; d < 3; d++) { u[d] = x1[d] - x0[d]; v[d] = x2[d] - x0[d]; w[d] = x3[d] - x0[d]; }
                    double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if (det < 0) { int32_t tmp = el[2]; el[2] = el[3]; el[3] = tmp; }
                    e++;
                }
            }
#undef TU_ID
    return m;
}

/* The handle experiment on a tet bar 6x2x2 over [0,3]x[0,1]x[0,1]: the x = 0 face fixed, the
 * x = 3 face moved by (0, 0.8, 0.3). Outputs the mesh, the malloc'd handle indices (*nh of them)
 * and their targets (*nh x 3); the caller frees all three. */
static inline void tu_bar3d_handles(df_mesh *m, int32_t **h, int *nh, double **tg)
{
    *m = tu_bar3d(6, 2, 2, 3.0, 1.0, 1.0);
    *h = malloc((size_t)m->nv * sizeof(int32_t));
    *tg = malloc((size_t)m->nv * 3 * sizeof(double));
    *nh = 0;
    for (int32_t i = 0; i < m->nv; i++) {
        double x = m->V[3 * i];
        if (x == 0.0 || x == 3.0) {
            (*h)[*nh] = i;
            memcpy(*tg + 3 * *nh, m->V + 3 * i, 24);
            if (x == 3.0) { (*tg)[3 * *nh + 1] += 0.8; (*tg)[3 * *nh + 2] += 0.3; }
            (*nh)++;
        }
    }
}

static inline void tu_free(df_mesh *m)
{
    free(m->V);
    free(m->E);
    memset(m, 0, sizeof(*m));
}

/* tu_bar3d_handles' outputs in one record (tu_bar_load / tu_bar_free) */
typedef struct tu_bar {
    df_mesh m;
    int32_t *h;    /* nh handle indices */
    int nh;
    double *tg;    /* nh x 3 targets */
} tu_bar;

/* tu_bar3d_handles into a tu_bar; the caller frees it with tu_bar_free */
static inline tu_bar tu_bar_load(void)
{
    tu_bar b;
    tu_bar3d_handles(&b.m, &b.h, &b.nh, &b.tg);
    return b;
}

/* frees a tu_bar_load result (mesh, handles, targets) */
static inline void tu_bar_free(tu_bar *b)
{
    free(b->h);
    free(b->tg);
    tu_free(&b->m);
}

/* dense SPD solve A x = b (n x n row-major, overwritten), Cholesky; returns 0 on success */
static inline int tu_chol_solve(double *A, double *b, int n, int nrhs)
{
    for (int j = 0; j < n; j++) {
        double d = A[j * n + j];
        for (int k = 0; k < j; k++) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 0)) return -1;
        d = sqrt(d);
        A[j * n + j] = d;
        for (int i = j + 1; i < n; i++) {
            double s = A[i * n + j];
            for (int k = 0; k < j; k++) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s / d;
        }
    }
    for (int r = 0; r < nrhs; r++) {
        double *x = b + (size_t)r * n;
        for (int i = 0; i < n; i++) {
            double s = x[i];
            for (int k = 0; k < i; k++) s -= A[i * n + k] * x[k];
            x[i] = s / A[i * n + i];
        }
        for (int i = n - 1; i >= 0; i--) {
            double s = x[i];
            for (int k = i + 1; k < n; k++) s -= A[k * n + i] * x[k];
            x[i] = s / A[i * n + i];
        }
    }
    return 0;
}

/* the shared meshes folder: $MESHES or ../shared/meshes; skips the test (unit_skip: a failure under CI=true) when
 * the folder or `file` is missing */
static inline const char *tu_mesh_path(const char *file, char *buf, size_t len)
{
    const char *dir = getenv("MESHES");
    if (!dir || !*dir) dir = "../shared/meshes";
    snprintf(buf, len, "%s/%s", dir, file);
    FILE *f = fopen(buf, "r");
    if (!f)
        unit_skip("mesh file %s not found (set MESHES to the shared meshes folder)", buf);
    fclose(f);
    return buf;
}

/* reads one 0-based index per line; returns a malloc'd array or NULL */
static inline int32_t *tu_read_indices(const char *path, int32_t *n)
{
    FILE *f = fopen(path, "r");
    if (!f) return NULL;
    int32_t cap = 1024, k = 0, v;
    int32_t *a = malloc((size_t)cap * sizeof(int32_t));
    while (fscanf(f, "%d", &v) == 1) {
        if (k == cap) { cap *= 2; a = realloc(a, (size_t)cap * sizeof(int32_t)); }
        a[k++] = v;
    }
    fclose(f);
    *n = k;
    return a;
}

static inline double tu_dist(const double *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* 1 when every handle of `bh` sits within `tol` of its target in positions V (nv x 3), else 0. */
static inline int tu_handles_on_target(const double *V, const tu_bar *bh, double tol)
{
    for (int k = 0; k < bh->nh; k++)
        if (!(tu_dist(V + 3 * (size_t)bh->h[k], bh->tg + 3 * k) <= tol)) return 0;
    return 1;
}

#endif

/* op_cotan.c — cotangent weights per element and the assembled cotangent Laplacian
 * (see operators.h). */
#include "core/mesh/operators.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_geom.h"
#include "core/mesh/mesh_io.h"

/* Half cotangent of the angle at corner `a` of triangle (a, b, c); 0 when degenerate. */
static double half_cot(const double *a, const double *b, const double *c)
{
    double u[3], v[3], x[3];
    df_geom_sub(b, a, u);
    df_geom_sub(c, a, v);
    df_geom_cross(u, v, x);
    double s = df_geom_norm(x);
    return s > 0.0 ? 0.5 * df_geom_dot(u, v) / s : 0.0;
}

/* Weights of element e into w[0 .. local edges - 1]. */
static void element_weights(const df_mesh *m, int32_t e, double *w)
{
    int k = df_mesh_elem_size(m->kind);
    const int32_t *c = m->E + (size_t)k * (size_t)e;
    if (k == 2) {
        double d[3];
        df_geom_sub(m->V + 3 * (size_t)c[1], m->V + 3 * (size_t)c[0], d);
        double l = df_geom_norm(d);
        w[0] = l > 0.0 ? 1.0 / l : 0.0;
        return;
    }
    if (k == 3) {
        for (int i = 0; i < 3; i++)
            w[i] = half_cot(m->V + 3 * (size_t)c[i], m->V + 3 * (size_t)c[(i + 1) % 3],
                            m->V + 3 * (size_t)c[(i + 2) % 3]);
        return;
    }
    /* Tets: w_ij = -|V| grad(phi_i) . grad(phi_j), the P1 stiffness, which equals
     * |x_k - x_l| cot(dihedral angle at (k, l)) / 6. grad(phi_1..3) are the rows of Dm^-1. */
    double Dm[9], Di[9], vol;
    const int (*pairs)[2];
    int ne = df_mesh_local_edges(m->kind, &pairs);
    if (df_mesh_rest_one(m, e, Dm, Di, &vol)) {
        for (int i = 0; i < ne; i++)
            w[i] = 0.0;
        return;
    }
    double g[4][3];
    for (int r = 0; r < 3; r++) {
        g[0][r] = -(Di[r] + Di[3 + r] + Di[6 + r]);
        for (int i = 0; i < 3; i++)
            g[i + 1][r] = Di[3 * i + r];
    }
    for (int i = 0; i < ne; i++)
        w[i] = -fabs(vol) * df_geom_dot(g[pairs[i][0]], g[pairs[i][1]]);
}

int df_mesh_cotan_weights(const df_mesh *m, double *W, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!W && m->ne > 0)
        return df_error_set(err, DF_EINVAL, "df_mesh_cotan_weights: NULL output");
    int ne = df_mesh_local_edges(m->kind, NULL);
    for (int32_t e = 0; e < m->ne; e++)
        element_weights(m, e, W + (size_t)ne * (size_t)e);
    return DF_OK;
}

/* Position of column j in row i of s (must exist). */
static int32_t find(const df_mesh_sparse *s, int32_t i, int32_t j)
{
    int32_t lo = s->ptr[i], hi = s->ptr[i + 1] - 1;
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (s->idx[mid] < j)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

int df_mesh_cotan_laplacian(const df_mesh *m, df_mesh_sparse *L, df_error *err)
{
    if (!L)
        return df_error_set(err, DF_EINVAL, "df_mesh_cotan_laplacian: NULL output");
    df_mesh_sparse A;
    int rc = df_mesh_vertex_adjacency(m, &A, err);
    if (rc)
        return rc;
    df_mesh_sparse S = {m->nv, m->nv, malloc(((size_t)m->nv + 1) * sizeof(int32_t)),
                        malloc(((size_t)A.ptr[m->nv] + (size_t)m->nv + 1) * sizeof(int32_t)),
                        calloc((size_t)A.ptr[m->nv] + (size_t)m->nv + 1, sizeof(double))};
    if (!S.ptr || !S.idx || !S.val) {
        df_mesh_sparse_free(&A);
        df_mesh_sparse_free(&S);
        return df_error_set(err, DF_ENOMEM, "out of memory for a %d x %d Laplacian", (int)m->nv,
                            (int)m->nv);
    }
    int32_t w = 0;
    for (int32_t i = 0; i < m->nv; i++) { /* insert the diagonal in each sorted row */
        S.ptr[i] = w;
        int32_t t = A.ptr[i];
        while (t < A.ptr[i + 1] && A.idx[t] < i)
            S.idx[w++] = A.idx[t++];
        S.idx[w++] = i;
        while (t < A.ptr[i + 1])
            S.idx[w++] = A.idx[t++];
    }
    S.ptr[m->nv] = w;
    df_mesh_sparse_free(&A);
    const int (*pairs)[2];
    int nle = df_mesh_local_edges(m->kind, &pairs), k = df_mesh_elem_size(m->kind);
    double we[6];
    for (int32_t e = 0; e < m->ne; e++) {
        element_weights(m, e, we);
        const int32_t *c = m->E + (size_t)k * (size_t)e;
        for (int l = 0; l < nle; l++) {
            int32_t a = c[pairs[l][0]], b = c[pairs[l][1]];
            if (a == b)
                continue;
            S.val[find(&S, a, b)] += we[l];
            S.val[find(&S, b, a)] += we[l];
            S.val[find(&S, a, a)] -= we[l];
            S.val[find(&S, b, b)] -= we[l];
        }
    }
    *L = S;
    return DF_OK;
}

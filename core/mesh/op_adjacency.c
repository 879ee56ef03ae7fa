/* op_adjacency.c — edges, vertex adjacency, vertex-element incidence, spokes-and-rims sets and
 * tet-mesh boundary faces (see operators.h). */
#include "core/mesh/operators.h"

#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_geom.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_topo.h"

/* Sorted unique edge keys of m (self-loops from repeated indices dropped). */
static int unique_keys(const df_mesh *m, uint64_t **keys, int64_t *n, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    uint64_t *k;
    int64_t nk;
    rc = df_topo_edge_keys(m->E, m->ne, df_mesh_elem_size(m->kind), &k, &nk, err);
    if (rc)
        return rc;
    int64_t w = 0;
    for (int64_t i = 0; i < nk; i++) {
        if ((uint32_t)(k[i] >> 32) == (uint32_t)k[i])
            continue;
        if (w == 0 || k[w - 1] != k[i])
            k[w++] = k[i];
    }
    *keys = k;
    *n = w;
    return DF_OK;
}

int df_mesh_edges(const df_mesh *m, int32_t **edges, int32_t *n_edges, df_error *err)
{
    if (!edges || !n_edges)
        return df_error_set(err, DF_EINVAL, "df_mesh_edges: NULL output");
    uint64_t *k;
    int64_t n;
    int rc = unique_keys(m, &k, &n, err);
    if (rc)
        return rc;
    int32_t *E = malloc((size_t)(n ? n : 1) * 2 * sizeof *E);
    if (!E) {
        free(k);
        return df_error_set(err, DF_ENOMEM, "out of memory for %lld edges", (long long)n);
    }
    for (int64_t i = 0; i < n; i++) {
        E[2 * i] = (int32_t)(k[i] >> 32);
        E[2 * i + 1] = (int32_t)(uint32_t)k[i];
    }
    free(k);
    *edges = E;
    *n_edges = (int32_t)n;
    return DF_OK;
}

int df_mesh_vertex_adjacency(const df_mesh *m, df_mesh_sparse *A, df_error *err)
{
    if (!A)
        return df_error_set(err, DF_EINVAL, "df_mesh_vertex_adjacency: NULL output");
    uint64_t *k;
    int64_t n;
    int rc = unique_keys(m, &k, &n, err);
    if (rc)
        return rc;
    df_mesh_sparse S = {m->nv, m->nv, calloc((size_t)m->nv + 1, sizeof(int32_t)),
                        malloc((size_t)(2 * n + 1) * sizeof(int32_t)), NULL};
    int32_t *fill = calloc((size_t)m->nv + 1, sizeof(int32_t));
    if (!S.ptr || !S.idx || !fill) {
        free(k);
        free(fill);
        df_mesh_sparse_free(&S);
        return df_error_set(err, DF_ENOMEM, "out of memory for vertex adjacency");
    }
    for (int64_t i = 0; i < n; i++) {
        S.ptr[(k[i] >> 32) + 1]++;
        S.ptr[(uint32_t)k[i] + 1]++;
    }
    for (int32_t i = 0; i < m->nv; i++)
        S.ptr[i + 1] += S.ptr[i];
    /* Keys are sorted by (i, j), i < j: every row fills in ascending order (see header). */
    for (int64_t t = 0; t < n; t++) {
        int32_t i = (int32_t)(k[t] >> 32), j = (int32_t)(uint32_t)k[t];
        S.idx[S.ptr[i] + fill[i]++] = j;
        S.idx[S.ptr[j] + fill[j]++] = i;
    }
    free(k);
    free(fill);
    *A = S;
    return DF_OK;
}

int df_mesh_vertex_elements(const df_mesh *m, df_mesh_sparse *VE, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!VE)
        return df_error_set(err, DF_EINVAL, "df_mesh_vertex_elements: NULL output");
    int k = df_mesh_elem_size(m->kind);
    size_t total = (size_t)m->ne * (size_t)k;
    df_mesh_sparse S = {m->nv, m->ne, calloc((size_t)m->nv + 1, sizeof(int32_t)),
                        malloc((total ? total : 1) * sizeof(int32_t)), NULL};
    int32_t *fill = calloc((size_t)m->nv + 1, sizeof(int32_t));
    if (!S.ptr || !S.idx || !fill) {
        free(fill);
        df_mesh_sparse_free(&S);
        return df_error_set(err, DF_ENOMEM, "out of memory for vertex-element incidence");
    }
    for (size_t t = 0; t < total; t++)
        S.ptr[m->E[t] + 1]++;
    for (int32_t i = 0; i < m->nv; i++)
        S.ptr[i + 1] += S.ptr[i];
    for (int32_t e = 0; e < m->ne; e++)
        for (int c = 0; c < k; c++) {
            int32_t v = m->E[(size_t)k * (size_t)e + (size_t)c];
            if (fill[v] > 0 && S.idx[S.ptr[v] + fill[v] - 1] == e)
                continue; /* repeated index inside one element */
            S.idx[S.ptr[v] + fill[v]++] = e;
        }
    /* Compact rows shortened by repeated indices. */
    int32_t w = 0;
    for (int32_t i = 0; i < m->nv; i++) {
        int32_t start = S.ptr[i];
        S.ptr[i] = w;
        memmove(S.idx + w, S.idx + start, (size_t)fill[i] * sizeof(int32_t));
        w += fill[i];
    }
    S.ptr[m->nv] = w;
    free(fill);
    *VE = S;
    return DF_OK;
}

void df_mesh_spokes_free(df_mesh_spokes *s)
{
    if (!s)
        return;
    free(s->ptr);
    free(s->a);
    free(s->b);
    free(s->elem);
    free(s->w);
    memset(s, 0, sizeof *s);
}

int df_mesh_spokes_rims(const df_mesh *m, df_mesh_spokes *out, df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "df_mesh_spokes_rims: NULL output");
    df_mesh_sparse VE;
    int rc = df_mesh_vertex_elements(m, &VE, err);
    if (rc)
        return rc;
    const int (*pairs)[2];
    int nle = df_mesh_local_edges(m->kind, &pairs), k = df_mesh_elem_size(m->kind);
    double *W = malloc(((size_t)m->ne * (size_t)nle + 1) * sizeof(double));
    size_t total = (size_t)VE.ptr[m->nv] * (size_t)nle;
    df_mesh_spokes s = {m->nv, malloc(((size_t)m->nv + 1) * sizeof(int32_t)),
                        malloc((total + 1) * sizeof(int32_t)), malloc((total + 1) * sizeof(int32_t)),
                        malloc((total + 1) * sizeof(int32_t)), malloc((total + 1) * sizeof(double))};
    if (!W || !s.ptr || !s.a || !s.b || !s.elem || !s.w) {
        free(W);
        df_mesh_sparse_free(&VE);
        df_mesh_spokes_free(&s);
        return df_error_set(err, DF_ENOMEM, "out of memory for spokes-and-rims sets");
    }
    rc = df_mesh_cotan_weights(m, W, err);
    size_t t = 0;
    for (int32_t i = 0; !rc && i < m->nv; i++) {
        s.ptr[i] = (int32_t)t;
        for (int32_t r = VE.ptr[i]; r < VE.ptr[i + 1]; r++) {
            int32_t e = VE.idx[r];
            const int32_t *c = m->E + (size_t)k * (size_t)e;
            for (int l = 0; l < nle; l++, t++) {
                s.a[t] = c[pairs[l][0]];
                s.b[t] = c[pairs[l][1]];
                s.elem[t] = e;
                s.w[t] = W[(size_t)nle * (size_t)e + (size_t)l];
            }
        }
    }
    if (!rc)
        s.ptr[m->nv] = (int32_t)t;
    free(W);
    df_mesh_sparse_free(&VE);
    if (rc) {
        df_mesh_spokes_free(&s);
        return rc;
    }
    *out = s;
    return DF_OK;
}

int df_mesh_boundary_faces(const df_mesh *m, int32_t **F, int32_t *nf, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!F || !nf)
        return df_error_set(err, DF_EINVAL, "df_mesh_boundary_faces: NULL output");
    if (m->kind != DF_MESH_TET)
        return df_error_set(err, DF_EINVAL, "df_mesh_boundary_faces needs a tetrahedral mesh");
    df_topo_face *f;
    rc = df_topo_tet_faces(m, &f, err);
    if (rc)
        return rc;
    int64_t n = 4 * (int64_t)m->ne, nb = 0;
    int32_t *B = malloc((size_t)(n ? n : 1) * 3 * sizeof *B);
    if (!B) {
        free(f);
        return df_error_set(err, DF_ENOMEM, "out of memory for boundary faces");
    }
    for (int64_t i = 0; i < n;) {
        int64_t j = i + 1;
        while (j < n && !memcmp(f[j].k, f[i].k, sizeof f[i].k))
            j++;
        if (j - i == 1) {
            const int32_t *c = m->E + 4 * (size_t)f[i].tet;
            const int *lc = df_topo_tet_face_corners[f[i].local];
            double lmax;
            int flip = df_geom_elem_measure(m, f[i].tet, &lmax) < 0.0;
            B[3 * nb] = c[lc[0]];
            B[3 * nb + 1] = c[lc[flip ? 2 : 1]];
            B[3 * nb + 2] = c[lc[flip ? 1 : 2]];
            nb++;
        }
        i = j;
    }
    free(f);
    int32_t *shrunk = realloc(B, (size_t)(nb ? nb : 1) * 3 * sizeof *B);
    *F = shrunk ? shrunk : B;
    *nf = (int32_t)nb;
    return DF_OK;
}

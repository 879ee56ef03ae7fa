/* mesh_analyze.c — degenerate/inverted elements, manifoldness and boundaries of a mesh, and the
 * solver admission check (see mesh_io.h). */
#include "core/mesh/mesh_io.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_geom.h"
#include "core/mesh/mesh_topo.h"

static int repeats_index(const int32_t *c, int k)
{
    for (int i = 0; i < k; i++)
        for (int j = i + 1; j < k; j++)
            if (c[i] == c[j])
                return 1;
    return 0;
}

static void count_runs(const uint64_t *keys, int64_t n, int32_t *ones, int32_t *over2)
{
    for (int64_t i = 0; i < n;) {
        int64_t j = i + 1;
        while (j < n && keys[j] == keys[i])
            j++;
        if (j - i == 1)
            (*ones)++;
        else if (j - i > 2)
            (*over2)++;
        i = j;
    }
}

static int cmp_elem4(const void *a, const void *b)
{
    return memcmp(a, b, 4 * sizeof(int32_t));
}

/* Elements whose sorted vertex set equals an earlier element's (e.g. the same face twice). */
static int count_duplicates(const df_mesh *m, int k, int32_t *dup, df_error *err)
{
    if (m->ne < 2)
        return DF_OK;
    int32_t (*s)[4] = malloc((size_t)m->ne * sizeof *s);
    if (!s)
        return df_error_set(err, DF_ENOMEM, "out of memory analysing a mesh");
    for (int32_t e = 0; e < m->ne; e++) {
        int32_t *r = s[e];
        r[0] = r[1] = r[2] = r[3] = -1;
        for (int i = 0; i < k; i++) { /* insertion sort; equal sets give equal bytes */
            int32_t v = m->E[(size_t)k * (size_t)e + (size_t)i];
            int j = i;
            while (j > 0 && r[j - 1] > v) {
                r[j] = r[j - 1];
                j--;
            }
            r[j] = v;
        }
    }
    qsort(s, (size_t)m->ne, sizeof *s, cmp_elem4);
    for (int32_t e = 1; e < m->ne; e++)
        *dup += !memcmp(s[e], s[e - 1], sizeof *s);
    free(s);
    return DF_OK;
}

static int tri_topology(const int32_t *T, int64_t nt, int32_t *boundary, int32_t *nonmanifold,
                        df_error *err)
{
    uint64_t *keys;
    int64_t n;
    int rc = df_topo_edge_keys(T, nt, 3, &keys, &n, err);
    if (rc)
        return rc;
    count_runs(keys, n, boundary, nonmanifold);
    free(keys);
    return DF_OK;
}

static int tet_topology(const df_mesh *m, df_mesh_report *r, df_error *err)
{
    df_topo_face *f;
    int rc = df_topo_tet_faces(m, &f, err);
    if (rc)
        return rc;
    int64_t n = 4 * (int64_t)m->ne;
    int32_t *bt = malloc((size_t)(n ? n : 1) * 3 * sizeof *bt);
    if (!bt) {
        free(f);
        return df_error_set(err, DF_ENOMEM, "out of memory listing boundary faces");
    }
    int64_t nb = 0;
    for (int64_t i = 0; i < n;) {
        int64_t j = i + 1;
        while (j < n && !memcmp(f[j].k, f[i].k, sizeof f[i].k))
            j++;
        if (j - i == 1) {
            memcpy(bt + 3 * nb, f[i].k, 3 * sizeof *bt);
            nb++;
        } else if (j - i > 2) {
            r->nonmanifold_faces++;
        }
        i = j;
    }
    free(f);
    r->boundary_faces = (int32_t)nb;
    int32_t open_edges = 0;
    rc = tri_topology(bt, nb, &open_edges, &r->nonmanifold_edges, err);
    free(bt);
    return rc;
}

int df_mesh_analyze(const df_mesh *m, df_mesh_report *rep, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!rep)
        return df_error_set(err, DF_EINVAL, "report is NULL");
    df_mesh_report r;
    memset(&r, 0, sizeof r);
    r.format = DF_FMT_AUTO;
    r.first_degenerate = -1;
    r.first_inverted = -1;
    r.min_signed_volume = m->ne > 0 ? DBL_MAX : 0.0;
    int k = df_mesh_elem_size(m->kind);
    int planar_tri = m->kind == DF_MESH_TRIANGLE && m->planar;
    int32_t n_pos = 0, n_neg = 0;
    for (int pass = 0; pass < (planar_tri ? 2 : 1); pass++) {
        /* Planar triangles: pass 0 counts orientations; pass 1 flags the minority as inverted.
         * Tets: negative volume is inverted. */
        double good_sign = !planar_tri || n_pos >= n_neg ? 1.0 : -1.0;
        for (int32_t e = 0; e < m->ne; e++) {
            double lmax;
            double v = df_geom_elem_measure(m, e, &lmax);
            double scale = k == 2 ? lmax : k == 3 ? lmax * lmax : lmax * lmax * lmax;
            int degenerate = repeats_index(m->E + (size_t)k * (size_t)e, k) ||
                             fabs(v) <= DF_MESH_DEGENERATE_REL * scale || scale == 0.0;
            if (planar_tri && pass == 0) {
                n_pos += !degenerate && v > 0.0;
                n_neg += !degenerate && v < 0.0;
                continue;
            }
            if (v < r.min_signed_volume)
                r.min_signed_volume = v;
            if (degenerate) {
                if (r.degenerate_elements++ == 0)
                    r.first_degenerate = e;
            } else if ((m->kind == DF_MESH_TET || planar_tri) && v * good_sign < 0.0) {
                if (r.inverted_elements++ == 0)
                    r.first_inverted = e;
            }
        }
    }
    unsigned char *used = calloc((size_t)(m->nv ? m->nv : 1), 1);
    if (!used)
        return df_error_set(err, DF_ENOMEM, "out of memory analysing a mesh");
    for (size_t i = 0; i < (size_t)m->ne * (size_t)k; i++)
        used[m->E[i]] = 1;
    for (int32_t i = 0; i < m->nv; i++)
        r.unreferenced_vertices += !used[i];
    free(used);
    rc = count_duplicates(m, k, &r.duplicate_elements, err);
    if (rc)
        return rc;
    if (m->kind == DF_MESH_TRIANGLE)
        rc = tri_topology(m->E, m->ne, &r.boundary_edges, &r.nonmanifold_edges, err);
    else if (m->kind == DF_MESH_TET)
        rc = tet_topology(m, &r, err);
    if (rc)
        return rc;
    *rep = r;
    return DF_OK;
}

int df_mesh_check_for_solver(const df_mesh *m, df_mesh_report *rep, df_error *err)
{
    df_mesh_report r;
    int rc = df_mesh_analyze(m, &r, err);
    if (rc)
        return rc;
    if (rep)
        *rep = r;
    if (m->ne == 0)
        return df_error_set(err, DF_EINVAL, "mesh has no elements");
    if (r.degenerate_elements > 0)
        return df_error_set(err, DF_EINVAL,
                            "mesh has %d degenerate element(s) (first: element %d); the solver "
                            "needs non-zero element measures",
                            (int)r.degenerate_elements, (int)r.first_degenerate);
    if (r.inverted_elements > 0)
        return df_error_set(err, DF_EINVAL,
                            "mesh has %d inverted element(s) (first: element %d, signed measure "
                            "%g); the solver refuses inverted elements",
                            (int)r.inverted_elements, (int)r.first_inverted, r.min_signed_volume);
    return DF_OK;
}

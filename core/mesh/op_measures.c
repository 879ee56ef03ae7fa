/* op_measures.c — local edge tables, element measures and barycentric vertex measures
 * (see operators.h). */
#include "core/mesh/operators.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_geom.h"
#include "core/mesh/mesh_io.h"

static const int seg_edges[1][2] = {{0, 1}};
static const int tri_edges[3][2] = {{1, 2}, {2, 0}, {0, 1}};
static const int tet_edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

int df_mesh_local_edges(df_mesh_kind kind, const int (**pairs)[2])
{
    const int (*p)[2] = kind == DF_MESH_POLYLINE ? seg_edges
                        : kind == DF_MESH_TRIANGLE ? tri_edges
                        : kind == DF_MESH_TET ? tet_edges : NULL;
    if (pairs)
        *pairs = p;
    return kind == DF_MESH_POLYLINE ? 1 : kind == DF_MESH_TRIANGLE ? 3 : kind == DF_MESH_TET ? 6 : 0;
}

void df_mesh_sparse_free(df_mesh_sparse *s)
{
    if (!s)
        return;
    free(s->ptr);
    free(s->idx);
    free(s->val);
    memset(s, 0, sizeof *s);
}

int df_mesh_element_volumes(const df_mesh *m, double *vol, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!vol && m->ne > 0)
        return df_error_set(err, DF_EINVAL, "df_mesh_element_volumes: NULL output");
    for (int32_t e = 0; e < m->ne; e++) {
        double lmax;
        vol[e] = df_geom_elem_measure(m, e, &lmax);
    }
    return DF_OK;
}

int df_mesh_vertex_areas(const df_mesh *m, double *mass, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!mass && m->nv > 0)
        return df_error_set(err, DF_EINVAL, "df_mesh_vertex_areas: NULL output");
    int k = df_mesh_elem_size(m->kind);
    for (int32_t i = 0; i < m->nv; i++)
        mass[i] = 0.0;
    for (int32_t e = 0; e < m->ne; e++) {
        double lmax;
        double share = fabs(df_geom_elem_measure(m, e, &lmax)) / k;
        for (int c = 0; c < k; c++)
            mass[m->E[(size_t)k * (size_t)e + (size_t)c]] += share;
    }
    return DF_OK;
}

/* dc_meshout.c — float32 wire mesh -> df_mesh -> df_mesh_write_file (see dc_meshout.h). */
#include "client/dc_meshout.h"

#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_io.h"
#include "core/mesh/operators.h"

/* 1 when `path` names a surface-only format (.obj .off .ply), which cannot hold tetrahedra. */
static int surface_format(const char *path)
{
    df_mesh_format f = df_mesh_format_from_path(path);
    return f == DF_FMT_OBJ || f == DF_FMT_OFF || f == DF_FMT_PLY || f == DF_FMT_PLY_BINARY;
}

int dc_meshout_write(const char *path, int kind, int planar, uint32_t nv, const float *xyz,
                     uint32_t ne, const int32_t *E, uint32_t nf, const int32_t *F,
                     int32_t *surface_nf, df_error *err)
{
    int es = df_mesh_elem_size((df_mesh_kind)kind);
    if (!path || !xyz || !E || es == 0 || nv == 0 || nv > INT32_MAX || ne > INT32_MAX ||
        nf > INT32_MAX || (nf && !F))
        return df_error_set(err, DF_EINVAL, "write mesh: bad arguments (kind %d, %u vertices)",
                            kind, nv);
    df_mesh m;
    df_mesh_init(&m);
    m.kind = (df_mesh_kind)kind;
    m.planar = planar ? 1 : 0;
    m.nv = (int32_t)nv;
    m.ne = (int32_t)ne;
    m.nf = (int32_t)nf;
    m.V = malloc((size_t)nv * 3 * sizeof(double));
    if (!m.V)
        return df_error_set(err, DF_ENOMEM, "write mesh: out of memory for %u vertices", nv);
    for (size_t i = 0; i < (size_t)nv * 3; i++)
        m.V[i] = (double)xyz[i];
    if (m.planar)
        for (size_t i = 0; i < nv; i++)
            m.V[3 * i + 2] = 0.0;
    m.E = (int32_t *)E;
    m.F = nf ? (int32_t *)F : NULL;
    int32_t *B = NULL;
    int32_t nb = -1;
    int rc = DF_OK;
    if (m.kind == DF_MESH_TET && surface_format(path)) {
        /* the format holds no tets: write the boundary triangles over every vertex */
        rc = df_mesh_boundary_faces(&m, &B, &nb, err);
        if (rc == DF_OK) {
            m.kind = DF_MESH_TRIANGLE;
            m.ne = nb;
            m.E = B;
            m.nf = 0;
            m.F = NULL;
        }
    }
    if (rc == DF_OK)
        rc = df_mesh_write_file(path, &m, err);
    if (rc == DF_OK && surface_nf)
        *surface_nf = nb;
    free(B);
    free(m.V);
    return rc;
}

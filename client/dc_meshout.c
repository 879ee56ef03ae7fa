/* dc_meshout.c — float32 wire mesh -> df_mesh -> df_mesh_write_file (see dc_meshout.h). */
#include "client/dc_meshout.h"

#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_io.h"

int dc_meshout_write(const char *path, int kind, int planar, uint32_t nv, const float *xyz,
                     uint32_t ne, const int32_t *E, uint32_t nf, const int32_t *F, df_error *err)
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
    int rc = df_mesh_write_file(path, &m, err);
    free(m.V);
    return rc;
}

/* op_rest.c — per-element rest shape matrices Dm, their (pseudo-)inverses and measures
 * (see operators.h). */
#include "core/mesh/operators.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_geom.h"
#include "core/mesh/mesh_io.h"

int df_mesh_rest_one(const df_mesh *m, int32_t e, double *Dm, double *Dm_inv, double *vol)
{
    int k = df_mesh_elem_size(m->kind), dim = k - 1;
    const int32_t *c = m->E + (size_t)k * (size_t)e;
    double col[3][3];
    for (int j = 0; j < dim; j++)
        df_geom_sub(m->V + 3 * (size_t)c[j + 1], m->V + 3 * (size_t)c[0], col[j]);
    double lmax;
    double v = df_geom_elem_measure(m, e, &lmax);
    double scale = dim == 1 ? lmax : dim == 2 ? lmax * lmax : lmax * lmax * lmax;
    if (!(fabs(v) > DF_MESH_DEGENERATE_REL * scale) || scale == 0.0)
        return -1;
    memset(Dm, 0, 9 * sizeof *Dm);
    memset(Dm_inv, 0, 9 * sizeof *Dm_inv);
    for (int j = 0; j < dim; j++)
        for (int r = 0; r < 3; r++)
            Dm[3 * r + j] = col[j][r];
    if (dim == 1) {
        double q = df_geom_dot(col[0], col[0]);
        for (int r = 0; r < 3; r++)
            Dm_inv[r] = col[0][r] / q;
    } else if (dim == 2) { /* (D^T D)^-1 D^T */
        double a = df_geom_dot(col[0], col[0]), b = df_geom_dot(col[0], col[1]);
        double d = df_geom_dot(col[1], col[1]), det = a * d - b * b;
        for (int r = 0; r < 3; r++) {
            Dm_inv[r] = (d * col[0][r] - b * col[1][r]) / det;
            Dm_inv[3 + r] = (-b * col[0][r] + a * col[1][r]) / det;
        }
    } else { /* rows of the inverse are the cross products of the columns over det */
        double x[3];
        double det = 6.0 * v;
        df_geom_cross(col[1], col[2], x);
        for (int r = 0; r < 3; r++)
            Dm_inv[r] = x[r] / det;
        df_geom_cross(col[2], col[0], x);
        for (int r = 0; r < 3; r++)
            Dm_inv[3 + r] = x[r] / det;
        df_geom_cross(col[0], col[1], x);
        for (int r = 0; r < 3; r++)
            Dm_inv[6 + r] = x[r] / det;
    }
    *vol = v;
    return 0;
}

void df_mesh_rest_free(df_mesh_rest *r)
{
    if (!r)
        return;
    free(r->Dm);
    free(r->Dm_inv);
    free(r->vol);
    memset(r, 0, sizeof *r);
}

int df_mesh_rest_shapes(const df_mesh *m, df_mesh_rest *out, df_error *err)
{
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    if (!out)
        return df_error_set(err, DF_EINVAL, "df_mesh_rest_shapes: NULL output");
    size_t n = m->ne > 0 ? (size_t)m->ne : 1;
    df_mesh_rest r = {m->ne, df_mesh_elem_size(m->kind) - 1, malloc(9 * n * sizeof(double)),
                      malloc(9 * n * sizeof(double)), malloc(n * sizeof(double))};
    if (!r.Dm || !r.Dm_inv || !r.vol) {
        df_mesh_rest_free(&r);
        return df_error_set(err, DF_ENOMEM, "out of memory for %d rest shapes", (int)m->ne);
    }
    for (int32_t e = 0; e < m->ne; e++)
        if (df_mesh_rest_one(m, e, r.Dm + 9 * (size_t)e, r.Dm_inv + 9 * (size_t)e, r.vol + e)) {
            df_mesh_rest_free(&r);
            return df_error_set(err, DF_ESINGULAR,
                                "element %d is degenerate: its rest shape matrix is singular",
                                (int)e);
        }
    *out = r;
    return DF_OK;
}

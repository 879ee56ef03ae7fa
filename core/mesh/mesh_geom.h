/* mesh_geom.h — internal: tiny 3-vector helpers and per-element measures shared by the mesh
 * analysis and the operators. Vectors are double[3]. */
#ifndef DF_MESH_GEOM_H
#define DF_MESH_GEOM_H

#include <math.h>

#include "core/mesh/mesh.h"

static inline void df_geom_sub(const double *a, const double *b, double *o)
{
    o[0] = a[0] - b[0];
    o[1] = a[1] - b[1];
    o[2] = a[2] - b[2];
}

static inline double df_geom_dot(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void df_geom_cross(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double df_geom_norm(const double *a)
{
    return sqrt(df_geom_dot(a, a));
}

/* Signed measure of element e of m (length; area: signed by z-orientation when m->planar, else
 * unsigned; tet volume det/6) and, in *lmax, its longest edge length. */
static inline double df_geom_elem_measure(const df_mesh *m, int32_t e, double *lmax)
{
    int k = df_mesh_elem_size(m->kind);
    const int32_t *c = m->E + (size_t)k * (size_t)e;
    const double *x0 = m->V + 3 * (size_t)c[0];
    double l2 = 0.0;
    for (int i = 0; i < k; i++)
        for (int j = i + 1; j < k; j++) {
            double d[3];
            df_geom_sub(m->V + 3 * (size_t)c[j], m->V + 3 * (size_t)c[i], d);
            double q = df_geom_dot(d, d);
            if (q > l2)
                l2 = q;
        }
    *lmax = sqrt(l2);
    double a[3], b[3], n[3];
    df_geom_sub(m->V + 3 * (size_t)c[1], x0, a);
    if (k == 2)
        return df_geom_norm(a);
    df_geom_sub(m->V + 3 * (size_t)c[2], x0, b);
    df_geom_cross(a, b, n);
    if (k == 3)
        return m->planar ? 0.5 * n[2] : 0.5 * df_geom_norm(n);
    double d[3];
    df_geom_sub(m->V + 3 * (size_t)c[3], x0, d);
    return df_geom_dot(n, d) / 6.0;
}

/* Rest shape of element e (op_rest.c): Dm (3x3 row-major, first dim columns = x_{j+1} - x_0),
 * Dm_inv (first dim rows = pseudo-inverse), *vol signed measure. 0, or -1 when degenerate. */
int df_mesh_rest_one(const df_mesh *m, int32_t e, double *Dm, double *Dm_inv, double *vol);

#endif

/* mesh_core.c — init, free, copy, validation and format names for df_mesh (see mesh_io.h). */
#include "core/mesh/mesh_io.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void df_mesh_init(df_mesh *m)
{
    if (m)
        memset(m, 0, sizeof *m);
}

void df_mesh_free(df_mesh *m)
{
    if (!m)
        return;
    free(m->V);
    free(m->E);
    free(m->F);
    memset(m, 0, sizeof *m);
}

df_mesh_read_opts df_mesh_read_opts_default(void)
{
    df_mesh_read_opts o = {DF_MESH_DEFAULT_MAX_VERTICES, DF_MESH_DEFAULT_MAX_ELEMENTS, 1, 0, 0,
                           NULL, NULL};
    return o;
}

static int header_ok(const df_mesh *m, df_error *err)
{
    if (!m)
        return df_error_set(err, DF_EINVAL, "mesh is NULL");
    if (df_mesh_elem_size(m->kind) == 0)
        return df_error_set(err, DF_EINVAL, "unknown mesh kind %d", (int)m->kind);
    if (m->nv < 0 || m->ne < 0 || m->nf < 0)
        return df_error_set(err, DF_EINVAL, "negative counts (nv %d, ne %d, nf %d)", (int)m->nv,
                            (int)m->ne, (int)m->nf);
    if ((m->nv > 0 && !m->V) || (m->ne > 0 && !m->E) || (m->nf > 0 && !m->F))
        return df_error_set(err, DF_EINVAL, "mesh array is NULL for a non-zero count");
    return DF_OK;
}

int df_mesh_copy(const df_mesh *src, df_mesh *dst, df_error *err)
{
    int rc = header_ok(src, err);
    if (rc)
        return rc;
    if (!dst)
        return df_error_set(err, DF_EINVAL, "destination mesh is NULL");
    size_t sv = (size_t)src->nv * 3 * sizeof(double);
    size_t se = (size_t)src->ne * (size_t)df_mesh_elem_size(src->kind) * sizeof(int32_t);
    size_t sf = (size_t)src->nf * 3 * sizeof(int32_t);
    double *V = sv ? malloc(sv) : NULL;
    int32_t *E = se ? malloc(se) : NULL;
    int32_t *F = sf ? malloc(sf) : NULL;
    if ((sv && !V) || (se && !E) || (sf && !F)) {
        free(V);
        free(E);
        free(F);
        return df_error_set(err, DF_ENOMEM, "out of memory copying a mesh of %d vertices",
                            (int)src->nv);
    }
    if (sv)
        memcpy(V, src->V, sv);
    if (se)
        memcpy(E, src->E, se);
    if (sf)
        memcpy(F, src->F, sf);
    *dst = *src;
    dst->V = V;
    dst->E = E;
    dst->F = F;
    return DF_OK;
}

int df_mesh_validate(const df_mesh *m, df_error *err)
{
    int rc = header_ok(m, err);
    if (rc)
        return rc;
    int allz = 1;
    for (int32_t i = 0; i < m->nv; i++) {
        const double *v = m->V + 3 * (size_t)i;
        if (!isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[2]))
            return df_error_set(err, DF_EINVAL, "vertex %d has a non-finite coordinate", (int)i);
        if (v[2] != 0.0)
            allz = 0;
    }
    if (m->planar && !allz)
        return df_error_set(err, DF_EINVAL, "mesh flagged planar but has z != 0");
    int k = df_mesh_elem_size(m->kind);
    size_t n = (size_t)m->ne * (size_t)k;
    for (size_t i = 0; i < n; i++)
        if (m->E[i] < 0 || m->E[i] >= m->nv)
            return df_error_set(err, DF_EINVAL, "element %zu: vertex index %d out of range (%d vertices)",
                                i / (size_t)k, (int)m->E[i], (int)m->nv);
    for (size_t i = 0; i < (size_t)m->nf * 3; i++)
        if (m->F[i] < 0 || m->F[i] >= m->nv)
            return df_error_set(err, DF_EINVAL, "face %zu: vertex index %d out of range (%d vertices)",
                                i / 3, (int)m->F[i], (int)m->nv);
    return DF_OK;
}

const char *df_mesh_format_name(df_mesh_format fmt)
{
    switch (fmt) {
    case DF_FMT_AUTO: return "auto";
    case DF_FMT_OBJ: return "obj";
    case DF_FMT_OFF: return "off";
    case DF_FMT_PLY: return "ply";
    case DF_FMT_MEDIT: return "mesh";
    case DF_FMT_TETGEN: return "tetgen";
    case DF_FMT_PLY_BINARY: return "ply-binary";
    }
    return "unknown";
}

df_mesh_format df_mesh_format_from_path(const char *path)
{
    if (!path)
        return DF_FMT_AUTO;
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return DF_FMT_AUTO;
    dot++;
    if (!strcasecmp(dot, "obj"))
        return DF_FMT_OBJ;
    if (!strcasecmp(dot, "off"))
        return DF_FMT_OFF;
    if (!strcasecmp(dot, "ply"))
        return DF_FMT_PLY;
    if (!strcasecmp(dot, "mesh"))
        return DF_FMT_MEDIT;
    if (!strcasecmp(dot, "node") || !strcasecmp(dot, "ele"))
        return DF_FMT_TETGEN;
    return DF_FMT_AUTO;
}

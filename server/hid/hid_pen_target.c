/* hid_pen_target.c — where a pen points on a session's surface (see hid_pen_target.h). */
#include "server/hid/hid_pen_target.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom/raycast.h"
#include "core/geom/view_ray.h"
#include "core/mesh/operators.h"

struct df_pen_cache {
    int32_t nv, nf;
    int32_t *F;            /* nf x 3 surface faces */
    df_raycast *rc;        /* NULL until the first query */
    uint64_t version;      /* session version rc was built / refitted for */
};

int df_pen_cache_create(const df_mesh *mesh, df_pen_cache **out, df_error *err)
{
    if (!mesh || !out)
        return df_error_set(err, DF_EINVAL, "pen target: NULL %s", !mesh ? "mesh" : "output");
    if (mesh->kind == DF_MESH_POLYLINE)
        return df_error_set(err, DF_EUNSUPPORTED,
                            "pen target: a polyline session has no surface for a pen to point at");
    if ((mesh->kind != DF_MESH_TRIANGLE && mesh->kind != DF_MESH_TET) || mesh->nv < 1
        || mesh->ne < 1 || !mesh->E)
        return df_error_set(err, DF_EINVAL, "pen target: invalid mesh (kind %d, %d vertices, "
                            "%d elements)", (int)mesh->kind, (int)mesh->nv, (int)mesh->ne);
    int32_t *F = NULL, nf = 0;
    if (mesh->kind == DF_MESH_TRIANGLE) {
        nf = mesh->ne;
        F = malloc(3 * (size_t)nf * sizeof *F);
        if (!F)
            return df_error_set(err, DF_ENOMEM, "pen target: out of memory for %d faces", (int)nf);
        memcpy(F, mesh->E, 3 * (size_t)nf * sizeof *F);
    } else {
        int rv = df_mesh_boundary_faces(mesh, &F, &nf, err);
        if (rv != DF_OK)
            return rv;
        if (nf < 1) {
            free(F);
            return df_error_set(err, DF_EUNSUPPORTED, "pen target: the tet mesh has no boundary "
                                "faces for a pen to point at");
        }
    }
    for (int64_t i = 0; i < 3 * (int64_t)nf; i++)
        if (F[i] < 0 || F[i] >= mesh->nv) {
            int bad = F[i];
            free(F);
            return df_error_set(err, DF_EINVAL, "pen target: face %lld index %d out of range "
                                "(%d vertices)", (long long)(i / 3), bad, (int)mesh->nv);
        }
    df_pen_cache *pc = calloc(1, sizeof *pc);
    if (!pc) {
        free(F);
        return df_error_set(err, DF_ENOMEM, "pen target: out of memory");
    }
    pc->nv = mesh->nv;
    pc->nf = nf;
    pc->F = F;
    *out = pc;
    return DF_OK;
}

/* Brings the scene to `pos` at `version`: build on first use, refit on a new version. */
static int fit(df_pen_cache *pc, const double *pos, uint64_t version, df_error *err)
{
    if (!pc->rc) {
        df_raycast *rc = NULL;
        int rv = df_raycast_create(pos, pc->nv, pc->F, pc->nf, &rc, err);
        if (rv != DF_OK)
            return rv;
        pc->rc = rc;
        pc->version = version;
        return DF_OK;
    }
    if (version == pc->version)
        return DF_OK;
    int rv = df_raycast_refit(pc->rc, pos, err);
    if (rv == DF_EINTERNAL || rv == DF_ENOMEM) {
        /* Embree failed mid-refit: drop the scene, the next query rebuilds it. */
        df_raycast_free(pc->rc);
        pc->rc = NULL;
    }
    if (rv == DF_OK)
        pc->version = version;
    return rv;
}

int df_pen_target(df_pen_cache *pc, const double *pos, uint64_t version,
                  const double view_proj[16], const double viewport[4], double nx, double ny,
                  double center[3], df_error *err)
{
    if (!pc || !pos || !view_proj || !viewport || !center)
        return df_error_set(err, DF_EINVAL, "pen target: NULL argument");
    double px, py, org[3], dir[3];
    int rv = df_view_pen_pixel(viewport, nx, ny, &px, &py, err);
    if (rv == DF_OK)
        rv = df_view_ray(view_proj, viewport, px, py, org, dir, err);
    if (rv == DF_OK)
        rv = fit(pc, pos, version, err);
    if (rv != DF_OK)
        return rv;
    df_ray_hit h;
    if (!df_raycast_hit(pc->rc, org, dir, &h))
        return 0;
    for (int k = 0; k < 3; k++)
        center[k] = h.point[k];
    return 1;
}

void df_pen_cache_free(df_pen_cache *pc)
{
    if (!pc)
        return;
    df_raycast_free(pc->rc);
    free(pc->F);
    free(pc);
}

int df_pen_view_check(const double view_proj[16], const double viewport[4], df_error *err)
{
    if (!view_proj || !viewport)
        return df_error_set(err, DF_EINVAL, "pen view: NULL %s", !view_proj ? "view_proj"
                                                                            : "viewport");
    double org[3], dir[3];
    return df_view_ray(view_proj, viewport, viewport[0] + 0.5 * viewport[2],
                       viewport[1] + 0.5 * viewport[3], org, dir, err);
}

/* surface_cache.c — per-session surface-brush distances (see surface_cache.h). */
#include "server/session/surface_cache.h"

#include <stdlib.h>
#include <string.h>

#include "core/mesh/geodesic.h"
#include "core/mesh/operators.h"
#include "server/session/stroke_recipe.h"

typedef struct entry {
    uint64_t used;
    int32_t src;
    double *dist;                /* nv, NULL when the slot is empty */
} entry;

struct df_surface_cache {
    df_mesh_sparse adj;
    int32_t nv;
    uint64_t clock;
    unsigned long hits;
    entry e[DF_SURFACE_CACHE_ENTRIES];
};

/* The cache *pc, created with the mesh's adjacency on first use. */
static int cache_of(df_surface_cache **pc, const df_mesh *mesh, df_error *err)
{
    if (*pc) return DF_OK;
    df_surface_cache *c = calloc(1, sizeof *c);
    if (!c) return df_error_set(err, DF_ENOMEM, "surface brush: out of memory");
    int rc = df_mesh_vertex_adjacency(mesh, &c->adj, err);
    if (rc != DF_OK) {
        free(c);
        return rc;
    }
    c->nv = mesh->nv;
    *pc = c;
    return DF_OK;
}

int df_surface_cache_adjacency(df_surface_cache **pc, const df_mesh *mesh,
                               const df_mesh_sparse **adj, df_error *err)
{
    if (!pc || !mesh || !adj || mesh->nv <= 0)
        return df_error_set(err, DF_EINVAL, "surface brush: bad arguments");
    int rc = cache_of(pc, mesh, err);
    if (rc == DF_OK) *adj = &(*pc)->adj;
    return rc;
}

int df_surface_cache_dist(df_surface_cache **pc, const df_mesh *mesh, const float *x0,
                          int32_t nv, const double *centre, int32_t *src, double **dist,
                          df_error *err)
{
    if (!pc || !mesh || !x0 || !centre || !src || !dist || nv <= 0 || mesh->nv != nv)
        return df_error_set(err, DF_EINVAL, "surface brush: bad arguments");
    int rc0 = cache_of(pc, mesh, err);
    if (rc0 != DF_OK) return rc0;
    df_surface_cache *c = *pc;
    double *d = malloc((size_t)nv * sizeof *d);
    if (!d) return df_error_set(err, DF_ENOMEM, "surface brush: out of memory (%d vertices)", nv);
    int32_t s = df_stroke_surface_src(x0, nv, centre);
    entry *hit = NULL, *victim = &c->e[0];
    for (int k = 0; k < DF_SURFACE_CACHE_ENTRIES; k++) {
        entry *e = &c->e[k];
        if (e->dist && e->src == s) hit = e;
        if (!e->dist || (victim->dist && e->used < victim->used)) victim = e;
    }
    int rc = DF_OK;
    if (hit) {
        memcpy(d, hit->dist, (size_t)nv * sizeof *d);
        hit->used = ++c->clock;
        c->hits++;
    } else {
        rc = df_mesh_geodesic_from(&c->adj, mesh->V, s, d, err); /* df_stroke_surface_dist */
        double *keep = rc == DF_OK ? malloc((size_t)nv * sizeof *keep) : NULL;
        if (keep) { /* cache it (a failed copy only costs the cache) */
            memcpy(keep, d, (size_t)nv * sizeof *keep);
            free(victim->dist);
            *victim = (entry){.used = ++c->clock, .src = s, .dist = keep};
        }
    }
    if (rc != DF_OK) {
        free(d);
        return rc;
    }
    *src = s;
    *dist = d;
    return DF_OK;
}

unsigned long df_surface_cache_hits(const df_surface_cache *c)
{
    return c ? c->hits : 0;
}

void df_surface_cache_free(df_surface_cache *c)
{
    if (!c) return;
    for (int k = 0; k < DF_SURFACE_CACHE_ENTRIES; k++) free(c->e[k].dist);
    df_mesh_sparse_free(&c->adj);
    free(c);
}

/* surface_cache.h — per-session cache of surface-aware brush distances (issue 14 item 7).
 *
 * A surface-aware stroke needs the edge-graph distances over the mesh at rest from the vertex
 * nearest to its centre (stroke_recipe.h df_stroke_surface_dist). They depend on that vertex
 * only, so the session keeps the mesh's vertex adjacency (built on first use) and the distances
 * of its last DF_SURFACE_CACHE_ENTRIES centre vertices: strokes started again near the same
 * vertex skip Dijkstra. Used by the session's running job only (jobs of a session are serial,
 * as for its K_pp cache); freed with the session. Not charged to cache_memory_mb: at most
 * (ENTRIES + 1) x 8 bytes and the adjacency per vertex. */
#ifndef DF_SERVER_SURFACE_CACHE_H
#define DF_SERVER_SURFACE_CACHE_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"

#define DF_SURFACE_CACHE_ENTRIES 4

typedef struct df_surface_cache df_surface_cache;

/* The distances for a stroke whose start points are x0 (nv x 3 float32) on session mesh `mesh`
 * (topology and rest positions mesh->V): *src and a new malloc'd copy *dist (nv doubles, owned
 * by the caller) — exactly df_stroke_surface_dist(adj, mesh->V, x0, nv, centre). *pc is created
 * on first use. Errors: DF_EINVAL, DF_ENOMEM; the cache is unchanged on error. */
int df_surface_cache_dist(df_surface_cache **pc, const df_mesh *mesh, const float *x0,
                          int32_t nv, const double *centre, int32_t *src, double **dist,
                          df_error *err);

/* The mesh's vertex adjacency (*adj, owned by the cache), built on first use as by
 * df_surface_cache_dist. Errors: DF_EINVAL, DF_ENOMEM. */
int df_surface_cache_adjacency(df_surface_cache **pc, const df_mesh *mesh,
                               const df_mesh_sparse **adj, df_error *err);

/* Lookups answered from the cache so far (stats and tests). */
unsigned long df_surface_cache_hits(const df_surface_cache *c);

/* Frees the cache (NULL is fine). */
void df_surface_cache_free(df_surface_cache *c);

#endif

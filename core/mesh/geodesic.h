/* geodesic.h — distances along a mesh's edge graph (Dijkstra), the geodesic used by
 * surface-aware brushes (core/kelvinlet/kelvinlet_surface.h).
 *
 * The graph: the vertex adjacency of df_mesh_vertex_adjacency (every pair of vertices sharing
 * an element), each edge weighted by the Euclidean length between the given positions. The
 * edge-path distance over-estimates the true surface geodesic by a bounded factor (at most
 * ~1.15 on a well-shaped triangulation, less after refinement) and is exact in the one thing a
 * surface brush needs: vertices of a part not connected to the source are unreachable. */
#ifndef DF_MESH_GEODESIC_H
#define DF_MESH_GEODESIC_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/operators.h"

/* Single-source edge-graph distances. In: adj (n_rows = nv vertex adjacency pattern), xyz
 * (nv x 3 positions, any length unit), src in [0, nv). Out: dist[nv] in the positions' unit,
 * dist[src] = 0, INFINITY for vertices not connected to src. Deterministic (ties broken by
 * vertex index). Errors: DF_EINVAL (NULL, src out of range, a non-finite position),
 * DF_ENOMEM; dist unspecified on error. Any thread; O(E log V). */
int df_mesh_geodesic_from(const df_mesh_sparse *adj, const double *xyz, int32_t src,
                          double *dist, df_error *err);

/* The vertex nearest to point c[3] (Euclidean; the lowest index among ties) over nv x 3
 * positions; -1 when nv <= 0 or an argument is NULL. */
int32_t df_mesh_nearest_vertex(const double *xyz, int32_t nv, const double *c);

#endif

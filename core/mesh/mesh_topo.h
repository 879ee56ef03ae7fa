/* mesh_topo.h — internal: sorted edge and face records used for topology queries (manifoldness,
 * boundaries, unique edges). */
#ifndef DF_MESH_TOPO_H
#define DF_MESH_TOPO_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* One tet face: sorted corner triple `k`, the tet it came from and its local face 0..3 (the face
 * opposite local corner `local`). */
typedef struct df_topo_face {
    int32_t k[3];
    int32_t tet;
    int32_t local;
} df_topo_face;

/* Outward-oriented corner triples of a positively oriented tet's faces, face f opposite corner f. */
extern const int df_topo_tet_face_corners[4][3];

/* Key of the undirected edge (i, j): min << 32 | max. */
static inline uint64_t df_topo_edge_key(int32_t i, int32_t j)
{
    uint32_t a = (uint32_t)(i < j ? i : j), b = (uint32_t)(i < j ? j : i);
    return ((uint64_t)a << 32) | b;
}

/* Sorts n keys ascending (LSD radix sort; `n` may be 0). DF_ENOMEM on failure. */
int df_topo_sort_u64(uint64_t *keys, int64_t n, df_error *err);

/* All 4 * ne faces of tet mesh m, sorted by corner triple: *faces malloc'd. */
int df_topo_tet_faces(const df_mesh *m, df_topo_face **faces, df_error *err);

/* Keys of all local edges of the `ne` elements of width `k` (2, 3 or 4) at E, sorted: *keys
 * malloc'd with ne * (1, 3 or 6) entries (duplicates kept). */
int df_topo_edge_keys(const int32_t *E, int64_t ne, int k, uint64_t **keys, int64_t *n,
                      df_error *err);

#endif

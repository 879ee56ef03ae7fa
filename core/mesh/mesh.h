/* mesh.h — the mesh type shared by every core module, the server and the clients.
 *
 * One mesh has one kind of element: polyline segments, triangles or tetrahedra. Positions are
 * double (the solvers' precision); the wire carries float32. 2D meshes (polylines or triangles in
 * the z = 0 plane) are stored with z = 0 and flagged `planar`: only when the file declares 2D
 * (two coordinates per vertex) or the reader was asked for 2D. A flat 3D mesh (every z = 0,
 * e.g. a subdivided plane) is not planar and deforms in 3D.
 *
 * Ownership: a df_mesh owns its arrays (malloc'd); df_mesh_free releases them. */
#ifndef DF_MESH_H
#define DF_MESH_H

#include <stdint.h>

typedef enum df_mesh_kind {
    DF_MESH_POLYLINE = 1,  /* elements are segments, 2 indices each */
    DF_MESH_TRIANGLE = 2,  /* elements are triangles, 3 indices each */
    DF_MESH_TET = 3        /* elements are tetrahedra, 4 indices each */
} df_mesh_kind;

typedef struct df_mesh {
    df_mesh_kind kind;
    int planar;          /* 1: a 2D mesh (declared so; every z is exactly 0), else 0 */
    int32_t nv;          /* number of vertices */
    double *V;           /* nv x 3, row-major: V[3*i + k] */
    int32_t ne;          /* number of elements */
    int32_t *E;          /* ne x df_mesh_elem_size(kind), row-major, 0-based vertex indices */
    int32_t nf;          /* boundary triangles of a tet mesh when known (MEDIT Triangles), else 0 */
    int32_t *F;          /* nf x 3, 0-based; NULL when nf == 0 */
} df_mesh;

/* Number of vertex indices per element of `kind`: 2, 3 or 4 (0 for an unknown kind). */
static inline int df_mesh_elem_size(df_mesh_kind kind)
{
    return kind == DF_MESH_POLYLINE ? 2 : kind == DF_MESH_TRIANGLE ? 3 : kind == DF_MESH_TET ? 4 : 0;
}

#endif

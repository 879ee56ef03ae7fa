/* operators.h — geometric operators on a df_mesh (see mesh.h): element measures, barycentric
 * vertex measures, cotangent weights and Laplacian, rest shape matrices, adjacency.
 *
 * Conventions. Element measure: length (segments), area (triangles), volume (tets), in the mesh's
 * length unit to the power 1, 2, 3. Local edges of an element are listed by df_mesh_local_edges:
 *   segment: (0,1);  triangle: (1,2) (2,0) (0,1) — edge k is opposite corner k;
 *   tet: (0,1) (0,2) (0,3) (1,2) (1,3) (2,3) — edge (i,j) is opposite edge (k,l) = the other two.
 * Cotangent weights (all symmetric, positive on well-shaped meshes):
 *   segment: 1 / length;   triangle edge k: cot(angle at corner k) / 2;
 *   tet edge (i,j): |x_k - x_l| cot(dihedral angle at edge (k,l)) / 6.
 * The cotangent Laplacian is L_ij = sum of the weights of edge (i,j) over elements, L_ii = -sum_j
 * L_ij (negative semi-definite; L * 1 = 0, and (L x)_i = 0 at interior vertices for linear x).
 * All inputs must be valid meshes (df_mesh_validate); functions fail with DF_EINVAL otherwise and
 * leave outputs untouched on every error. */
#ifndef DF_MESH_OPERATORS_H
#define DF_MESH_OPERATORS_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* Number of local edges of an element of `kind` (1, 3, 6; 0 for unknown) and, when `pairs` is
 * not NULL, the static table of local corner pairs (2 ints per edge, order as above). */
int df_mesh_local_edges(df_mesh_kind kind, const int (**pairs)[2]);

/* Compressed sparse rows: row i holds columns idx[ptr[i] .. ptr[i+1]-1] (sorted ascending) and,
 * when val != NULL, their values. Arrays are malloc'd; free with df_mesh_sparse_free. */
typedef struct df_mesh_sparse {
    int32_t n_rows, n_cols;
    int32_t *ptr;   /* n_rows + 1 */
    int32_t *idx;   /* ptr[n_rows] */
    double *val;    /* ptr[n_rows] or NULL (pattern only) */
} df_mesh_sparse;

/* Frees the arrays of `s` and zeroes it; NULL-safe. */
void df_mesh_sparse_free(df_mesh_sparse *s);

/* Signed element measures into vol[ne]: segment length; triangle area (planar meshes: signed,
 * positive when counter-clockwise seen from +z; 3D surfaces: unsigned); tet volume
 * (det[x1-x0, x2-x0, x3-x0] / 6, positive for positively oriented tets). */
int df_mesh_element_volumes(const df_mesh *m, double *vol, df_error *err);

/* Barycentric (lumped) vertex measures into mass[nv]: each element gives |measure| / (corners) to
 * each of its corners (half a segment length, a third of a triangle area, a quarter of a tet
 * volume). Sums to the total |measure|; unreferenced vertices get 0. */
int df_mesh_vertex_areas(const df_mesh *m, double *mass, df_error *err);

/* Per-element cotangent weights into W[ne * df_mesh_local_edges(kind)], row-major by element, in
 * the local edge order above. Degenerate elements give weight 0 on their edges (no NaN/Inf). */
int df_mesh_cotan_weights(const df_mesh *m, double *W, df_error *err);

/* Assembled nv x nv cotangent Laplacian (definition above), every row holding its diagonal and
 * its neighbours in ascending column order. *L receives new arrays (previous ones not freed). */
int df_mesh_cotan_laplacian(const df_mesh *m, df_mesh_sparse *L, df_error *err);

/* Rest shapes of every element: dim = 1, 2 or 3 (segment, triangle, tet). For element e, Dm is the
 * 3 x 3 row-major matrix whose column j < dim is x_{j+1} - x_0 (other columns 0) and Dm_inv the
 * 3 x 3 row-major matrix whose first `dim` rows are the Moore-Penrose pseudo-inverse of those
 * columns (the true inverse for tets; other rows 0), so Dm_inv * Dm = diag(1..1 (dim), 0..).
 * vol = signed measure as df_mesh_element_volumes. Deformation gradient: F = Ds * Dm_inv. */
typedef struct df_mesh_rest {
    int32_t ne;
    int dim;
    double *Dm;      /* ne x 9 */
    double *Dm_inv;  /* ne x 9 */
    double *vol;     /* ne */
} df_mesh_rest;

/* Computes every rest shape. Errors: DF_EINVAL (invalid mesh), DF_ESINGULAR naming the first
 * degenerate element, DF_ENOMEM. *out receives new arrays; free with df_mesh_rest_free. */
int df_mesh_rest_shapes(const df_mesh *m, df_mesh_rest *out, df_error *err);

/* Frees and zeroes `r`; NULL-safe. */
void df_mesh_rest_free(df_mesh_rest *r);

/* Vertex -> vertex adjacency (pattern only, val = NULL): row i lists the distinct vertices sharing
 * an element with i, ascending, without i itself. n_rows = n_cols = nv. */
int df_mesh_vertex_adjacency(const df_mesh *m, df_mesh_sparse *A, df_error *err);

/* Vertex -> element incidence (pattern only): row i lists the elements using vertex i, ascending.
 * n_rows = nv, n_cols = ne. */
int df_mesh_vertex_elements(const df_mesh *m, df_mesh_sparse *VE, df_error *err);

/* Unique undirected edges: *edges receives a malloc'd n x 2 array of (i, j), i < j, sorted
 * lexicographically; *n_edges its row count. */
int df_mesh_edges(const df_mesh *m, int32_t **edges, int32_t *n_edges, df_error *err);

/* "Spokes and rims" edge sets (Chao et al. 2010; the ARAP cell of the local-deformation paper) for
 * every vertex: for vertex i, every local edge of every element incident to i, with that element's
 * cotangent weight (an edge shared by two incident elements appears once per element). Row i of
 * the CSR-like arrays is entries ptr[i] .. ptr[i+1]-1; entry t is the edge (a[t], b[t]) (the
 * element's local order) with weight w[t] and element elem[t]. */
typedef struct df_mesh_spokes {
    int32_t nv;
    int32_t *ptr;    /* nv + 1 */
    int32_t *a, *b;  /* ptr[nv] each */
    int32_t *elem;   /* ptr[nv] */
    double *w;       /* ptr[nv] */
} df_mesh_spokes;

/* Builds the spokes-and-rims sets. Errors: DF_EINVAL, DF_ENOMEM. Free with df_mesh_spokes_free. */
int df_mesh_spokes_rims(const df_mesh *m, df_mesh_spokes *out, df_error *err);

/* Frees and zeroes `s`; NULL-safe. */
void df_mesh_spokes_free(df_mesh_spokes *s);

/* Boundary of a tet mesh: every triangle used by exactly one tet, oriented with its normal pointing
 * out of the tet (for positively oriented tets: outward). *F receives a malloc'd nf x 3 array
 * (sorted by the face's sorted corner triple), *nf its row count. Errors: DF_EINVAL (not a tet
 * mesh / invalid), DF_ENOMEM. */
int df_mesh_boundary_faces(const df_mesh *m, int32_t **F, int32_t *nf, df_error *err);

#endif

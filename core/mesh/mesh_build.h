/* mesh_build.h — internal: growable vertex/element storage shared by the mesh readers, and the
 * final step that turns it into a df_mesh (kind choice, limits, analysis, inverted-element policy). */
#ifndef DF_MESH_BUILD_H
#define DF_MESH_BUILD_H

#include <stdint.h>

#include "core/mesh/mesh_io.h"

typedef struct df_mesh_build_list {
    int32_t *a;      /* n x width indices */
    int64_t n, cap;  /* rows used / allocated */
} df_mesh_build_list;

typedef struct df_mesh_build {
    const char *name;
    int binary;                 /* locations are byte offsets (1) or lines (0) */
    int32_t max_v, max_e;       /* resolved limits */
    int allow_inverted;
    double *V;
    int64_t nv, cap_v;
    int vertex_dims;            /* coordinates the reader is giving per vertex: 2 (file
                                 * declares 2D: OBJ `v x y`, MEDIT Dimension 2, 2D .node, PLY
                                 * without z) or 3 (default); set by the reader */
    int64_t v2d, v3d;           /* vertices given with 2 / 3 coordinates */
    int want_2d;                /* the caller asks for a 2D mesh (df_mesh_read_opts.want_2d) */
    df_mesh_build_list seg, tri, tet;   /* widths 2, 3, 4 */
    int32_t polygons, triangulated, ignored;
} df_mesh_build;

/* Prepares an empty builder with the limits of `o` (NULL -> defaults). */
void df_mesh_build_init(df_mesh_build *b, const char *name, int binary, const df_mesh_read_opts *o);

/* Frees everything the builder still owns. */
void df_mesh_build_free(df_mesh_build *b);

/* Formats "name:line" or "name: byte offset N" for `loc` into buf (size n). */
void df_mesh_build_where(const df_mesh_build *b, long long loc, char *buf, size_t n);

/* Checks a declared count against a limit and against what `bytes_left` could hold when each item
 * needs at least `min_bytes` bytes; DF_ELIMIT or DF_EFORMAT (truncated) with a message. */
int df_mesh_build_check_count(const df_mesh_build *b, long long loc, const char *what,
                              int64_t count, int64_t limit, size_t bytes_left, size_t min_bytes,
                              df_error *err);

/* Reserves room for `nv` more vertices (already checked against the limit). */
int df_mesh_build_reserve_vertices(df_mesh_build *b, int64_t nv, df_error *err);

/* Appends one vertex (z = 0 when b->vertex_dims is 2). DF_ELIMIT past max_v, DF_EFORMAT when a
 * coordinate is not finite or is outside the float32 range (it would become +-inf when stored as
 * float32). */
int df_mesh_build_vertex(df_mesh_build *b, long long loc, double x, double y, double z,
                         df_error *err);

/* Converts a file index `raw` with base `base` to 0-based and checks it against the vertices
 * read so far (or `nv_total` when >= 0). */
int df_mesh_build_index(const df_mesh_build *b, long long loc, int64_t raw, int base,
                        int64_t nv_total, int32_t *out, df_error *err);

/* Appends a segment (width 2), a triangle (3) or a tet (4) of 0-based indices. */
int df_mesh_build_elem(df_mesh_build *b, long long loc, int width, const int32_t *idx,
                       df_error *err);

/* Appends a polygon of n >= 3 0-based indices, fan-triangulated (0, i, i+1); counts it. */
int df_mesh_build_polygon(df_mesh_build *b, long long loc, const int32_t *idx, int n,
                          df_error *err);

/* Moves the data into `out`: tets win (triangles become the boundary F), else triangles, else
 * segments; no elements is DF_EFORMAT. The mesh is 2D (`planar`) only when every vertex was
 * given with 2 coordinates or want_2d asks for it (then every z must be 0: DF_EFORMAT naming the
 * first vertex with z != 0; a tet mesh cannot be 2D); a flat 3D mesh stays 3D. Runs df_mesh_analyze, applies allow_inverted, fills `rep`
 * (may be NULL) with `fmt`, `base` and the polygon counts. On error `out` is untouched. */
int df_mesh_build_finish(df_mesh_build *b, df_mesh_format fmt, int base, df_mesh *out,
                         df_mesh_report *rep, df_error *err);

#endif

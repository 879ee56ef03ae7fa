/* mesh_io.h — reading, writing, copying and checking df_mesh (see mesh.h).
 *
 * Formats: OBJ (v, f with v/vt/vn forms and negative indices, quads and n-gons fan-triangulated,
 * l polylines), OFF (also COFF/NOFF/CNOFF; per-row extras ignored), PLY (ASCII and binary little
 * endian; vertex x y [z], face vertex_indices lists fan-triangulated, edge vertex1 vertex2), MEDIT
 * .mesh (Vertices, Edges, Triangles, Quadrilaterals, Tetrahedra), TetGen .node + .ele (0- or
 * 1-based, detected from the first node id; 3 nodes per element = triangles, 4 or 10 = tets).
 *
 * OBJ faces may only reference vertices defined above them (negative indices count back from the
 * last one); `\` line continuations are not supported. Numbers go through strtod/printf, so
 * LC_NUMERIC must stay "C" (the default; nothing in deformd calls setlocale).
 *
 * Parsers work on explicit (pointer, length) buffers which need not be NUL-terminated; they never
 * read outside them. Every error names the file (or the caller's name for a buffer), the line (text)
 * or byte offset (binary) and the problem, e.g. "pig.ele:17: vertex index 10417 out of range
 * (10416 vertices)". On error the output mesh and report are left untouched. */
#ifndef DF_MESH_IO_H
#define DF_MESH_IO_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* Default limits used when df_mesh_read_opts is NULL or a limit is <= 0. */
#define DF_MESH_DEFAULT_MAX_VERTICES 20000000
#define DF_MESH_DEFAULT_MAX_ELEMENTS 100000000
/* Largest polygon (OBJ/OFF/PLY face) accepted; bigger faces are a format error. */
#define DF_MESH_MAX_POLYGON 1024
/* An element is degenerate when |volume| <= DF_MESH_DEGENERATE_REL * (longest edge)^d, d = 1, 2, 3
 * for segments, triangles and tets, or when it repeats a vertex index. */
#define DF_MESH_DEGENERATE_REL 1e-12

/* Sets `m` to the empty mesh (all zero, NULL arrays). */
void df_mesh_init(df_mesh *m);

/* Frees m->V, m->E, m->F and re-zeroes `m`. NULL-safe; safe on an init'ed or already freed mesh. */
void df_mesh_free(df_mesh *m);

/* Deep copy of `src` into `dst` (dst's previous arrays are NOT freed: pass an init'ed or freed
 * mesh). Errors: DF_EINVAL (NULL, negative counts, unknown kind), DF_ENOMEM. dst untouched on error. */
int df_mesh_copy(const df_mesh *src, df_mesh *dst, df_error *err);

typedef enum df_mesh_format {
    DF_FMT_AUTO = 0,       /* read: sniff the content; write: from the file extension */
    DF_FMT_OBJ,
    DF_FMT_OFF,
    DF_FMT_PLY,            /* read: ASCII or binary_little_endian; write: ASCII */
    DF_FMT_MEDIT,
    DF_FMT_TETGEN,         /* .node + .ele pair */
    DF_FMT_PLY_BINARY      /* write only: binary_little_endian PLY (reads as DF_FMT_PLY) */
} df_mesh_format;

/* Reader options. Start from df_mesh_read_opts_default(): a zero-initialized struct gets the
 * default limits but allow_inverted = 0 (inverted elements then fail the read). */
typedef struct df_mesh_read_opts {
    int32_t max_vertices;  /* refuse (DF_ELIMIT) more vertices; <= 0 means the default */
    int32_t max_elements;  /* refuse (DF_ELIMIT) more elements after triangulation; <= 0: default */
    int allow_inverted;    /* 0: inverted elements fail the read (DF_EFORMAT); 1: reported only */
    int want_2d;           /* 1: the mesh is 2D (`planar`) even if the file gives z: every z must
                            * be 0 and it must not have tets (else DF_EFORMAT); 0: 2D only when
                            * the file declares it (OBJ `v x y`, MEDIT Dimension 2, TetGen .node
                            * dimension 2, PLY without z) */
    int redact_content;    /* 1: error messages never quote bytes of the input (names, lines and
                              counts only): for files a server reads on a client's behalf */
    /* Optional progress of text formats (NULL: none): called on the reading thread with the
     * bytes of the current buffer scanned so far and its length, every DF_SCAN_PROGRESS_LINES
     * (16384) lines; TetGen calls it for the .node then the .ele buffer. Binary PLY bodies do
     * not report. It must not call back into the reader. */
    void (*progress)(void *user, size_t done, size_t total);
    void *progress_user;
} df_mesh_read_opts;

/* The defaults used for a NULL opts: default limits, allow_inverted = 1 (read succeeds, the report
 * counts inverted elements; df_mesh_check_for_solver refuses them). */
df_mesh_read_opts df_mesh_read_opts_default(void);

/* What a reader (or df_mesh_analyze) found. Counts are over the final elements (after
 * triangulation); `first_*` are 0-based element indices, -1 when none. */
typedef struct df_mesh_report {
    df_mesh_format format;        /* format actually parsed (DF_FMT_AUTO from df_mesh_analyze) */
    int index_base;               /* TetGen: 0 or 1 (first node id); OBJ/MEDIT: 1; OFF/PLY: 0 */
    int32_t input_polygons;       /* faces as written in the file (before fan triangulation) */
    int32_t polygons_triangulated;/* of those, how many had > 3 vertices (quads, n-gons) */
    int32_t ignored_elements;     /* dropped lower-dimensional elements: OBJ `l` lines or PLY edges
                                     in a file with faces, MEDIT Edges in a triangle/tet mesh,
                                     skipped MEDIT sections (Hexahedra, ...) */
    int32_t duplicate_elements;   /* elements with the same vertex set as an earlier one */
    int32_t degenerate_elements;  /* zero-measure or repeated-index elements */
    int32_t inverted_elements;    /* tets with negative volume; planar triangles whose orientation
                                     disagrees with the majority (all-clockwise is consistent) */
    int32_t nonmanifold_edges;    /* edges shared by > 2 triangles (tets: > 2 boundary triangles) */
    int32_t nonmanifold_faces;    /* tets: triangles shared by > 2 tets */
    int32_t boundary_edges;       /* triangle meshes: edges used by exactly one triangle */
    int32_t boundary_faces;       /* tet meshes: triangles used by exactly one tet */
    int32_t unreferenced_vertices;/* vertices no element uses */
    int32_t first_degenerate;
    int32_t first_inverted;
    double min_signed_volume;     /* smallest signed element measure (length/area/volume) */
} df_mesh_report;

/* The other half of a TetGen pair, keeping the case of the extension: "X.node" -> "X.ele",
 * "X.NODE" -> "X.ELE" (an all-upper-case extension stays upper case), "X.ele" -> "X.node".
 * Writes a NUL-terminated path into out (n bytes). Returns 0, or -1 when `path` does not end in
 * .node/.ele (any case) or out is too small. */
int df_mesh_tetgen_sibling(const char *path, char *out, size_t n);

/* Reads a mesh from `path`; the format comes from the extension (.obj .off .ply .mesh .node
 * .ele; case-insensitive). Only regular files are read. For X.node (or X.ele) the pair is read,
 * the sibling named by df_mesh_tetgen_sibling; a .node without
 * its .ele is an error (DF_EIO naming the missing file; use df_mesh_read_tetgen_nodes for positions
 * only). An unknown extension falls back to content sniffing. `o` may be NULL (defaults), `rep` may
 * be NULL. Errors: DF_EINVAL (NULL args), DF_EIO, DF_EFORMAT, DF_ELIMIT, DF_ENOMEM. On success
 * `out` receives a new mesh (its previous arrays are not freed: pass an init'ed or freed mesh). */
int df_mesh_read_file(const char *path, const df_mesh_read_opts *o, df_mesh *out,
                      df_mesh_report *rep, df_error *err);

/* Reads a mesh from the `len` bytes at `buf` (not NUL-terminated). `fmt` DF_FMT_AUTO sniffs:
 * "ply" -> PLY, [C][N]OFF -> OFF, MeshVersionFormatted/Dimension/Vertices -> MEDIT, else OBJ.
 * DF_FMT_TETGEN needs two buffers: it fails with DF_EUNSUPPORTED pointing to
 * df_mesh_read_tetgen_memory. `name_for_errors` (NULL -> "<memory>") prefixes messages.
 * Errors and ownership as df_mesh_read_file. */
int df_mesh_read_memory(const void *buf, size_t len, df_mesh_format fmt, const char *name_for_errors,
                        const df_mesh_read_opts *o, df_mesh *out, df_mesh_report *rep,
                        df_error *err);

/* Reads a TetGen pair from memory: `node` (node_len bytes) and `ele` (ele_len bytes). Element
 * indices use the base of the first node id. `name_for_errors` is the common stem ("pig" gives
 * messages about "pig.node" / "pig.ele"; NULL -> "<memory>") or the name of either half, whose
 * case is kept ("T1.NODE" gives "T1.NODE" / "T1.ELE"). Errors as df_mesh_read_file. */
int df_mesh_read_tetgen_memory(const void *node, size_t node_len, const void *ele, size_t ele_len,
                               const char *name_for_errors, const df_mesh_read_opts *o,
                               df_mesh *out, df_mesh_report *rep, df_error *err);

/* Positions only from a TetGen .node file (the paper's *_init*.node handle-target files):
 * *V receives a malloc'd nv x 3 row-major array (z = 0 for 2D files), *nv its row count. Rows are
 * in file order (ids must be consecutive from the first). Errors: DF_EINVAL, DF_EIO, DF_EFORMAT,
 * DF_ELIMIT (> DF_MESH_DEFAULT_MAX_VERTICES), DF_ENOMEM; *V and *nv untouched on error. */
int df_mesh_read_tetgen_nodes(const char *path, double **V, int32_t *nv, df_error *err);

/* Same as df_mesh_read_tetgen_nodes on a buffer. */
int df_mesh_read_tetgen_nodes_memory(const void *buf, size_t len, const char *name_for_errors,
                                     double **V, int32_t *nv, df_error *err);

/* Writes `m` to `path`, format from the extension: .obj (triangles, polylines), .off (triangles),
 * .ply (ASCII; triangles, polylines as `edge` elements), .mesh (all kinds; tet meshes also write
 * their F boundary triangles), .node (tets or triangles: writes X.node and X.ele, 1-based).
 * Coordinates are written with "%.17g" so write -> read round trips are bit-exact. A 2D mesh
 * (`planar`) is written in each format's 2D form (OBJ `v x y`, PLY without z, MEDIT Dimension 2,
 * .node dimension 2) and reads back 2D; OFF has none (x y 0: reads back as a flat 3D mesh).
 * Errors: DF_EINVAL (bad mesh or unknown extension), DF_EUNSUPPORTED (kind not representable in the
 * format, e.g. tets in OBJ), DF_EIO, DF_ENOMEM. */
int df_mesh_write_file(const char *path, const df_mesh *m, df_error *err);

/* Serializes `m` to a malloc'd buffer: *buf (NUL-terminated for text formats, but *len excludes
 * the NUL), *len bytes. `fmt` is one of OBJ, OFF, PLY, PLY_BINARY, MEDIT; for DF_FMT_TETGEN
 * this writes the .node part only (use df_mesh_write_tetgen_memory for both).
 * Errors as df_mesh_write_file; *buf and *len untouched on error. */
int df_mesh_write_memory(const df_mesh *m, df_mesh_format fmt, char **buf, size_t *len,
                         df_error *err);

/* Serializes a tet (or triangle) mesh as a TetGen pair: *node / *ele (malloc'd, 1-based ids). */
int df_mesh_write_tetgen_memory(const df_mesh *m, char **node, size_t *node_len, char **ele,
                                size_t *ele_len, df_error *err);

/* Structural check of an in-memory mesh: known kind, nv/ne >= 0 with matching non-NULL arrays,
 * finite coordinates, every index in [0, nv), F indices likewise, `planar` consistent with z.
 * Errors: DF_EINVAL with the first offending vertex/element in the message. */
int df_mesh_validate(const df_mesh *m, df_error *err);

/* Fills `rep` (not NULL) with the geometric and topological findings for a valid mesh:
 * degenerate / inverted elements, non-manifold and boundary edges and faces, unreferenced vertices.
 * `format` is set to DF_FMT_AUTO, `index_base` to 0 and polygon counts to 0.
 * Errors: those of df_mesh_validate, DF_ENOMEM. */
int df_mesh_analyze(const df_mesh *m, df_mesh_report *rep, df_error *err);

/* Refuses meshes the ADMM/elastic solvers cannot use: invalid structure (df_mesh_validate), no
 * elements, any degenerate element, any inverted element (tets with negative volume; planar
 * triangles oriented against the majority). Non-manifold edges and unreferenced vertices are allowed (reported in `rep`).
 * `rep` may be NULL. Errors: DF_EINVAL naming the count and the first bad element, DF_ENOMEM. */
int df_mesh_check_for_solver(const df_mesh *m, df_mesh_report *rep, df_error *err);

/* Short lower-case name of a format ("obj", "ply", ...), "auto" for DF_FMT_AUTO. */
const char *df_mesh_format_name(df_mesh_format fmt);

/* Format from a path's extension (case-insensitive), DF_FMT_AUTO when unknown. .ele and .node
 * both give DF_FMT_TETGEN. */
df_mesh_format df_mesh_format_from_path(const char *path);

#endif

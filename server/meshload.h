/* meshload.h — the server's use of core/mesh I/O for load requests, behind an interface that
 * needs only mesh.h. Wire format numbers equal core/mesh/mesh_io.h's df_mesh_format values
 * (0 auto, 1 obj, 2 off, 3 ply, 4 medit, 5 tetgen; see proto/messages.h). Pure functions, safe on
 * worker threads. */
#ifndef DF_SERVER_MESHLOAD_H
#define DF_SERVER_MESHLOAD_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* Parses an inline upload: `len` bytes at `data` in wire format `fmt` (0..5); for TetGen (5)
 * bytes [0, part2) are the .node file and [part2, len) the .ele file. Refuses more than
 * `max_vertices` vertices (DF_ELIMIT). `want_2d` 1: a 2D mesh even if the file gives z (every
 * z must be 0, no tets: else DF_EFORMAT); 0: 2D only when the file declares it. On success
 * *out holds a new mesh.
 * Errors: those of df_mesh_read_memory / df_mesh_read_tetgen_memory; DF_EINVAL for a bad fmt. */
int df_meshload_memory(const uint8_t *data, size_t len, int fmt, size_t part2,
                       int32_t max_vertices, int want_2d, const char *name, df_mesh *out,
                       df_error *err);

/* Reads a server-side file (format 0 = from the extension); want_2d as above. Errors as
 * df_mesh_read_file. */
int df_meshload_file(const char *path, int fmt, int32_t max_vertices, int want_2d, df_mesh *out,
                     df_error *err);

/* df_mesh_free. */
void df_meshload_free(df_mesh *m);

#endif

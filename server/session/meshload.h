/* meshload.h — the server's parsing of inline uploads (server-side paths: pathload.h). Wire
 * format numbers equal core/mesh/mesh_io.h's df_mesh_format values
 * (0 auto, 1 obj, 2 off, 3 ply, 4 medit, 5 tetgen; see proto/messages.h). Pure functions, safe on
 * worker threads. */
#ifndef DF_SERVER_MESHLOAD_H
#define DF_SERVER_MESHLOAD_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

/* A parse progress callback (df_mesh_read_opts.progress, with its user pointer). */
typedef struct df_mesh_progress {
    void (*fn)(void *user, size_t done, size_t total);
    void *user;
} df_mesh_progress;

/* Parses an inline upload: `len` bytes at `data` in wire format `fmt` (0..5); for TetGen (5)
 * bytes [0, part2) are the .node file and [part2, len) the .ele file. Refuses more than
 * `max_vertices` vertices (DF_ELIMIT). `want_2d` 1: a 2D mesh even if the file gives z (every
 * z must be 0, no tets: else DF_EFORMAT); 0: 2D only when the file declares it. Errors name
 * `name` (the user's file name; for TetGen "X.node"/"X.ele" or the stem X). On success *out
 * holds a new mesh and *rep (may be NULL) the reader's report. `progress` (may be NULL) is
 * called while text formats are parsed (df_mesh_read_opts.progress). Errors: those of
 * df_mesh_read_memory / df_mesh_read_tetgen_memory; DF_EINVAL for a bad fmt. (Server-side
 * paths: pathload.h.) */
int df_meshload_memory(const uint8_t *data, size_t len, int fmt, size_t part2,
                       int32_t max_vertices, int want_2d, const char *name, df_mesh *out,
                       df_mesh_report *rep, const df_mesh_progress *progress, df_error *err);

/* df_mesh_free. */
void df_meshload_free(df_mesh *m);

#endif

/* pathload.h — reading the mesh files a client names by server-side path (LOAD_MESH source 1).
 *
 * Every file the daemon opens for a client, both halves of a TetGen pair included, goes through
 * df_pathload_read: the path is resolved (realpath) and must lie inside a config allow_paths
 * directory; it is opened O_RDONLY|O_NONBLOCK|O_NOFOLLOW and the opened descriptor must still be
 * that resolved path (a component swapped for a symlink after the check is refused), a regular
 * file (FIFOs, devices, directories refused: nothing blocks a worker) of at most `max_bytes`
 * (checked with fstat before reading). A missing and a disallowed file give the same error
 * (DF_EIO "not allowed or not found") without the resolved path, so errors are no oracle for the
 * daemon's file system. Parse errors never quote file content (df_mesh_read_opts.redact_content).
 * Pure functions, safe on worker threads. */
#ifndef DF_SERVER_PATHLOAD_H
#define DF_SERVER_PATHLOAD_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh_io.h"
#include "server/session/meshload.h"
#include "server/config.h"

/* Largest server-side mesh file (both halves of a TetGen pair together): the inline upload cap,
 * max_upload_mb (at most DF_MAX_MESH_BYTES, 1 GiB). */
size_t df_pathload_max_bytes(const df_server_config *cfg);

/* Reads the whole file `path` (as the client gave it) after the checks above. On success *buf is
 * malloc'd (caller frees) and *len its size. Errors: DF_EUNSUPPORTED (no allow_paths configured),
 * DF_EIO ("not allowed or not found"; "not a regular file"; read error), DF_ELIMIT (larger than
 * max_bytes), DF_ENOMEM. Messages name `path` as given, never the resolved path. */
int df_pathload_read(const df_server_config *cfg, const char *path, size_t max_bytes, char **buf,
                     size_t *len, df_error *err);

/* Loads the mesh at client path `path`: `fmt` 0 takes the format from the extension (.obj .off
 * .ply .mesh .node .ele, any case; another extension is DF_EFORMAT "format not recognised",
 * listing the formats), 1..5 forces it (5 = TetGen needs a .node/.ele path). X.node / X.ele
 * reads both halves, the sibling found by df_mesh_tetgen_sibling (case kept: T1.NODE + T1.ELE),
 * each through df_pathload_read. At most `max_vertices` vertices. `want_2d` 1: a 2D mesh even
 * if the file gives z (every z must be 0, no tets: else DF_EFORMAT); 0: 2D only when the file
 * declares it. *out receives the mesh, *rep (may be NULL) the reader's report; `progress` (may
 * be NULL) is called while text formats are parsed (meshload.h). Errors: those of
 * df_pathload_read and of the readers. */
int df_pathload_mesh(const df_server_config *cfg, const char *path, int fmt,
                     int32_t max_vertices, int want_2d, df_mesh *out, df_mesh_report *rep,
                     const df_mesh_progress *progress, df_error *err);

#endif

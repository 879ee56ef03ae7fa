/* dc_files.h — deformctl's small text inputs, parsed by pure functions (text in, arrays out) with
 * thin file wrappers:
 *   index files   one 0-based vertex index per line (handles)
 *   point files   one "x y z" per line (pinned points, move targets)
 *   TetGen .node  "n dim attrs markers" header then "id x y z [attrs] [marker]" rows; ids may
 *                 start at 0 or 1 (detected from the first row)
 * Blank lines and lines whose first non-blank character is '#' are skipped everywhere. Errors
 * are DF_EFORMAT with "<name>:<line>: <what>" messages, DF_EIO for unreadable files, DF_ELIMIT
 * past DC_FILES_MAX_ROWS, DF_ENOMEM. Outputs are malloc'd and untouched on error. */
#ifndef DF_CLIENT_DC_FILES_H
#define DF_CLIENT_DC_FILES_H

#include <stdint.h>

#include "core/common/df_error.h"

/* Most rows any of these files may have, and largest file read (bytes). */
#define DC_FILES_MAX_ROWS 50000000
#define DC_FILES_MAX_BYTES (2048LL << 20)

/* Parses an index file `text` (NUL-terminated; `name` labels errors). Every index must be an
 * integer in [0, INT32_MAX). On success *idx (n entries, malloc'd) and *n are set; an empty
 * file is an error. */
int dc_parse_index_text(const char *text, const char *name, int32_t **idx, int32_t *n,
                        df_error *err);

/* Parses a point file: exactly three finite numbers per line. *xyz is n x 3 row-major doubles. */
int dc_parse_points_text(const char *text, const char *name, double **xyz, int32_t *n,
                         df_error *err);

/* Parses a TetGen .node text into *xyz (n x 3; 2D files get z = 0) and *n: core/mesh's
 * df_mesh_read_tetgen_nodes_memory (header count vs rows, consecutive ids from base 0 or 1). */
int dc_parse_node_text(const char *text, const char *name, double **xyz, int32_t *n,
                       df_error *err);

/* Targets of `nh` handles (vertex indices `handles`) from `text`: when `is_node`, the .node rows
 * at the handle indices (error when an index is >= the node count); otherwise a point file that
 * must have exactly nh rows. *targets is nh x 3 doubles. */
int dc_parse_targets_text(const char *text, const char *name, int is_node, const int32_t *handles,
                          int32_t nh, double **targets, df_error *err);

/* Reads a whole file into a NUL-terminated malloc'd buffer (*len excludes the NUL; may be NULL).*/
int dc_read_file(const char *path, char **text, long long *len, df_error *err);

/* File wrappers of the parsers above; dc_load_targets picks the .node reader when `path` ends
 * in ".node" (any case). */
int dc_load_index_file(const char *path, int32_t **idx, int32_t *n, df_error *err);
int dc_load_points_file(const char *path, double **xyz, int32_t *n, df_error *err);
int dc_load_targets(const char *path, const int32_t *handles, int32_t nh, double **targets,
                    df_error *err);

#endif

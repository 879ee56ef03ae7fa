/* mesh_readers.h — internal: the per-format parsers behind df_mesh_read_memory. Each parses the
 * `len` bytes at `buf` (not NUL-terminated), names errors after `name`, and follows the contract of
 * df_mesh_read_memory (outputs untouched on error). */
#ifndef DF_MESH_READERS_H
#define DF_MESH_READERS_H

#include <stddef.h>

#include "core/mesh/mesh_io.h"

int df_mesh_read_obj(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err);
int df_mesh_read_off(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err);
int df_mesh_read_ply(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err);
int df_mesh_read_medit(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                       df_mesh *out, df_mesh_report *rep, df_error *err);

#endif

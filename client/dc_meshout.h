/* dc_meshout.h — writes a mesh fetched from the daemon (float32 wire positions, int32 indices)
 * to a file through core/mesh's df_mesh_write_file (format from the extension: .obj .off .ply
 * .node .mesh). Used by `deformctl get`. */
#ifndef DF_CLIENT_DC_MESHOUT_H
#define DF_CLIENT_DC_MESHOUT_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* Writes the mesh of `kind` (df_mesh_kind), `planar` flag, nv float32 positions `xyz` (nv x 3),
 * ne elements `E` (ne x elem size, 0-based) and nf boundary faces `F` (nf x 3, may be NULL when
 * nf == 0) to `path`. Positions are widened to double exactly. A tet mesh written to a surface
 * format (.obj .off .ply) is written as its boundary surface instead: every triangle used by
 * exactly one tet (df_mesh_boundary_faces, outward), over ALL nv vertices (so vertex i of the
 * file is vertex i of the mesh; interior vertices are unreferenced); *surface_nf (may be NULL)
 * then receives the number of boundary triangles written, else -1. Errors: those of
 * df_mesh_write_file (DF_EINVAL unknown extension or bad mesh, DF_EUNSUPPORTED kind not
 * representable in the format, DF_EIO), of df_mesh_boundary_faces, DF_ENOMEM;
 * *surface_nf untouched on error. */
int dc_meshout_write(const char *path, int kind, int planar, uint32_t nv, const float *xyz,
                     uint32_t ne, const int32_t *E, uint32_t nf, const int32_t *F,
                     int32_t *surface_nf, df_error *err);

#endif

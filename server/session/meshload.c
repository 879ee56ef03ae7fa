/* meshload.c — mesh parsing for load requests (see meshload.h). */
#include "server/session/meshload.h"

#include "core/mesh/mesh_io.h"

int df_meshload_memory(const uint8_t *data, size_t len, int fmt, size_t part2,
                       int32_t max_vertices, int want_2d, const char *name, df_mesh *out,
                       df_mesh_report *rep, const df_mesh_progress *progress, df_error *err)
{
    df_mesh_read_opts o = df_mesh_read_opts_default();
    if (progress) {
        o.progress = progress->fn;
        o.progress_user = progress->user;
    }
    o.max_vertices = max_vertices;
    o.want_2d = want_2d;
    if (fmt < DF_FMT_AUTO || fmt > DF_FMT_TETGEN)
        return df_error_set(err, DF_EINVAL, "load: unknown mesh format %d", fmt);
    df_mesh_init(out);
    if (fmt == DF_FMT_TETGEN) {
        if (part2 == 0 || part2 >= len)
            return df_error_set(err, DF_EINVAL, "load: tetgen upload needs .node and .ele parts");
        return df_mesh_read_tetgen_memory(data, part2, data + part2, len - part2, name, &o, out,
                                          rep, err);
    }
    return df_mesh_read_memory(data, len, (df_mesh_format)fmt, name, &o, out, rep, err);
}

void df_meshload_free(df_mesh *m) { df_mesh_free(m); }

/* libFuzzer target for the mesh readers: every input is parsed as each format (auto-sniffed, OBJ,
 * OFF, PLY, MEDIT), as a TetGen pair (split at the first NUL byte, else in the middle) and as a
 * positions-only .node. A successful read must give a valid mesh that survives a write -> read round
 * trip bit-exactly (OBJ / binary PLY / MEDIT as the kind allows); anything else traps. Odd-sized
 * inputs are read with redact_content (the server's path loads). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_roundtrip(const df_mesh *m, df_mesh_format fmt)
{
    char *buf = NULL;
    size_t len = 0;
    int rc = df_mesh_write_memory(m, fmt, &buf, &len, NULL);
    if (rc == DF_EUNSUPPORTED)
        return;
    if (rc != DF_OK)
        __builtin_trap();
    df_mesh back;
    df_mesh_init(&back);
    if (df_mesh_read_memory(buf, len, fmt, "rt", NULL, &back, NULL, NULL) != DF_OK)
        __builtin_trap();
    if (back.kind != m->kind || back.nv != m->nv || back.ne != m->ne ||
        memcmp(back.V, m->V, (size_t)m->nv * 3 * sizeof(double)) ||
        memcmp(back.E, m->E, (size_t)m->ne * (size_t)df_mesh_elem_size(m->kind) * sizeof(int32_t)))
        __builtin_trap();
    df_mesh_free(&back);
    free(buf);
}

static void after_read(int rc, df_mesh *m, const df_error *err)
{
    if (rc != DF_OK) {
        if (err->msg[0] == '\0' || m->V || m->E)
            __builtin_trap(); /* errors carry a message and leave the output untouched */
        return;
    }
    if (df_mesh_validate(m, NULL) != DF_OK)
        __builtin_trap();
    check_roundtrip(m, DF_FMT_OBJ);
    check_roundtrip(m, DF_FMT_PLY_BINARY);
    check_roundtrip(m, DF_FMT_MEDIT);
    df_mesh_free(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const df_mesh_format fmts[] = {DF_FMT_AUTO, DF_FMT_OBJ, DF_FMT_OFF, DF_FMT_PLY,
                                          DF_FMT_MEDIT};
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.max_vertices = 100000; /* keep single runs small */
    o.max_elements = 100000;
    o.redact_content = (int)(size & 1); /* both message paths (server-side files are redacted) */
    for (size_t f = 0; f < sizeof fmts / sizeof fmts[0]; f++) {
        df_mesh m;
        df_error err;
        df_mesh_init(&m);
        df_error_clear(&err);
        after_read(df_mesh_read_memory(data, size, fmts[f], "fuzz", &o, &m, NULL, &err), &m, &err);
    }
    const uint8_t *nul = memchr(data, 0, size);
    size_t split = nul ? (size_t)(nul - data) : size / 2;
    size_t rest = nul ? split + 1 : split;
    df_mesh m;
    df_error err;
    df_mesh_init(&m);
    df_error_clear(&err);
    after_read(df_mesh_read_tetgen_memory(data, split, data + rest, size - rest, "fuzz", &o, &m,
                                          NULL, &err), &m, &err);
    double *V = NULL;
    int32_t nv = 0;
    if (df_mesh_read_tetgen_nodes_memory(data, size, "fuzz", &V, &nv, NULL) == DF_OK)
        free(V);
    return 0;
}

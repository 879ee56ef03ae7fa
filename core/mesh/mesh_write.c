/* mesh_write.c — mesh writers: OBJ, OFF, PLY (ASCII and binary little endian), MEDIT, TetGen
 * (see mesh_io.h). Coordinates use "%.17g" (binary PLY: raw doubles) so round trips are exact. */
#include "core/mesh/mesh_io.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    char *p;
    size_t n, cap;
    int failed;
} sbuf;

static void sb_reserve(sbuf *b, size_t extra)
{
    if (b->failed || b->n + extra + 1 <= b->cap)
        return;
    size_t nc = b->cap ? b->cap : 4096;
    while (nc < b->n + extra + 1)
        nc *= 2;
    char *np = realloc(b->p, nc);
    if (!np) {
        b->failed = 1;
        return;
    }
    b->p = np;
    b->cap = nc;
}

__attribute__((format(printf, 2, 3))) static void sb_printf(sbuf *b, const char *fmt, ...)
{
    sb_reserve(b, 256);
    if (b->failed)
        return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    if (k < 0) {
        b->failed = 1;
        return;
    }
    if ((size_t)k >= b->cap - b->n) {
        sb_reserve(b, (size_t)k);
        if (b->failed)
            return;
        va_start(ap, fmt);
        vsnprintf(b->p + b->n, b->cap - b->n, fmt, ap);
        va_end(ap);
    }
    b->n += (size_t)k;
}

static void sb_bytes(sbuf *b, const void *d, size_t n)
{
    sb_reserve(b, n);
    if (b->failed)
        return;
    memcpy(b->p + b->n, d, n);
    b->n += n;
    b->p[b->n] = '\0';
}

static int unsupported(const df_mesh *m, const char *fmt, df_error *err)
{
    static const char *kinds[] = {"", "polyline", "triangle", "tetrahedral"};
    return df_error_set(err, DF_EUNSUPPORTED, "cannot write a %s mesh as %s", kinds[m->kind], fmt);
}

static void put_xyz(sbuf *b, const char *prefix, const double *v, int dim, const char *suffix)
{
    if (dim == 2)
        sb_printf(b, "%s%.17g %.17g%s\n", prefix, v[0], v[1], suffix);
    else
        sb_printf(b, "%s%.17g %.17g %.17g%s\n", prefix, v[0], v[1], v[2], suffix);
}

static int write_obj(const df_mesh *m, sbuf *b, df_error *err)
{
    if (m->kind == DF_MESH_TET)
        return unsupported(m, "OBJ", err);
    sb_printf(b, "# deformd mesh: %d vertices, %d %s\n", (int)m->nv, (int)m->ne,
              m->kind == DF_MESH_TRIANGLE ? "triangles" : "segments");
    for (int32_t i = 0; i < m->nv; i++) /* a 2D mesh as `v x y`: read back as 2D */
        put_xyz(b, "v ", m->V + 3 * (size_t)i, m->planar ? 2 : 3, "");
    for (int32_t e = 0; e < m->ne; e++) {
        const int32_t *c = m->E + (size_t)df_mesh_elem_size(m->kind) * (size_t)e;
        if (m->kind == DF_MESH_TRIANGLE)
            sb_printf(b, "f %d %d %d\n", (int)c[0] + 1, (int)c[1] + 1, (int)c[2] + 1);
        else
            sb_printf(b, "l %d %d\n", (int)c[0] + 1, (int)c[1] + 1);
    }
    return DF_OK;
}

static int write_off(const df_mesh *m, sbuf *b, df_error *err)
{
    if (m->kind != DF_MESH_TRIANGLE)
        return unsupported(m, "OFF", err);
    sb_printf(b, "OFF\n%d %d 0\n", (int)m->nv, (int)m->ne);
    for (int32_t i = 0; i < m->nv; i++)
        put_xyz(b, "", m->V + 3 * (size_t)i, 3, "");
    for (int32_t e = 0; e < m->ne; e++)
        sb_printf(b, "3 %d %d %d\n", (int)m->E[3 * e], (int)m->E[3 * e + 1], (int)m->E[3 * e + 2]);
    return DF_OK;
}

static int write_ply(const df_mesh *m, int binary, sbuf *b, df_error *err)
{
    if (m->kind == DF_MESH_TET)
        return unsupported(m, "PLY", err);
    int tri = m->kind == DF_MESH_TRIANGLE;
    int dim = m->planar ? 2 : 3;   /* a 2D mesh without z: read back as 2D */
    sb_printf(b, "ply\nformat %s 1.0\ncomment deformd\nelement vertex %d\n"
                 "property double x\nproperty double y\n%s",
              binary ? "binary_little_endian" : "ascii", (int)m->nv,
              dim == 3 ? "property double z\n" : "");
    if (tri)
        sb_printf(b, "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
                  (int)m->ne);
    else
        sb_printf(b, "element edge %d\nproperty int vertex1\nproperty int vertex2\nend_header\n",
                  (int)m->ne);
    int k = tri ? 3 : 2;
    if (binary) { /* x86-64 is little endian: raw copies are the file's byte order */
        if (dim == 3)
            sb_bytes(b, m->V, (size_t)m->nv * 3 * sizeof(double));
        else
            for (int32_t i = 0; i < m->nv; i++)
                sb_bytes(b, m->V + 3 * (size_t)i, 2 * sizeof(double));
        for (int32_t e = 0; e < m->ne; e++) {
            unsigned char three = 3;
            if (tri)
                sb_bytes(b, &three, 1);
            sb_bytes(b, m->E + (size_t)k * (size_t)e, (size_t)k * sizeof(int32_t));
        }
        return DF_OK;
    }
    for (int32_t i = 0; i < m->nv; i++)
        put_xyz(b, "", m->V + 3 * (size_t)i, dim, "");
    for (int32_t e = 0; e < m->ne; e++) {
        const int32_t *c = m->E + (size_t)k * (size_t)e;
        if (tri)
            sb_printf(b, "3 %d %d %d\n", (int)c[0], (int)c[1], (int)c[2]);
        else
            sb_printf(b, "%d %d\n", (int)c[0], (int)c[1]);
    }
    return DF_OK;
}

static void medit_section(sbuf *b, const char *kw, const int32_t *E, int32_t n, int k)
{
    if (n == 0)
        return;
    sb_printf(b, "%s\n%d\n", kw, (int)n);
    for (int32_t e = 0; e < n; e++) {
        const int32_t *c = E + (size_t)k * (size_t)e;
        if (k == 2)
            sb_printf(b, "%d %d 0\n", (int)c[0] + 1, (int)c[1] + 1);
        else if (k == 3)
            sb_printf(b, "%d %d %d 0\n", (int)c[0] + 1, (int)c[1] + 1, (int)c[2] + 1);
        else
            sb_printf(b, "%d %d %d %d 0\n", (int)c[0] + 1, (int)c[1] + 1, (int)c[2] + 1,
                      (int)c[3] + 1);
    }
}

static void write_medit(const df_mesh *m, sbuf *b)
{
    int dim = m->planar ? 2 : 3;
    sb_printf(b, "MeshVersionFormatted 2\nDimension %d\nVertices\n%d\n", dim, (int)m->nv);
    for (int32_t i = 0; i < m->nv; i++)
        put_xyz(b, "", m->V + 3 * (size_t)i, dim, " 0");
    static const char *kw[] = {"", "Edges", "Triangles", "Tetrahedra"};
    if (m->kind == DF_MESH_TET)
        medit_section(b, "Triangles", m->F, m->nf, 3);
    medit_section(b, kw[m->kind], m->E, m->ne, df_mesh_elem_size(m->kind));
    sb_printf(b, "End\n");
}

static int write_node(const df_mesh *m, sbuf *b, df_error *err)
{
    if (m->kind == DF_MESH_POLYLINE)
        return unsupported(m, "TetGen", err);
    int dim = m->kind == DF_MESH_TRIANGLE && m->planar ? 2 : 3;
    sb_printf(b, "%d %d 0 0\n", (int)m->nv, dim);
    char id[24];
    for (int32_t i = 0; i < m->nv; i++) {
        snprintf(id, sizeof id, "%d ", (int)i + 1);
        put_xyz(b, id, m->V + 3 * (size_t)i, dim, "");
    }
    return DF_OK;
}

static void write_ele(const df_mesh *m, sbuf *b)
{
    int k = df_mesh_elem_size(m->kind);
    sb_printf(b, "%d %d 0\n", (int)m->ne, k);
    for (int32_t e = 0; e < m->ne; e++) {
        const int32_t *c = m->E + (size_t)k * (size_t)e;
        if (k == 3)
            sb_printf(b, "%d %d %d %d\n", (int)e + 1, (int)c[0] + 1, (int)c[1] + 1, (int)c[2] + 1);
        else
            sb_printf(b, "%d %d %d %d %d\n", (int)e + 1, (int)c[0] + 1, (int)c[1] + 1,
                      (int)c[2] + 1, (int)c[3] + 1);
    }
}

static int finish(sbuf *b, int rc, char **buf, size_t *len, df_error *err)
{
    if (!rc && b->failed)
        rc = df_error_set(err, DF_ENOMEM, "out of memory serializing a mesh");
    if (!rc && !b->p)
        sb_reserve(b, 0);
    if (rc || b->failed) {
        free(b->p);
        return rc ? rc : df_error_set(err, DF_ENOMEM, "out of memory serializing a mesh");
    }
    b->p[b->n] = '\0';
    *buf = b->p;
    *len = b->n;
    return DF_OK;
}

int df_mesh_write_memory(const df_mesh *m, df_mesh_format fmt, char **buf, size_t *len,
                         df_error *err)
{
    if (!buf || !len)
        return df_error_set(err, DF_EINVAL, "df_mesh_write_memory: NULL output");
    int rc = df_mesh_validate(m, err);
    if (rc)
        return rc;
    sbuf b = {0};
    switch (fmt) {
    case DF_FMT_OBJ: rc = write_obj(m, &b, err); break;
    case DF_FMT_OFF: rc = write_off(m, &b, err); break;
    case DF_FMT_PLY: rc = write_ply(m, 0, &b, err); break;
    case DF_FMT_PLY_BINARY: rc = write_ply(m, 1, &b, err); break;
    case DF_FMT_MEDIT: write_medit(m, &b); break;
    case DF_FMT_TETGEN: rc = write_node(m, &b, err); break;
    default: rc = df_error_set(err, DF_EINVAL, "cannot write mesh format %d", (int)fmt); break;
    }
    return finish(&b, rc, buf, len, err);
}

int df_mesh_write_tetgen_memory(const df_mesh *m, char **node, size_t *node_len, char **ele,
                                size_t *ele_len, df_error *err)
{
    if (!node || !node_len || !ele || !ele_len)
        return df_error_set(err, DF_EINVAL, "df_mesh_write_tetgen_memory: NULL output");
    char *nb;
    size_t nl;
    int rc = df_mesh_write_memory(m, DF_FMT_TETGEN, &nb, &nl, err);
    if (rc)
        return rc;
    sbuf b = {0};
    write_ele(m, &b);
    rc = finish(&b, DF_OK, ele, ele_len, err);
    if (rc) {
        free(nb);
        return rc;
    }
    *node = nb;
    *node_len = nl;
    return DF_OK;
}

static int save(const char *path, const char *buf, size_t len, df_error *err)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return df_error_set(err, DF_EIO, "%s: cannot create: %s", path, strerror(errno));
    size_t w = fwrite(buf, 1, len, f);
    int bad = fclose(f) != 0 || w != len;
    if (bad)
        return df_error_set(err, DF_EIO, "%s: write failed after %zu of %zu bytes", path, w, len);
    return DF_OK;
}

int df_mesh_write_file(const char *path, const df_mesh *m, df_error *err)
{
    if (!path)
        return df_error_set(err, DF_EINVAL, "df_mesh_write_file: NULL path");
    df_mesh_format fmt = df_mesh_format_from_path(path);
    if (fmt == DF_FMT_AUTO)
        return df_error_set(err, DF_EINVAL, "%s: unknown mesh file extension", path);
    char *b1 = NULL, *b2 = NULL;
    size_t l1 = 0, l2 = 0;
    int rc;
    if (fmt != DF_FMT_TETGEN) {
        rc = df_mesh_write_memory(m, fmt, &b1, &l1, err);
        if (!rc)
            rc = save(path, b1, l1, err);
        free(b1);
        return rc;
    }
    rc = df_mesh_write_tetgen_memory(m, &b1, &l1, &b2, &l2, err);
    if (!rc) {
        const char *dot = strrchr(path, '.');
        size_t stem = (size_t)(dot - path);
        char *p = malloc(stem + 6);
        if (!p) {
            rc = df_error_set(err, DF_ENOMEM, "out of memory");
        } else {
            snprintf(p, stem + 6, "%.*s.node", (int)stem, path);
            rc = save(p, b1, l1, err);
            snprintf(p, stem + 6, "%.*s.ele", (int)stem, path);
            if (!rc)
                rc = save(p, b2, l2, err);
            free(p);
        }
    }
    free(b1);
    free(b2);
    return rc;
}

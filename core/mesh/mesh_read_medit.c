/* mesh_read_medit.c — MEDIT .mesh reader (ASCII): MeshVersionFormatted, Dimension 2|3, Vertices
 * (coordinates + reference), Edges, Triangles, Quadrilaterals (split in two triangles),
 * Tetrahedra (1-based indices + reference), End. Known auxiliary sections (Corners, Ridges,
 * Normals, Hexahedra, ...) are skipped; an unknown keyword is an error. */
#include "core/mesh/mesh_readers.h"

#include "core/mesh/mesh_build.h"
#include "core/mesh/mesh_scan.h"

/* Auxiliary sections: keyword and number of tokens per row. */
static const struct { const char *kw; int width; } skip_sections[] = {
    {"Corners", 1}, {"RequiredVertices", 1}, {"Ridges", 1}, {"RequiredEdges", 1},
    {"RequiredTriangles", 1}, {"RequiredQuadrilaterals", 1}, {"Normals", 3}, {"Tangents", 3},
    {"NormalAtVertices", 2}, {"TangentAtVertices", 2}, {"NormalAtTriangleVertices", 3},
    {"TangentAtEdgeVertices", 3}, {"Hexahedra", 9}, {"Prisms", 7}, {"Pyramids", 6}};

static int section_count(df_scan *s, df_mesh_build *b, const char *what, int64_t limit,
                         int width, int32_t *n, df_error *err)
{
    int rc = df_scan_int(s, 1, what, n, err);
    if (!rc)
        rc = df_mesh_build_check_count(b, s->line, what, *n, limit, s->len - s->pos,
                                       (size_t)width * 2, err);
    return rc;
}

static int read_vertices(df_scan *s, df_mesh_build *b, int dim, df_error *err)
{
    int32_t n;
    int rc = section_count(s, b, "vertices", b->max_v, dim + 1, &n, err);
    if (!rc)
        rc = df_mesh_build_reserve_vertices(b, n, err);
    b->vertex_dims = dim;   /* Dimension 2: a 2D mesh */
    for (int32_t i = 0; !rc && i < n; i++) {
        double x[3] = {0, 0, 0};
        const char *t;
        for (int k = 0; !rc && k < dim; k++)
            rc = df_scan_double(s, 1, "vertex coordinate", &x[k], err);
        if (!rc && df_scan_token(s, 1, &t) == 0)
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: truncated: vertex %d lacks its reference",
                              s->name, (int)s->line, (int)i + 1);
        if (!rc)
            rc = df_mesh_build_vertex(b, s->line, x[0], x[1], x[2], err);
    }
    return rc;
}

/* Elements of `width` corners (2, 3, 4) + reference; quads (as_quads) split into triangles. */
static int read_elements(df_scan *s, df_mesh_build *b, const char *what, int width, int as_quads,
                         df_error *err)
{
    int32_t n;
    int rc = section_count(s, b, what, b->max_e, width + 1, &n, err);
    for (int32_t i = 0; !rc && i < n; i++) {
        int32_t idx[4], raw;
        for (int k = 0; !rc && k < width; k++) {
            rc = df_scan_int(s, 1, "vertex index", &raw, err);
            if (!rc)
                rc = df_mesh_build_index(b, s->line, raw, 1, -1, idx + k, err);
        }
        if (!rc)
            rc = df_scan_int(s, 1, "element reference", &raw, err);
        if (!rc)
            rc = as_quads ? df_mesh_build_polygon(b, s->line, idx, 4, err)
                          : df_mesh_build_elem(b, s->line, width, idx, err);
    }
    return rc;
}

static int skip_section(df_scan *s, df_mesh_build *b, const char *kw, int width, df_error *err)
{
    int32_t n;
    int rc = section_count(s, b, kw, INT32_MAX, width, &n, err);
    for (int64_t i = 0; !rc && i < (int64_t)n * width; i++) {
        const char *t;
        if (df_scan_token(s, 1, &t) == 0)
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: truncated inside section %s", s->name,
                              (int)s->line, kw);
    }
    if (!rc && width >= 6)
        b->ignored += n;
    return rc;
}

static int read_sections(df_scan *s, df_mesh_build *b, df_error *err)
{
    int dim = 3, rc = DF_OK;
    for (;;) {
        const char *t;
        size_t n = df_scan_token(s, 1, &t);
        int32_t v;
        if (n == 0 || df_scan_tok_eq(t, n, "End"))
            return DF_OK;
        if (df_scan_tok_eq(t, n, "MeshVersionFormatted")) {
            rc = df_scan_int(s, 1, "mesh version", &v, err);
        } else if (df_scan_tok_eq(t, n, "Dimension")) {
            rc = df_scan_int(s, 1, "dimension", &dim, err);
            if (!rc && dim != 2 && dim != 3)
                rc = df_error_set(err, DF_EFORMAT, "%s:%d: dimension %d (need 2 or 3)", s->name,
                                  (int)s->line, dim);
        } else if (df_scan_tok_eq(t, n, "Vertices")) {
            rc = read_vertices(s, b, dim, err);
        } else if (df_scan_tok_eq(t, n, "Edges")) {
            rc = read_elements(s, b, "edges", 2, 0, err);
        } else if (df_scan_tok_eq(t, n, "Triangles")) {
            rc = read_elements(s, b, "triangles", 3, 0, err);
        } else if (df_scan_tok_eq(t, n, "Quadrilaterals")) {
            rc = read_elements(s, b, "quadrilaterals", 4, 1, err);
        } else if (df_scan_tok_eq(t, n, "Tetrahedra")) {
            rc = read_elements(s, b, "tetrahedra", 4, 0, err);
        } else {
            size_t k = 0, nk = sizeof skip_sections / sizeof skip_sections[0];
            while (k < nk && !df_scan_tok_eq(t, n, skip_sections[k].kw))
                k++;
            if (k == nk)
            {
                char q[48];
                return df_error_set(err, DF_EFORMAT, "%s:%d: unknown MEDIT keyword %s", s->name,
                                    (int)s->line, df_scan_quote(s, t, n, q, sizeof q));
            }
            rc = skip_section(s, b, skip_sections[k].kw, skip_sections[k].width, err);
        }
        if (rc)
            return rc;
    }
}

int df_mesh_read_medit(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                       df_mesh *out, df_mesh_report *rep, df_error *err)
{
    df_scan s;
    df_scan_init(&s, buf, len, name);
    s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&s, o->progress, o->progress_user);
    df_mesh_build b;
    df_mesh_build_init(&b, s.name, 0, o);
    int rc = read_sections(&s, &b, err);
    if (!rc)
        rc = df_mesh_build_finish(&b, DF_FMT_MEDIT, 1, out, rep, err);
    df_mesh_build_free(&b);
    return rc;
}

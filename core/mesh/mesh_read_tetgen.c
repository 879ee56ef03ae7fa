/* mesh_read_tetgen.c — TetGen .node / .ele reader. .node: `n dim attrs markers`, then rows
 * `id x y [z] [attrs] [marker]`; .ele: `n nodes_per_elem attrs`, then `id a b c [d ..] [attr]`.
 * Ids must be consecutive from the first; the first node id (0 or 1) fixes the index base of the
 * elements. 3 nodes per element read as triangles, 4 as tets, 10 (quadratic) as their 4 corners. */
#include "core/mesh/mesh_io.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/mesh/mesh_build.h"
#include "core/mesh/mesh_scan.h"

static int trailing(df_scan *s, const char *what, int32_t n, df_error *err)
{
    df_scan_skip_ws(s);
    if (!df_scan_eof(s))
        return df_error_set(err, DF_EFORMAT,
                            "%s:%d: wrong counts: data after the %d %s the header declares",
                            s->name, (int)s->line, (int)n, what);
    return DF_OK;
}

static int row_id(df_scan *s, int32_t i, int *base, const char *what, df_error *err)
{
    int32_t id;
    int rc = df_scan_int(s, 1, what, &id, err);
    if (rc)
        return rc;
    if (i == 0) {
        if (id != 0 && id != 1)
            return df_error_set(err, DF_EFORMAT, "%s:%d: first %s %d (must be 0 or 1)", s->name,
                                (int)s->line, what, (int)id);
        *base = id;
    } else if (id != *base + i) {
        return df_error_set(err, DF_EFORMAT, "%s:%d: %s %d out of sequence (expected %d)",
                            s->name, (int)s->line, what, (int)id, (int)(*base + i));
    }
    return DF_OK;
}

/* Parses a .node buffer into b's vertices; *base receives the first id. */
static int parse_nodes(df_scan *s, df_mesh_build *b, int *base, df_error *err)
{
    int32_t n, dim, nattr, nmark;
    int rc = df_scan_int(s, 1, "node count", &n, err);
    if (!rc)
        rc = df_scan_int(s, 0, "dimension", &dim, err);
    if (!rc && !df_scan_at_eol(s))
        rc = df_scan_int(s, 0, "attribute count", &nattr, err);
    if (!rc && !df_scan_at_eol(s))
        rc = df_scan_int(s, 0, "marker flag", &nmark, err);
    if (rc)
        return rc;
    if (dim != 2 && dim != 3)
        return df_error_set(err, DF_EFORMAT, "%s:%d: dimension %d (need 2 or 3)", s->name,
                            (int)s->line, (int)dim);
    if (n == 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: no nodes", s->name, (int)s->line);
    df_scan_next_line(s);
    rc = df_mesh_build_check_count(b, s->line, "nodes", n, b->max_v, s->len - s->pos,
                                   (size_t)(dim + 1) * 2, err);
    if (!rc)
        rc = df_mesh_build_reserve_vertices(b, n, err);
    b->vertex_dims = dim;   /* a 2D .node: a 2D mesh */
    for (int32_t i = 0; !rc && i < n; i++) {
        double x[3] = {0, 0, 0};
        rc = row_id(s, i, base, "node id", err);
        for (int k = 0; !rc && k < dim; k++)
            rc = df_scan_double(s, 0, "node coordinate", &x[k], err);
        if (!rc)
            rc = df_mesh_build_vertex(b, s->line, x[0], x[1], x[2], err);
        df_scan_next_line(s);
    }
    return rc ? rc : trailing(s, "nodes", n, err);
}

static int parse_elements(df_scan *s, df_mesh_build *b, int base, df_error *err)
{
    int32_t n, npe, nattr = 0;
    int rc = df_scan_int(s, 1, "element count", &n, err);
    if (!rc)
        rc = df_scan_int(s, 0, "nodes per element", &npe, err);
    if (!rc && !df_scan_at_eol(s))
        rc = df_scan_int(s, 0, "attribute count", &nattr, err);
    if (rc)
        return rc;
    if (npe != 3 && npe != 4 && npe != 10)
        return df_error_set(err, DF_EFORMAT, "%s:%d: %d nodes per element (need 3, 4 or 10)",
                            s->name, (int)s->line, (int)npe);
    df_scan_next_line(s);
    rc = df_mesh_build_check_count(b, s->line, "elements", n, b->max_e, s->len - s->pos,
                                   (size_t)(npe + 1) * 2, err);
    int width = npe == 3 ? 3 : 4, ebase = 0;
    for (int32_t i = 0; !rc && i < n; i++) {
        int32_t idx[10], raw;
        rc = row_id(s, i, &ebase, "element id", err);
        for (int k = 0; !rc && k < npe; k++) {
            rc = df_scan_int(s, 0, "element vertex index", &raw, err);
            if (!rc)
                rc = df_mesh_build_index(b, s->line, raw, base, -1, idx + k, err);
        }
        if (!rc)
            rc = df_mesh_build_elem(b, s->line, width, idx, err);
        df_scan_next_line(s);
    }
    return rc ? rc : trailing(s, "elements", n, err);
}

/* Message names of the two halves: "X.node" / "X.ele" for a stem X; a name that already ends in
 * .node or .ele (any case) keeps its case, the other half from df_mesh_tetgen_sibling. */
static void stem_names(const char *stem, char *node, char *ele, size_t n)
{
    const char *st = stem ? stem : "<memory>";
    size_t l = strlen(st);
    const char *dot = strrchr(st, '.');
    char other[256];
    if (l < 200 && dot && df_mesh_tetgen_sibling(st, other, sizeof other) == 0) {
        int is_node = strcasecmp(dot, ".node") == 0;
        snprintf(node, n, "%s", is_node ? st : other);
        snprintf(ele, n, "%s", is_node ? other : st);
        return;
    }
    snprintf(node, n, "%.*s.node", (int)(l > 200 ? 200 : l), st);
    snprintf(ele, n, "%.*s.ele", (int)(l > 200 ? 200 : l), st);
}

int df_mesh_read_tetgen_memory(const void *node, size_t node_len, const void *ele, size_t ele_len,
                               const char *name_for_errors, const df_mesh_read_opts *o,
                               df_mesh *out, df_mesh_report *rep, df_error *err)
{
    if (!out || (!node && node_len) || (!ele && ele_len))
        return df_error_set(err, DF_EINVAL, "df_mesh_read_tetgen_memory: NULL argument");
    char nn[256], en[256];
    stem_names(name_for_errors, nn, en, sizeof nn);
    df_scan s;
    df_scan_init(&s, node, node_len, nn);
    s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&s, o->progress, o->progress_user);
    df_mesh_build b;
    df_mesh_build_init(&b, nn, 0, o);
    int base = 0;
    int rc = parse_nodes(&s, &b, &base, err);
    if (!rc) {
        df_scan_init(&s, ele, ele_len, en);
        s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&s, o->progress, o->progress_user);
        b.name = en;
        rc = parse_elements(&s, &b, base, err);
    }
    if (!rc)
        rc = df_mesh_build_finish(&b, DF_FMT_TETGEN, base, out, rep, err);
    df_mesh_build_free(&b);
    return rc;
}

int df_mesh_read_tetgen_nodes_memory(const void *buf, size_t len, const char *name_for_errors,
                                     double **V, int32_t *nv, df_error *err)
{
    if (!V || !nv || (!buf && len))
        return df_error_set(err, DF_EINVAL, "df_mesh_read_tetgen_nodes: NULL argument");
    df_scan s;
    df_scan_init(&s, buf, len, name_for_errors);
    df_mesh_build b;
    df_mesh_build_init(&b, s.name, 0, NULL);
    int base = 0;
    int rc = parse_nodes(&s, &b, &base, err);
    if (!rc) {
        double *v = realloc(b.V, (size_t)b.nv * 3 * sizeof(double));
        *V = v ? v : b.V;
        *nv = (int32_t)b.nv;
        b.V = NULL;
    }
    df_mesh_build_free(&b);
    return rc;
}

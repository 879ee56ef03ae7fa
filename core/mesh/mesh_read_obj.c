/* mesh_read_obj.c — Wavefront OBJ reader: `v x y [z]`, `f` with v, v/vt, v//vn, v/vt/vn forms
 * and negative (relative) indices, polygons fan-triangulated, `l` polylines as segments. Other
 * statements (vt, vn, o, g, s, usemtl, mtllib, ...) are ignored. */
#include "core/mesh/mesh_readers.h"

#include <string.h>

#include "core/mesh/mesh_build.h"
#include "core/mesh/mesh_scan.h"

/* Parses one face/line corner token ("7", "-1", "3/4", "3//5", "3/4/5") into a 0-based index. */
static int corner(const df_mesh_build *b, const df_scan *s, const char *t, size_t n, int32_t *out,
                  df_error *err)
{
    const char *slash = memchr(t, '/', n);
    size_t vn = slash ? (size_t)(slash - t) : n;
    int64_t raw;
    char qb[48];
    if (df_scan_parse_int(t, vn, &raw) != 0 || raw == 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: bad vertex reference %s", s->name,
                            (int)s->line, df_scan_quote(s, t, n, qb, sizeof qb));
    size_t p = vn;
    for (int part = 0; p < n && part < 2; part++) { /* validate /vt and /vn parts */
        size_t q = p + 1;
        while (q < n && t[q] != '/')
            q++;
        int64_t dummy;
        if (q > p + 1 && df_scan_parse_int(t + p + 1, q - p - 1, &dummy) != 0)
            return df_error_set(err, DF_EFORMAT, "%s:%d: bad vertex reference %s", s->name,
                                (int)s->line, df_scan_quote(s, t, n, qb, sizeof qb));
        p = q;
    }
    if (p < n)
        return df_error_set(err, DF_EFORMAT, "%s:%d: bad vertex reference %s", s->name,
                            (int)s->line, df_scan_quote(s, t, n, qb, sizeof qb));
    if (raw < 0 && -raw > b->nv)
        return df_error_set(err, DF_EFORMAT, "%s:%d: vertex index %lld out of range (%lld vertices "
                            "so far)", s->name, (int)s->line, (long long)raw, (long long)b->nv);
    if (raw < 0)
        raw = b->nv + raw + 1; /* -1 is the last vertex so far; make it 1-based */
    return df_mesh_build_index(b, s->line, raw, 1, -1, out, err);
}

static int read_vertex(df_mesh_build *b, df_scan *s, df_error *err)
{
    double x, y, z = 0.0;
    int32_t line = s->line;
    int rc = df_scan_double(s, 0, "vertex x", &x, err);
    if (!rc)
        rc = df_scan_double(s, 0, "vertex y", &y, err);
    int has_z = !rc && !df_scan_at_eol(s);
    if (has_z)
        rc = df_scan_double(s, 0, "vertex z", &z, err);
    b->vertex_dims = has_z ? 3 : 2;   /* `v x y`: a 2D file (when every vertex is so) */
    if (!rc)
        rc = df_mesh_build_vertex(b, line, x, y, z, err);
    return rc;
}

static int read_corners(df_mesh_build *b, df_scan *s, int32_t *idx, int *n, df_error *err)
{
    const char *t;
    size_t tn;
    *n = 0;
    while ((tn = df_scan_token(s, 0, &t)) > 0) {
        if (*n >= DF_MESH_MAX_POLYGON)
            return df_error_set(err, DF_EFORMAT, "%s:%d: more than %d vertices in one face", s->name,
                                (int)s->line, DF_MESH_MAX_POLYGON);
        int rc = corner(b, s, t, tn, idx + *n, err);
        if (rc)
            return rc;
        (*n)++;
    }
    return DF_OK;
}

int df_mesh_read_obj(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err)
{
    df_scan s;
    df_scan_init(&s, buf, len, name);
    s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&s, o->progress, o->progress_user);
    df_mesh_build b;
    df_mesh_build_init(&b, s.name, 0, o);
    int32_t idx[DF_MESH_MAX_POLYGON];
    int rc = DF_OK;
    while (!rc) {
        df_scan_skip_ws(&s);
        if (df_scan_eof(&s))
            break;
        const char *t;
        size_t tn = df_scan_token(&s, 0, &t);
        int n = 0;
        if (df_scan_tok_eq(t, tn, "v")) {
            rc = read_vertex(&b, &s, err);
        } else if (df_scan_tok_eq(t, tn, "f") || df_scan_tok_eq(t, tn, "fo")) {
            rc = read_corners(&b, &s, idx, &n, err);
            if (!rc)
                rc = df_mesh_build_polygon(&b, s.line, idx, n, err);
        } else if (df_scan_tok_eq(t, tn, "l")) {
            rc = read_corners(&b, &s, idx, &n, err);
            if (!rc && n < 2)
                rc = df_error_set(err, DF_EFORMAT, "%s:%d: line with %d vertices (need at least 2)",
                                  s.name, (int)s.line, n);
            for (int i = 0; !rc && i + 1 < n; i++)
                rc = df_mesh_build_elem(&b, s.line, 2, idx + i, err);
        }
        if (!rc)
            df_scan_next_line(&s);
    }
    if (!rc)
        rc = df_mesh_build_finish(&b, DF_FMT_OBJ, 1, out, rep, err);
    df_mesh_build_free(&b);
    return rc;
}

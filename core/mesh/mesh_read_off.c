/* mesh_read_off.c — OFF reader: header OFF (or COFF, NOFF, CNOFF, STOFF...), counts
 * `nv nf [ne]`, nv vertex rows (extra values such as colours ignored), nf face rows
 * `n i0 .. i(n-1)` (0-based; n-gons fan-triangulated; trailing colours ignored). */
#include "core/mesh/mesh_readers.h"

#include "core/mesh/mesh_build.h"
#include "core/mesh/mesh_scan.h"

static int off_header(const char *t, size_t n)
{
    if (n < 3 || n > 8 || t[n - 3] != 'O' || t[n - 2] != 'F' || t[n - 1] != 'F')
        return 0;
    for (size_t i = 0; i + 3 < n; i++)
        if (t[i] != 'S' && t[i] != 'T' && t[i] != 'C' && t[i] != 'N')
            return 0;
    return 1;
}

static int read_counts(df_scan *s, df_mesh_build *b, int32_t *nv, int32_t *nf, df_error *err)
{
    const char *t;
    size_t n = df_scan_token(s, 1, &t);
    char q[48];
    if (!off_header(t, n))
        return df_error_set(err, DF_EFORMAT, "%s:%d: missing OFF header (found %s)", s->name,
                            (int)s->line, df_scan_quote(s, t, n > 16 ? 16 : n, q, sizeof q));
    int32_t ne = 0;
    int rc = df_scan_int(s, 1, "vertex count", nv, err);
    if (!rc)
        rc = df_scan_int(s, 0, "face count", nf, err);
    if (!rc && !df_scan_at_eol(s))
        rc = df_scan_int(s, 0, "edge count", &ne, err);
    if (rc)
        return rc;
    df_scan_next_line(s);
    size_t left = s->len - s->pos;
    rc = df_mesh_build_check_count(b, s->line, "vertices", *nv, b->max_v, left, 6, err);
    if (!rc)
        rc = df_mesh_build_check_count(b, s->line, "faces", *nf, b->max_e, left, 2, err);
    return rc;
}

int df_mesh_read_off(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err)
{
    df_scan s;
    df_scan_init(&s, buf, len, name);
    s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&s, o->progress, o->progress_user);
    df_mesh_build b;
    df_mesh_build_init(&b, s.name, 0, o);
    int32_t nv = 0, nf = 0;
    int rc = read_counts(&s, &b, &nv, &nf, err);
    if (!rc)
        rc = df_mesh_build_reserve_vertices(&b, nv, err);
    for (int32_t i = 0; !rc && i < nv; i++) {
        double x, y, z;
        rc = df_scan_double(&s, 1, "vertex x", &x, err);
        int32_t line = s.line;
        if (!rc)
            rc = df_scan_double(&s, 0, "vertex y", &y, err);
        if (!rc)
            rc = df_scan_double(&s, 0, "vertex z", &z, err);
        if (!rc)
            rc = df_mesh_build_vertex(&b, line, x, y, z, err);
        df_scan_next_line(&s);
    }
    int32_t idx[DF_MESH_MAX_POLYGON];
    for (int32_t f = 0; !rc && f < nf; f++) {
        int32_t n;
        rc = df_scan_int(&s, 1, "face size", &n, err);
        if (!rc && (n < 3 || n > DF_MESH_MAX_POLYGON))
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: face %d has %d vertices (need 3..%d)",
                              s.name, (int)s.line, (int)f, (int)n, DF_MESH_MAX_POLYGON);
        for (int32_t k = 0; !rc && k < n; k++) {
            int32_t raw;
            rc = df_scan_int(&s, 0, "face vertex index", &raw, err);
            if (!rc)
                rc = df_mesh_build_index(&b, s.line, raw, 0, -1, idx + k, err);
        }
        if (!rc)
            rc = df_mesh_build_polygon(&b, s.line, idx, n, err);
        df_scan_next_line(&s);
    }
    if (!rc) {
        df_scan_skip_ws(&s);
        if (!df_scan_eof(&s))
            rc = df_error_set(err, DF_EFORMAT,
                              "%s:%d: wrong counts: data after the %d faces the header declares",
                              s.name, (int)s.line, (int)nf);
    }
    if (!rc)
        rc = df_mesh_build_finish(&b, DF_FMT_OFF, 0, out, rep, err);
    df_mesh_build_free(&b);
    return rc;
}

/* mesh_read_ply.c — PLY reader (format ascii 1.0 or binary_little_endian 1.0). Elements:
 * `vertex` (properties x, y, [z]; others skipped), `face` (list vertex_indices or vertex_index,
 * fan-triangulated), `edge` (vertex1, vertex2 -> polyline segments); other elements skipped. */
#include "core/mesh/mesh_readers.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh_build.h"
#include "core/mesh/mesh_scan.h"

#define PLY_MAX_ELEMENTS 16
#define PLY_MAX_PROPS 32
#define PLY_NAME_MAX 32

enum { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 };

typedef struct {
    int type, list, count_type;
    char name[PLY_NAME_MAX];
} ply_prop;

typedef struct {
    char name[PLY_NAME_MAX];
    int64_t count;
    int np;
    ply_prop p[PLY_MAX_PROPS];
} ply_elem;

typedef struct {
    df_scan s;          /* header and ASCII body */
    int binary;
    size_t pos;         /* binary body offset */
    int ne;
    ply_elem e[PLY_MAX_ELEMENTS];
    df_mesh_build b;
} ply_ctx;

static int type_of(const char *t, size_t n)
{
    static const struct { const char *name; int type; } names[] = {
        {"char", T_I8}, {"int8", T_I8}, {"uchar", T_U8}, {"uint8", T_U8},
        {"short", T_I16}, {"int16", T_I16}, {"ushort", T_U16}, {"uint16", T_U16},
        {"int", T_I32}, {"int32", T_I32}, {"uint", T_U32}, {"uint32", T_U32},
        {"float", T_F32}, {"float32", T_F32}, {"double", T_F64}, {"float64", T_F64}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (df_scan_tok_eq(t, n, names[i].name))
            return names[i].type;
    return T_NONE;
}

static size_t type_size(int t)
{
    static const size_t sz[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return sz[t];
}

static void copy_name(char *dst, const char *t, size_t n)
{
    if (n >= PLY_NAME_MAX)
        n = PLY_NAME_MAX - 1;
    memcpy(dst, t, n);
    dst[n] = '\0';
}

static int hdr_err(ply_ctx *c, const char *what, df_error *err)
{
    return df_error_set(err, DF_EFORMAT, "%s:%d: bad PLY header: %s", c->s.name, (int)c->s.line,
                        what);
}

static int parse_property(ply_ctx *c, df_error *err)
{
    df_scan *s = &c->s;
    if (c->ne == 0)
        return hdr_err(c, "property before any element", err);
    ply_elem *e = &c->e[c->ne - 1];
    if (e->np >= PLY_MAX_PROPS)
        return hdr_err(c, "too many properties", err);
    ply_prop *p = &e->p[e->np];
    memset(p, 0, sizeof *p);
    const char *t;
    size_t n = df_scan_token(s, 0, &t);
    if (df_scan_tok_eq(t, n, "list")) {
        p->list = 1;
        n = df_scan_token(s, 0, &t);
        p->count_type = type_of(t, n);
        if (p->count_type == T_NONE || p->count_type >= T_F32)
            return hdr_err(c, "bad list count type", err);
        n = df_scan_token(s, 0, &t);
    }
    p->type = type_of(t, n);
    if (p->type == T_NONE)
        return hdr_err(c, "unknown property type", err);
    n = df_scan_token(s, 0, &t);
    if (n == 0)
        return hdr_err(c, "property without a name", err);
    copy_name(p->name, t, n);
    e->np++;
    return DF_OK;
}

static int parse_header(ply_ctx *c, df_error *err)
{
    df_scan *s = &c->s;
    s->comment = 0;
    const char *t;
    size_t n = df_scan_token(s, 0, &t);
    if (!df_scan_tok_eq(t, n, "ply") || !df_scan_at_eol(s))
        return hdr_err(c, "missing 'ply' magic", err);
    int have_format = 0;
    for (;;) {
        df_scan_next_line(s);
        if (df_scan_eof(s))
            return df_error_set(err, DF_EFORMAT, "%s:%d: truncated: PLY header has no end_header",
                                s->name, (int)s->line);
        n = df_scan_token(s, 0, &t);
        if (df_scan_tok_eq(t, n, "end_header")) {
            df_scan_next_line(s);
            break;
        } else if (df_scan_tok_eq(t, n, "format")) {
            n = df_scan_token(s, 0, &t);
            if (df_scan_tok_eq(t, n, "ascii"))
                c->binary = 0;
            else if (df_scan_tok_eq(t, n, "binary_little_endian"))
                c->binary = 1;
            else
            {
                char q[48];
                return df_error_set(err, DF_EFORMAT, "%s:%d: unsupported PLY format %s", s->name,
                                    (int)s->line, df_scan_quote(s, t, n, q, sizeof q));
            }
            have_format = 1;
        } else if (df_scan_tok_eq(t, n, "element")) {
            if (c->ne >= PLY_MAX_ELEMENTS)
                return hdr_err(c, "too many elements", err);
            ply_elem *e = &c->e[c->ne];
            memset(e, 0, sizeof *e);
            n = df_scan_token(s, 0, &t);
            if (n == 0)
                return hdr_err(c, "element without a name", err);
            copy_name(e->name, t, n);
            int32_t cnt;
            char q[48];
            int rc = df_scan_int(s, 0, "element count", &cnt, err);
            if (rc)
                return rc;
            if (cnt < 0)
                return df_error_set(err, DF_EFORMAT, "%s:%d: wrong counts: element %s count %d",
                                    s->name, (int)s->line,
                                    df_scan_quote(s, e->name, strlen(e->name), q, sizeof q),
                                    (int)cnt);
            e->count = cnt;
            c->ne++;
        } else if (df_scan_tok_eq(t, n, "property")) {
            int rc = parse_property(c, err);
            if (rc)
                return rc;
        } else if (n == 0 || df_scan_tok_eq(t, n, "comment") || df_scan_tok_eq(t, n, "obj_info")) {
            continue;
        } else {
            return hdr_err(c, "unknown header line", err);
        }
    }
    if (!have_format)
        return hdr_err(c, "no format line", err);
    return DF_OK;
}

/* Reads one scalar of `type` from the body as a double. */
static int read_value(ply_ctx *c, int type, double *v, df_error *err)
{
    if (!c->binary) {
        const char *t;
        size_t n = df_scan_token(&c->s, 1, &t);
        if (n == 0)
            return df_error_set(err, DF_EFORMAT, "%s:%d: truncated: PLY data ends early",
                                c->s.name, (int)c->s.line);
        char q[48];
        if (df_scan_parse_double(t, n, v) != 0)
            return df_error_set(err, DF_EFORMAT, "%s:%d: %s is not a number", c->s.name,
                                (int)c->s.line, df_scan_quote(&c->s, t, n, q, sizeof q));
        return DF_OK;
    }
    size_t sz = type_size(type);
    if (c->pos + sz > c->s.len)
        return df_error_set(err, DF_EFORMAT, "%s: byte offset %zu: truncated: PLY data ends early",
                            c->s.name, c->pos);
    const unsigned char *p = (const unsigned char *)c->s.p + c->pos;
    c->pos += sz;
    union { uint8_t b[8]; int8_t i8; int16_t i16; uint16_t u16; int32_t i32; uint32_t u32;
            float f; double d; } u;
    memcpy(u.b, p, sz); /* x86-64 is little endian, like the data */
    switch (type) {
    case T_I8: *v = u.i8; break;
    case T_U8: *v = u.b[0]; break;
    case T_I16: *v = u.i16; break;
    case T_U16: *v = u.u16; break;
    case T_I32: *v = u.i32; break;
    case T_U32: *v = u.u32; break;
    case T_F32: *v = u.f; break;
    default: *v = u.d; break;
    }
    return DF_OK;
}

static long long loc(const ply_ctx *c)
{
    return c->binary ? (long long)c->pos : (long long)c->s.line;
}

static int to_index(ply_ctx *c, double v, int32_t *out, df_error *err)
{
    long long l = loc(c);
    if (v != floor(v) || fabs(v) > 2147483647.0) {
        char w[160];
        df_mesh_build_where(&c->b, l, w, sizeof w);
        return df_error_set(err, DF_EFORMAT, "%s: vertex index %g is not an integer", w, v);
    }
    return df_mesh_build_index(&c->b, l, (int64_t)v, 0, -1, out, err);
}

static int find_prop(const ply_elem *e, const char *name)
{
    for (int i = 0; i < e->np; i++)
        if (!strcmp(e->p[i].name, name))
            return i;
    return -1;
}

/* Reads one row of element e; role: 0 skip, 1 vertex, 2 face, 3 edge. */
static int read_row(ply_ctx *c, const ply_elem *e, int role, const int *key, df_error *err)
{
    double xyz[3] = {0, 0, 0};
    int32_t idx[DF_MESH_MAX_POLYGON];
    int ni = 0, n_edge = 0;
    long long l0 = loc(c);
    for (int i = 0; i < e->np; i++) {
        const ply_prop *p = &e->p[i];
        double v;
        int rc;
        if (!p->list) {
            if ((rc = read_value(c, p->type, &v, err)))
                return rc;
            if (role == 1 && (i == key[0] || i == key[1] || i == key[2]))
                xyz[i == key[0] ? 0 : i == key[1] ? 1 : 2] = v;
            if (role == 3 && (i == key[0] || i == key[1])) {
                if ((rc = to_index(c, v, idx + (i == key[0] ? 0 : 1), err)))
                    return rc;
                n_edge++;
            }
            continue;
        }
        if ((rc = read_value(c, p->count_type, &v, err)))
            return rc;
        if (v < 0 || v > DF_MESH_MAX_POLYGON) {
            char w[160];
            df_mesh_build_where(&c->b, loc(c), w, sizeof w);
            return df_error_set(err, DF_EFORMAT, "%s: list of %g items (limit %d)", w, v,
                                DF_MESH_MAX_POLYGON);
        }
        int cnt = (int)v;
        for (int k = 0; k < cnt; k++) {
            double x;
            if ((rc = read_value(c, p->type, &x, err)))
                return rc;
            if (role == 2 && i == key[0]) {
                if ((rc = to_index(c, x, idx + k, err)))
                    return rc;
                ni = k + 1;
            }
        }
    }
    if (role == 1)
        return df_mesh_build_vertex(&c->b, l0, xyz[0], xyz[1], xyz[2], err);
    if (role == 2)
        return df_mesh_build_polygon(&c->b, l0, idx, ni, err);
    if (role == 3 && n_edge == 2)
        return df_mesh_build_elem(&c->b, l0, 2, idx, err);
    return DF_OK;
}

static int read_element(ply_ctx *c, const ply_elem *e, df_error *err)
{
    int role = 0, key[3] = {-1, -1, -1};
    size_t min_row = 0;
    for (int i = 0; i < e->np; i++)
        min_row += c->binary ? type_size(e->p[i].list ? e->p[i].count_type : e->p[i].type) : 2;
    size_t left = c->binary ? c->s.len - c->pos : c->s.len - c->s.pos;
    if (!strcmp(e->name, "vertex")) {
        key[0] = find_prop(e, "x");
        key[1] = find_prop(e, "y");
        key[2] = find_prop(e, "z");
        if (key[0] < 0 || key[1] < 0 || e->p[key[0]].list || e->p[key[1]].list ||
            (key[2] >= 0 && e->p[key[2]].list))
            return df_error_set(err, DF_EFORMAT, "%s: PLY vertex element lacks scalar x/y",
                                c->s.name);
        role = 1;
        c->b.vertex_dims = key[2] >= 0 ? 3 : 2;   /* no z property: a 2D mesh */
        int rc = df_mesh_build_check_count(&c->b, loc(c), "vertices", e->count, c->b.max_v, left,
                                           min_row, err);
        if (!rc)
            rc = df_mesh_build_reserve_vertices(&c->b, e->count, err);
        if (rc)
            return rc;
    } else if (!strcmp(e->name, "face")) {
        key[0] = find_prop(e, "vertex_indices");
        if (key[0] < 0)
            key[0] = find_prop(e, "vertex_index");
        if (key[0] < 0 || !e->p[key[0]].list)
            return df_error_set(err, DF_EFORMAT, "%s: PLY face element lacks a vertex_indices list",
                                c->s.name);
        role = 2;
    } else if (!strcmp(e->name, "edge")) {
        key[0] = find_prop(e, "vertex1");
        key[1] = find_prop(e, "vertex2");
        role = key[0] >= 0 && key[1] >= 0 ? 3 : 0;
    }
    const char *what = c->s.redact ? "element" : e->name; /* element names are file content */
    int rc = df_mesh_build_check_count(&c->b, loc(c), what, e->count, INT32_MAX, left,
                                       min_row, err);
    for (int64_t r = 0; !rc && e->np > 0 && r < e->count; r++)
        rc = read_row(c, e, role, key, err);
    if (!rc && role == 0)
        c->b.ignored += (int32_t)e->count;
    return rc;
}

int df_mesh_read_ply(const char *buf, size_t len, const char *name, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err)
{
    static ply_ctx zero;
    ply_ctx *c = malloc(sizeof *c);
    if (!c)
        return df_error_set(err, DF_ENOMEM, "out of memory reading PLY");
    *c = zero;
    df_scan_init(&c->s, buf, len, name);
    c->s.redact = o && o->redact_content;
    if (o) df_scan_set_progress(&c->s, o->progress, o->progress_user);
    int rc = parse_header(c, err);
    df_mesh_build_init(&c->b, c->s.name, c->binary, o);
    c->pos = c->s.pos;
    for (int i = 0; !rc && i < c->ne; i++)
        rc = read_element(c, &c->e[i], err);
    if (!rc)
        rc = df_mesh_build_finish(&c->b, DF_FMT_PLY, 0, out, rep, err);
    df_mesh_build_free(&c->b);
    free(c);
    return rc;
}

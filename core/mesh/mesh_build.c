/* mesh_build.c — growable storage for the mesh readers (see mesh_build.h). */
#include "core/mesh/mesh_build.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void df_mesh_build_init(df_mesh_build *b, const char *name, int binary, const df_mesh_read_opts *o)
{
    memset(b, 0, sizeof *b);
    df_mesh_read_opts d = df_mesh_read_opts_default();
    b->name = name ? name : "<memory>";
    b->binary = binary;
    b->max_v = (o && o->max_vertices > 0) ? o->max_vertices : d.max_vertices;
    b->max_e = (o && o->max_elements > 0) ? o->max_elements : d.max_elements;
    b->allow_inverted = o ? o->allow_inverted : d.allow_inverted;
    b->want_2d = o ? o->want_2d : 0;
    b->vertex_dims = 3;
}

void df_mesh_build_free(df_mesh_build *b)
{
    free(b->V);
    free(b->seg.a);
    free(b->tri.a);
    free(b->tet.a);
    b->V = NULL;
    b->seg.a = b->tri.a = b->tet.a = NULL;
    b->nv = b->cap_v = 0;
    b->seg.n = b->tri.n = b->tet.n = 0;
    b->seg.cap = b->tri.cap = b->tet.cap = 0;
}

void df_mesh_build_where(const df_mesh_build *b, long long loc, char *buf, size_t n)
{
    if (b->binary)
        snprintf(buf, n, "%s: byte offset %lld", b->name, loc);
    else
        snprintf(buf, n, "%s:%lld", b->name, loc);
}

int df_mesh_build_check_count(const df_mesh_build *b, long long loc, const char *what,
                              int64_t count, int64_t limit, size_t bytes_left, size_t min_bytes,
                              df_error *err)
{
    char w[160];
    df_mesh_build_where(b, loc, w, sizeof w);
    if (count < 0)
        return df_error_set(err, DF_EFORMAT, "%s: wrong count: %lld %s", w, (long long)count, what);
    if (count > limit)
        return df_error_set(err, DF_ELIMIT, "%s: %lld %s exceed the configured limit %lld", w,
                            (long long)count, what, (long long)limit);
    if (min_bytes > 0 && (uint64_t)count > bytes_left / min_bytes)
        return df_error_set(err, DF_EFORMAT,
                            "%s: truncated: %lld %s declared but only %zu bytes remain", w,
                            (long long)count, what, bytes_left);
    return DF_OK;
}

static int grow(void **arr, int64_t *cap, int64_t need, size_t item, df_error *err)
{
    if (need <= *cap)
        return DF_OK;
    int64_t nc = *cap < 64 ? 64 : *cap;
    while (nc < need)
        nc += nc / 2;
    void *p = realloc(*arr, (size_t)nc * item);
    if (!p)
        return df_error_set(err, DF_ENOMEM, "out of memory growing a mesh array to %lld items",
                            (long long)nc);
    *arr = p;
    *cap = nc;
    return DF_OK;
}

int df_mesh_build_reserve_vertices(df_mesh_build *b, int64_t nv, df_error *err)
{
    void *p = b->V;
    int rc = grow(&p, &b->cap_v, b->nv + nv, 3 * sizeof(double), err);
    b->V = p;
    return rc;
}

int df_mesh_build_vertex(df_mesh_build *b, long long loc, double x, double y, double z,
                         df_error *err)
{
    char w[160];
    if (b->nv >= b->max_v) {
        df_mesh_build_where(b, loc, w, sizeof w);
        return df_error_set(err, DF_ELIMIT, "%s: more than %d vertices (configured limit)", w,
                            (int)b->max_v);
    }
    if (!isfinite(x) || !isfinite(y) || !isfinite(z)) {
        df_mesh_build_where(b, loc, w, sizeof w);
        return df_error_set(err, DF_EFORMAT, "%s: vertex %lld has a non-finite coordinate (NaN/Inf)",
                            w, (long long)b->nv);
    }
    const double xyz[3] = {x, y, z};
    for (int k = 0; k < 3; k++)
        if (isinf((float)xyz[k])) { /* positions are stored and streamed as float32 */
            df_mesh_build_where(b, loc, w, sizeof w);
            return df_error_set(err, DF_EFORMAT,
                                "%s: vertex %lld coordinate %c is outside the float32 range "
                                "(|value| <= %g)", w, (long long)b->nv, "xyz"[k], (double)FLT_MAX);
        }
    if (b->nv == b->cap_v) {
        int rc = df_mesh_build_reserve_vertices(b, 1, err);
        if (rc)
            return rc;
    }
    double *v = b->V + 3 * b->nv++;
    v[0] = x;
    v[1] = y;
    v[2] = b->vertex_dims == 2 ? 0.0 : z;
    if (b->vertex_dims == 2)
        b->v2d++;
    else
        b->v3d++;
    return DF_OK;
}

int df_mesh_build_index(const df_mesh_build *b, long long loc, int64_t raw, int base,
                        int64_t nv_total, int32_t *out, df_error *err)
{
    int64_t n = nv_total >= 0 ? nv_total : b->nv;
    int64_t i = raw - base;
    if (i < 0 || i >= n) {
        char w[160];
        df_mesh_build_where(b, loc, w, sizeof w);
        return df_error_set(err, DF_EFORMAT, "%s: vertex index %lld out of range (%lld vertices%s)",
                            w, (long long)raw, (long long)n, base ? ", 1-based" : ", 0-based");
    }
    *out = (int32_t)i;
    return DF_OK;
}

static df_mesh_build_list *list_for(df_mesh_build *b, int width)
{
    return width == 2 ? &b->seg : width == 3 ? &b->tri : &b->tet;
}

int df_mesh_build_elem(df_mesh_build *b, long long loc, int width, const int32_t *idx,
                       df_error *err)
{
    df_mesh_build_list *l = list_for(b, width);
    if (l->n >= b->max_e) {
        char w[160];
        df_mesh_build_where(b, loc, w, sizeof w);
        return df_error_set(err, DF_ELIMIT, "%s: more than %d elements (configured limit)", w,
                            (int)b->max_e);
    }
    if (l->n == l->cap) {
        void *p = l->a;
        int rc = grow(&p, &l->cap, l->n + 1, (size_t)width * sizeof(int32_t), err);
        l->a = p;
        if (rc)
            return rc;
    }
    memcpy(l->a + (size_t)width * (size_t)l->n++, idx, (size_t)width * sizeof(int32_t));
    return DF_OK;
}

int df_mesh_build_polygon(df_mesh_build *b, long long loc, const int32_t *idx, int n,
                          df_error *err)
{
    if (n < 3) {
        char w[160];
        df_mesh_build_where(b, loc, w, sizeof w);
        return df_error_set(err, DF_EFORMAT, "%s: face with %d vertices (need at least 3)", w, n);
    }
    for (int i = 1; i + 1 < n; i++) {
        int32_t t[3] = {idx[0], idx[i], idx[i + 1]};
        int rc = df_mesh_build_elem(b, loc, 3, t, err);
        if (rc)
            return rc;
    }
    b->polygons++;
    if (n > 3)
        b->triangulated++;
    return DF_OK;
}

int df_mesh_build_finish(df_mesh_build *b, df_mesh_format fmt, int base, df_mesh *out,
                         df_mesh_report *rep, df_error *err)
{
    df_mesh m;
    df_mesh_init(&m);
    int32_t ignored = b->ignored;
    if (b->tet.n > 0) {
        m.kind = DF_MESH_TET;
        m.ne = (int32_t)b->tet.n;
        m.E = b->tet.a;
        m.nf = (int32_t)b->tri.n;
        m.F = b->tri.n ? b->tri.a : NULL;
        ignored += (int32_t)b->seg.n;
    } else if (b->tri.n > 0) {
        m.kind = DF_MESH_TRIANGLE;
        m.ne = (int32_t)b->tri.n;
        m.E = b->tri.a;
        ignored += (int32_t)b->seg.n;
    } else if (b->seg.n > 0) {
        m.kind = DF_MESH_POLYLINE;
        m.ne = (int32_t)b->seg.n;
        m.E = b->seg.a;
    } else {
        return df_error_set(err, DF_EFORMAT, "%s: no elements (faces, lines or tetrahedra) found",
                            b->name);
    }
    m.nv = (int32_t)b->nv;
    m.V = b->V;
    /* 2D only when the file says so (every vertex with two coordinates) or the caller asks:
     * a flat 3D mesh (every z = 0) deforms in 3D like any other. */
    m.planar = m.kind != DF_MESH_TET && b->v2d > 0 && b->v3d == 0;
    if (b->want_2d) {
        if (m.kind == DF_MESH_TET)
            return df_error_set(err, DF_EFORMAT, "%s: 2D requested, but the mesh has "
                                "tetrahedra", b->name);
        for (int64_t i = 0; i < b->nv; i++)
            if (m.V[3 * i + 2] != 0.0)
                return df_error_set(err, DF_EFORMAT, "%s: 2D requested, but vertex %lld "
                                    "(0-based) has z = %g (a 2D mesh lies in the z = 0 plane)",
                                    b->name, (long long)i, m.V[3 * i + 2]);
        m.planar = 1;
    }
    if (m.planar) /* store +0.0 (not -0.0) so every writer reproduces the same bits */
        for (int64_t i = 0; i < b->nv; i++)
            m.V[3 * i + 2] = 0.0;

    df_mesh_report r;
    int rc = df_mesh_analyze(&m, &r, err);
    if (rc)
        return rc;
    if (!b->allow_inverted && r.inverted_elements > 0)
        return df_error_set(err, DF_EFORMAT,
                            "%s: %d inverted element(s) (first: element %d, 0-based) and "
                            "allow_inverted is off",
                            b->name, (int)r.inverted_elements, (int)r.first_inverted);
    r.format = fmt;
    r.index_base = base;
    r.input_polygons = b->polygons;
    r.polygons_triangulated = b->triangulated;
    r.ignored_elements = ignored;

    /* Hand the arrays over; free the unused lists; shrink. */
    if (m.E != b->seg.a)
        free(b->seg.a);
    if (m.E != b->tri.a && m.F != b->tri.a)
        free(b->tri.a);
    if (m.E != b->tet.a)
        free(b->tet.a);
    b->seg.a = b->tri.a = b->tet.a = NULL;
    b->V = NULL;
    df_mesh_build_free(b);
    if (m.nv > 0) {
        double *v = realloc(m.V, (size_t)m.nv * 3 * sizeof(double));
        if (v)
            m.V = v;
    }
    int es = df_mesh_elem_size(m.kind);
    int32_t *e = realloc(m.E, (size_t)m.ne * (size_t)es * sizeof(int32_t));
    if (e)
        m.E = e;
    *out = m;
    if (rep)
        *rep = r;
    return DF_OK;
}

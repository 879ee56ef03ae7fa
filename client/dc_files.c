/* dc_files.c — index, point, TetGen .node and target files (see dc_files.h). */
#include "client/dc_files.h"

#include "core/mesh/mesh_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Line cursor over a NUL-terminated text: yields the next non-blank, non-comment line. */
typedef struct line_cur {
    const char *p;
    long lineno;
} line_cur;

/* Sets *line to the start of the next content line and *end to its end; returns 0 at EOF. */
static int next_line(line_cur *c, const char **line, const char **end)
{
    while (*c->p) {
        const char *s = c->p;
        const char *e = strchr(s, '\n');
        if (!e)
            e = s + strlen(s);
        c->p = *e ? e + 1 : e;
        c->lineno++;
        const char *q = s;
        while (q < e && (*q == ' ' || *q == '\t' || *q == '\r'))
            q++;
        if (q == e || *q == '#')
            continue;
        *line = q;
        *end = e;
        return 1;
    }
    return 0;
}

/* Parses up to `max` numbers of the line [s, e) into v; returns the count, or -1 on a token that
 * is not a finite number. Stops at a '#' comment. */
static int line_numbers(const char *s, const char *e, double *v, int max)
{
    char buf[512];
    size_t len = (size_t)(e - s);
    if (len >= sizeof buf)
        len = sizeof buf - 1;
    memcpy(buf, s, len);
    buf[len] = '\0';
    char *hash = strchr(buf, '#');
    if (hash)
        *hash = '\0';
    int k = 0;
    char *p = buf;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        if (!*p)
            return k;
        char *q;
        errno = 0;
        double d = strtod(p, &q);
        if (q == p || (*q && *q != ' ' && *q != '\t' && *q != '\r') || !isfinite(d))
            return -1;
        if (k < max)
            v[k] = d;
        k++;
        p = q;
    }
}

int dc_parse_index_text(const char *text, const char *name, int32_t **idx, int32_t *n,
                        df_error *err)
{
    line_cur c = {text, 0};
    const char *s, *e;
    int32_t cnt = 0, cap = 0;
    int32_t *a = NULL;
    while (next_line(&c, &s, &e)) {
        double v[2];
        int k = line_numbers(s, e, v, 2);
        if (k != 1 || v[0] != floor(v[0]) || v[0] < 0 || v[0] >= 2147483647.0) {
            free(a);
            return df_error_set(err, DF_EFORMAT, "%s:%ld: expected one 0-based vertex index", name,
                                c.lineno);
        }
        if (cnt >= DC_FILES_MAX_ROWS) {
            free(a);
            return df_error_set(err, DF_ELIMIT, "%s: more than %d rows", name, DC_FILES_MAX_ROWS);
        }
        if (cnt == cap) {
            cap = cap ? cap * 2 : 64;
            int32_t *b = realloc(a, (size_t)cap * sizeof *a);
            if (!b) {
                free(a);
                return df_error_set(err, DF_ENOMEM, "%s: out of memory", name);
            }
            a = b;
        }
        a[cnt++] = (int32_t)v[0];
    }
    if (cnt == 0)
        return df_error_set(err, DF_EFORMAT, "%s: no indices", name);
    *idx = a;
    *n = cnt;
    return DF_OK;
}

int dc_parse_points_text(const char *text, const char *name, double **xyz, int32_t *n,
                         df_error *err)
{
    line_cur c = {text, 0};
    const char *s, *e;
    int32_t cnt = 0, cap = 0;
    double *a = NULL;
    while (next_line(&c, &s, &e)) {
        double v[4];
        if (line_numbers(s, e, v, 4) != 3) {
            free(a);
            return df_error_set(err, DF_EFORMAT, "%s:%ld: expected three numbers 'x y z'", name,
                                c.lineno);
        }
        if (cnt >= DC_FILES_MAX_ROWS) {
            free(a);
            return df_error_set(err, DF_ELIMIT, "%s: more than %d rows", name, DC_FILES_MAX_ROWS);
        }
        if (cnt == cap) {
            cap = cap ? cap * 2 : 64;
            double *b = realloc(a, (size_t)cap * 3 * sizeof *a);
            if (!b) {
                free(a);
                return df_error_set(err, DF_ENOMEM, "%s: out of memory", name);
            }
            a = b;
        }
        memcpy(a + 3 * (size_t)cnt, v, 3 * sizeof *v);
        cnt++;
    }
    if (cnt == 0)
        return df_error_set(err, DF_EFORMAT, "%s: no points", name);
    *xyz = a;
    *n = cnt;
    return DF_OK;
}

int dc_parse_node_text(const char *text, const char *name, double **xyz, int32_t *n,
                       df_error *err)
{
    return df_mesh_read_tetgen_nodes_memory(text, strlen(text), name, xyz, n, err);
}

int dc_parse_targets_text(const char *text, const char *name, int is_node, const int32_t *handles,
                          int32_t nh, double **targets, df_error *err)
{
    if (nh < 1 || !handles)
        return df_error_set(err, DF_EINVAL, "no handles to take targets for");
    double *p = NULL;
    int32_t np = 0;
    int rc = is_node ? dc_parse_node_text(text, name, &p, &np, err)
                     : dc_parse_points_text(text, name, &p, &np, err);
    if (rc)
        return rc;
    if (!is_node) {
        if (np != nh) {
            free(p);
            return df_error_set(err, DF_EFORMAT, "%s: %d targets for %d handles", name, np, nh);
        }
        *targets = p;
        return DF_OK;
    }
    double *t = malloc((size_t)nh * 3 * sizeof *t);
    if (!t) {
        free(p);
        return df_error_set(err, DF_ENOMEM, "out of memory");
    }
    for (int32_t i = 0; i < nh; i++) {
        if (handles[i] < 0 || handles[i] >= np) {
            free(p);
            free(t);
            return df_error_set(err, DF_EFORMAT, "%s: handle %d (vertex %d) beyond its %d nodes",
                                name, i, handles[i], np);
        }
        memcpy(t + 3 * (size_t)i, p + 3 * (size_t)handles[i], 3 * sizeof *t);
    }
    free(p);
    *targets = t;
    return DF_OK;
}

int dc_read_file(const char *path, char **text, long long *len, df_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return df_error_set(err, DF_EIO, "cannot open %s: %s", path, strerror(errno));
    if (fseeko(f, 0, SEEK_END) != 0) {
        fclose(f);
        return df_error_set(err, DF_EIO, "cannot seek %s: %s", path, strerror(errno));
    }
    long long sz = (long long)ftello(f);
    if (sz < 0 || fseeko(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return df_error_set(err, DF_EIO, "cannot size %s", path);
    }
    if (sz > DC_FILES_MAX_BYTES) {
        fclose(f);
        return df_error_set(err, DF_ELIMIT, "%s: %lld bytes exceeds %lld", path, sz,
                            (long long)DC_FILES_MAX_BYTES);
    }
    char *b = malloc((size_t)sz + 1);
    if (!b) {
        fclose(f);
        return df_error_set(err, DF_ENOMEM, "out of memory reading %s", path);
    }
    size_t got = fread(b, 1, (size_t)sz, f);
    int bad = ferror(f);
    fclose(f);
    if (bad || got != (size_t)sz) {
        free(b);
        return df_error_set(err, DF_EIO, "short read on %s", path);
    }
    b[sz] = '\0';
    *text = b;
    if (len)
        *len = sz;
    return DF_OK;
}

int dc_load_index_file(const char *path, int32_t **idx, int32_t *n, df_error *err)
{
    char *t;
    int rc = dc_read_file(path, &t, NULL, err);
    if (rc)
        return rc;
    rc = dc_parse_index_text(t, path, idx, n, err);
    free(t);
    return rc;
}

int dc_load_points_file(const char *path, double **xyz, int32_t *n, df_error *err)
{
    char *t;
    int rc = dc_read_file(path, &t, NULL, err);
    if (rc)
        return rc;
    rc = dc_parse_points_text(t, path, xyz, n, err);
    free(t);
    return rc;
}

int dc_load_targets(const char *path, const int32_t *handles, int32_t nh, double **targets,
                    df_error *err)
{
    size_t L = strlen(path);
    int is_node = L >= 5 && strcasecmp(path + L - 5, ".node") == 0;
    char *t;
    int rc = dc_read_file(path, &t, NULL, err);
    if (rc)
        return rc;
    rc = dc_parse_targets_text(t, path, is_node, handles, nh, targets, err);
    free(t);
    return rc;
}

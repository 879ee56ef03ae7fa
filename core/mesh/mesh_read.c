/* mesh_read.c — format dispatch for the mesh readers: content sniffing, files, TetGen pairs
 * (see mesh_io.h). */
#include "core/mesh/mesh_io.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <unistd.h>

#include "core/mesh/mesh_readers.h"
#include "core/mesh/mesh_scan.h"

/* Largest file df_mesh_read_file loads (bytes). */
#define DF_MESH_MAX_FILE_BYTES ((size_t)1 << 32)

static df_mesh_format sniff(const char *buf, size_t len)
{
    df_scan s;
    df_scan_init(&s, buf, len, NULL);
    if (len >= 3 && !memcmp(buf, "ply", 3))
        return DF_FMT_PLY;
    const char *t;
    size_t n = df_scan_token(&s, 1, &t);
    if (n >= 3 && n <= 8 && !memcmp(t + n - 3, "OFF", 3))
        return DF_FMT_OFF;
    if (df_scan_tok_eq(t, n, "MeshVersionFormatted") || df_scan_tok_eq(t, n, "Dimension") ||
        df_scan_tok_eq(t, n, "Vertices"))
        return DF_FMT_MEDIT;
    return DF_FMT_OBJ;
}

int df_mesh_read_memory(const void *buf, size_t len, df_mesh_format fmt, const char *name_for_errors,
                        const df_mesh_read_opts *o, df_mesh *out, df_mesh_report *rep,
                        df_error *err)
{
    const char *name = name_for_errors ? name_for_errors : "<memory>";
    if (!out || (!buf && len))
        return df_error_set(err, DF_EINVAL, "%s: NULL buffer or output mesh", name);
    if (fmt == DF_FMT_AUTO)
        fmt = sniff(buf, len);
    switch (fmt) {
    case DF_FMT_OBJ: return df_mesh_read_obj(buf, len, name, o, out, rep, err);
    case DF_FMT_OFF: return df_mesh_read_off(buf, len, name, o, out, rep, err);
    case DF_FMT_PLY:
    case DF_FMT_PLY_BINARY: return df_mesh_read_ply(buf, len, name, o, out, rep, err);
    case DF_FMT_MEDIT: return df_mesh_read_medit(buf, len, name, o, out, rep, err);
    case DF_FMT_TETGEN:
        return df_error_set(err, DF_EUNSUPPORTED,
                            "%s: TetGen needs a .node and an .ele buffer: use "
                            "df_mesh_read_tetgen_memory", name);
    default: break;
    }
    return df_error_set(err, DF_EINVAL, "%s: unknown mesh format %d", name, (int)fmt);
}

/* Loads a whole regular file: *buf malloc'd, *len its size. Devices, pipes and directories are
 * refused (a FIFO or /dev/zero would block or never end). */
static int load(const char *path, char **buf, size_t *len, df_error *err)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return df_error_set(err, DF_EIO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    memset(&st, 0, sizeof st);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return df_error_set(err, DF_EIO, "%s: %s", path,
                            S_ISDIR(st.st_mode) ? "is a directory" : "not a regular file");
    }
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        close(fd);
        return df_error_set(err, DF_ENOMEM, "%s: out of memory", path);
    }
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    int rc = b ? DF_OK : df_error_set(err, DF_ENOMEM, "%s: out of memory", path);
    if (!rc && fseek(f, 0, SEEK_END) == 0) {
        long sz = ftell(f);
        if (sz >= 0 && (size_t)sz >= DF_MESH_MAX_FILE_BYTES)
            rc = df_error_set(err, DF_ELIMIT, "%s: %ld bytes is larger than the %zu byte limit",
                              path, sz, DF_MESH_MAX_FILE_BYTES);
        else if (sz > 0 && (size_t)sz + 1 > cap) {
            char *nb = realloc(b, (size_t)sz + 1);
            if (nb) {
                b = nb;
                cap = (size_t)sz + 1;
            }
        }
        rewind(f);
    }
    while (!rc) {
        if (n == cap) {
            char *nb = n < DF_MESH_MAX_FILE_BYTES ? realloc(b, cap * 2) : NULL;
            if (!nb) {
                rc = df_error_set(err, DF_ENOMEM, "%s: out of memory reading %zu bytes", path, n);
                break;
            }
            b = nb;
            cap *= 2;
        }
        size_t got = fread(b + n, 1, cap - n, f);
        n += got;
        if (got == 0) {
            if (ferror(f))
                rc = df_error_set(err, DF_EIO, "%s: read error after %zu bytes", path, n);
            break;
        }
    }
    fclose(f);
    if (rc) {
        free(b);
        return rc;
    }
    *buf = b;
    *len = n;
    return DF_OK;
}

int df_mesh_tetgen_sibling(const char *path, char *out, size_t n)
{
    const char *dot = path ? strrchr(path, '.') : NULL;
    if (!dot || strchr(dot, '/') || !out)
        return -1;
    const char *ext;
    if (!strcasecmp(dot, ".node"))
        ext = ".ele";
    else if (!strcasecmp(dot, ".ele"))
        ext = ".node";
    else
        return -1;
    int upper = 1; /* an all-upper-case extension (X.NODE) keeps its case: X.ELE */
    for (const char *c = dot + 1; *c; c++)
        upper &= *c >= 'A' && *c <= 'Z';
    size_t stem = (size_t)(dot - path);
    if (stem + strlen(ext) + 1 > n)
        return -1;
    memcpy(out, path, stem);
    for (size_t i = 0; ext[i]; i++)
        out[stem + i] = upper ? (char)(ext[i] >= 'a' ? ext[i] - 32 : ext[i]) : ext[i];
    out[stem + strlen(ext)] = '\0';
    return 0;
}

static int read_tetgen_file(const char *path, const df_mesh_read_opts *o, df_mesh *out,
                            df_mesh_report *rep, df_error *err)
{
    char other[4096], stem[4096];
    if (strlen(path) + 8 > sizeof other || df_mesh_tetgen_sibling(path, other, sizeof other))
        return df_error_set(err, DF_EINVAL, "%s: path too long", path);
    int is_node = !strcasecmp(strrchr(path, '.'), ".node");
    const char *np = is_node ? path : other, *ep = is_node ? other : path;
    const char *base = strrchr(path, '/');
    snprintf(stem, sizeof stem, "%s", base ? base + 1 : path); /* keeps the extension's case */
    char *nb = NULL, *eb = NULL;
    size_t nl = 0, el = 0;
    int rc = load(np, &nb, &nl, err);
    if (!rc)
        rc = load(ep, &eb, &el, err);
    if (!rc)
        rc = df_mesh_read_tetgen_memory(nb, nl, eb, el, stem, o, out, rep, err);
    free(nb);
    free(eb);
    return rc;
}

int df_mesh_read_file(const char *path, const df_mesh_read_opts *o, df_mesh *out,
                      df_mesh_report *rep, df_error *err)
{
    if (!path || !out)
        return df_error_set(err, DF_EINVAL, "df_mesh_read_file: NULL path or output mesh");
    df_mesh_format fmt = df_mesh_format_from_path(path);
    if (fmt == DF_FMT_TETGEN)
        return read_tetgen_file(path, o, out, rep, err);
    char *buf;
    size_t len;
    int rc = load(path, &buf, &len, err);
    if (rc)
        return rc;
    const char *base = strrchr(path, '/');
    rc = df_mesh_read_memory(buf, len, fmt, base ? base + 1 : path, o, out, rep, err);
    free(buf);
    return rc;
}

int df_mesh_read_tetgen_nodes(const char *path, double **V, int32_t *nv, df_error *err)
{
    if (!path || !V || !nv)
        return df_error_set(err, DF_EINVAL, "df_mesh_read_tetgen_nodes: NULL argument");
    char *buf;
    size_t len;
    int rc = load(path, &buf, &len, err);
    if (rc)
        return rc;
    const char *base = strrchr(path, '/');
    rc = df_mesh_read_tetgen_nodes_memory(buf, len, base ? base + 1 : path, V, nv, err);
    free(buf);
    return rc;
}

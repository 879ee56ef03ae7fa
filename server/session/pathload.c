/* pathload.c — checked reads of client-named server-side mesh files (see pathload.h). */
#include "server/session/pathload.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "proto/messages.h"

#define M "load_mesh"

size_t df_pathload_max_bytes(const df_server_config *cfg)
{
    uint64_t cap = cfg ? (uint64_t)cfg->max_upload_mb << 20 : (uint64_t)DF_MAX_MESH_BYTES;
    return (size_t)(cap < (uint64_t)DF_MAX_MESH_BYTES ? cap : (uint64_t)DF_MAX_MESH_BYTES);
}

static int hidden(const char *path, df_error *err)
{
    return df_error_set(err, DF_EIO, "%s: %s: not allowed or not found (config allow_paths)", M,
                        path);
}

/* 1 when descriptor fd is the file at `real` (no component was swapped after realpath). */
static int fd_is(int fd, const char *real)
{
    char link[64], target[PATH_MAX + 1];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    ssize_t n = readlink(link, target, sizeof target - 1);
    if (n < 0)
        return 1; /* no /proc: O_NOFOLLOW on the resolved path is the remaining guard */
    target[n] = '\0';
    return strcmp(target, real) == 0;
}

int df_pathload_read(const df_server_config *cfg, const char *path, size_t max_bytes, char **buf,
                     size_t *len, df_error *err)
{
    if (!cfg || !path || !buf || !len)
        return df_error_set(err, DF_EINVAL, "%s: NULL argument", M);
    if (cfg->n_allow == 0)
        return df_error_set(err, DF_EUNSUPPORTED,
                            "%s: server-side paths are disabled (no allow_paths in the config)", M);
    char *real = realpath(path, NULL);
    if (!real || !df_config_path_allowed(cfg, real)) {
        free(real);
        return hidden(path, err);
    }
    int fd = open(real, O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_CLOEXEC);
    if (fd >= 0 && !fd_is(fd, real)) {
        close(fd);
        fd = -1;
        errno = ENOENT;
    }
    free(real);
    if (fd < 0)
        return hidden(path, err);
    struct stat st;
    memset(&st, 0, sizeof st);
    int rc = DF_OK;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
        rc = df_error_set(err, DF_EIO, "%s: %s: not a regular file (FIFOs, devices and "
                          "directories are not read)", M, path);
    else if ((uint64_t)st.st_size > (uint64_t)max_bytes)
        rc = df_error_set(err, DF_ELIMIT, "%s: %s: %lld bytes is more than the %zu byte limit", M,
                          path, (long long)st.st_size, max_bytes);
    size_t want = rc ? 0 : (size_t)st.st_size, got = 0;
    char *b = rc ? NULL : malloc(want + 1);
    if (!rc && !b)
        rc = df_error_set(err, DF_ENOMEM, "%s: %s: out of memory for %zu bytes", M, path, want);
    while (!rc && got < want) { /* never more than fstat said: a growing file is cut there */
        ssize_t n = read(fd, b + got, want - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            rc = df_error_set(err, DF_EIO, "%s: %s: read error after %zu bytes: %s", M, path, got,
                              strerror(errno));
        else if (n == 0)
            break;
        else
            got += (size_t)n;
    }
    close(fd);
    if (rc) {
        free(b);
        return rc;
    }
    *buf = b;
    *len = got;
    return DF_OK;
}

static const char *base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

static int read_pair(const df_server_config *cfg, const char *path, const df_mesh_read_opts *o,
                     df_mesh *out, df_mesh_report *rep, df_error *err)
{
    const char *dot = strrchr(path, '.');
    char *other = malloc(strlen(path) + 8);
    if (!other)
        return df_error_set(err, DF_ENOMEM, "%s: out of memory", M);
    if (!dot || df_mesh_tetgen_sibling(path, other, strlen(path) + 8) != 0) {
        free(other);
        return df_error_set(err, DF_EFORMAT,
                            "%s: %s: a TetGen load names the .node (or .ele) file of the pair", M,
                            path);
    }
    int is_node = strcasecmp(dot, ".node") == 0;
    const char *np = is_node ? path : other, *ep = is_node ? other : path;
    char *nb = NULL, *eb = NULL;
    size_t nl = 0, el = 0, cap = df_pathload_max_bytes(cfg);
    int rc = df_pathload_read(cfg, np, cap, &nb, &nl, err);
    if (!rc)
        rc = df_pathload_read(cfg, ep, cap - nl, &eb, &el, err);
    if (!rc) {
        const char *b = base_name(path);
        char *stem = strndup(b, (size_t)(strrchr(b, '.') - b));
        rc = stem ? df_mesh_read_tetgen_memory(nb, nl, eb, el, stem, o, out, rep, err)
                  : df_error_set(err, DF_ENOMEM, "%s: out of memory", M);
        free(stem);
    }
    free(nb);
    free(eb);
    free(other);
    return rc;
}

int df_pathload_mesh(const df_server_config *cfg, const char *path, int fmt,
                     int32_t max_vertices, int want_2d, df_mesh *out, df_mesh_report *rep,
                     const df_mesh_progress *progress, df_error *err)
{
    if (!cfg || !path || !out)
        return df_error_set(err, DF_EINVAL, "%s: NULL argument", M);
    if (fmt < DF_FMT_AUTO || fmt > DF_FMT_TETGEN)
        return df_error_set(err, DF_EINVAL, "%s: unknown mesh format %d", M, fmt);
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.max_vertices = max_vertices;
    o.redact_content = 1;
    o.want_2d = want_2d;
    if (progress) {
        o.progress = progress->fn;
        o.progress_user = progress->user;
    }
    df_mesh_format f = fmt ? (df_mesh_format)fmt : df_mesh_format_from_path(path);
    if (f == DF_FMT_AUTO)
        return df_error_set(err, DF_EFORMAT,
                            "%s: %s: mesh format not recognised from the file name; formats: "
                            ".obj, .off, .ply, .mesh (MEDIT), .node + .ele (TetGen)", M, path);
    df_mesh_init(out);
    if (f == DF_FMT_TETGEN)
        return read_pair(cfg, path, &o, out, rep, err);
    char *buf = NULL;
    size_t len = 0;
    int rc = df_pathload_read(cfg, path, df_pathload_max_bytes(cfg), &buf, &len, err);
    if (rc)
        return rc;
    rc = df_mesh_read_memory(buf, len, f, base_name(path), &o, out, rep, err);
    free(buf);
    return rc;
}

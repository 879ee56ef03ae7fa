/* dc_cli.c — table-driven option parser and typed value parsers (see dc_cli.h). */
#include "client/dc_cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/un.h>

int dc_cli_find(const dc_cli_opt *opts, int nopts, const char *name)
{
    for (int i = 0; i < nopts; i++)
        if (strcmp(opts[i].name, name) == 0)
            return i;
    return -1;
}

static int has_help(int argc, char **argv)
{
    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--") == 0)
            return 0;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    }
    return 0;
}

int dc_cli_parse(int argc, char **argv, const dc_cli_opt *opts, int nopts, int max_pos,
                 dc_cli_args *out, df_error *err)
{
    memset(out, 0, sizeof *out);
    if (nopts < 0 || nopts > DC_CLI_MAX_OPTS || max_pos < 0 || max_pos > DC_CLI_MAX_POS)
        return df_error_set(err, DF_EINVAL, "option table too large");
    if (has_help(argc, argv)) {
        out->help = 1;
        return DF_OK;
    }
    int only_pos = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (!only_pos && strcmp(a, "--") == 0) {
            only_pos = 1;
            continue;
        }
        if (only_pos || a[0] != '-' || a[1] == '\0' || (a[1] != '-' && (a[1] == '.' || (a[1] >= '0' && a[1] <= '9')))) {
            if (out->npos >= max_pos)
                return df_error_set(err, DF_EINVAL, "unexpected argument '%s'", a);
            out->pos[out->npos++] = a;
            continue;
        }
        if (a[1] != '-')
            return df_error_set(err, DF_EINVAL, "unknown option '%s' (options are --long)", a);
        const char *name = a + 2;
        const char *eq = strchr(name, '=');
        char nm[64];
        size_t nlen = eq ? (size_t)(eq - name) : strlen(name);
        if (nlen == 0 || nlen >= sizeof nm)
            return df_error_set(err, DF_EINVAL, "unknown option '%s'", a);
        memcpy(nm, name, nlen);
        nm[nlen] = '\0';
        int k = dc_cli_find(opts, nopts, nm);
        if (k < 0)
            return df_error_set(err, DF_EINVAL, "unknown option '--%s'", nm);
        if (out->val[k])
            return df_error_set(err, DF_EINVAL, "option '--%s' given twice", nm);
        if (!opts[k].has_arg) {
            if (eq)
                return df_error_set(err, DF_EINVAL, "option '--%s' takes no value", nm);
            out->val[k] = "";
        } else if (eq) {
            out->val[k] = eq + 1;
        } else {
            if (i + 1 >= argc)
                return df_error_set(err, DF_EINVAL, "option '--%s' needs a value", nm);
            out->val[k] = argv[++i];
        }
    }
    return DF_OK;
}

int dc_cli_double(const char *s, const char *what, int allow_inf, double *out, df_error *err)
{
    if (!s || !*s)
        return df_error_set(err, DF_EINVAL, "%s: empty number", what);
    const char *t = (*s == '+' || *s == '-') ? s + 1 : s;
    if (strcasecmp(t, "inf") == 0 || strcasecmp(t, "infinity") == 0) {
        if (!allow_inf)
            return df_error_set(err, DF_EINVAL, "%s: '%s' must be finite", what, s);
        *out = *s == '-' ? -INFINITY : INFINITY;
        return DF_OK;
    }
    errno = 0;
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end != '\0')
        return df_error_set(err, DF_EINVAL, "%s: '%s' is not a number", what, s);
    if (!isfinite(v) || errno == ERANGE)
        return df_error_set(err, DF_EINVAL, "%s: '%s' must be a finite number", what, s);
    *out = v;
    return DF_OK;
}

int dc_cli_int(const char *s, const char *what, long long lo, long long hi, long long *out,
               df_error *err)
{
    if (!s || !*s)
        return df_error_set(err, DF_EINVAL, "%s: empty integer", what);
    errno = 0;
    char *end = NULL;
    long long v = strtoll(s, &end, 10);
    if (end == s || *end != '\0')
        return df_error_set(err, DF_EINVAL, "%s: '%s' is not an integer", what, s);
    if (errno == ERANGE || v < lo || v > hi)
        return df_error_set(err, DF_EINVAL, "%s: %s out of range %lld..%lld", what, s, lo, hi);
    *out = v;
    return DF_OK;
}

int dc_cli_vec(const char *s, const char *what, int n, double *out, df_error *err)
{
    if (n < 1 || n > 16)
        return df_error_set(err, DF_EINVAL, "%s: bad vector length %d", what, n);
    if (!s)
        return df_error_set(err, DF_EINVAL, "%s: missing value", what);
    double tmp[16];
    int k = 0;
    const char *p = s;
    for (;;) {
        const char *c = strchr(p, ',');
        size_t len = c ? (size_t)(c - p) : strlen(p);
        char tok[64];
        if (len == 0 || len >= sizeof tok)
            return df_error_set(err, DF_EINVAL, "%s: '%s' is not %d comma-separated numbers", what,
                                s, n);
        if (k >= n)
            return df_error_set(err, DF_EINVAL, "%s: '%s' has more than %d numbers", what, s, n);
        memcpy(tok, p, len);
        tok[len] = '\0';
        int rc = dc_cli_double(tok, what, 0, &tmp[k], err);
        if (rc)
            return rc;
        k++;
        if (!c)
            break;
        p = c + 1;
    }
    if (k != n)
        return df_error_set(err, DF_EINVAL, "%s: '%s' has %d numbers, expected %d", what, s, k, n);
    memcpy(out, tmp, (size_t)n * sizeof *out);
    return DF_OK;
}

int dc_cli_choice(const char *s, const char *what, const char *const *choices, df_error *err)
{
    char list[256];
    size_t used = 0;
    list[0] = '\0';
    for (int i = 0; choices[i]; i++) {
        if (s && strcmp(s, choices[i]) == 0)
            return i;
        int w = snprintf(list + used, sizeof list - used, "%s%s", i ? "|" : "", choices[i]);
        if (w > 0 && (size_t)w < sizeof list - used)
            used += (size_t)w;
    }
    return df_error_set(err, DF_EINVAL, "%s: '%s' is not one of %s", what, s ? s : "", list);
}

int dc_cli_hostport(const char *s, char *host, int host_cap, int *port, df_error *err)
{
    if (!s || !*s)
        return df_error_set(err, DF_EINVAL, "--tcp: empty HOST:PORT");
    const char *hs = s, *he, *colon;
    if (s[0] == '[') {
        hs = s + 1;
        he = strchr(hs, ']');
        if (!he || he[1] != ':')
            return df_error_set(err, DF_EINVAL, "--tcp: '%s' is not [HOST]:PORT", s);
        colon = he + 1;
    } else {
        colon = strrchr(s, ':');
        if (!colon)
            return df_error_set(err, DF_EINVAL, "--tcp: '%s' is not HOST:PORT", s);
        he = colon;
    }
    size_t hl = (size_t)(he - hs);
    if (hl == 0)
        return df_error_set(err, DF_EINVAL, "--tcp: '%s' has no host (HOST:PORT, e.g. "
                            "127.0.0.1:7878)", s);
    if ((int)hl >= host_cap)
        return df_error_set(err, DF_EINVAL, "--tcp: the host in '%s' is longer than %d bytes", s,
                            host_cap - 1);
    long long p;
    int rc = dc_cli_int(colon + 1, "--tcp port", 1, 65535, &p, err);
    if (rc)
        return rc;
    memcpy(host, hs, hl);
    host[hl] = '\0';
    *port = (int)p;
    return DF_OK;
}

int dc_cli_socket_path(const char *s, df_error *err)
{
    struct sockaddr_un sa;
    if (!s || !*s)
        return df_error_set(err, DF_EINVAL, "--socket: empty path");
    size_t n = strlen(s);
    if (n >= sizeof sa.sun_path)
        return df_error_set(err, DF_EINVAL, "--socket: path of %zu bytes is too long (at most "
                            "%zu)", n, sizeof sa.sun_path - 1);
    return DF_OK;
}

int dc_cli_default_socket(char *buf, int cap, df_error *err)
{
    const char *env = getenv("DEFORMD_SOCKET");
    const char *xdg = getenv("XDG_RUNTIME_DIR");
    int n;
    if (env && *env)
        n = snprintf(buf, (size_t)cap, "%s", env);
    else if (xdg && *xdg)
        n = snprintf(buf, (size_t)cap, "%s/deformd.sock", xdg);
    else
        n = snprintf(buf, (size_t)cap, "/run/deformd/deformd.sock");
    if (n < 0 || n >= cap)
        return df_error_set(err, DF_ELIMIT, "default socket path does not fit in %d bytes", cap);
    return DF_OK;
}

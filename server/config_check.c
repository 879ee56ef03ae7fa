/* config_check.c — deformd --check-config (see config_check.h). */
#include "server/config_check.h"

#include <ctype.h>
#include <errno.h>
#include <grp.h>
#include <netdb.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/hid/hid_source.h"
#include "server/net/listener.h"
#include "server/net/tls.h"

typedef struct check_out {
    char *buf;
    size_t cap, len;
    int n;
} check_out;

/* The line (1-based) of cfg->config_path that sets `key` last (and whose value holds `needle`
 * when not NULL), 0 when none (the setting came from the command line or the default). */
static int key_line(const df_server_config *cfg, const char *key, const char *needle)
{
    if (!cfg->config_path[0]) return 0;
    FILE *f = fopen(cfg->config_path, "r");
    if (!f) return 0;
    char line[DF_CONFIG_LINE_MAX];
    int n = 0, found = 0;
    size_t kl = strlen(key);
    while (fgets(line, sizeof line, f)) {
        n++;
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        char *s = line;
        while (isspace((unsigned char)*s)) s++;
        if (strncmp(s, key, kl) != 0) continue;
        char *e = s + kl;
        while (*e == ' ' || *e == '\t') e++;
        if (*e != '=') continue;
        if (!needle || strstr(e + 1, needle)) found = n;
    }
    fclose(f);
    return found;
}

static void problem(check_out *o, const df_server_config *cfg, const char *key,
                    const char *needle, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line = key_line(cfg, key, needle);
    int w;
    if (line)
        w = snprintf(o->buf + o->len, o->cap - o->len, "%s:%d: %s\n", cfg->config_path, line, msg);
    else
        w = snprintf(o->buf + o->len, o->cap - o->len, "command line: %s\n", msg);
    if (w > 0) o->len += (size_t)w < o->cap - o->len ? (size_t)w : o->cap - o->len - 1;
    o->n++;
}

static void check_socket(check_out *o, const df_server_config *cfg)
{
    const char *path = cfg->socket_path;
    if (getenv("LISTEN_FDS")) return;
    if (!path[0] && !cfg->tcp_host[0]) {
        problem(o, cfg, "socket", path, "no listener: socket = none and no tcp");
        return;
    }
    if (!path[0]) return;
    char dir[DF_CONFIG_SOCKET_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == dir) dir[1] = '\0';
    else *slash = '\0';
    struct stat st;
    if (stat(dir, &st) != 0)
        problem(o, cfg, "socket", path, "socket %s: directory %s: %s", path, dir,
                strerror(errno));
    else if (!S_ISDIR(st.st_mode))
        problem(o, cfg, "socket", path, "socket %s: %s is not a directory", path, dir);
    else if (access(dir, W_OK | X_OK) != 0)
        problem(o, cfg, "socket", path, "socket %s: cannot create it in %s: %s", path, dir,
                strerror(errno));
    if (lstat(path, &st) == 0 && !S_ISSOCK(st.st_mode))
        problem(o, cfg, "socket", path, "socket %s: exists and is not a socket", path);
}

static void check_group(check_out *o, const df_server_config *cfg)
{
    const char *g = cfg->socket_group;
    if (!g[0]) return;
    char buf[4096];
    struct group gr, *res = NULL;
    if (getgrnam_r(g, &gr, buf, sizeof buf, &res) == 0 && res) return;
    if (strspn(g, "0123456789") == strlen(g)) return; /* a number: used as is */
    problem(o, cfg, "socket_group", g, "socket_group: no group '%s'", g);
}

static void check_tcp(check_out *o, const df_server_config *cfg)
{
    if (!cfg->tcp_host[0]) return;
    char port[16];
    snprintf(port, sizeof port, "%d", cfg->tcp_port);
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE;
    const char *host = strcmp(cfg->tcp_host, "*") == 0 ? NULL : cfg->tcp_host;
    int rc = getaddrinfo(host, port, &hints, &res);
    if (rc != 0) {
        problem(o, cfg, "tcp", cfg->tcp_host, "tcp %s:%s: %s", cfg->tcp_host, port,
                gai_strerror(rc));
        return;
    }
    if (!df_listener_is_loopback(res->ai_addr) && !cfg->tcp_insecure &&
        !(cfg->access.key_file[0] && cfg->access.tls_cert[0]))
        problem(o, cfg, "tcp", cfg->tcp_host, "tcp %s:%s: a non-loopback address needs "
                "key_file (--key-file) and tls_cert/tls_key (--tls-cert, --tls-key)",
                cfg->tcp_host, port);
    freeaddrinfo(res);
}

/* tls_cert / tls_key load as start-up would load them (both set, readable, key private and
 * matching the certificate). */
static void check_tls(check_out *o, const df_server_config *cfg)
{
    const df_access_config *a = &cfg->access;
    if (!a->tls_cert[0] && !a->tls_key[0]) return;
    df_tls_server *s = NULL;
    df_error e;
    if (df_tls_server_new(a->tls_cert, a->tls_key, &s, &e) != DF_OK)
        problem(o, cfg, a->tls_key[0] ? "tls_key" : "tls_cert",
                a->tls_key[0] ? a->tls_key : a->tls_cert, "%s", e.msg);
    df_tls_server_free(s);
}

static void check_allow(check_out *o, const df_server_config *cfg)
{
    for (int i = 0; i < cfg->n_allow; i++) {
        const char *a = cfg->allow_paths[i];
        struct stat st;
        if (stat(a, &st) != 0)
            problem(o, cfg, "allow_paths", a, "allow_paths: %s: %s", a, strerror(errno));
        else if (!S_ISDIR(st.st_mode))
            problem(o, cfg, "allow_paths", a, "allow_paths: %s: not a directory", a);
    }
}

static void check_replay(check_out *o, const df_server_config *cfg)
{
    for (int i = 0; i < cfg->n_hid_replay; i++) {
        const char *file = cfg->hid_replay[i];
        df_hid_backend *b = NULL;
        df_error err = {0, ""};
        if (df_hid_backend_replay(&file, 1, NULL, &b, &err) != DF_OK)
            problem(o, cfg, "hid_replay", file, "hid_replay: %s", err.msg);
        else
            df_hid_backend_destroy(b);
    }
}

/* cluster mode (cluster/cluster.h): a local store, and an address to advertise. Redis itself is
 * not contacted here (start-up refuses when it does not answer). */
static void check_cluster(check_out *o, const df_server_config *cfg)
{
    if (!cfg->cluster[0]) return;
    if (strcmp(cfg->store_path, "none") == 0)
        problem(o, cfg, "cluster", NULL, "cluster: needs a local store (store = PATH, not none)");
    if (!cfg->advertise[0] && !cfg->tcp_host[0])
        problem(o, cfg, "cluster", NULL, "cluster: needs advertise = HOST:PORT or a tcp listener "
                "(the address other daemons redirect clients to)");
}

int df_config_check(const df_server_config *cfg, char *out, size_t cap)
{
    char dummy[1];
    check_out o = {out && cap ? out : dummy, out && cap ? cap : 1, 0, 0};
    o.buf[0] = '\0';
    check_socket(&o, cfg);
    check_group(&o, cfg);
    check_tcp(&o, cfg);
    check_tls(&o, cfg);
    check_allow(&o, cfg);
    check_replay(&o, cfg);
    check_cluster(&o, cfg);
    return o.n;
}

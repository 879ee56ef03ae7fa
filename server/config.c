/* config.c — defaults, config file and command line of deformd (see config.h). */
#include "server/config.h"

#include <ctype.h>
#include <stddef.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "proto/shm_ring.h"
#include "server/cluster/slot.h"
#include "server/log.h"
#include "server/session/membudget.h"

void df_config_defaults(df_server_config *cfg, const char *xdg_runtime_dir)
{
    memset(cfg, 0, sizeof *cfg);
    if (xdg_runtime_dir && xdg_runtime_dir[0] &&
        strlen(xdg_runtime_dir) + sizeof "/deformd.sock" <= DF_CONFIG_SOCKET_MAX)
        snprintf(cfg->socket_path, sizeof cfg->socket_path, "%s/deformd.sock", xdg_runtime_dir);
    else
        snprintf(cfg->socket_path, sizeof cfg->socket_path, "/run/deformd/deformd.sock");
    cfg->max_clients = DF_CONFIG_DEFAULT_MAX_CLIENTS;
    cfg->output_queue_limit = DF_CONFIG_DEFAULT_QUEUE_LIMIT;
    cfg->shm_ring_bytes = DF_CONFIG_DEFAULT_SHM_RING;
    cfg->cache_memory_mb = DF_CONFIG_DEFAULT_CACHE_MB;
    cfg->log_level = DF_LOG_INFO;
    cfg->max_mesh_vertices = DF_CONFIG_DEFAULT_MAX_VERTICES;
    cfg->max_sessions = DF_CONFIG_DEFAULT_MAX_SESSIONS;
    cfg->threads = DF_CONFIG_DEFAULT_THREADS;
    cfg->spin_us = DF_CONFIG_DEFAULT_SPIN_US;
    cfg->inline_us = DF_CONFIG_DEFAULT_INLINE_US;
    cfg->admm_active = 0;
    cfg->cursor_hz = DF_CONFIG_DEFAULT_CURSOR_HZ;
    cfg->shm_total_bytes = DF_CONFIG_DEFAULT_SHM_TOTAL;
    cfg->max_upload_mb = DF_CONFIG_DEFAULT_MAX_UPLOAD_MB;
    cfg->uploads_max_mb = DF_CONFIG_DEFAULT_UPLOADS_MB;
    uint64_t ram_mb = df_mem_physical_bytes() >> 20;
    uint64_t hist = ram_mb / DF_CONFIG_HISTORY_RAM_DIVISOR;
    if (hist < DF_CONFIG_HISTORY_MIN_DEFAULT_MB) hist = DF_CONFIG_HISTORY_MIN_DEFAULT_MB;
    if (hist > DF_CONFIG_HISTORY_MAX_DEFAULT_MB) hist = DF_CONFIG_HISTORY_MAX_DEFAULT_MB;
    cfg->history_max_mb = (int)hist;
    cfg->resync_ring_mb = DF_CONFIG_DEFAULT_RESYNC_RING_MB;
    cfg->history_replay_ms = DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS;
    uint64_t mem = ram_mb ? ram_mb / DF_CONFIG_MEMORY_RAM_DIVISOR : DF_CONFIG_MEMORY_UNKNOWN_RAM_MB;
    if (mem < DF_CONFIG_MEMORY_MIN_DEFAULT_MB) mem = DF_CONFIG_MEMORY_MIN_DEFAULT_MB;
    if (mem > DF_CONFIG_MAX_MEMORY_MB) mem = DF_CONFIG_MAX_MEMORY_MB;
    cfg->memory_max_mb = (int)mem;
    cfg->socket_mode = DF_CONFIG_DEFAULT_SOCKET_MODE;
    cfg->handshake_timeout_s = DF_CONFIG_DEFAULT_HANDSHAKE_TIMEOUT_S;
    cfg->idle_timeout_s = DF_CONFIG_DEFAULT_IDLE_TIMEOUT_S;
    cfg->hid_on = 1;
    cfg->hid_replay_speed = 1.0;
    cfg->hid_enumerate_s = DF_CONFIG_DEFAULT_HID_ENUMERATE_S;
    cfg->cluster_lease_ms = 3000;
    df_access_config_defaults(&cfg->access);
}

/* hid_replay: a comma-separated list of files, appended (each must be readable now). */
static int add_hid_replay(df_server_config *cfg, const char *value, df_error *err)
{
    int n = cfg->n_hid_replay;
    char tmp[DF_CONFIG_MAX_HID_REPLAY][DF_CONFIG_PATH_MAX];
    const char *p = value;
    while (*p) {
        size_t l = strcspn(p, ",");
        while (l && isspace((unsigned char)*p)) p++, l--;
        size_t e = l;
        while (e && isspace((unsigned char)p[e - 1])) e--;
        if (e) {
            if (n >= DF_CONFIG_MAX_HID_REPLAY)
                return df_error_set(err, DF_EINVAL, "hid_replay: more than %d files",
                                    DF_CONFIG_MAX_HID_REPLAY);
            if (e >= DF_CONFIG_PATH_MAX)
                return df_error_set(err, DF_EINVAL, "hid_replay: path longer than %d bytes",
                                    DF_CONFIG_PATH_MAX - 1);
            memcpy(tmp[n - cfg->n_hid_replay], p, e);
            tmp[n - cfg->n_hid_replay][e] = '\0';
            if (access(tmp[n - cfg->n_hid_replay], R_OK) != 0)
                return df_error_set(err, DF_EINVAL, "hid_replay: cannot read '%s': %s",
                                    tmp[n - cfg->n_hid_replay], strerror(errno));
            n++;
        }
        p += l;
        if (*p == ',') p++;
    }
    if (n == cfg->n_hid_replay)
        return df_error_set(err, DF_EINVAL, "hid_replay: no file given");
    for (int i = cfg->n_hid_replay; i < n; i++)
        strcpy(cfg->hid_replay[i], tmp[i - cfg->n_hid_replay]);
    cfg->n_hid_replay = n;
    return DF_OK;
}

/* Parses a non-negative integer with an optional k/m/g (binary) suffix, <= max. */
static int parse_size(const char *s, unsigned long long max, unsigned long long *out)
{
    if (!s || !isdigit((unsigned char)s[0])) return DF_EINVAL;
    errno = 0;
    char *end = NULL;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno) return DF_EINVAL;
    unsigned shift = 0;
    if (*end == 'k' || *end == 'K') shift = 10, end++;
    else if (*end == 'm' || *end == 'M') shift = 20, end++;
    else if (*end == 'g' || *end == 'G') shift = 30, end++;
    if (*end == 'b' || *end == 'B') end++;
    if (*end != '\0') return DF_EINVAL;
    if (shift && v > (max >> shift)) return DF_EINVAL;
    v <<= shift;
    if (v > max) return DF_EINVAL;
    *out = v;
    return DF_OK;
}

static int set_tcp(df_server_config *cfg, const char *value, df_error *err)
{
    if (value[0] == '\0' || strcmp(value, "none") == 0 || strcmp(value, "off") == 0) {
        cfg->tcp_host[0] = '\0';
        cfg->tcp_port = 0;
        return DF_OK;
    }
    const char *colon = strrchr(value, ':');
    if (!colon || colon == value)
        return df_error_set(err, DF_EINVAL, "tcp: expected HOST:PORT, got '%s'", value);
    size_t hl = (size_t)(colon - value);
    const char *h = value;
    if (hl >= 2 && h[0] == '[' && h[hl - 1] == ']') h++, hl -= 2; /* [::1]:port */
    if (hl == 0 || hl >= sizeof cfg->tcp_host)
        return df_error_set(err, DF_EINVAL, "tcp: bad host in '%s'", value);
    unsigned long long port;
    if (parse_size(colon + 1, 65535, &port) != DF_OK || strpbrk(colon + 1, "kKmMgGbB"))
        return df_error_set(err, DF_EINVAL, "tcp: bad port in '%s' (0..65535)", value);
    memcpy(cfg->tcp_host, h, hl);
    cfg->tcp_host[hl] = '\0';
    cfg->tcp_port = (int)port;
    return DF_OK;
}

static int add_allow(df_server_config *cfg, const char *value, df_error *err)
{
    char item[DF_CONFIG_PATH_MAX];
    const char *p = value;
    int n = cfg->n_allow;
    char tmp[DF_CONFIG_MAX_ALLOW][DF_CONFIG_PATH_MAX];
    while (*p) {
        size_t l = strcspn(p, ":,");
        while (l && isspace((unsigned char)*p)) p++, l--;
        while (l && isspace((unsigned char)p[l - 1])) l--;
        if (l) {
            if (l >= sizeof item)
                return df_error_set(err, DF_EINVAL, "allow_paths: entry too long");
            memcpy(item, p, l);
            item[l] = '\0';
            if (item[0] != '/')
                return df_error_set(err, DF_EINVAL, "allow_paths: '%s' is not absolute", item);
            char *real = realpath(item, NULL);
            const char *use = real ? real : item;
            size_t ul = strlen(use);
            while (ul > 1 && use[ul - 1] == '/') ul--;
            if (n >= DF_CONFIG_MAX_ALLOW) {
                free(real);
                return df_error_set(err, DF_ELIMIT, "allow_paths: more than %d entries",
                                    DF_CONFIG_MAX_ALLOW);
            }
            memcpy(tmp[n - cfg->n_allow], use, ul);
            tmp[n - cfg->n_allow][ul] = '\0';
            n++;
            free(real);
        }
        p += strcspn(p, ":,");
        if (*p) p++;
    }
    for (int i = cfg->n_allow; i < n; i++) strcpy(cfg->allow_paths[i], tmp[i - cfg->n_allow]);
    cfg->n_allow = n;
    return DF_OK;
}

/* The plain integer settings (an `int` field each): key, field, accepted range. */
typedef struct int_key {
    const char *key;
    size_t offset;
    int min, max;
} int_key;

static const int_key k_int_keys[] = {
    {"max_clients", offsetof(df_server_config, max_clients), 1, DF_CONFIG_MAX_CLIENTS_LIMIT},
    {"max_sessions", offsetof(df_server_config, max_sessions), 1, 1 << 20},
    {"threads", offsetof(df_server_config, threads), 1, DF_CONFIG_MAX_THREADS},
    {"spin_us", offsetof(df_server_config, spin_us), 0, DF_CONFIG_MAX_SPIN_US},
    {"inline_us", offsetof(df_server_config, inline_us), 0, DF_CONFIG_MAX_INLINE_US},
    {"admm_active", offsetof(df_server_config, admm_active), 0, 2},
    {"cursor_hz", offsetof(df_server_config, cursor_hz), 0, DF_CONFIG_MAX_CURSOR_HZ},
    {"max_upload_mb", offsetof(df_server_config, max_upload_mb), 1,
     DF_CONFIG_DEFAULT_MAX_UPLOAD_MB},
    {"uploads_max_mb", offsetof(df_server_config, uploads_max_mb), 1, DF_CONFIG_MAX_UPLOADS_MB},
    {"history_max_mb", offsetof(df_server_config, history_max_mb), 0, DF_CONFIG_MAX_HISTORY_MB},
    {"resync_ring_mb", offsetof(df_server_config, resync_ring_mb), 0,
     DF_CONFIG_MAX_RESYNC_RING_MB},
    {"history_replay_ms", offsetof(df_server_config, history_replay_ms), 0,
     DF_CONFIG_MAX_HISTORY_REPLAY_MS},
    {"memory_max_mb", offsetof(df_server_config, memory_max_mb), DF_CONFIG_MIN_MEMORY_MB,
     DF_CONFIG_MAX_MEMORY_MB},
    {"handshake_timeout_s", offsetof(df_server_config, handshake_timeout_s), 0,
     DF_CONFIG_MAX_TIMEOUT_S},
    {"idle_timeout_s", offsetof(df_server_config, idle_timeout_s), 0, DF_CONFIG_MAX_TIMEOUT_S},
    {"hid_enumerate_s", offsetof(df_server_config, hid_enumerate_s), 0,
     DF_CONFIG_MAX_HID_ENUMERATE_S},
    {"store_max_mb", offsetof(df_server_config, store_max_mb), 0, 1 << 30},
    {"cluster_lease_ms", offsetof(df_server_config, cluster_lease_ms), 300, 600000},
    {"stream_coalesce_start", offsetof(df_server_config, stream_coalesce_start), 0, 1 << 30},
    {"stream_coalesce_resume", offsetof(df_server_config, stream_coalesce_resume), 0, 1 << 30},
};

/* socket_mode: octal permission bits, 0..0777, with or without a leading 0. */
static int set_socket_mode(df_server_config *cfg, const char *value, df_error *err)
{
    char *end = NULL;
    errno = 0;
    long v = value[0] >= '0' && value[0] <= '7' ? strtol(value, &end, 8) : -1;
    if (errno || v < 0 || v > 0777 || !end || *end)
        return df_error_set(err, DF_EINVAL, "socket_mode: '%s' is not an octal mode 0..0777",
                            value);
    cfg->socket_mode = (int)v;
    return DF_OK;
}

int df_config_set(df_server_config *cfg, const char *key, const char *value, df_error *err)
{
    unsigned long long v;
    if (!cfg || !key || !value) return df_error_set(err, DF_EINVAL, "config: NULL argument");
    if (strncmp(key, "hid.", 4) == 0) return df_hid_config_set(&cfg->hid, key, value, err);
    if (df_access_config_has(key)) return df_access_config_set(&cfg->access, key, value, err);
    for (size_t i = 0; i < sizeof k_int_keys / sizeof k_int_keys[0]; i++) {
        const int_key *ik = &k_int_keys[i];
        if (strcmp(key, ik->key) != 0) continue;
        if (parse_size(value, (unsigned long long)ik->max, &v) || v < (unsigned long long)ik->min)
            return df_error_set(err, DF_EINVAL, "%s: '%s' not in %d..%d", key, value, ik->min,
                                ik->max);
        *(int *)((char *)cfg + ik->offset) = (int)v;
        return DF_OK;
    }
    if (strcmp(key, "socket") == 0) {
        if (strcmp(value, "none") == 0 || value[0] == '\0') {
            cfg->socket_path[0] = '\0';
            return DF_OK;
        }
        if (strlen(value) >= sizeof cfg->socket_path)
            return df_error_set(err, DF_EINVAL, "socket: path longer than %d bytes",
                                DF_CONFIG_SOCKET_MAX - 1);
        strcpy(cfg->socket_path, value);
        return DF_OK;
    }
    if (strcmp(key, "tcp") == 0) return set_tcp(cfg, value, err);
    if (strcmp(key, "store") == 0) {
        if (!value[0] || strlen(value) >= sizeof cfg->store_path)
            return df_error_set(err, DF_EINVAL, "store: '%s' is not a path (1..%d bytes) or none",
                                value, DF_CONFIG_PATH_MAX - 1);
        strcpy(cfg->store_path, value);
        return DF_OK;
    }
    if (strcmp(key, "cluster") == 0) {
        df_redis_node_addr seeds[DF_REDIS_SEEDS_MAX];
        size_t n;
        if (strlen(value) >= sizeof cfg->cluster)
            return df_error_set(err, DF_EINVAL, "cluster: longer than %d bytes",
                                DF_CONFIG_PATH_MAX - 1);
        if (value[0]) {
            int rc = df_slot_parse_seeds(value, seeds, DF_REDIS_SEEDS_MAX, &n, err);
            if (rc != DF_OK) return rc;
        }
        strcpy(cfg->cluster, value);
        return DF_OK;
    }
    if (strcmp(key, "advertise") == 0) {
        const char *colon = strrchr(value, ':');
        if (value[0] && (!colon || colon == value || !colon[1] || strlen(value) > 255))
            return df_error_set(err, DF_EINVAL, "advertise: '%s' is not HOST:PORT (at most 255 bytes)", value);
        strcpy(cfg->advertise, value);
        return DF_OK;
    }
    if (strcmp(key, "durability") == 0) {
        static const char *const names[] = {"full", "normal", "off"}; /* DF_DURABILITY_* */
        for (int i = 0; i < 3; i++)
            if (strcmp(value, names[i]) == 0) return cfg->durability = i, DF_OK;
        return df_error_set(err, DF_EINVAL, "durability: '%s' is not full|normal|off", value);
    }
    if (strcmp(key, "tcp_insecure") == 0) {
        if (df_hid_config_bool(value, &cfg->tcp_insecure) != DF_OK)
            return df_error_set(err, DF_EINVAL, "tcp_insecure: '%s' is not yes or no", value);
        return DF_OK;
    }
    if (strcmp(key, "socket_mode") == 0) return set_socket_mode(cfg, value, err);
    if (strcmp(key, "socket_group") == 0) {
        if (strlen(value) >= sizeof cfg->socket_group || strpbrk(value, " \t:/"))
            return df_error_set(err, DF_EINVAL, "socket_group: '%s' is not a group name or id",
                                value);
        strcpy(cfg->socket_group, value);
        return DF_OK;
    }
    if (strcmp(key, "allow_paths") == 0) return add_allow(cfg, value, err);
    if (strcmp(key, "hid") == 0) {
        if (df_hid_config_bool(value, &cfg->hid_on) != DF_OK)
            return df_error_set(err, DF_EINVAL, "hid: '%s' is not on or off", value);
        return DF_OK;
    }
    if (strcmp(key, "hid_replay") == 0) return add_hid_replay(cfg, value, err);
    if (strcmp(key, "hid_replay_end") == 0) {
        static const char *const names[] = {"unplug", "loop", "hold"}; /* DF_HID_REPLAY_END_* */
        for (int i = 0; i < 3; i++)
            if (strcmp(value, names[i]) == 0) return cfg->hid_replay_end = i, DF_OK;
        return df_error_set(err, DF_EINVAL, "hid_replay_end: '%s' is not unplug|hold|loop",
                            value);
    }
    if (strcmp(key, "hid_replay_speed") == 0) {
        char *end = NULL;
        errno = 0;
        double speed = strtod(value, &end);
        if (errno || !end || end == value || *end || !(speed >= 0 && speed <= 1e6))
            return df_error_set(err, DF_EINVAL, "hid_replay_speed: '%s' is not in 0..1e6 "
                                "(0 = at once)", value);
        cfg->hid_replay_speed = speed;
        return DF_OK;
    }

    if (strcmp(key, "log_level") == 0) {
        int l;
        if (df_log_parse_level(value, &l) != DF_OK)
            return df_error_set(err, DF_EINVAL, "log_level: '%s' is not error|warn|info|debug",
                                value);
        cfg->log_level = l;
        return DF_OK;
    }
    if (strcmp(key, "output_queue_limit") == 0) {
        if (parse_size(value, (unsigned long long)1 << 40, &v) || v < 4096)
            return df_error_set(err, DF_EINVAL, "output_queue_limit: '%s' not in 4096..1T",
                                value);
        cfg->output_queue_limit = (size_t)v;
        return DF_OK;
    }
    if (strcmp(key, "shm_ring_bytes") == 0) {
        if (parse_size(value, DF_SHM_MAX_CAPACITY, &v) || (v && v < DF_CONFIG_MIN_SHM_RING))
            return df_error_set(err, DF_EINVAL, "shm_ring_bytes: '%s' is not 0 or 64k..4g",
                                value);
        cfg->shm_ring_bytes = v;
        return DF_OK;
    }
    if (strcmp(key, "shm_total_bytes") == 0) {
        if (parse_size(value, DF_CONFIG_MAX_SHM_TOTAL, &v) || v < DF_CONFIG_MIN_SHM_RING)
            return df_error_set(err, DF_EINVAL, "shm_total_bytes: '%s' is not in 64k..1t", value);
        cfg->shm_total_bytes = v;
        return DF_OK;
    }
    if (strcmp(key, "cache_memory_mb") == 0) {
        if (parse_size(value, (unsigned long long)1 << 30, &v))
            return df_error_set(err, DF_EINVAL, "cache_memory_mb: '%s' is not a size", value);
        cfg->cache_memory_mb = (size_t)v;
        return DF_OK;
    }
    if (strcmp(key, "max_mesh_vertices") == 0) {
        if (parse_size(value, INT32_MAX / 3, &v) || v < 1)
            return df_error_set(err, DF_EINVAL, "max_mesh_vertices: '%s' not in 1..%d", value,
                                INT32_MAX / 3);
        cfg->max_mesh_vertices = (int32_t)v;
        return DF_OK;
    }
    return df_error_set(err, DF_EINVAL, "unknown config key '%s'", key);
}

int df_config_parse(df_server_config *cfg, const char *text, size_t len, const char *name,
                    df_error *err)
{
    if (!cfg || (!text && len)) return df_error_set(err, DF_EINVAL, "config: NULL argument");
    if (!name) name = "config";
    df_server_config *tmp = malloc(sizeof *tmp);
    char *line = malloc(DF_CONFIG_LINE_MAX);
    if (!tmp || !line) {
        free(tmp);
        free(line);
        return df_error_set(err, DF_ENOMEM, "config: out of memory");
    }
    *tmp = *cfg;
    /* hid.* cross-key checks (nu_min <= nu_max, ...) apply to the whole file (a file may pass
     * through an inconsistent state, e.g. led_min_radius before led_max_radius); an error names
     * the line of the hid key from which the keys stay inconsistent to the end. */
    int rc = DF_OK, lineno = 0, hid_bad_line = 0;
    size_t pos = 0;
    while (pos < len && rc == DF_OK) {
        size_t end = pos;
        while (end < len && text[end] != '\n') end++;
        lineno++;
        size_t l = end - pos;
        if (l >= DF_CONFIG_LINE_MAX) {
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: line longer than %d bytes", name, lineno,
                              DF_CONFIG_LINE_MAX - 1);
            break;
        }
        memcpy(line, text + pos, l);
        line[l] = '\0';
        pos = end + 1;
        if (memchr(line, '\0', l)) {
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: NUL byte", name, lineno);
            break;
        }
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        char *s = line;
        while (isspace((unsigned char)*s)) s++;
        char *e = s + strlen(s);
        while (e > s && isspace((unsigned char)e[-1])) *--e = '\0';
        if (*s == '\0') continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: expected 'key = value'", name, lineno);
            break;
        }
        char *k = s, *ke = eq;
        while (ke > k && isspace((unsigned char)ke[-1])) ke--;
        *ke = '\0';
        char *val = eq + 1;
        while (isspace((unsigned char)*val)) val++;
        if (*k == '\0') {
            rc = df_error_set(err, DF_EFORMAT, "%s:%d: empty key", name, lineno);
            break;
        }
        df_error e2;
        rc = df_config_set(tmp, k, val, &e2);
        if (rc != DF_OK) df_error_set(err, rc, "%s:%d: %s", name, lineno, e2.msg);
        else if (strncmp(k, "hid.", 4) == 0)
            hid_bad_line = df_hid_config_check(&tmp->hid, &e2) != DF_OK
                               ? (hid_bad_line ? hid_bad_line : lineno) : 0;
    }
    if (rc == DF_OK) {
        df_error e2;
        rc = df_hid_config_check(&tmp->hid, &e2);
        if (rc != DF_OK && hid_bad_line)
            df_error_set(err, rc, "%s:%d: %s", name, hid_bad_line, e2.msg);
        else if (rc != DF_OK)
            df_error_set(err, rc, "%s: %s", name, e2.msg);
    }
    if (rc == DF_OK) *cfg = *tmp;
    free(tmp);
    free(line);
    return rc;
}

int df_config_load(df_server_config *cfg, const char *path, df_error *err)
{
    if (!cfg || !path) return df_error_set(err, DF_EINVAL, "config: NULL argument");
    FILE *f = fopen(path, "rb");
    if (!f) return df_error_set(err, DF_EIO, "%s: %s", path, strerror(errno));
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    int rc = DF_OK;
    while (buf) {
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (n < cap) break;
        if (cap >= ((size_t)1 << 24)) {
            rc = df_error_set(err, DF_ELIMIT, "%s: larger than 16 MiB", path);
            break;
        }
        char *nb = realloc(buf, cap * 2);
        if (!nb) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = nb;
        cap *= 2;
    }
    int ioerr = ferror(f);
    fclose(f);
    if (!buf) return df_error_set(err, DF_ENOMEM, "%s: out of memory", path);
    if (rc == DF_OK && ioerr) rc = df_error_set(err, DF_EIO, "%s: read error", path);
    if (rc == DF_OK) {
        rc = df_config_parse(cfg, buf, n, path, err);
        if (rc == DF_OK) snprintf(cfg->config_path, sizeof cfg->config_path, "%s", path);
    }
    free(buf);
    return rc;
}

/* Matches "--opt VALUE" or "--opt=VALUE"; advances *i; *val set. 1 match, 0 no, -1 missing. */
static int opt_value(int argc, char **argv, int *i, const char *opt, const char **val)
{
    const char *a = argv[*i];
    size_t ol = strlen(opt);
    if (strncmp(a, opt, ol) != 0) return 0;
    if (a[ol] == '=') {
        *val = a + ol + 1;
        return 1;
    }
    if (a[ol] != '\0') return 0;
    if (*i + 1 >= argc) return -1;
    *val = argv[++*i];
    return 1;
}

int df_config_from_args(df_server_config *cfg, int argc, char **argv, const char *xdg_runtime_dir,
                        df_cli_action *action, df_error *err)
{
    if (!cfg || !action || (argc > 0 && !argv))
        return df_error_set(err, DF_EINVAL, "config: NULL argument");
    df_server_config *tmp = malloc(sizeof *tmp);
    if (!tmp) return df_error_set(err, DF_ENOMEM, "config: out of memory");
    df_config_defaults(tmp, xdg_runtime_dir);
    *action = DF_CLI_RUN;
    int rc = DF_OK;
    /* Pass 1: --help and --config. */
    for (int i = 1; i < argc && rc == DF_OK; i++) {
        const char *v = NULL;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            *action = DF_CLI_HELP;
            free(tmp);
            return DF_OK;
        }
        int m = opt_value(argc, argv, &i, "--config", &v);
        if (m < 0) rc = df_error_set(err, DF_EINVAL, "--config needs a FILE");
        else if (m > 0) rc = df_config_load(tmp, v, err);
    }
    /* Pass 2: everything else on top. The first --hid-replay replaces the file's hid_replay
     * list (options override the file); further --hid-replay options add to it. */
    int cli_replay = 0;
    for (int i = 1; i < argc && rc == DF_OK; i++) {
        const char *v = NULL;
        int m;
        if ((m = opt_value(argc, argv, &i, "--config", &v)) != 0) continue;
        if (strcmp(argv[i], "--check-config") == 0) {
            *action = DF_CLI_CHECK;
            continue;
        }
        if (strcmp(argv[i], "--foreground") == 0 || strcmp(argv[i], "-f") == 0) {
            tmp->foreground = 1;
            continue;
        }
        if (strcmp(argv[i], "--tcp-insecure") == 0) {
            tmp->tcp_insecure = 1;
            continue;
        }
        static const char *const map[][2] = {
            {"--socket", "socket"}, {"--tcp", "tcp"}, {"--log-level", "log_level"},
            {"--spin-us", "spin_us"}, {"--inline-us", "inline_us"},
            {"--hid-replay", "hid_replay"}, {"--key-file", "key_file"},
            {"--store", "store"}, {"--tls-cert", "tls_cert"}, {"--tls-key", "tls_key"}};
        int done = 0;
        for (int k = 0; k < (int)(sizeof map / sizeof map[0]) && !done && rc == DF_OK; k++) {
            m = opt_value(argc, argv, &i, map[k][0], &v);
            if (m < 0) rc = df_error_set(err, DF_EINVAL, "%s needs a value", map[k][0]);
            else if (m > 0) {
                df_error e2;
                if (strcmp(map[k][1], "hid_replay") == 0 && !cli_replay++)
                    tmp->n_hid_replay = 0;
                rc = df_config_set(tmp, map[k][1], v, &e2);
                if (rc != DF_OK) df_error_set(err, rc, "%s: %s", map[k][0], e2.msg);
                done = 1;
            }
        }
        if (!done && rc == DF_OK)
            rc = df_error_set(err, DF_EINVAL, "unknown option '%s' (try --help)", argv[i]);
    }
    if (rc == DF_OK) *cfg = *tmp;
    free(tmp);
    return rc;
}

int df_config_path_allowed(const df_server_config *cfg, const char *path)
{
    if (!cfg || !path || path[0] != '/') return 0;
    for (int i = 0; i < cfg->n_allow; i++) {
        const char *a = cfg->allow_paths[i];
        size_t l = strlen(a);
        if (l == 1 && a[0] == '/') return 1;
        if (strncmp(path, a, l) == 0 && path[l] == '/') return 1;
    }
    return 0;
}

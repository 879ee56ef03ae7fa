/* store.c — opening, checking and creating the durable store (see store.h). */
#include "server/store/store.h"

#include <errno.h>
#include <fcntl.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/store/journal.h" /* DF_JOURNAL_BRUSH, for the version 1 migration */

typedef struct log_size { /* one session's change log since its last snapshot */
    uint64_t id, bytes;
} log_size;

struct df_store {
    sqlite3 *db;
    char *path;
    uint64_t log_bytes, log_changes;
    uint64_t snapshot_min;
    log_size *logs;           /* df_store_session_log; a few dozen sessions: a linear search */
    size_t n_logs, cap_logs;
    int upgrade;              /* the file has schema DF_STORE_SCHEMA_V1: marked current at open */
};

static const char k_schema[] =
    "CREATE TABLE meta(key TEXT PRIMARY KEY, value INTEGER NOT NULL);"
    "CREATE TABLE sessions(id INTEGER PRIMARY KEY, name TEXT NOT NULL, kind INTEGER NOT NULL,"
    " planar INTEGER NOT NULL, nv INTEGER NOT NULL, ne INTEGER NOT NULL, nf INTEGER NOT NULL,"
    " base BLOB NOT NULL, elems BLOB, faces BLOB, version INTEGER NOT NULL,"
    " brush BLOB, brush_seq INTEGER NOT NULL DEFAULT 0, handles BLOB,"
    " cur BLOB, rest BLOB, log_bytes INTEGER NOT NULL DEFAULT 0);"
    "CREATE TABLE changes(id INTEGER PRIMARY KEY, session INTEGER NOT NULL,"
    " version INTEGER NOT NULL, kind INTEGER NOT NULL, who INTEGER NOT NULL,"
    " flags INTEGER NOT NULL, delta BLOB, aux BLOB);"
    "CREATE INDEX changes_session ON changes(session, id);"
    "INSERT INTO meta VALUES('next_session_id', 0);";

int df_store_resolve_path(const char *cfg, const char *state_directory,
                          const char *xdg_state_home, const char *home, char *out, size_t cap,
                          int *is_default, df_error *err)
{
    if (is_default) *is_default = 0;
    if (cap) out[0] = '\0';
    if (cfg && strcmp(cfg, "none") == 0) return 1;
    int n;
    if (cfg && cfg[0]) {
        n = snprintf(out, cap, "%s", cfg);
    } else {
        if (is_default) *is_default = 1;
        if (state_directory && state_directory[0]) {
            size_t l = strcspn(state_directory, ":"); /* the first of the unit's directories */
            n = snprintf(out, cap, "%.*s/deformd.db", (int)l, state_directory);
        } else if (xdg_state_home && xdg_state_home[0] == '/') {
            n = snprintf(out, cap, "%s/deformd/deformd.db", xdg_state_home);
        } else if (home && home[0]) {
            n = snprintf(out, cap, "%s/.local/state/deformd/deformd.db", home);
        } else {
            return df_error_set(err, DF_EINVAL, "store: no default location (neither "
                                "STATE_DIRECTORY, XDG_STATE_HOME nor HOME is set): set store = "
                                "PATH or store = none");
        }
    }
    if (n < 0 || (size_t)n >= cap) {
        if (cap) out[0] = '\0';
        return df_error_set(err, DF_EINVAL, "store: path too long (%d bytes at most)",
                            (int)cap - 1);
    }
    return 0;
}

int df_store_fail(df_store *st, int code, const char *what, df_error *err)
{
    int busy = sqlite3_errcode(st->db) == SQLITE_BUSY;
    return df_error_set(err, code, "store %s: %s: %s%s", st->path, what, sqlite3_errmsg(st->db),
                        busy ? " (in use by another process: another deformd?)" : "");
}

int df_store_exec(df_store *st, const char *sql, const char *what, df_error *err)
{
    if (sqlite3_exec(st->db, sql, NULL, NULL, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, what, err);
    return DF_OK;
}

/* Runs a one-value query; *out the integer (0 when no row). */
static int query_int(df_store *st, const char *sql, int64_t *out, df_error *err)
{
    sqlite3_stmt *q = NULL;
    *out = 0;
    if (sqlite3_prepare_v2(st->db, sql, -1, &q, NULL) != SQLITE_OK) {
        int rc = sqlite3_errcode(st->db);
        return df_error_set(err, rc == SQLITE_NOTADB ? DF_EFORMAT : DF_EIO,
                            "store %s: %s%s%s", st->path, sqlite3_errmsg(st->db),
                            rc == SQLITE_BUSY ? " (in use by another process: another "
                                                "deformd?)" : "",
                            rc == SQLITE_NOTADB ? " (not a deformd store: move it away or set "
                                                  "another store path)" : "");
    }
    int rc = sqlite3_step(q);
    if (rc == SQLITE_ROW) *out = sqlite3_column_int64(q, 0);
    int ec = sqlite3_errcode(st->db);
    sqlite3_finalize(q);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE)
        return df_error_set(err, ec == SQLITE_NOTADB || ec == SQLITE_CORRUPT ? DF_EFORMAT : DF_EIO,
                            "store %s: %s (%s)%s", st->path, sqlite3_errstr(ec),
                            ec == SQLITE_BUSY ? "in use by another process: another deformd?"
                                              : sql,
                            ec == SQLITE_NOTADB ? ": not a deformd store (move it away or set "
                                                  "another store path)" : "");
    return DF_OK;
}

/* Integrity: every row of the check must say "ok". */
static int check_integrity(df_store *st, int64_t size, const char **checked, df_error *err)
{
    const char *pragma = size <= DF_STORE_FULL_CHECK_BYTES ? "integrity_check" : "quick_check";
    if (checked) *checked = pragma;
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA %s(1)", pragma);
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(st->db, sql, -1, &q, NULL) != SQLITE_OK)
        return df_error_set(err, DF_EFORMAT, "store %s: corrupt (%s: %s)", st->path, pragma,
                            sqlite3_errmsg(st->db));
    int rc = sqlite3_step(q);
    char first[160] = "";
    if (rc == SQLITE_ROW) snprintf(first, sizeof first, "%s", sqlite3_column_text(q, 0));
    int ec = sqlite3_errcode(st->db);
    sqlite3_finalize(q);
    if (rc != SQLITE_ROW)
        return df_error_set(err, DF_EFORMAT, "store %s: corrupt (%s: %s)", st->path, pragma,
                            sqlite3_errstr(ec));
    if (strcmp(first, "ok") != 0)
        return df_error_set(err, DF_EFORMAT, "store %s: corrupt (%s: %s); move it away to "
                            "start an empty store", st->path, pragma, first);
    return DF_OK;
}

/* The schema check of an existing database; *fresh = 1 when it holds nothing (new file). */
static int check_schema(df_store *st, int *fresh, df_error *err)
{
    int64_t app, ver, tables;
    int rc;
    if ((rc = query_int(st, "PRAGMA application_id", &app, err)) != DF_OK ||
        (rc = query_int(st, "PRAGMA user_version", &ver, err)) != DF_OK ||
        (rc = query_int(st, "SELECT count(*) FROM sqlite_master", &tables, err)) != DF_OK)
        return rc;
    *fresh = app == 0 && ver == 0 && tables == 0;
    if (*fresh) return DF_OK;
    if (app != DF_STORE_APP_ID)
        return df_error_set(err, DF_EFORMAT, "store %s: not a deformd store (an SQLite database "
                            "of another application: application_id 0x%llx, %lld table(s)); "
                            "set another store path", st->path, (unsigned long long)app,
                            (long long)tables);
    if (ver != DF_STORE_SCHEMA && ver != DF_STORE_SCHEMA_V1)
        return df_error_set(err, DF_EFORMAT, "store %s: schema version %lld, this deformd "
                            "knows versions %d and %d only", st->path, (long long)ver,
                            DF_STORE_SCHEMA_V1, DF_STORE_SCHEMA);
    st->upgrade = ver == DF_STORE_SCHEMA_V1;
    return DF_OK;
}

static int mkdir_p(const char *path, df_error *err)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s", path);
    char *slash = strrchr(tmp, '/');
    if (!slash || slash == tmp) return DF_OK;
    *slash = '\0';
    for (char *p = tmp + 1; *p; p++) {
        if (*p != '/') continue;
        *p = '\0';
        if (mkdir(tmp, 0700) != 0 && errno != EEXIST)
            return df_error_set(err, DF_EIO, "store %s: cannot create directory %s: %s (set "
                                "store = PATH or store = none)", path, tmp, strerror(errno));
        *p = '/';
    }
    if (mkdir(tmp, 0700) != 0 && errno != EEXIST)
        return df_error_set(err, DF_EIO, "store %s: cannot create directory %s: %s (set store = "
                            "PATH or store = none)", path, tmp, strerror(errno));
    return DF_OK;
}

/* After the checks: WAL, the synchronous mode, the size cap. */
static int configure(df_store *st, int durability, int max_mb, df_error *err)
{
    static const char *const sync[] = {"FULL", "NORMAL", "OFF"};
    char sql[160];
    int rc;
    int64_t dummy;
    if ((rc = query_int(st, "PRAGMA journal_mode=WAL", &dummy, err)) != DF_OK) return rc;
    snprintf(sql, sizeof sql, "PRAGMA synchronous=%s", sync[durability]);
    if ((rc = df_store_exec(st, sql, "synchronous", err)) != DF_OK) return rc;
    if (max_mb > 0) {
        int64_t page;
        if ((rc = query_int(st, "PRAGMA page_size", &page, err)) != DF_OK) return rc;
        snprintf(sql, sizeof sql, "PRAGMA max_page_count=%lld",
                 (long long)(((int64_t)max_mb << 20) / (page > 0 ? page : 4096)));
        if ((rc = df_store_exec(st, sql, "max_page_count", err)) != DF_OK) return rc;
    }
    return DF_OK;
}

int df_store_open(const char *path, int durability, int max_mb, int mkdir_parent,
                  df_store **out, const char **checked, df_error *err)
{
    *out = NULL;
    if (checked) *checked = "";
    if (!path || !path[0] || durability < 0 || durability > DF_DURABILITY_OFF)
        return df_error_set(err, DF_EINVAL, "store: bad path or durability");
    if (mkdir_parent && mkdir_p(path, err) != DF_OK) return err ? err->code : DF_EIO;
    struct stat sb;
    int64_t size = 0;
    if (stat(path, &sb) == 0) {
        if (!S_ISREG(sb.st_mode))
            return df_error_set(err, DF_EFORMAT, "store %s: not a regular file", path);
        if (sb.st_size == 0)
            return df_error_set(err, DF_EFORMAT, "store %s: empty file, not a deformd store "
                                "(remove it to start a new store)", path);
        size = (int64_t)sb.st_size;
    } else if (errno == ENOENT) { /* created here, 0600 */
        int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        if (fd < 0)
            return df_error_set(err, DF_EIO, "store %s: cannot create: %s", path,
                                strerror(errno));
        close(fd);
    } else {
        return df_error_set(err, DF_EIO, "store %s: %s", path, strerror(errno));
    }
    df_store *st = calloc(1, sizeof *st);
    if (st) st->snapshot_min = DF_STORE_SNAPSHOT_MIN;
    if (!st || !(st->path = strdup(path))) {
        free(st);
        return df_error_set(err, DF_ENOMEM, "store %s: out of memory", path);
    }
    int rc = DF_OK;
    if (sqlite3_open_v2(path, &st->db, SQLITE_OPEN_READWRITE, NULL) != SQLITE_OK) {
        rc = df_error_set(err, DF_EIO, "store %s: cannot open: %s", path,
                          st->db ? sqlite3_errmsg(st->db) : "out of memory");
    } else {
        sqlite3_extended_result_codes(st->db, 0);
        sqlite3_busy_timeout(st->db, 0);
        int fresh = 0;
        /* read-only checks first (the first read fails on a text file: SQLITE_NOTADB); a
         * refused file is never written to */
        if ((rc = df_store_exec(st, "PRAGMA locking_mode=EXCLUSIVE", "locking", err)) == DF_OK &&
            (rc = check_schema(st, &fresh, err)) == DF_OK &&
            (fresh || (rc = check_integrity(st, size, checked, err)) == DF_OK) &&
            (rc = configure(st, durability, max_mb, err)) == DF_OK) {
            if (fresh) {
                char sql[sizeof k_schema + 128];
                snprintf(sql, sizeof sql, "BEGIN IMMEDIATE;%sPRAGMA application_id=%d;"
                         "PRAGMA user_version=%d;COMMIT", k_schema, DF_STORE_APP_ID,
                         DF_STORE_SCHEMA);
                rc = df_store_exec(st, sql, "creating the schema", err);
                if (rc != DF_OK) sqlite3_exec(st->db, "ROLLBACK", NULL, NULL, NULL);
            } else if (st->upgrade) { /* version 1: brush_seq as of the snapshot (store.h) */
                char sql[256];
                snprintf(sql, sizeof sql, "BEGIN IMMEDIATE;UPDATE sessions SET brush_seq ="
                         " brush_seq - (SELECT count(*) FROM changes WHERE session = sessions.id"
                         " AND flags & %d);PRAGMA user_version=%d;COMMIT", DF_JOURNAL_BRUSH,
                         DF_STORE_SCHEMA);
                rc = df_store_exec(st, sql, "migrating the store to schema version 2", err);
                if (rc != DF_OK) sqlite3_exec(st->db, "ROLLBACK", NULL, NULL, NULL);
            }
        }
        /* take the exclusive lock now: a second daemon on this file is refused at start */
        if (rc == DF_OK &&
            (rc = df_store_exec(st, "BEGIN IMMEDIATE;COMMIT", "locking the store", err)) != DF_OK)
            sqlite3_exec(st->db, "ROLLBACK", NULL, NULL, NULL);
    }
    if (rc != DF_OK) {
        df_store_close(st);
        return rc;
    }
    *out = st;
    return DF_OK;
}

void df_store_close(df_store *st)
{
    if (!st) return;
    if (st->db) sqlite3_close_v2(st->db);
    free(st->logs);
    free(st->path);
    free(st);
}

const char *df_store_path(const df_store *st) { return st->path; }
struct sqlite3 *df_store_db(df_store *st) { return st->db; }
uint64_t df_store_log_bytes(const df_store *st) { return st->log_bytes; }
uint64_t df_store_snapshot_min(const df_store *st) { return st->snapshot_min; }
void df_store_set_snapshot_min(df_store *st, uint64_t bytes) { st->snapshot_min = bytes; }
uint64_t df_store_log_changes(const df_store *st) { return st->log_changes; }

void df_store_count_change(df_store *st, uint64_t bytes)
{
    st->log_bytes += bytes;
    st->log_changes++;
}

uint64_t *df_store_session_log(df_store *st, uint64_t id)
{
    for (size_t i = 0; i < st->n_logs; i++)
        if (st->logs[i].id == id) return &st->logs[i].bytes;
    if (st->n_logs == st->cap_logs) {
        size_t cap = st->cap_logs ? 2 * st->cap_logs : 16;
        log_size *n = realloc(st->logs, cap * sizeof *n);
        if (!n) return NULL;
        st->logs = n;
        st->cap_logs = cap;
    }
    st->logs[st->n_logs] = (log_size){id, 0};
    return &st->logs[st->n_logs++].bytes;
}

void df_store_forget_session(df_store *st, uint64_t id)
{
    for (size_t i = 0; i < st->n_logs; i++)
        if (st->logs[i].id == id) {
            st->logs[i] = st->logs[--st->n_logs];
            return;
        }
}

/* Unit tests for server/store/store.c: the store path's default, creating a new store (schema,
 * application id, WAL), reopening it (integrity check), and every file that must be refused at
 * open with a message naming it and without being changed: an empty file, a text file, another
 * application's SQLite database, an unknown schema version, a corrupt store, a store in use. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>
#include <sqlite3.h>

#include "server/config.h"
#include "server/store/store.h"

static char g_dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/df-store-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void path_of(char *out, size_t cap, const char *name)
{
    snprintf(out, cap, "%s/%s", g_dir, name);
}

static void write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    fclose(f);
}

/* The whole file's bytes (malloc'd; *len its size). */
static uint8_t *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

/* Opening `path` must fail with `code`, name the file and leave its bytes unchanged. */
static void assert_refused(const char *path, int code, const char *words)
{
    size_t n0, n1;
    uint8_t *before = read_file(path, &n0);
    df_store *st = (df_store *)1;
    df_error e;
    assert_int_equal(df_store_open(path, DF_DURABILITY_FULL, 0, 0, &st, NULL, &e), code);
    assert_null(st);
    assert_non_null(strstr(e.msg, path));
    if (!strstr(e.msg, words)) fail_msg("message '%s' lacks '%s'", e.msg, words);
    uint8_t *after = read_file(path, &n1);
    assert_int_equal(n0, n1);
    assert_memory_equal(before, after, n0);
    free(before);
    free(after);
}

static void test_resolve_path(void **state)
{
    (void)state;
    char out[256];
    int def;
    df_error e;
    assert_int_equal(df_store_resolve_path("none", "/s", "/x", "/h", out, sizeof out, &def, &e), 1);
    assert_string_equal(out, "");
    assert_int_equal(df_store_resolve_path("/a/b.db", "/s", "/x", "/h", out, sizeof out, &def,
                                           &e), 0);
    assert_string_equal(out, "/a/b.db");
    assert_int_equal(def, 0);
    /* systemd's StateDirectory= wins, first entry of a list */
    assert_int_equal(df_store_resolve_path("", "/var/lib/deformd:/var/lib/other", "/x", "/h", out,
                                           sizeof out, &def, &e), 0);
    assert_string_equal(out, "/var/lib/deformd/deformd.db");
    assert_int_equal(def, 1);
    assert_int_equal(df_store_resolve_path("", NULL, "/x", "/h", out, sizeof out, &def, &e), 0);
    assert_string_equal(out, "/x/deformd/deformd.db");
    /* XDG: a relative XDG_STATE_HOME is ignored */
    assert_int_equal(df_store_resolve_path(NULL, "", "rel", "/h", out, sizeof out, &def, &e), 0);
    assert_string_equal(out, "/h/.local/state/deformd/deformd.db");
    assert_int_equal(df_store_resolve_path("", NULL, NULL, NULL, out, sizeof out, &def, &e),
                     DF_EINVAL);
    assert_non_null(strstr(e.msg, "store = none"));
    assert_int_equal(df_store_resolve_path("", NULL, NULL, "/h", out, 8, &def, &e), DF_EINVAL);
}

static int64_t pragma(df_store *st, const char *sql)
{
    sqlite3_stmt *q;
    assert_int_equal(sqlite3_prepare_v2(df_store_db(st), sql, -1, &q, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    int64_t v = sqlite3_column_int64(q, 0);
    sqlite3_finalize(q);
    return v;
}

static void make_db(const char *p, const char *sql)
{
    sqlite3 *db;
    assert_int_equal(sqlite3_open(p, &db), SQLITE_OK);
    assert_int_equal(sqlite3_exec(db, sql, NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(db);
}

static void test_create_and_reopen(void **state)
{
    (void)state;
    char p[128];
    path_of(p, sizeof p, "sub/dir/new.db");
    df_store *st;
    const char *checked;
    df_error e;
    /* without mkdir_parent a missing directory is an error naming the file */
    assert_int_equal(df_store_open(p, DF_DURABILITY_NORMAL, 0, 0, &st, &checked, &e), DF_EIO);
    assert_non_null(strstr(e.msg, p));
    assert_int_equal(df_store_open(p, DF_DURABILITY_NORMAL, 0, 1, &st, &checked, &e), DF_OK);
    assert_string_equal(checked, ""); /* a new file: nothing to check */
    assert_int_equal(pragma(st, "PRAGMA application_id"), DF_STORE_APP_ID);
    assert_int_equal(pragma(st, "PRAGMA user_version"), DF_STORE_SCHEMA);
    assert_int_equal(pragma(st, "PRAGMA synchronous"), 1); /* NORMAL */
    assert_int_equal(pragma(st, "SELECT count(*) FROM sessions"), 0);
    struct stat sb;
    assert_int_equal(stat(p, &sb), 0);
    assert_int_equal(sb.st_mode & 0777, 0600);
    /* a second daemon on the same file is refused while the first holds it */
    df_store *st2 = NULL;
    assert_int_equal(df_store_open(p, DF_DURABILITY_FULL, 0, 0, &st2, NULL, &e), DF_EIO);
    assert_null(st2);
    assert_non_null(strstr(e.msg, "in use"));
    assert_non_null(strstr(e.msg, p));
    df_store_close(st);
    assert_int_equal(df_store_open(p, DF_DURABILITY_FULL, 0, 0, &st, &checked, &e), DF_OK);
    assert_string_equal(checked, "integrity_check");
    assert_int_equal(pragma(st, "PRAGMA synchronous"), 2); /* FULL */
    char mode[16];
    sqlite3_stmt *q;
    assert_int_equal(sqlite3_prepare_v2(df_store_db(st), "PRAGMA journal_mode", -1, &q, NULL),
                     SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    snprintf(mode, sizeof mode, "%s", sqlite3_column_text(q, 0));
    sqlite3_finalize(q);
    assert_string_equal(mode, "wal");
    df_store_close(st);
    assert_int_equal(df_store_open(p, DF_DURABILITY_OFF, 0, 0, &st, &checked, &e), DF_OK);
    assert_int_equal(pragma(st, "PRAGMA synchronous"), 0); /* OFF */
    df_store_close(st);
    /* a schema version 1 file (same tables; its session rows also held the current version)
     * opens and is marked version 2, the version this build writes (store.h) */
    make_db(p, "PRAGMA user_version=1");
    assert_int_equal(df_store_open(p, DF_DURABILITY_OFF, 0, 0, &st, &checked, &e), DF_OK);
    assert_int_equal(pragma(st, "PRAGMA user_version"), DF_STORE_SCHEMA);
    assert_int_equal(DF_STORE_SCHEMA, DF_STORE_SCHEMA_V1 + 1);
    df_store_close(st);
}

static void test_refuses_empty_and_text(void **state)
{
    (void)state;
    char p[128];
    path_of(p, sizeof p, "empty.db");
    write_file(p, "", 0);
    assert_refused(p, DF_EFORMAT, "empty");
    path_of(p, sizeof p, "text.db");
    const char text[] = "socket = /tmp/x\nthis is a config file, not a database\n";
    write_file(p, text, sizeof text - 1);
    assert_refused(p, DF_EFORMAT, "not a deformd store");
    /* a text file longer than SQLite's header */
    char big[8192];
    for (size_t i = 0; i < sizeof big; i++) big[i] = (char)('a' + i % 26);
    write_file(p, big, sizeof big);
    assert_refused(p, DF_EFORMAT, "not a deformd store");
}

/* Creates an SQLite database at p with `sql` run in it. */
static void test_refuses_foreign_and_unknown_version(void **state)
{
    (void)state;
    char p[128];
    path_of(p, sizeof p, "foreign.db");
    make_db(p, "CREATE TABLE songs(title TEXT); INSERT INTO songs VALUES('x');");
    assert_refused(p, DF_EFORMAT, "another application");
    path_of(p, sizeof p, "foreign2.db");
    make_db(p, "PRAGMA application_id=1234; CREATE TABLE t(a);");
    assert_refused(p, DF_EFORMAT, "another application");
    path_of(p, sizeof p, "future.db");
    char sql[128];
    snprintf(sql, sizeof sql, "PRAGMA application_id=%d; PRAGMA user_version=%d; CREATE TABLE "
             "t(a);", DF_STORE_APP_ID, DF_STORE_SCHEMA + 1);
    make_db(p, sql);
    assert_refused(p, DF_EFORMAT, "schema version");
}

static void test_refuses_corrupt(void **state)
{
    (void)state;
    char p[128];
    path_of(p, sizeof p, "corrupt.db");
    df_store *st;
    df_error e;
    assert_int_equal(df_store_open(p, DF_DURABILITY_FULL, 0, 0, &st, NULL, &e), DF_OK);
    /* enough rows for several b-tree pages in `sessions` and its index-less table `changes` */
    assert_int_equal(df_store_exec(st, "WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i+1 "
                                   "FROM n WHERE i < 400) INSERT INTO changes(session, version,"
                                   " kind, who, flags, delta) SELECT 1, i, 0, 0, 0, "
                                   "randomblob(200) FROM n", "filling", &e),
                     DF_OK);
    df_store_close(st); /* checkpoints the WAL into the file */
    size_t n;
    uint8_t *b = read_file(p, &n);
    assert_true(n > 8 * 4096);
    /* garbage over the middle of page 4 (a b-tree page: headers and cell pointers) */
    for (size_t i = 3 * 4096; i < 3 * 4096 + 64; i++) b[i] = 0xA5;
    write_file(p, b, n);
    free(b);
    assert_refused(p, DF_EFORMAT, "corrupt");
}

/* The config keys and option: store, durability, store_max_mb, --store. */
static void test_config_keys(void **state)
{
    (void)state;
    df_server_config c;
    df_error e;
    df_config_defaults(&c, NULL);
    assert_string_equal(c.store_path, ""); /* the default location */
    assert_int_equal(c.durability, DF_DURABILITY_FULL);
    assert_int_equal(c.store_max_mb, 0);
    const char text[] = "store = /var/lib/x.db\ndurability = normal\nstore_max_mb = 64\n";
    assert_int_equal(df_config_parse(&c, text, sizeof text - 1, "t.conf", &e), DF_OK);
    assert_string_equal(c.store_path, "/var/lib/x.db");
    assert_int_equal(c.durability, DF_DURABILITY_NORMAL);
    assert_int_equal(c.store_max_mb, 64);
    assert_int_equal(df_config_set(&c, "durability", "off", &e), DF_OK);
    assert_int_equal(c.durability, DF_DURABILITY_OFF);
    assert_int_equal(df_config_set(&c, "durability", "fsync", &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "full|normal|off"));
    assert_int_equal(c.durability, DF_DURABILITY_OFF);
    assert_int_equal(df_config_set(&c, "store", "", &e), DF_EINVAL);
    assert_int_equal(df_config_set(&c, "store_max_mb", "-1", &e), DF_EINVAL);
    char *argv[] = {"deformd", "--store", "none", NULL};
    df_cli_action a;
    assert_int_equal(df_config_from_args(&c, 3, argv, NULL, &a, &e), DF_OK);
    assert_string_equal(c.store_path, "none");
    char *argv2[] = {"deformd", "--store", NULL};
    assert_int_equal(df_config_from_args(&c, 2, argv2, NULL, &a, &e), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resolve_path),
        cmocka_unit_test(test_config_keys),
        cmocka_unit_test(test_create_and_reopen),
        cmocka_unit_test(test_refuses_empty_and_text),
        cmocka_unit_test(test_refuses_foreign_and_unknown_version),
        cmocka_unit_test(test_refuses_corrupt),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

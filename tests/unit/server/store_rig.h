/* store_rig.h — the store unit tests' rig: a temporary directory per test program, an in-process
 * df_server with its store opened on a file there, and one-value SQL queries. Header-only
 * (static inline: each test uses what it needs). Include after cmocka.h. */
#ifndef DF_TESTS_STORE_RIG_H
#define DF_TESTS_STORE_RIG_H

#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/config.h"
#include "server/session/session.h"
#include "server/store/restore.h"
#include "server/store/store.h"

static char g_dir[64]; /* the program's temporary directory (rig_setup) */

/* cmocka group setup / teardown: makes / removes g_dir. */
static inline int rig_setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/df-store-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static inline int rig_teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* A server with default settings and its store on g_dir/file (restored when it exists). */
static inline void server_open(df_server *srv, const char *file)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
    snprintf(srv->cfg.store_path, sizeof srv->cfg.store_path, "%s/%s", g_dir, file);
    df_error e;
    if (df_store_start(srv, &e) != DF_OK) fail_msg("df_store_start: %s", e.msg);
    assert_non_null(srv->store_ops);
}

/* Destroys every session (nothing journaled) and closes the store. */
static inline void server_close(df_server *srv)
{
    while (srv->sessions) df_session_destroy(srv->sessions);
    df_store_stop(srv);
}

/* The first column of the first row of `sql` on the server's store, -1 without a row. */
static inline int64_t query(df_server *srv, const char *sql)
{
    sqlite3_stmt *q;
    assert_int_equal(sqlite3_prepare_v2(df_store_db(srv->store), sql, -1, &q, NULL), SQLITE_OK);
    int64_t v = sqlite3_step(q) == SQLITE_ROW ? sqlite3_column_int64(q, 0) : -1;
    sqlite3_finalize(q);
    return v;
}

#endif

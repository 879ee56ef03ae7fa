/* A session's store rows as replicated bytes (server/cluster/rows.h): dump, delete, load back
 * gives the same rows; only the changes after a rowid are dumped; malformed bytes and rows of
 * another session are refused with DF_EFORMAT and load nothing. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../unit_skip.h"

#include <sqlite3.h>
#include <unistd.h>

#include "server/cluster/rows.h"
#include "server/store/store.h"

static df_store *open_store(char *path)
{
    strcpy(path, "/tmp/df-unit-rows-XXXXXX");
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    unlink(path);
    df_store *st;
    assert_int_equal(df_store_open(path, 2, 0, 0, &st, NULL, NULL), DF_OK);
    return st;
}

static void drop_store(df_store *st, const char *path)
{
    df_store_close(st);
    char p[64];
    unlink(path);
    snprintf(p, sizeof p, "%s-wal", path);
    unlink(p);
    snprintf(p, sizeof p, "%s-shm", path);
    unlink(p);
}

/* Session id's rows: a session row, two blobs (one with NUL bytes), an access row, 3 changes. */
static void fill(df_store *st, uint64_t id)
{
    char sql[1024];
    snprintf(sql, sizeof sql,
             "INSERT INTO sessions(id, name, kind, planar, nv, ne, nf, version, brush, brush_seq,"
             " log_bytes, snap_version, replay_ns) VALUES(%llu, 'n%llu', 2, 0, 3, 1, 1, 7,"
             " x'00010203', 2, 10, 4, 99);"
             "INSERT INTO blobs(session, name, data) VALUES(%llu, 'base', x'0000ff00aa'),"
             " (%llu, 'faces', x'000000000100000002000000');"
             "INSERT INTO access(session, owner, mode, observers, key_hash, members) VALUES(%llu,"
             " 'uid:1', 1, 1, NULL, 'uid:2\n');"
             "INSERT INTO changes(session, version, kind, who, flags, delta, aux, recipe) VALUES"
             " (%llu, 5, 48, 3, 0, x'0102', NULL, NULL), (%llu, 6, 49, 3, 8, NULL, NULL, x'00ff'),"
             " (%llu, 7, 50, 4, 16, NULL, x'', NULL);",
             (unsigned long long)id, (unsigned long long)id, (unsigned long long)id,
             (unsigned long long)id, (unsigned long long)id, (unsigned long long)id,
             (unsigned long long)id, (unsigned long long)id);
    assert_int_equal(df_store_exec(st, sql, "fill", NULL), DF_OK);
}

static void test_dump_delete_load_round_trip(void **state)
{
    (void)state;
    char path[64];
    df_store *st = open_store(path);
    fill(st, 5);
    fill(st, 6); /* another session: untouched */
    uint8_t *a, *b;
    size_t al, bl;
    assert_int_equal(df_rows_dump_session(st, 5, &a, &al, NULL), DF_OK);
    assert_int_equal(df_rows_delete_session(st, 5, NULL), DF_OK);
    uint8_t *empty;
    size_t el;
    assert_int_equal(df_rows_dump_session(st, 5, &empty, &el, NULL), DF_OK);
    assert_int_equal(el, 8); /* the header: no row left */
    free(empty);
    assert_int_equal(df_store_exec(st, "BEGIN", "t", NULL), DF_OK);
    assert_int_equal(df_rows_load(st, 5, a, al, NULL), DF_OK);
    assert_int_equal(df_store_exec(st, "COMMIT", "t", NULL), DF_OK);
    assert_int_equal(df_rows_dump_session(st, 5, &b, &bl, NULL), DF_OK);
    assert_int_equal(al, bl);
    assert_memory_equal(a, b, al);
    free(b);
    /* the changes after a rowid: the last two of session 5 */
    int64_t last, first_last;
    assert_int_equal(df_rows_last_change(st, 5, &last, NULL), DF_OK);
    int n;
    assert_int_equal(df_rows_dump_changes(st, 5, last - 2, &b, &bl, &n, &first_last, NULL),
                     DF_OK);
    assert_int_equal(n, 2);
    assert_int_equal(first_last, last);
    free(b);
    free(a);
    drop_store(st, path);
}

static void test_malformed_and_foreign_rows_are_refused(void **state)
{
    (void)state;
    char path[64];
    df_store *st = open_store(path);
    fill(st, 5);
    uint8_t *a;
    size_t al;
    assert_int_equal(df_rows_dump_session(st, 5, &a, &al, NULL), DF_OK);
    assert_int_equal(df_rows_delete_session(st, 5, NULL), DF_OK);
    df_error e;
    /* each load in a transaction rolled back after its error, as the rebuild does */
#define LOAD(id, p, n) (df_store_exec(st, "BEGIN", "t", NULL), load_rc = df_rows_load(st, id, p, n, &e), \
                        df_store_exec(st, "ROLLBACK", "t", NULL), load_rc)
    int load_rc;
    /* rows of session 5 offered as session 9's */
    assert_int_equal(LOAD(9, a, al), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "session 9"));
    /* every truncation, and a bad magic */
    for (size_t cut = 0; cut < al; cut += 7)
        assert_int_equal(LOAD(5, a, cut), DF_EFORMAT);
    uint8_t *bad = malloc(al + 1);
    memcpy(bad, a, al);
    bad[0] ^= 1;
    assert_int_equal(LOAD(5, bad, al), DF_EFORMAT);
    memcpy(bad, a, al);
    bad[al] = 0;
    assert_int_equal(LOAD(5, bad, al + 1), DF_EFORMAT); /* trailing byte */
    assert_non_null(strstr(e.msg, "trailing"));
    free(bad);
    free(a);
    uint8_t *left;
    size_t ll;
    assert_int_equal(df_rows_dump_session(st, 5, &left, &ll, NULL), DF_OK);
    assert_int_equal(ll, 8); /* nothing loaded */
    free(left);
    drop_store(st, path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dump_delete_load_round_trip),
        cmocka_unit_test(test_malformed_and_foreign_rows_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

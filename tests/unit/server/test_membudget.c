/* Unit tests for server/session/membudget.c: charges by kind against the total (memory_max_mb) and the
 * per-kind caps (uploads_max_mb, shm_total_bytes), refusals that name the limit and its config
 * key and charge nothing, release clamping, room, unchecked adjustment; and the shared-memory
 * ring size derived from the session (server/net/shm.c). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/membudget.h"
#include "server/net/shm.h"

#define MiB ((uint64_t)1 << 20)

static void test_charge_release_and_total_cap(void **state)
{
    (void)state;
    df_membudget b;
    df_error e;
    df_mem_init(&b, 10 * MiB, 4 * MiB, 3 * MiB);
    assert_int_equal(df_mem_used(&b), 0);
    assert_int_equal(df_mem_charge(&b, DF_MEM_SESSIONS, 6 * MiB, "load", &e), DF_OK);
    assert_int_equal(df_mem_charge(&b, DF_MEM_HISTORY, 3 * MiB, "load", &e), DF_OK);
    assert_int_equal(df_mem_used(&b), 9 * MiB);
    assert_int_equal(df_mem_room(&b, DF_MEM_HISTORY), 1 * MiB);
    /* over the total: refused, names memory_max_mb, nothing charged */
    assert_int_equal(df_mem_charge(&b, DF_MEM_SESSIONS, 2 * MiB, "session of 9 vertices", &e),
                     DF_ELIMIT);
    assert_int_equal(e.code, DF_ELIMIT);
    assert_non_null(strstr(e.msg, "memory_max_mb"));
    assert_non_null(strstr(e.msg, "session of 9 vertices"));
    assert_int_equal(df_mem_used(&b), 9 * MiB);
    assert_int_equal(b.refused, 1);
    /* exactly up to the cap is fine */
    assert_int_equal(df_mem_charge(&b, DF_MEM_SESSIONS, 1 * MiB, "load", &e), DF_OK);
    assert_int_equal(df_mem_room(&b, DF_MEM_SESSIONS), 0);
    df_mem_release(&b, DF_MEM_SESSIONS, 7 * MiB);
    assert_int_equal(df_mem_used(&b), 3 * MiB);
    df_mem_release(&b, DF_MEM_HISTORY, 100 * MiB); /* clamped */
    assert_int_equal(b.used[DF_MEM_HISTORY], 0);
    assert_int_equal(df_mem_charge(&b, DF_MEM_KINDS, 1, "x", &e), DF_EINVAL);
}

static void test_kind_caps_name_their_config_keys(void **state)
{
    (void)state;
    df_membudget b;
    df_error e;
    df_mem_init(&b, 100 * MiB, 4 * MiB, 3 * MiB);
    assert_int_equal(df_mem_charge(&b, DF_MEM_UPLOADS, 3 * MiB, "load_mesh", &e), DF_OK);
    assert_int_equal(df_mem_room(&b, DF_MEM_UPLOADS), 1 * MiB);
    assert_int_equal(df_mem_charge(&b, DF_MEM_UPLOADS, 2 * MiB, "load_mesh", &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "uploads_max_mb"));
    assert_non_null(strstr(e.msg, "load_mesh"));
    assert_int_equal(b.used[DF_MEM_UPLOADS], 3 * MiB);
    assert_int_equal(df_mem_charge(&b, DF_MEM_SHM, 3 * MiB + 1, "stream_shm", &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "shm_total_bytes"));
    assert_int_equal(b.used[DF_MEM_SHM], 0);
    assert_int_equal(b.refused, 2);
    /* the other kinds have no cap of their own */
    assert_int_equal(df_mem_charge(&b, DF_MEM_HISTORY, 50 * MiB, "commit", &e), DF_OK);
    /* adjust is unchecked (a self-bounding holder) */
    df_mem_adjust(&b, DF_MEM_HISTORY, 50 * MiB, 200 * MiB);
    assert_int_equal(b.used[DF_MEM_HISTORY], 200 * MiB);
    assert_int_equal(df_mem_room(&b, DF_MEM_SESSIONS), 0);
    assert_int_equal(df_mem_charge(&b, DF_MEM_SESSIONS, 1, "load", &e), DF_ELIMIT);
}

/* Item 11: a ring holds DF_SHM_RING_VERSIONS dense versions of its session, not shm_ring_bytes. */
static void test_ring_size_follows_the_session(void **state)
{
    (void)state;
    const uint64_t cap = 64 * MiB;
    assert_int_equal(df_shm_ring_size(1, cap), 64 << 10);             /* the minimum */
    assert_int_equal(df_shm_ring_size(100, cap), 192 << 10);          /* 128 x 1328 B, rounded */
    assert_int_equal(df_shm_ring_size(1000, cap), 1536 << 10);        /* 1k vertices: 1.5 MiB */
    assert_int_equal(df_shm_ring_size(1000000, cap), cap);            /* capped */
    assert_int_equal(df_shm_ring_size(1000, 64 << 10), 64 << 10);
    assert_int_equal(df_shm_ring_size(1000, 0), 0);
    for (int32_t nv = 1; nv < 5000000; nv = nv * 3 + 7) {
        uint64_t r = df_shm_ring_size(nv, 4096 * MiB);
        assert_int_equal(r % DF_SHM_RING_ROUND, 0);
        assert_true(r >= (uint64_t)DF_SHM_RING_VERSIONS * 12 * (uint64_t)nv);
    }
}

static void test_physical_memory_is_known(void **state)
{
    (void)state;
    assert_true(df_mem_physical_bytes() >= 64 * MiB);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_charge_release_and_total_cap),
        cmocka_unit_test(test_kind_caps_name_their_config_keys),
        cmocka_unit_test(test_ring_size_follows_the_session),
        cmocka_unit_test(test_physical_memory_is_known),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

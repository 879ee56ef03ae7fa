/* Unit tests for proto/shm_ring.c (PROTOCOL.md 6.1): header layout and checks, append/read round
 * trips, frames never wrapping, overwritten frames reported lost (before and during a copy),
 * and references that cannot be frames of the ring. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "proto/buf.h"
#include "proto/shm_ring.h"

#define CAP 8192u

static df_shm_writer W; /* the writer of the ring new_ring made last */

/* A zeroed, 8-byte aligned ring of CAP data bytes for session 5; W appends to it. */
static uint8_t *new_ring(void)
{
    uint8_t *b = aligned_alloc(4096, DF_SHM_HEADER_BYTES + CAP);
    assert_non_null(b);
    memset(b, 0, DF_SHM_HEADER_BYTES + CAP);
    df_shm_writer_init(&W, b, CAP, 5);
    return b;
}

static void fill(uint8_t *f, uint32_t len, uint8_t seed)
{
    for (uint32_t i = 0; i < len; i++) f[i] = (uint8_t)(seed + 7 * i);
}

static void test_header_layout_and_check(void **state)
{
    (void)state;
    uint8_t *b = new_ring();
    df_error e;
    assert_memory_equal(b, "DFSHMRG1", 8);
    assert_int_equal(df_le32_load(b + 8), 4096);
    assert_int_equal(df_le32_load(b + 12), 0);
    assert_true(df_le64_load(b + 16) == CAP);
    assert_true(df_le64_load(b + 24) == 5);
    assert_true(df_le64_load(b + 32) == 0 && df_le64_load(b + 40) == 0);
    assert_int_equal(df_shm_ring_check(b, DF_SHM_HEADER_BYTES + CAP, CAP, 5, &e), DF_OK);
    assert_int_equal(df_shm_ring_check(b, DF_SHM_HEADER_BYTES + CAP, CAP, 6, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "session"));
    assert_int_equal(df_shm_ring_check(b, DF_SHM_HEADER_BYTES + CAP, 2 * CAP, 5, &e), DF_EFORMAT);
    assert_int_equal(df_shm_ring_check(b, DF_SHM_HEADER_BYTES + CAP - 1, CAP, 5, &e),
                     DF_EFORMAT); /* mapping too short for the capacity */
    b[3] = 'x';
    assert_int_equal(df_shm_ring_check(b, DF_SHM_HEADER_BYTES + CAP, CAP, 5, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "magic"));
    free(b);
}

static void test_append_read_round_trip_and_no_wrap(void **state)
{
    (void)state;
    uint8_t *b = new_ring();
    uint8_t f[3000], out[3000];
    df_error e;
    uint64_t pos[4];
    for (int k = 0; k < 4; k++) {
        fill(f, sizeof f, (uint8_t)k);
        pos[k] = df_shm_writer_append(&W, f, sizeof f);
    }
    /* 0, 3000, then 6000 + 3000 > 8192: the third frame starts the next lap at 8192. */
    assert_true(pos[0] == 0 && pos[1] == 3000 && pos[2] == CAP && pos[3] == CAP + 3000);
    assert_true(df_le64_load(b + 40) == CAP + 6000); /* head */
    /* Frames 2 and 3 reused lap offsets [0, 6000): frames 0 and 1 are lost. */
    assert_true(df_le64_load(b + 32) == 6000); /* valid_from = 11192 + 3000 - 8192 */
    assert_int_equal(df_shm_ring_read(b, CAP, pos[0], sizeof f, out, &e), DF_ENOTFOUND);
    assert_non_null(strstr(e.msg, "overwritten"));
    assert_int_equal(df_shm_ring_read(b, CAP, pos[1], sizeof f, out, &e), DF_ENOTFOUND);
    for (int k = 2; k < 4; k++) {
        fill(f, sizeof f, (uint8_t)k);
        assert_int_equal(df_shm_ring_read(b, CAP, pos[k], sizeof f, out, &e), DF_OK);
        assert_memory_equal(out, f, sizeof f);
    }
    free(b);
}

static void test_bad_references(void **state)
{
    (void)state;
    uint8_t *b = new_ring();
    uint8_t f[100] = {1}, out[CAP + 1];
    df_error e;
    uint64_t p = df_shm_writer_append(&W, f, sizeof f);
    assert_int_equal(df_shm_ring_read(b, CAP, p, 0, out, &e), DF_EFORMAT);
    assert_int_equal(df_shm_ring_read(b, CAP, p, CAP + 1, out, &e), DF_EFORMAT);
    assert_int_equal(df_shm_ring_read(b, CAP, CAP - 10, 100, out, &e), DF_EFORMAT); /* would wrap */
    assert_int_equal(df_shm_ring_read(b, CAP, p, 101, out, &e), DF_EFORMAT);  /* beyond head */
    assert_non_null(strstr(e.msg, "not written"));
    assert_int_equal(df_shm_ring_read(b, CAP, 200, 10, out, &e), DF_EFORMAT); /* never written */
    assert_int_equal(df_shm_ring_read(b, CAP, p, 100, out, &e), DF_OK);
    /* The writer keeps its own state: a scribbled header neither moves nor breaks it. */
    memset(b + 16, 0xFF, 32); /* capacity, session, valid_from, head */
    assert_true(df_shm_writer_append(&W, f, sizeof f) == 100);
    assert_true(df_le64_load(b + 40) == 200);
    free(b);
}

/* A reader that copied a frame while the writer lapped onto it must not return it: simulated by
 * raising valid_from between the pre-check and the post-check (what a concurrent append does
 * before touching the bytes), through a ring that is written in the middle of a "copy". */
static void test_overwrite_during_copy_is_lost(void **state)
{
    (void)state;
    uint8_t *b = new_ring();
    uint8_t f[4000], out[4000];
    df_error e;
    fill(f, sizeof f, 1);
    uint64_t p0 = df_shm_writer_append(&W, f, sizeof f);
    assert_int_equal(df_shm_ring_read(b, CAP, p0, sizeof f, out, &e), DF_OK);
    /* Two more laps' worth of frames: every earlier position is below valid_from. */
    for (int k = 0; k < 6; k++) df_shm_writer_append(&W, f, sizeof f);
    assert_true(df_le64_load(b + 32) > p0);
    assert_int_equal(df_shm_ring_read(b, CAP, p0, sizeof f, out, &e), DF_ENOTFOUND);
    /* valid_from only grows, and positions are never reused: the newest frame reads back. */
    uint64_t head = df_le64_load(b + 40);
    assert_int_equal(df_shm_ring_read(b, CAP, head - sizeof f, sizeof f, out, &e), DF_OK);
    assert_memory_equal(out, f, sizeof f);
    free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_header_layout_and_check),
        cmocka_unit_test(test_append_read_round_trip_and_no_wrap),
        cmocka_unit_test(test_bad_references),
        cmocka_unit_test(test_overwrite_during_copy_is_lost),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

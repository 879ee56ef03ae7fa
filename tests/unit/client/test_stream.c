/* Unit tests for the displacement-stream helpers of libdeformclient: df_client_disp_apply,
 * df_client_positions and the version-tracking replica fed with frames encoded by proto/. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "client/deformclient.h"

static df_msg_disp dense(uint64_t version, uint64_t base, uint8_t kind, uint32_t nv, uint32_t off,
                         uint32_t count, float *xyz)
{
    df_msg_disp d;
    memset(&d, 0, sizeof d);
    d.session_id = 7;
    d.version = version;
    d.base_version = base;
    d.kind = kind;
    d.encoding = DF_DISP_DENSE;
    d.nv = nv;
    d.total = nv;
    d.offset = off;
    d.count = count;
    d.xyz = xyz;
    return d;
}

static void test_apply_dense_and_sparse(void **state)
{
    (void)state;
    float u[12] = {0};
    float rows[6] = {1, 2, 3, 4, 5, 6};
    df_msg_disp d = dense(1, 0, DF_CHANGE_BRUSH, 4, 1, 2, rows);
    df_error e;
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_OK);
    const float want[12] = {0, 0, 0, 1, 2, 3, 4, 5, 6, 0, 0, 0};
    assert_memory_equal(u, want, sizeof want);
    int32_t idx[2] = {0, 3};
    float sv[6] = {-1, -2, -3, 7, 8, 9};
    df_msg_disp s = d;
    s.encoding = DF_DISP_SPARSE;
    s.total = 2;
    s.offset = 0;
    s.count = 2;
    s.idx = idx;
    s.xyz = sv;
    assert_int_equal(df_client_disp_apply(&s, u, 4, &e), DF_OK);
    const float want2[12] = {-1, -2, -3, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    assert_memory_equal(u, want2, sizeof want2);
}

static void test_apply_rejects_bad_chunks_untouched(void **state)
{
    (void)state;
    float u[12], keep[12];
    for (int i = 0; i < 12; i++)
        u[i] = keep[i] = (float)i;
    float rows[6] = {1, 2, 3, 4, 5, 6};
    df_error e;
    df_msg_disp d = dense(1, 0, DF_CHANGE_BRUSH, 4, 3, 2, rows);
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_EINVAL); /* rows 3..4 of 4 */
    d = dense(1, 0, DF_CHANGE_BRUSH, 5, 0, 2, rows);
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_EINVAL); /* nv mismatch */
    assert_string_equal(e.msg, "disp apply: frame has 5 vertices, replica 4");
    rows[4] = NAN;
    d = dense(1, 0, DF_CHANGE_BRUSH, 4, 0, 2, rows);
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_EINVAL);
    assert_string_equal(e.msg, "disp apply: row 1 has a non-finite value");
    rows[4] = 5;
    int32_t idx[2] = {1, 4};
    d.encoding = DF_DISP_SPARSE;
    d.total = 2;
    d.idx = idx;
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_EINVAL);
    assert_string_equal(e.msg, "disp apply: row 1 index 4 outside 0..3");
    d.encoding = 9;
    assert_int_equal(df_client_disp_apply(&d, u, 4, &e), DF_EINVAL);
    assert_memory_equal(u, keep, sizeof keep);
}

static void test_positions_float32(void **state)
{
    (void)state;
    const float base[3] = {0.1f, 1e8f, -3.0f};
    const float u[3] = {0.2f, 1.0f, 0.5f};
    float out[3];
    df_client_positions(base, u, 1, out);
    volatile float a = 0.1f, b = 0.2f;
    float want0 = a + b;
    assert_memory_equal(&out[0], &want0, sizeof(float));
    assert_true(out[1] == 1e8f); /* 1e8 + 1 rounds back to 1e8 in float32 */
    assert_true(out[2] == -2.5f);
}

/* Encodes `d` (or a progress wrapping it) as a frame: *h and the payload in b. */
static void frame_of(const df_msg_disp *d, uint16_t type, uint16_t flags, df_frame_header *h,
                     df_buf *b)
{
    df_buf_reset(b);
    df_error e;
    if (type == DF_MSG_PROGRESS) {
        df_msg_progress p;
        memset(&p, 0, sizeof p);
        p.status = DF_MOVE_CONVERGED;
        p.final = 1;
        p.iteration = 12;
        p.objective = 1.5;
        p.residual = 1e-12;
        p.disp = *d;
        assert_int_equal(df_msg_progress_encode(&p, b, &e), DF_OK);
    } else {
        assert_int_equal(df_msg_disp_encode(d, b, &e), DF_OK);
    }
    df_frame_header t = {DF_FRAME_MAGIC, DF_PROTO_VERSION, type, flags, 0, 0, (uint32_t)b->len};
    *h = t;
}

static void test_replica_versions_chunks_gaps_snapshot(void **state)
{
    (void)state;
    const float base[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    df_client_replica r;
    df_error e;
    assert_int_equal(df_client_replica_init(&r, 7, 3, base, NULL, 0, &e), DF_OK);
    df_buf b;
    df_buf_init(&b);
    df_frame_header h;
    /* version 1 in two chunks: rows 0..1 then row 2 */
    float c1[6] = {0.5f, 0, 0, 0, 0.25f, 0};
    float c2[3] = {0, 0, -1};
    df_msg_disp d = dense(1, 0, DF_CHANGE_BRUSH, 3, 0, 2, c1);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT | DF_FLAG_MORE, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 0);
    assert_int_equal(r.version, 0);
    d = dense(1, 0, DF_CHANGE_BRUSH, 3, 2, 1, c2);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 1);
    assert_int_equal(r.version, 1);
    float pos[9];
    df_client_replica_positions(&r, pos);
    const float want[9] = {0.5f, 0, 0, 1, 0.25f, 0, 0, 1, -1};
    assert_memory_equal(pos, want, sizeof want);
    /* another session's frame is ignored */
    d.session_id = 8;
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 0);
    /* a gap: version 3 from 2 while at 1 */
    float z[9] = {0};
    d = dense(3, 2, DF_CHANGE_BRUSH, 3, 0, 3, z);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), DF_ESTATE);
    assert_int_equal(r.stale, 1);
    assert_string_equal(e.msg, "stream: version 3 applies to 2, replica is at 1");
    /* a snapshot of version 3 resyncs */
    float s3[9] = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    d = dense(3, 0, DF_CHANGE_SNAPSHOT, 3, 0, 3, s3);
    frame_of(&d, DF_MSG_SNAPSHOT, DF_FLAG_REPLY, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 1);
    assert_int_equal(r.stale, 0);
    assert_int_equal(r.version, 3);
    assert_memory_equal(r.u, s3, sizeof s3);
    /* an old version is skipped; a progress iterate (sparse) applies */
    d = dense(3, 2, DF_CHANGE_BRUSH, 3, 0, 3, z);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 0);
    int32_t idx[1] = {1};
    float sv[3] = {-4, 0, 0};
    d = dense(4, 3, DF_CHANGE_HANDLE_MOVE, 3, 0, 1, sv);
    d.encoding = DF_DISP_SPARSE;
    d.total = 1;
    d.idx = idx;
    frame_of(&d, DF_MSG_PROGRESS, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 1);
    assert_int_equal(r.version, 4);
    assert_true(r.u[3] == -4 && r.u[4] == 0 && r.u[0] == 1 && r.u[8] == 3);
    /* reset rest: sparse, total 0, positions unchanged, version advances */
    d = dense(5, 4, DF_CHANGE_RESET_REST, 3, 0, 0, NULL);
    d.encoding = DF_DISP_SPARSE;
    d.total = 0;
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), 1);
    assert_int_equal(r.version, 5);
    assert_int_equal(r.versions_applied, 4);
    /* a chunk out of order marks the replica stale */
    d = dense(6, 5, DF_CHANGE_BRUSH, 3, 1, 2, c1);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), DF_EFORMAT);
    assert_int_equal(r.stale, 1);
    /* a truncated payload is rejected */
    d = dense(6, 5, DF_CHANGE_BRUSH, 3, 0, 3, z);
    frame_of(&d, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, &h, &b);
    h.payload_len -= 4;
    assert_int_equal(df_client_replica_feed(&r, &h, b.data, &e), DF_EPROTO_TRUNCATED);
    df_buf_free(&b);
    df_client_replica_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_apply_dense_and_sparse),
        cmocka_unit_test(test_apply_rejects_bad_chunks_untouched),
        cmocka_unit_test(test_positions_float32),
        cmocka_unit_test(test_replica_versions_chunks_gaps_snapshot),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

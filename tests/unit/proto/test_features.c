/* test_features.c — feature bits advertise only what exists: DF_FEAT_ALL (what this build
 * implements, what libdeformclient announces) lacks the reserved bit 6 (HID, withdrawn until it
 * lands); a hello_reply carrying bit 6 still decodes and re-encodes (compatible both ways), any
 * other unknown bit is refused. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"

static df_msg_hello_reply reply(uint32_t features)
{
    df_msg_hello_reply r;
    memset(&r, 0, sizeof r);
    r.version = r.server_max_version = 1;
    r.features = features;
    r.max_frame_payload = DF_MAX_FRAME_PAYLOAD;
    r.max_mesh_vertices = DF_MAX_MESH_VERTICES;
    r.max_mesh_elements = DF_MAX_MESH_ELEMENTS;
    r.max_pending_requests = DF_MAX_PENDING_REQUESTS;
    r.max_sessions = DF_MAX_SESSIONS;
    r.max_mesh_bytes = DF_MAX_MESH_BYTES;
    r.max_client_queue_bytes = 1u << 20;
    strcpy(r.server_name, "t");
    return r;
}

static void test_all_lacks_the_reserved_bit(void **state)
{
    (void)state;
    assert_int_equal(DF_FEAT_ALL & DF_FEAT_RESERVED, 0);
    assert_int_equal(DF_FEAT_RESERVED, 1u << 6);
    assert_int_equal(DF_FEAT_ALL, 0xBFu);
    assert_int_equal(DF_FEAT_DECODE_MASK, 0xFFu);
}

static void test_reserved_bit_decodes_other_unknown_bits_do_not(void **state)
{
    (void)state;
    df_error e;
    df_buf b;
    df_buf_init(&b);
    df_msg_hello_reply r = reply(DF_FEAT_ALL | DF_FEAT_RESERVED), out;
    assert_int_equal(df_msg_hello_reply_encode(&r, &b, &e), DF_OK);
    assert_int_equal(df_msg_hello_reply_decode(b.data, b.len, &out, &e), DF_OK);
    assert_int_equal(out.features, DF_FEAT_ALL | DF_FEAT_RESERVED);
    df_buf_free(&b);
    df_buf_init(&b);
    r = reply(DF_FEAT_KELVINLET | (1u << 8));
    assert_int_equal(df_msg_hello_reply_encode(&r, &b, &e), DF_EINVAL);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_lacks_the_reserved_bit),
        cmocka_unit_test(test_reserved_bit_decodes_other_unknown_bits_do_not),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

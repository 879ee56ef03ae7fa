/* test_features.c — feature bits advertise only what exists: DF_FEAT_ALL (what this build
 * implements, what libdeformclient announces) has bit 6 again (HID, withdrawn while it did not
 * exist; decoders always accepted it, so older clients keep working with a daemon that sets
 * it); a hello_reply carrying it decodes and re-encodes, any other unknown bit is refused. */
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

static void test_hid_is_bit_6_again(void **state)
{
    (void)state;
    assert_int_equal(DF_FEAT_HID, 1u << 6);
    assert_int_equal(DF_FEAT_ALL & DF_FEAT_HID, DF_FEAT_HID);
    assert_int_equal(DF_FEAT_ALL, 0xFFu);
    assert_int_equal(DF_FEAT_DECODE_MASK, 0xFFu);
}

static void test_hid_bit_decodes_other_unknown_bits_do_not(void **state)
{
    (void)state;
    df_error e;
    df_buf b;
    df_buf_init(&b);
    df_msg_hello_reply r = reply(DF_FEAT_KELVINLET | DF_FEAT_HID), out;
    assert_int_equal(df_msg_hello_reply_encode(&r, &b, &e), DF_OK);
    assert_int_equal(df_msg_hello_reply_decode(b.data, b.len, &out, &e), DF_OK);
    assert_int_equal(out.features, DF_FEAT_KELVINLET | DF_FEAT_HID);
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
        cmocka_unit_test(test_hid_is_bit_6_again),
        cmocka_unit_test(test_hid_bit_decodes_other_unknown_bits_do_not),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

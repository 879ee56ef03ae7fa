/* Unit tests for proto/frame.c, proto/buf.c and the error body: header round trips, every
 * malformed header (bad magic, version, reserved, flags, length 0, length 4 GiB, truncation at
 * every offset), frame begin/end, error frames, error code names. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"

static df_frame_header sample(void)
{
    df_frame_header h = {DF_FRAME_MAGIC, DF_PROTO_VERSION, DF_MSG_BRUSH_UPDATE,
                         DF_FLAG_REPLY | DF_FLAG_MORE, 0, 0x0102030405060708ull, 136};
    return h;
}

static void test_header_layout_and_round_trip(void **state)
{
    (void)state;
    df_frame_header h = sample(), d;
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    df_error e;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    const uint8_t want[24] = {'D', 'F', 'M', 'D', 1, 0, 0x21, 0, 0x09, 0, 0, 0,
                              8, 7, 6, 5, 4, 3, 2, 1, 136, 0, 0, 0};
    assert_memory_equal(raw, want, 24);
    memset(&d, 0xAB, sizeof d);
    assert_int_equal(df_frame_header_decode(raw, sizeof raw, &d, &e), DF_OK);
    assert_int_equal(d.magic, DF_FRAME_MAGIC);
    assert_int_equal(d.version, 1);
    assert_int_equal(d.type, DF_MSG_BRUSH_UPDATE);
    assert_int_equal(d.flags, DF_FLAG_REPLY | DF_FLAG_MORE);
    assert_int_equal(d.reserved, 0);
    assert_true(d.request_id == 0x0102030405060708ull);
    assert_int_equal(d.payload_len, 136);
}

static int decode_mutated(size_t off, uint8_t byte, df_frame_header *d, df_error *e)
{
    df_frame_header h = sample();
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    assert_int_equal(df_frame_header_encode(&h, raw, NULL), DF_OK);
    raw[off] = byte;
    return df_frame_header_decode(raw, sizeof raw, d, e);
}

static void test_header_rejections(void **state)
{
    (void)state;
    df_frame_header d;
    df_error e;
    memset(&d, 0, sizeof d);
    assert_int_equal(decode_mutated(0, 'X', &d, &e), DF_EPROTO_BADMAGIC);
    assert_non_null(strstr(e.msg, "magic"));
    assert_int_equal(d.magic, 0); /* not filled on bad magic */
    assert_int_equal(decode_mutated(4, 2, &d, &e), DF_EPROTO_BADVERSION);
    assert_int_equal(decode_mutated(4, 0, &d, &e), DF_EPROTO_BADVERSION);
    assert_int_equal(decode_mutated(10, 1, &d, &e), DF_EPROTO_RESERVED);
    assert_int_equal(d.request_id, 0x0102030405060708ull); /* filled: reply can echo it */
    assert_int_equal(decode_mutated(11, 0x80, &d, &e), DF_EPROTO_RESERVED);
    assert_int_equal(decode_mutated(8, 0x10, &d, &e), DF_EPROTO_BADFLAGS);
    assert_int_equal(decode_mutated(9, 0x01, &d, &e), DF_EPROTO_BADFLAGS);
    assert_int_equal(decode_mutated(8, DF_FLAG_REPLY | DF_FLAG_EVENT, &d, &e), DF_EPROTO_BADFLAGS);
    assert_int_equal(decode_mutated(8, DF_FLAG_ERROR, &d, &e), DF_EPROTO_BADFLAGS);
    /* ERROR alone is fine on type DF_MSG_ERROR */
    df_frame_header h = {DF_FRAME_MAGIC, 1, DF_MSG_ERROR, DF_FLAG_ERROR, 0, 0, 10};
    uint8_t raw[24];
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    assert_int_equal(df_frame_header_decode(raw, 24, &d, &e), DF_OK);
    /* unknown types are not a header error */
    h.type = 0x7777;
    h.flags = 0;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    assert_int_equal(df_frame_header_decode(raw, 24, &d, &e), DF_OK);
    assert_int_equal(df_msg_type_valid(d.type), 0);
}

static void test_payload_length_limits(void **state)
{
    (void)state;
    df_frame_header h = sample(), d;
    uint8_t raw[24];
    df_error e;
    h.payload_len = 0;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    assert_int_equal(df_frame_header_decode(raw, 24, &d, &e), DF_OK);
    assert_int_equal(d.payload_len, 0);
    h.payload_len = DF_MAX_FRAME_PAYLOAD;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    assert_int_equal(df_frame_header_decode(raw, 24, &d, &e), DF_OK);
    h.payload_len = DF_MAX_FRAME_PAYLOAD + 1;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_EPROTO_TOOLARGE);
    /* 4 GiB - 1 written by hand */
    h.payload_len = 16;
    assert_int_equal(df_frame_header_encode(&h, raw, &e), DF_OK);
    memset(raw + 20, 0xFF, 4);
    assert_int_equal(df_frame_header_decode(raw, 24, &d, &e), DF_EPROTO_TOOLARGE);
    assert_non_null(strstr(e.msg, "4294967295"));
    assert_true(df_frame_error_is_fatal(DF_EPROTO_TOOLARGE));
    assert_true(df_frame_error_is_fatal(DF_EPROTO_BADMAGIC));
    assert_true(df_frame_error_is_fatal(DF_EPROTO_BADVERSION));
    assert_false(df_frame_error_is_fatal(DF_EPROTO_RESERVED));
    assert_false(df_frame_error_is_fatal(DF_EPROTO_BADFLAGS));
}

static void test_truncated_header_every_offset(void **state)
{
    (void)state;
    df_frame_header h = sample(), d;
    uint8_t raw[24];
    assert_int_equal(df_frame_header_encode(&h, raw, NULL), DF_OK);
    for (size_t n = 0; n < 24; n++) {
        uint8_t *heap = malloc(n ? n : 1);
        memcpy(heap, raw, n);
        memset(&d, 0x5A, sizeof d);
        df_error e;
        assert_int_equal(df_frame_header_decode(heap, n, &d, &e), DF_EPROTO_TRUNCATED);
        assert_int_equal(d.magic, 0x5A5A5A5A);
        free(heap);
    }
}

static void test_begin_end_and_rollback(void **state)
{
    (void)state;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    size_t s;
    assert_int_equal(df_frame_begin(&b, 0, 0, 1, &s, &e), DF_EPROTO_BADTYPE);
    assert_int_equal(df_frame_begin(&b, DF_MSG_PING, 0x40, 1, &s, &e), DF_EPROTO_BADFLAGS);
    assert_int_equal(b.len, 0);
    assert_int_equal(df_frame_begin(&b, DF_MSG_PING, 0, 77, &s, &e), DF_OK);
    const uint8_t payload[5] = {1, 2, 3, 4, 5};
    df_msg_ping pm = {5, payload};
    assert_int_equal(df_msg_ping_encode(&pm, &b, &e), DF_OK);
    assert_int_equal(df_frame_end(&b, s, &e), DF_OK);
    assert_int_equal(b.len, 29);
    df_frame_header d;
    assert_int_equal(df_frame_header_decode(b.data, b.len, &d, &e), DF_OK);
    assert_int_equal(d.payload_len, 5);
    assert_true(d.request_id == 77);
    /* a second frame appended after the first */
    size_t s2;
    assert_int_equal(df_frame_begin(&b, DF_MSG_LIST_SESSIONS, 0, 78, &s2, &e), DF_OK);
    assert_int_equal(s2, 29);
    assert_int_equal(df_frame_end(&b, s2, &e), DF_OK);
    assert_int_equal(df_frame_header_decode(b.data + s2, 24, &d, &e), DF_OK);
    assert_int_equal(d.payload_len, 0);
    assert_int_equal(df_frame_end(&b, 3, &e), DF_EINVAL);
    assert_int_equal(df_frame_end(&b, 1000, &e), DF_EINVAL);
    /* oversize payload rolls back */
    size_t s3;
    assert_int_equal(df_frame_begin(&b, DF_MSG_PING, 0, 79, &s3, &e), DF_OK);
    assert_int_equal(df_buf_reserve(&b, DF_MAX_FRAME_PAYLOAD + 1, &e), DF_OK);
    memset(b.data + b.len, 0, DF_MAX_FRAME_PAYLOAD + 1);
    b.len += DF_MAX_FRAME_PAYLOAD + 1;
    assert_int_equal(df_frame_end(&b, s3, &e), DF_EPROTO_TOOLARGE);
    assert_int_equal(b.len, s3);
    df_buf_free(&b);
    assert_null(b.data);
}

static void test_buf_little_endian_and_overflow(void **state)
{
    (void)state;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_buf_reserve(&b, 30, &e), DF_OK);
    df_buf_put_u16(&b, 0xBEEF);
    df_buf_put_u32(&b, 0x11223344u);
    df_buf_put_u64(&b, 0x8877665544332211ull);
    df_buf_put_f32(&b, 1.0f);
    df_buf_put_f64(&b, -2.0);
    const uint8_t want[] = {0xEF, 0xBE, 0x44, 0x33, 0x22, 0x11, 0x11, 0x22, 0x33, 0x44, 0x55,
                            0x66, 0x77, 0x88, 0x00, 0x00, 0x80, 0x3F, 0, 0, 0, 0, 0, 0, 0, 0xC0};
    assert_int_equal(b.len, sizeof want);
    assert_memory_equal(b.data, want, sizeof want);
    assert_int_equal(df_le16_load(want), 0xBEEF);
    assert_true(df_le64_load(want + 6) == 0x8877665544332211ull);
    size_t len = b.len;
    assert_int_equal(df_buf_reserve(&b, SIZE_MAX - 3, &e), DF_ELIMIT);
    assert_int_equal(b.len, len);
    df_buf_reset(&b);
    assert_int_equal(b.len, 0);
    assert_true(b.cap >= 26);
    df_buf_free(&b);
}

static void test_error_body_and_frame(void **state)
{
    (void)state;
    df_buf b;
    df_buf_init(&b);
    df_error e, got;
    assert_int_equal(df_msg_error_frame(&b, DF_MSG_UNDO, 9, DF_ENOTFOUND, &e, "no session %d", 12),
                     DF_OK);
    const uint8_t want[43] = {0x44, 0x46, 0x4d, 0x44, 1, 0, 0x33, 0, 5, 0, 0, 0, 9, 0, 0, 0, 0, 0,
                              0, 0, 19, 0, 0, 0, 0xf9, 0xff, 0xff, 0xff, 13, 0, 'n', 'o', ' ',
                              's', 'e', 's', 's', 'i', 'o', 'n', ' ', '1', '2'};
    assert_int_equal(b.len, 43);
    assert_memory_equal(b.data, want, 43);
    assert_int_equal(df_msg_error_decode(b.data + 24, 19, &got, &e), DF_OK);
    assert_int_equal(got.code, DF_ENOTFOUND);
    assert_string_equal(got.msg, "no session 12");
    /* connection-level error: type ERROR, id 0, flags ERROR only */
    df_buf_reset(&b);
    assert_int_equal(df_msg_error_frame(&b, 0x9999, 0, DF_EPROTO_BADMAGIC, &e, "bad"), DF_OK);
    df_frame_header h;
    assert_int_equal(df_frame_header_decode(b.data, b.len, &h, &e), DF_OK);
    assert_int_equal(h.type, DF_MSG_ERROR);
    assert_int_equal(h.flags, DF_FLAG_ERROR);
    /* invalid codes are refused by the body codec */
    df_error bad = {5, "x"};
    assert_int_equal(df_msg_error_encode(&bad, &b, &e), DF_EINVAL);
    const uint8_t code0[] = {0, 0, 0, 0, 0, 0};
    assert_int_equal(df_msg_error_decode(code0, 6, &got, &e), DF_EINVAL);
    const uint8_t nul[] = {0xff, 0xff, 0xff, 0xff, 2, 0, 'a', 0};
    assert_int_equal(df_msg_error_decode(nul, 8, &got, &e), DF_EINVAL);
    const uint8_t longmsg[] = {0xff, 0xff, 0xff, 0xff, 0, 1};
    assert_int_equal(df_msg_error_decode(longmsg, 6, &got, &e), DF_ELIMIT);
    /* long messages are truncated to DF_MAX_ERROR_MSG_LEN on encode */
    df_error big;
    big.code = DF_EINVAL;
    memset(big.msg, 'z', sizeof big.msg - 1);
    big.msg[sizeof big.msg - 1] = '\0';
    df_buf_reset(&b);
    assert_int_equal(df_msg_error_encode(&big, &b, &e), DF_OK);
    assert_int_equal(b.len, 6 + DF_MAX_ERROR_MSG_LEN);
    df_buf_free(&b);
}

static void test_error_names(void **state)
{
    (void)state;
    assert_string_equal(df_proto_error_name(DF_EPROTO_TRUNCATED), "EPROTO_TRUNCATED");
    assert_string_equal(df_proto_error_name(DF_EPROTO_CHUNK), "EPROTO_CHUNK");
    assert_string_equal(df_proto_error_name(DF_ESTATE), "ESTATE");
    assert_string_equal(df_proto_error_name(-55), "EUNKNOWN");
    int valid = 0;
    for (int c = -200; c <= 0; c++)
        valid += df_proto_error_valid(c);
    assert_int_equal(valid, 13 + 11); /* DF_EINVAL .. DF_EMOVED, EPROTO_* */
    assert_string_equal(df_proto_error_name(DF_EEXIST), "EEXIST");
    assert_string_equal(df_proto_error_name(DF_EMOVED), "EMOVED");
    assert_string_equal(df_msg_type_name(DF_MSG_HANDLES_MOVE), "handles_move");
    assert_string_equal(df_msg_type_name(0x1234), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_header_layout_and_round_trip),
        cmocka_unit_test(test_header_rejections),
        cmocka_unit_test(test_payload_length_limits),
        cmocka_unit_test(test_truncated_header_every_offset),
        cmocka_unit_test(test_begin_end_and_rollback),
        cmocka_unit_test(test_buf_little_endian_and_overflow),
        cmocka_unit_test(test_error_body_and_frame),
        cmocka_unit_test(test_error_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

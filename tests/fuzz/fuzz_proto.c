/* fuzz_proto.c — libFuzzer target for the wire format (proto/). For every input:
 *  1. decode it as a frame header; if that succeeds, decode the (possibly short) payload as the
 *     body that (type, flags) selects;
 *  2. run every body decoder on the whole input;
 *  3. oracle: whenever a decoder accepts bytes, re-encoding the decoded message must reproduce
 *     exactly those bytes (decoders and encoders agree on every field), and decoded values must
 *     pass the encoder's validation (no NaN, no out-of-range index ever escapes a decoder).
 * Seeds: tests/fuzz/corpus/proto (tests/fuzz/gen_proto_corpus.c writes them). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"

/* Decodes p[0..n) as (type, flags); on success checks the re-encoding oracle. */
static void check(uint16_t type, uint16_t flags, const uint8_t *p, size_t n)
{
    df_msg_any m;
    df_error e;
    if (df_msg_any_decode(type, flags, p, n, &m, &e) != DF_OK) {
        if (e.code >= 0 || e.msg[0] == '\0')
            abort(); /* every failure must carry a code and a message */
        return;
    }
    df_buf out;
    df_buf_init(&out);
    if (df_msg_any_encode(&m, &out, &e) != DF_OK || out.len != n || (n && memcmp(out.data, p, n)))
        abort();
    df_buf_free(&out);
    df_msg_any_free(&m);
}

/* One representative (type, flags) per body kind. */
static const uint16_t kinds[][2] = {
    {DF_MSG_UNDO, DF_FLAG_REPLY | DF_FLAG_ERROR}, {DF_MSG_HELLO, 0},
    {DF_MSG_HELLO, DF_FLAG_REPLY}, {DF_MSG_AUTH, 0}, {DF_MSG_AUTH, DF_FLAG_REPLY},
    {DF_MSG_PING, 0}, {DF_MSG_LOAD_MESH, 0}, {DF_MSG_UNDO, 0}, {DF_MSG_OPEN_SESSION, 0},
    {DF_MSG_SUBSCRIBE, 0}, {DF_MSG_SUBSCRIBE, DF_FLAG_REPLY}, {DF_MSG_LIST_SESSIONS, DF_FLAG_REPLY},
    {DF_MSG_UNDO, DF_FLAG_REPLY}, {DF_MSG_BRUSH_BEGIN, 0}, {DF_MSG_BRUSH_UPDATE, 0},
    {DF_MSG_SET_BRUSH_PARAM, 0}, {DF_MSG_HANDLES_SET, 0}, {DF_MSG_HANDLES_MOVE, 0},
    {DF_MSG_HANDLES_MOVE, DF_FLAG_REPLY}, {DF_MSG_GET_MESH, 0}, {DF_MSG_GET_MESH, DF_FLAG_REPLY},
    {DF_MSG_SNAPSHOT, 0}, {DF_MSG_DISPLACEMENT, DF_FLAG_EVENT}, {DF_MSG_PROGRESS, DF_FLAG_EVENT},
    {DF_MSG_STATS, 0}, {DF_MSG_STATS, DF_FLAG_REPLY}, {DF_MSG_STREAM_SHM, DF_FLAG_REPLY},
    {DF_MSG_SHM_REF, DF_FLAG_EVENT},
    /* devices (HID) */
    {DF_MSG_DEVICE_STATE, DF_FLAG_EVENT}, {DF_MSG_DEVICES_LIST, DF_FLAG_REPLY},
    {DF_MSG_DEVICE_BIND, 0}, {DF_MSG_DEVICE_VIEW, 0},
    /* per-session access */
    {DF_MSG_SESSION_ACCESS, 0}, {DF_MSG_JOIN, 0}, {DF_MSG_SESSION_ACCESS, DF_FLAG_REPLY},
    /* session peers */
    {DF_MSG_SESSION_PEERS, DF_FLAG_REPLY},
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    df_frame_header h;
    df_error e;
    int rc = df_frame_header_decode(data, size, &h, &e);
    if (rc == DF_OK) {
        uint8_t raw[DF_FRAME_HEADER_SIZE];
        if (df_frame_header_encode(&h, raw, &e) != DF_OK || memcmp(raw, data, sizeof raw))
            abort();
        size_t n = size - DF_FRAME_HEADER_SIZE;
        if (n > h.payload_len)
            n = h.payload_len;
        df_body_kind k;
        if (df_msg_body_kind(h.type, h.flags, &k, &e) == DF_OK)
            check(h.type, h.flags, data + DF_FRAME_HEADER_SIZE, n);
    } else if (rc >= 0 || e.msg[0] == '\0') {
        abort();
    }
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        check(kinds[i][0], kinds[i][1], data, size);
    return 0;
}

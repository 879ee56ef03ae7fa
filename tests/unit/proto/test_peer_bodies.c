/* test_peer_bodies.c — SESSION_PEERS bodies (proto/msg_peers.c, PROTOCOL.md 4.38): the decoded
 * fields of the samples, the body kinds, the encoder's refusals and malformed payloads (each
 * refused with its code and message, the output untouched). The generic round trips,
 * truncations and trailing bytes of the samples run in test_messages.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "tests/unit/proto/proto_samples.h"

static sample S[N_SAMPLES];

static int setup(void **state)
{
    (void)state;
    build_samples(S);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free_samples(S);
    return 0;
}

static const sample *find(const char *name)
{
    for (int i = 0; i < N_SAMPLES; i++)
        if (!strcmp(S[i].name, name)) return &S[i];
    fail_msg("no sample %s", name);
    return NULL;
}

/* Decodes sample `name` with `len` bytes at `off` replaced by `patch` (little-endian value of
 * `len` bytes); checks the code, the message substring and that the output is untouched. */
static void patched(const char *name, size_t off, uint64_t v, size_t len, int code,
                    const char *needle)
{
    const sample *s = find(name);
    assert_true(off + len <= s->payload.len);
    uint8_t *p = malloc(s->payload.len);
    memcpy(p, s->payload.data, s->payload.len);
    for (size_t i = 0; i < len; i++) p[off + i] = (uint8_t)(v >> (8 * i));
    df_msg_any m, orig;
    memset(&m, 0xA5, sizeof m);
    memcpy(&orig, &m, sizeof m);
    df_error e = {0, ""};
    int rc = df_msg_any_decode(s->type, s->flags, p, s->payload.len, &m, &e);
    if (rc == DF_OK) df_msg_any_free(&m);
    if (rc != code || (needle && !strstr(e.msg, needle)))
        fail_msg("%s patched at %zu: rc %d (%s), want %d containing \"%s\"", name, off, rc,
                 e.msg, code, needle ? needle : "");
    if (code != DF_OK) assert_memory_equal(&m, &orig, sizeof m);
    free(p);
}

static void test_peer_list_fields(void **state)
{
    (void)state;
    const sample *s = find("peer_list");
    df_msg_peer_list l;
    df_error e;
    assert_int_equal(df_msg_peer_list_decode(s->payload.data, s->payload.len, &l, &e), DF_OK);
    assert_int_equal(l.count, 2);
    assert_true(l.items[0].client_id == 3 && l.items[1].client_id == 41);
    assert_int_equal(l.items[0].flags, DF_PEER_EDIT | DF_PEER_SHM);
    assert_int_equal(l.items[1].flags, DF_PEER_SELF);
    assert_int_equal(l.items[0].transport, DF_TRANSPORT_UNIX);
    assert_int_equal(l.items[1].transport, DF_TRANSPORT_TCP);
    assert_string_equal(l.items[0].name, "blender");
    assert_string_equal(l.items[0].principal, "uid:1000");
    assert_string_equal(l.items[1].name, "");
    assert_string_equal(l.items[1].principal, "key:bob");
    /* wire size: u32 count + per row 12 fixed bytes + two u16-length strings */
    size_t want = 4 + (12 + 2 + strlen("blender") + 2 + strlen("uid:1000")) +
                  (12 + 2 + 0 + 2 + strlen("key:bob"));
    assert_int_equal(s->payload.len, want);
    /* one row on its own encodes as its bytes inside the list */
    df_buf b;
    df_buf_init(&b);
    assert_int_equal(df_msg_peer_info_encode(&l.items[0], &b, &e), DF_OK);
    assert_memory_equal(b.data, s->payload.data + 4, b.len);
    df_msg_peer_info one;
    assert_int_equal(df_msg_peer_info_decode(b.data, b.len, &one, &e), DF_OK);
    assert_string_equal(one.principal, "uid:1000");
    df_buf_free(&b);
    df_msg_peer_list_free(&l);
    assert_null(l.items);
    const sample *z = find("peer_list_empty");
    assert_int_equal(z->payload.len, 4);
    assert_int_equal(df_msg_peer_list_decode(z->payload.data, 4, &l, &e), DF_OK);
    assert_int_equal(l.count, 0);
    assert_null(l.items);
}

static void test_peer_body_kinds(void **state)
{
    (void)state;
    df_body_kind k;
    df_error e;
    assert_int_equal(DF_MSG_SESSION_PEERS, 0x0019);
    assert_string_equal(df_msg_type_name(DF_MSG_SESSION_PEERS), "session_peers");
    assert_int_equal(df_msg_body_kind(DF_MSG_SESSION_PEERS, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_SESSION_REF);
    assert_int_equal(df_msg_body_kind(DF_MSG_SESSION_PEERS, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_PEER_LIST);
    assert_int_equal(df_msg_body_kind(DF_MSG_SESSION_PEERS, DF_FLAG_EVENT, &k, &e),
                     DF_EPROTO_BADTYPE);
}

static void test_peer_encoder_refusals(void **state)
{
    (void)state;
    df_msg_peer_info row;
    memset(&row, 0, sizeof row);
    row.client_id = 1;
    row.transport = DF_TRANSPORT_TCP;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    df_msg_peer_list big = {DF_MAX_PEERS + 1, &row}; /* count checked before any item */
    assert_int_equal(df_msg_peer_list_encode(&big, &b, &e), DF_ELIMIT);
    df_msg_peer_list one = {1, &row};
    row.client_id = 0;
    assert_int_equal(df_msg_peer_list_encode(&one, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "client_id 0"));
    row.client_id = 1;
    row.flags = 0x08;
    assert_int_equal(df_msg_peer_list_encode(&one, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "flag"));
    row.flags = 0;
    row.transport = 3;
    assert_int_equal(df_msg_peer_list_encode(&one, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "transport 3"));
    row.transport = DF_TRANSPORT_UNIX;
    memset(row.principal, 'p', DF_MAX_NAME_LEN + 1); /* no terminator within the limit */
    assert_int_equal(df_msg_peer_list_encode(&one, &b, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "principal"));
    assert_int_equal(b.len, 0); /* nothing written on error */
    df_buf_free(&b);
}

/* peer_list offsets: 0 count; row 0 at 4: 4 client_id, 12 flags, 13 transport, 14 reserved,
 * 16 name length (7, "blender"), 25 principal length */
static void test_peer_malformed(void **state)
{
    (void)state;
    patched("peer_list", 0, DF_MAX_PEERS + 1, 4, DF_ELIMIT, "peers");
    patched("peer_list", 0, 3, 4, DF_EPROTO_TRUNCATED, NULL);
    patched("peer_list", 0, 1, 4, DF_EPROTO_TRAILING, NULL);
    patched("peer_list", 4, 0, 8, DF_EINVAL, "client_id 0");
    patched("peer_list", 12, 0x10, 1, DF_EINVAL, "unknown flag bits 0x10");
    patched("peer_list", 13, 0, 1, DF_EINVAL, "transport 0");
    patched("peer_list", 13, 3, 1, DF_EINVAL, "transport 3");
    patched("peer_list", 14, 1, 2, DF_EPROTO_RESERVED, NULL);
    patched("peer_list", 16, 0xFFFF, 2, DF_ELIMIT, "name: string of 65535 bytes");
    patched("peer_list", 16, 255, 2, DF_EPROTO_TRUNCATED, NULL);
    /* name length 8 takes the principal length's low byte: its length is then 'u' << 8 */
    patched("peer_list", 16, 8, 2, DF_ELIMIT, "principal: string of 29952 bytes");
    patched("peer_list", 18, 0, 1, DF_EINVAL, NULL);           /* a NUL inside the name */
    patched("peer_list", 12, DF_PEER_SELF | DF_PEER_EDIT | DF_PEER_SHM, 1, DF_OK, NULL);
    patched("peer_list_empty", 0, 1, 4, DF_EPROTO_TRUNCATED, NULL);
    patched("session_peers", 0, 0, 8, DF_EINVAL, "session_id");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_peer_list_fields),
        cmocka_unit_test(test_peer_body_kinds),
        cmocka_unit_test(test_peer_encoder_refusals),
        cmocka_unit_test(test_peer_malformed),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

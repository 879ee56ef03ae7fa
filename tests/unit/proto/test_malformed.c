/* Unit tests: every malformed field value we could think of, per body, patched into a valid
 * encoding at its documented offset (PROTOCOL.md section 4). Each must fail with the listed code
 * and a message naming the problem, leave the output untouched, and the encoder must refuse the
 * same bad value. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "proto/messages.h"
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
        if (!strcmp(S[i].name, name))
            return &S[i];
    fail_msg("no sample %s", name);
    return NULL;
}

/* Copies sample `name`, overwrites `len` bytes at `off` (or truncates/extends the payload to
 * `off` when patch is NULL), decodes and checks code, message substring, untouched output. */
static void expect(const char *name, size_t off, const void *patch, size_t len, int code,
                   const char *needle)
{
    const sample *s = find(name);
    size_t n = patch ? s->payload.len : off;
    uint8_t *p = calloc(n > s->payload.len ? n : s->payload.len, 1);
    memcpy(p, s->payload.data, s->payload.len);
    if (patch) {
        assert_true(off + len <= n);
        memcpy(p + off, patch, len);
    }
    df_msg_any m, orig;
    memset(&m, 0xA5, sizeof m);
    memcpy(&orig, &m, sizeof m);
    df_error e = {0, ""};
    int rc = df_msg_any_decode(s->type, s->flags, p, n, &m, &e);
    if (rc == DF_OK)
        df_msg_any_free(&m);
    if (rc != code || (needle && !strstr(e.msg, needle)))
        fail_msg("%s patched at %zu: rc %d (%s), want %d containing \"%s\"", name, off, rc,
                 e.msg, code, needle ? needle : "");
    if (code != DF_OK) {
        assert_int_equal(e.code, code);
        assert_memory_equal(&m, &orig, sizeof m);
    }
    free(p);
}

static void u8(const char *name, size_t off, uint8_t v, int code, const char *needle)
{
    expect(name, off, &v, 1, code, needle);
}

static void u16(const char *name, size_t off, uint16_t v, int code, const char *needle)
{
    uint8_t b[2];
    df_le16_store(b, v);
    expect(name, off, b, 2, code, needle);
}

static void u32(const char *name, size_t off, uint32_t v, int code, const char *needle)
{
    uint8_t b[4];
    df_le32_store(b, v);
    expect(name, off, b, 4, code, needle);
}

static void u64(const char *name, size_t off, uint64_t v, int code, const char *needle)
{
    uint8_t b[8];
    df_le64_store(b, v);
    expect(name, off, b, 8, code, needle);
}

static void f64(const char *name, size_t off, double v, int code, const char *needle)
{
    uint8_t b[8];
    memcpy(b, &v, 8);
    expect(name, off, b, 8, code, needle);
}

static void f32(const char *name, size_t off, float v, int code, const char *needle)
{
    uint8_t b[4];
    memcpy(b, &v, 4);
    expect(name, off, b, 4, code, needle);
}

static void test_handshake_bodies(void **state)
{
    (void)state;
    u16("hello", 0, 0, DF_EINVAL, "versions");
    u16("hello", 2, 0, DF_EINVAL, "versions");
    u16("hello", 8, 300, DF_ELIMIT, "client_name");
    u8("hello", 10, 0, DF_EINVAL, "NUL");
    u16("hello", 8, 200, DF_EPROTO_TRUNCATED, "client_name");
    u16("hello_reply", 0, 2, DF_EINVAL, "version 2");
    u32("hello_reply", 4, 1u << 20, DF_EINVAL, "feature");
    u32("hello_reply", 8, DF_MAX_FRAME_PAYLOAD + 1, DF_EINVAL, "max_frame_payload");
    u32("hello_reply", 20, 0, DF_EINVAL, "pending");
    u8("hello_reply", 44, 2, DF_EINVAL, "auth_required");
    u8("hello_reply", 45, 1, DF_EPROTO_RESERVED, "reserved");
    u16("auth", 2, 1, DF_EPROTO_RESERVED, "reserved");
    u32("auth", 4, DF_MAX_AUTH_TOKEN + 1, DF_ELIMIT, "token_len");
    u32("auth", 4, 0xFFFFFFFFu, DF_ELIMIT, "token_len");
    u32("auth", 4, 5, DF_EPROTO_TRUNCATED, "token");
    u32("auth", 4, 3, DF_EPROTO_TRAILING, "trailing");
    /* ping: length limit only */
    uint8_t *big = calloc(DF_MAX_PING_BYTES + 1, 1);
    df_msg_ping pm;
    df_error e;
    assert_int_equal(df_msg_ping_decode(big, DF_MAX_PING_BYTES, &pm, &e), DF_OK);
    assert_int_equal(pm.len, DF_MAX_PING_BYTES);
    assert_int_equal(df_msg_ping_decode(big, DF_MAX_PING_BYTES + 1, &pm, &e), DF_ELIMIT);
    df_msg_ping toolong = {DF_MAX_PING_BYTES + 1, big};
    df_buf b;
    df_buf_init(&b);
    assert_int_equal(df_msg_ping_encode(&toolong, &b, &e), DF_ELIMIT);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
    free(big);
}

static void test_load_mesh_bodies(void **state)
{
    (void)state;
    /* inline sample: total/part2/offset at 4/12/20, name at 28 ("tri": 5 bytes), path len at 33,
     * data_len at 35, data at 39 */
    u8("load_mesh", 0, 2, DF_EINVAL, "source");
    u8("load_mesh", 1, 6, DF_EINVAL, "format 6");
    /* options: bit 0 EXT, bit 1 2D, bit 2 PROGRESS; any other bit is EPROTO_RESERVED */
    u16("load_mesh", 2, 0xE, DF_EPROTO_RESERVED, "unknown bits 0x8");
    u16("load_mesh", 2, 8, DF_EPROTO_RESERVED, "unknown bits 0x8");
    u16("load_mesh", 2, 0x8000, DF_EPROTO_RESERVED, "unknown bits 0x8000");
    u16("load_mesh", 2, DF_LOAD_OPT_2D, DF_OK, NULL);          /* 2D alone: same layout */
    u16("load_mesh", 2, DF_LOAD_OPT_PROGRESS, DF_OK, NULL);    /* PROGRESS: same layout */
    u16("load_mesh", 2, DF_LOAD_OPT_EXT, DF_EPROTO_TRUNCATED, "file_name"); /* EXT needs it */
    u16("load_path_2d", 2, 0, DF_OK, NULL);
    u16("load_path_2d", 2, 6, DF_OK, NULL);                    /* 2D | PROGRESS */
    u16("load_path_2d", 2, 0xE, DF_EPROTO_RESERVED, "unknown bits 0x8");
    u16("load_mesh_ext", 2, 0, DF_EPROTO_TRAILING, NULL);  /* file_name without the EXT option */
    u16("load_mesh_ext", 2, 3, DF_OK, NULL);                   /* EXT | 2D */
    u16("load_mesh_ext", 2, 2, DF_EPROTO_TRAILING, NULL);      /* 2D without EXT: trailing */
    u16("load_mesh_ext", 2, 5, DF_OK, NULL);                   /* EXT | PROGRESS */
    u16("load_mesh_ext", 2, 9, DF_EPROTO_RESERVED, "unknown bits 0x8");
    /* load_reply: session_info "bunny" is 43 bytes, then format 43, index_base 44, reserved 45 */
    u8("load_reply", 43, 0, DF_EINVAL, "format");
    u8("load_reply", 43, 6, DF_EINVAL, "format");
    u8("load_reply", 44, 2, DF_EINVAL, "index_base");
    u16("load_reply", 45, 1, DF_EPROTO_RESERVED, "reserved");
    u8("load_reply", 16, 4, DF_EINVAL, "kind 4");
    u64("load_mesh", 4, 0, DF_ELIMIT, "total_size");
    u64("load_mesh", 4, DF_MAX_MESH_BYTES + 1, DF_ELIMIT, "total_size");
    u64("load_mesh", 4, 10, DF_EINVAL, "chunk");
    u64("load_mesh", 20, 1, DF_EINVAL, "chunk");
    u64("load_mesh", 20, UINT64_MAX, DF_EINVAL, "chunk");
    u64("load_mesh", 12, 5, DF_EINVAL, "part2_offset");
    u8("load_mesh", 1, DF_FMT_TETGEN, DF_EINVAL, "part2_offset");
    u32("load_mesh", 35, 0, DF_EPROTO_TRAILING, NULL);
    u32("load_mesh", 35, 0xFFFFFFFFu, DF_EPROTO_TRUNCATED, "data");
    u16("load_mesh", 33, 1, DF_EPROTO_TRUNCATED, NULL);
    /* path sample: name "spot" 6 bytes at 28, path length at 34 */
    u16("load_path", 34, 0, DF_EPROTO_TRUNCATED, "data"); /* path bytes read as data_len */
    u16("load_path", 34, DF_MAX_PATH_LEN + 1, DF_ELIMIT, "path");
    u64("load_path", 4, 10, DF_EINVAL, "path load");
    u8("load_path", 0, DF_LOAD_INLINE, DF_EINVAL, "must not carry a path");
    u8("load_path", 40, 0, DF_EINVAL, "NUL");
    /* encoder refuses a path load without a path and an inline load with a NULL chunk */
    df_buf b;
    df_buf_init(&b);
    df_error e;
    df_msg_load_mesh lp = {DF_LOAD_PATH, 0, "", NULL, 0, 0, 0, 0, NULL, 0, ""};
    assert_int_equal(df_msg_load_mesh_encode(&lp, &b, &e), DF_EINVAL);
    df_msg_load_mesh li = {DF_LOAD_INLINE, 0, "", NULL, 10, 0, 0, 10, NULL, 0, ""};
    assert_int_equal(df_msg_load_mesh_encode(&li, &b, &e), DF_EINVAL);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
}

static void test_session_bodies(void **state)
{
    (void)state;
    u64("session_ref", 0, 0, DF_EINVAL, "session_id 0");
    u64("handles_get", 0, 0, DF_EINVAL, "session_id 0");
    u64("open_session", 0, 5, DF_EINVAL, "not both");
    u16("open_session", 8, 0, DF_EPROTO_TRAILING, NULL);
    u32("subscribe", 8, 4, DF_EINVAL, "flag");
    u32("subscribe", 8, 2, DF_EPROTO_TRUNCATED, "from_version"); /* flag without its field */
    u32("subscribe_from", 8, 3, DF_EINVAL, "exclusive");
    u32("subscribe_from", 8, 0, DF_EPROTO_TRAILING, NULL); /* field without its flag */
    u64("subscribe", 0, 0, DF_EINVAL, "session_id");
    u8("session_info", 16, 4, DF_EINVAL, "kind 4");
    u8("session_info", 16, 0, DF_EINVAL, "kind 0");
    u8("session_info", 17, 2, DF_EINVAL, "planar");
    u32("session_info", 20, 0, DF_ELIMIT, "nv 0");
    u32("session_info", 20, DF_MAX_MESH_VERTICES + 1, DF_ELIMIT, "nv");
    u32("session_info", 24, DF_MAX_MESH_ELEMENTS + 1, DF_ELIMIT, "ne");
    u32("session_list", 0, 3, DF_EPROTO_TRUNCATED, NULL);
    u32("session_list", 0, 1, DF_EPROTO_TRAILING, NULL);
    u32("session_list", 0, DF_MAX_SESSIONS + 1, DF_ELIMIT, "count");
    u32("session_list", 0, 0xFFFFFFFFu, DF_ELIMIT, "count");
    u8("session_list", 4 + 16, 9, DF_EINVAL, "kind 9"); /* first item's kind */
    u64("ack", 0, 0, DF_EINVAL, "session_id");
    u32("get_mesh", 8, 4, DF_EINVAL, "flag");
    u64("snapshot_req", 0, 0, DF_EINVAL, "session_id");
    u32("stats", 0, DF_MAX_STATS_ENTRIES + 1, DF_ELIMIT, "count");
    u32("stats", 0, 4, DF_EPROTO_TRUNCATED, NULL);
    u8("stats", 6, 'S', DF_EINVAL, "outside");          /* "sessions" -> "Sessions" */
    u16("stats", 4, 0, DF_EINVAL, "length 0");
    u16("stats", 4, DF_MAX_STATS_KEY_LEN + 1, DF_ELIMIT, "key");
    f64("stats", 4 + 2 + 8, NAN, DF_EINVAL, "finite");
    f64("stats", 4 + 2 + 8, -INFINITY, DF_EINVAL, "finite");
    u64("stream_shm", 0, 0, DF_EINVAL, "session_id 0");
    u64("shm_info", 0, 0, DF_EINVAL, "session_id 0");
    u64("shm_info", 8, 4095, DF_EINVAL, "capacity");
    u64("shm_info", 8, (4ull << 30) + 1, DF_EINVAL, "capacity");
    u32("shm_info", 16, 23, DF_EINVAL, "frame bounds");      /* min below a header */
    u32("shm_info", 16, 40000, DF_EINVAL, "frame bounds");   /* min above max */
    u32("shm_info", 20, 65537, DF_EINVAL, "frame bounds");   /* max above capacity */
    u8("shm_info", 26, 'r', DF_EINVAL, "absolute");          /* "/run..." -> "rrun..." */
    u16("shm_info", 24, 0, DF_EPROTO_TRAILING, NULL);        /* empty path, bytes left over */
    u16("shm_info", 24, 200, DF_EPROTO_TRUNCATED, NULL);
    u64("shm_ref", 0, 0, DF_EINVAL, "session_id 0");
    u32("shm_ref", 16, 23, DF_EINVAL, "shorter than a frame header");
    u32("shm_ref", 20, 1, DF_EPROTO_RESERVED, "reserved");
    u32("move_result", 0, 0, DF_EINVAL, "session_id");
    u8("move_result", 16, DF_MOVE_RUNNING, DF_EINVAL, "status 0");
    u8("move_result", 16, 5, DF_EINVAL, "status 5");
    f64("move_result", 21, NAN, DF_EINVAL, "objective");
    f64("move_result", 29, -1, DF_EINVAL, "residual");
    f64("move_result", 37, INFINITY, DF_EINVAL, "elapsed");
}

static void test_brush_bodies(void **state)
{
    (void)state;
    u64("brush", 0, 0, DF_EINVAL, "session_id");
    u8("brush", 8, 0, DF_EINVAL, "type 0");
    u8("brush", 8, 6, DF_EINVAL, "type 6");
    u8("brush", 9, 1, DF_EINVAL, "dim 1");
    u8("brush", 10, 0, DF_EINVAL, "falloff 0");
    u8("brush", 10, 9, DF_EINVAL, "falloff 9");
    u8("brush", 10, 8, DF_OK, NULL);
    u8("brush", 11, 3, DF_EINVAL, "integrator 3");
    u16("brush", 12, 0, DF_EINVAL, "steps 0");
    u16("brush", 12, DF_MAX_BRUSH_STEPS + 1, DF_EINVAL, "steps 1025");
    u8("brush", 14, 2, DF_EINVAL, "moving 2");
    u8("brush", 15, 7, DF_EINVAL, "has_mirror 7");
    f64("brush", 16, 0, DF_EINVAL, "radius 0");
    f64("brush", 16, -1, DF_EINVAL, "radius -1");
    f64("brush", 16, NAN, DF_EINVAL, "radius");
    f64("brush", 16, INFINITY, DF_EINVAL, "radius inf");
    f64("brush", 24, 1.0, DF_EINVAL, "ratio 1");
    f64("brush", 32, NAN, DF_EINVAL, "nu is NaN");
    f64("brush", 32, -INFINITY, DF_OK, NULL);
    f64("brush", 32, 1e300, DF_OK, NULL);
    f64("brush", 40, INFINITY, DF_EINVAL, "strength");
    f64("brush", 48 + 16, NAN, DF_EINVAL, "center");
    f64("brush", 72, NAN, DF_EINVAL, "move");
    f64("brush", 96 + 8, -INFINITY, DF_EINVAL, "twist");
    f64("brush", 120, NAN, DF_EINVAL, "scale");
    f64("brush", 128 + 64, NAN, DF_EINVAL, "matrix");
    f64("brush", 200, INFINITY, DF_EINVAL, "mirror_point");
    f64("brush", 224, 0, DF_EINVAL, "zero vector"); /* normal (1,0,0) -> (0,0,0) */
    u32("brush", 248, 1, DF_EPROTO_TRAILING, NULL);
    u32("brush", 248, 3, DF_EPROTO_TRUNCATED, "n_pinned");
    u32("brush", 248, DF_MAX_PINNED_POINTS + 1, DF_ELIMIT, "n_pinned");
    u32("brush", 248, 0xFFFFFFFFu, DF_ELIMIT, "n_pinned");
    f64("brush", 253 + 40, NAN, DF_EINVAL, "pinned");
    u8("brush", 252, 0, DF_EINVAL, "pin_flags 0");
    u8("brush", 252, 4, DF_EINVAL, "pin_flags 4");
    f64("brush_update", 8 + 16, NAN, DF_EINVAL, "move");
    f64("brush_update", 56, INFINITY, DF_EINVAL, "scale");
    f64("brush_update", 64 + 8 * 8, NAN, DF_EINVAL, "matrix");
    u64("brush_update", 0, 0, DF_EINVAL, "session_id");
    /* brush_param: param at 8, value at 9 */
    u8("brush_param", 8, 0, DF_EINVAL, "param 0");
    u8("brush_param", 8, 6, DF_EINVAL, "param 6");
    f64("brush_param", 9, NAN, DF_EINVAL, "nu is NaN");
    uint8_t rad_neg[9] = {DF_BP_RADIUS};
    double v = -0.5;
    memcpy(rad_neg + 1, &v, 8);
    expect("brush_param", 8, rad_neg, 9, DF_EINVAL, "radius -0.5");
    uint8_t fo[9] = {DF_BP_FALLOFF};
    v = 2.5;
    memcpy(fo + 1, &v, 8);
    expect("brush_param", 8, fo, 9, DF_EINVAL, "falloff 2.5");
    v = 9;
    memcpy(fo + 1, &v, 8);
    expect("brush_param", 8, fo, 9, DF_EINVAL, "falloff 9");
    v = 8;
    memcpy(fo + 1, &v, 8);
    expect("brush_param", 8, fo, 9, DF_OK, NULL);
    uint8_t ra[9] = {DF_BP_RATIO};
    v = 0.5;
    memcpy(ra + 1, &v, 8);
    expect("brush_param", 8, ra, 9, DF_EINVAL, "ratio");
    uint8_t stn[9] = {DF_BP_STRENGTH};
    v = INFINITY;
    memcpy(stn + 1, &v, 8);
    expect("brush_param", 8, stn, 9, DF_EINVAL, "strength");
    /* encoder side: same rules */
    df_msg_brush br = sample_brush();
    df_buf b;
    df_buf_init(&b);
    df_error e;
    br.nu = NAN;
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_EINVAL);
    br = sample_brush();
    br.pinned = NULL;
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_EINVAL);
    br = sample_brush();
    br.n_pinned = DF_MAX_PINNED_POINTS + 1;
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_ELIMIT);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
}

/* Session brush (PROTOCOL.md 4.12 use_session, 4.14a-c), offsets per the tables there. */
static void test_brush_state_bodies(void **state)
{
    (void)state;
    const size_t trailer = 253 + 24 * 2; /* brush_use_session: 2 pinned points */
    u16("brush_use_session", trailer, 0x100, DF_EPROTO_RESERVED, "use_session");
    u16("brush_use_session", trailer, 0, DF_OK, NULL);       /* explicit 0 = absent */
    u16("brush_use_session", trailer, 0xFF, DF_OK, NULL);    /* every field */
    /* options after use_session (PROTOCOL.md 4.12): bit 0 PROGRESS, the others reserved */
    u32("brush_progress", trailer + 2, 2, DF_EPROTO_RESERVED, "unknown bits 0x2");
    u32("brush_progress", trailer + 2, 0, DF_OK, NULL);
    /* the surface byte after options (issue 14): 0/1, anything else EINVAL */
    u8("brush_surface", trailer + 6, 2, DF_EINVAL, "surface");
    u8("brush_surface", trailer + 6, 0, DF_OK, NULL);
    u8("brush_surface", trailer + 6, 1, DF_OK, NULL);
    /* brush_state_set: mask at 8, values at 10 (sample mask RADIUS | INTEGRATOR | MIRROR) */
    u64("brush_state_set", 0, 0, DF_EINVAL, "session_id");
    u16("brush_state_set", 8, 0, DF_EINVAL, "mask 0");
    u16("brush_state_set", 8, 0x102, DF_EPROTO_RESERVED, "0x100");
    f64("brush_state_set", 16, 0, DF_EINVAL, "radius 0");
    u8("brush_state_set", 12, 3, DF_EINVAL, "integrator 3");
    u16("brush_state_set", 14, 0, DF_EINVAL, "steps 0");
    u16("brush_state_set", 14, DF_MAX_BRUSH_STEPS + 1, DF_EINVAL, "steps 1025");
    u8("brush_state_set", 13, 2, DF_EINVAL, "has_mirror 2");
    f64("brush_state_set", 48, NAN, DF_EINVAL, "mirror_point");
    f64("brush_state_set", 72, 0, DF_EINVAL, "zero vector");
    /* fields the mask leaves out are carried unchecked */
    u8("brush_state_set", 10, 0, DF_OK, NULL);               /* type */
    u8("brush_state_set", 11, 0, DF_OK, NULL);               /* falloff */
    f64("brush_state_set", 24, NAN, DF_OK, NULL);            /* nu */
    f64("brush_state_set", 32, INFINITY, DF_OK, NULL);       /* strength */
    f64("brush_state_set", 40, 0.5, DF_OK, NULL);            /* ratio */
    u16("brush_state_set", 8, DF_BS_NU, DF_OK, NULL);        /* nu 0.5: valid */
    u16("brush_state_set", 8, DF_BS_RATIO, DF_OK, NULL);
    expect("brush_state_set", 95, NULL, 0, DF_EPROTO_TRUNCATED, NULL);
    /* brush_state event: origin_name "Surface Dial" (12 bytes) at 27, values at 41 */
    u64("brush_state_event", 0, 0, DF_EINVAL, "session_id");
    u16("brush_state_event", 16, 0x200, DF_EPROTO_RESERVED, "changed");
    u8("brush_state_event", 18, 3, DF_EINVAL, "origin_kind 3");
    u16("brush_state_event", 27, 200, DF_EPROTO_TRUNCATED, NULL);
    u8("brush_state_event", 41, 0, DF_EINVAL, "type 0");   /* every field is checked */
    u8("brush_state_event", 42, 9, DF_EINVAL, "falloff 9");
    f64("brush_state_event", 47, -1, DF_EINVAL, "radius -1");
    f64("brush_state_event", 55, NAN, DF_EINVAL, "nu");
    f64("brush_state_event", 55, -INFINITY, DF_OK, NULL);
    f64("brush_state_event", 63, NAN, DF_EINVAL, "strength");
    f64("brush_state_event", 71, 1, DF_EINVAL, "ratio 1");
    expect("brush_state_event", 41, NULL, 0, DF_EPROTO_TRUNCATED, NULL);
    /* brush_cursor: kind 8, id 9, flags 17, center 18, radius 42 */
    u64("brush_cursor", 0, 0, DF_EINVAL, "session_id");
    u8("brush_cursor", 8, 3, DF_EINVAL, "origin_kind 3");
    u8("brush_cursor", 17, 4, DF_EPROTO_RESERVED, "flags");
    u8("brush_cursor", 17, DF_CURSOR_IN_RANGE | DF_CURSOR_STROKE_ACTIVE, DF_OK, NULL);
    f64("brush_cursor", 18 + 8, NAN, DF_EINVAL, "center");
    f64("brush_cursor", 42, 0, DF_EINVAL, "radius 0");
    f64("brush_cursor", 42, INFINITY, DF_EINVAL, "radius");
    /* encoder side: same rules */
    df_buf b;
    df_buf_init(&b);
    df_error e;
    df_msg_brush br = sample_brush();
    br.use_session = 0x8000;
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_EPROTO_RESERVED);
    df_msg_brush_state_set set = {1, 0, {0}};
    df_msg_brush_values_defaults(&set.v);
    assert_int_equal(df_msg_brush_state_set_encode(&set, &b, &e), DF_EINVAL);
    set.mask = DF_BS_RADIUS;
    set.v.radius = -1;
    assert_int_equal(df_msg_brush_state_set_encode(&set, &b, &e), DF_EINVAL);
    df_msg_brush_cursor cur = {1, DF_ORIGIN_DEVICE, 2, 0, {0, 0, NAN}, 1};
    assert_int_equal(df_msg_brush_cursor_encode(&cur, &b, &e), DF_EINVAL);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
}

static void test_handle_bodies(void **state)
{
    (void)state;
    u8("handles", 8, 0, DF_EINVAL, "energy 0");
    /* the optional trailing options (PROTOCOL.md 4.15, 4.16): bit 0 PROGRESS, others reserved */
    u32("handles_progress", 193, 2, DF_EPROTO_RESERVED, "unknown bits 0x2");
    u32("handles_progress", 193, 0, DF_OK, NULL); /* an explicit 0: as if absent */
    u32("handle_move_progress", 120, 0x80000001u, DF_EPROTO_RESERVED, "unknown bits 0x80000000");
    u32("handle_move_progress", 120, 0, DF_OK, NULL);
    /* work_progress (4.37): stage at 8, final at 9, reserved at 10, done 12, total 20, ms 28 */
    u8("work_progress", 8, 0, DF_EINVAL, "stage 0");
    u8("work_progress", 8, 200, DF_OK, NULL); /* a stage newer than this build still decodes */
    u8("work_progress", 9, 2, DF_EINVAL, "final 2");
    u16("work_progress", 10, 1, DF_EPROTO_RESERVED, NULL);
    u32("work_progress", 12, 0xFFFFFFFFu, DF_EINVAL, "exceeds total");
    f64("work_progress", 28, NAN, DF_EINVAL, "elapsed_ms");
    f64("work_progress", 28, -1, DF_EINVAL, "elapsed_ms");
    u8("handles_reply", 8, 0, DF_EINVAL, "energy 0");   /* HANDLES_GET reply: same rules */
    u32("handles_reply", 92 + 4, DF_MAX_MESH_VERTICES, DF_EINVAL, "out of range");
    f64("handles_reply", 28, NAN, DF_EINVAL, "rho");
    u32("handles_reply", 108, 2, DF_EPROTO_TRUNCATED, NULL);
    u8("handles", 8, 6, DF_EINVAL, "energy 6");
    u8("handles", 9, 2, DF_EINVAL, "area_weighting 2");
    u8("handles", 10, 2, DF_EINVAL, "accelerate 2");
    u8("handles", 11, 0, DF_EINVAL, "anderson_m 0");
    u8("handles", 11, DF_MAX_ANDERSON + 1, DF_EINVAL, "anderson_m 21");
    f64("handles", 12, -1, DF_EINVAL, "w -1");
    f64("handles", 20, 0, DF_EINVAL, "s 0");
    f64("handles", 28, NAN, DF_EINVAL, "rho");
    f64("handles", 28, -1, DF_EINVAL, "rho -1");
    f64("handles", 28, 0, DF_OK, NULL); /* rho 0: the solver's adaptive penalty */
    f64("handles", 36, -1e-3, DF_EINVAL, "tol");
    f64("handles", 44, 0, DF_EINVAL, "youngs 0");
    f64("handles", 52, 0.5, DF_EINVAL, "poisson 0.5");
    f64("handles", 52, NAN, DF_EINVAL, "poisson");
    f64("handles", 60, 1.5, DF_EINVAL, "strain limits");
    f64("handles", 68, 0.95, DF_EINVAL, "strain limits");
    f64("handles", 68, INFINITY, DF_EINVAL, "strain limits");
    f64("handles", 76, -1, DF_EINVAL, "bending");
    u32("handles", 84, 0, DF_EINVAL, "max_iters 0");
    u32("handles", 84, DF_MAX_MOVE_ITERS + 1, DF_EINVAL, "max_iters");
    u32("handles", 88, 0, DF_EPROTO_TRAILING, NULL);
    u32("handles", 88, DF_MAX_HANDLES + 1, DF_ELIMIT, "n_handles");
    u32("handles", 88, 1000, DF_EPROTO_TRUNCATED, "count 1000");
    u32("handles", 92 + 4, DF_MAX_MESH_VERTICES, DF_EINVAL, "out of range");
    u32("handles", 92 + 4, 0x80000000u, DF_EINVAL, "out of range");
    u32("handles", 108, DF_MAX_AFFINE_SETS + 1, DF_ELIMIT, "n_affine");
    u32("handles", 108, 2, DF_EPROTO_TRUNCATED, NULL);
    u32("handles", 108, 0, DF_EPROTO_TRAILING, NULL);
    u8("handles", 112, 0, DF_EINVAL, "rows");
    u8("handles", 112, 4, DF_EINVAL, "rows");
    f64("handles", 113 + 8, NAN, DF_EINVAL, "affine.A");
    f64("handles", 161 + 8, INFINITY, DF_EINVAL, "affine.b");
    u32("handles", 177, 0, DF_EPROTO_TRAILING, NULL);
    u32("handles", 181 + 8, 0xFFFFFFFFu, DF_EINVAL, "out of range");
    /* handle_move: max_iters 8, n_targets 20, targets 24 */
    u32("handle_move", 8, DF_MAX_MOVE_ITERS + 1, DF_EINVAL, "max_iters");
    u32("handle_move", 20, 0, DF_EPROTO_TRAILING, NULL);
    u32("handle_move", 20, 5, DF_EPROTO_TRUNCATED, "n_targets");
    u32("handle_move", 20, 0xFFFFFFFFu, DF_ELIMIT, "n_targets");
    f64("handle_move", 24 + 8 * 7, NAN, DF_EINVAL, "targets");
    f64("handle_move", 24, -INFINITY, DF_EINVAL, "targets");
}

static void test_stream_bodies(void **state)
{
    (void)state;
    /* disp: version 8, base 16, kind 24, encoding 25, reserved 26, nv 28, total 32, offset 36,
     * count 40, rows 44 */
    u64("disp_sparse", 0, 0, DF_EINVAL, "session_id");
    u64("disp_sparse", 8, 10, DF_EINVAL, "inconsistent");
    u64("disp_sparse", 16, 11, DF_EINVAL, "inconsistent");
    u8("disp_sparse", 24, 0, DF_EINVAL, "kind 0");
    u8("disp_sparse", 24, 8, DF_EINVAL, "kind 8");
    u8("disp_sparse", 24, DF_CHANGE_SNAPSHOT, DF_EINVAL, "snapshot");
    u8("disp_sparse", 25, 3, DF_EINVAL, "encoding 3");
    u16("disp_sparse", 26, 1, DF_EPROTO_RESERVED, "reserved");
    u32("disp_sparse", 28, 0, DF_ELIMIT, "nv 0");
    u32("disp_sparse", 28, DF_MAX_MESH_VERTICES + 1, DF_ELIMIT, "nv");
    u32("disp_sparse", 28, 4, DF_EINVAL, "total 5");
    u32("disp_sparse", 36, 3, DF_EINVAL, "outside total");
    u32("disp_sparse", 40, 4, DF_EINVAL, "outside total");
    u32("disp_sparse", 40, 2, DF_EPROTO_TRAILING, NULL);
    u32("disp_sparse", 32, 100, DF_OK, NULL);
    u32("disp_sparse", 44 + 16, 100, DF_EINVAL, "out of range");
    u32("disp_sparse", 44 + 16, 2, DF_EINVAL, "not increasing");
    u32("disp_sparse", 44 + 32, 40, DF_EINVAL, "not increasing");
    f32("disp_sparse", 44 + 16 + 8, NAN, DF_EINVAL, "must be finite");
    f32("disp_sparse", 44 + 4, INFINITY, DF_EINVAL, "must be finite");
    u32("disp_dense", 32, 4, DF_EINVAL, "dense");
    u32("disp_dense", 40, 4, DF_EPROTO_TRAILING, NULL);
    u32("disp_dense", 40, 0xFFFFFFFFu, DF_EINVAL, "outside total");
    f32("disp_dense", 44 + 12 * 4 + 8, -INFINITY, DF_EINVAL, "row 4 component 2");
    u8("disp_dense", 25, DF_DISP_SPARSE, DF_EPROTO_TRUNCATED, "count");
    /* a snapshot has base 0 and any version, including 0 */
    uint8_t snap[17] = {0};
    snap[16] = DF_CHANGE_SNAPSHOT;
    expect("disp_dense", 8, snap, 17, DF_OK, NULL);
    /* progress: status 0, final 1, reserved 2, iteration 4, objective 8, residual 16,
     * elapsed 24, disp at 32 */
    u8("progress", 0, DF_MOVE_CONVERGED, DF_EINVAL, "final 0");
    u8("progress", 1, 1, DF_EINVAL, "final 1");
    u8("progress", 0, 5, DF_EINVAL, "status 5");
    u16("progress", 2, 9, DF_EPROTO_RESERVED, "reserved");
    f64("progress", 8, NAN, DF_EINVAL, "objective");
    f64("progress", 16, -1, DF_EINVAL, "residual");
    u8("progress", 32 + 24, DF_CHANGE_BRUSH, DF_EINVAL, "handle_move");
    uint8_t fin[2] = {DF_MOVE_BUDGET, 1};
    expect("progress", 0, fin, 2, DF_OK, NULL);
    /* mesh_chunk: kind 16, planar 17, section 18, reserved 19, nv 20, ne 24, nf 28, offset 32,
     * count 36, rows 40 */
    u8("mesh_chunk_xyz", 16, 0, DF_EINVAL, "kind 0");
    u8("mesh_chunk_xyz", 17, 3, DF_EINVAL, "planar");
    u8("mesh_chunk_xyz", 18, 0, DF_EINVAL, "section 0");
    u8("mesh_chunk_xyz", 18, 6, DF_EINVAL, "section 6");
    u8("mesh_chunk_xyz", 19, 1, DF_EPROTO_RESERVED, "reserved");
    u32("mesh_chunk_xyz", 20, 4, DF_EINVAL, "outside section");
    u32("mesh_chunk_xyz", 20, 0, DF_ELIMIT, "nv 0");
    u32("mesh_chunk_xyz", 32, 4, DF_EINVAL, "outside section");
    f32("mesh_chunk_xyz", 40 + 4, NAN, DF_EINVAL, "vertex 3 component 1");
    u8("mesh_chunk_xyz", 18, DF_SECTION_FACES, DF_EINVAL, "outside section");
    u32("mesh_chunk_elem", 28, 3, DF_OK, NULL);
    u8("mesh_chunk_elem", 16, 2, DF_EPROTO_TRAILING, NULL); /* triangles: 3 indices per row */
    u32("mesh_chunk_elem", 40 + 4 * 7, 5, DF_EINVAL, "index 5 out of range");
    u32("mesh_chunk_elem", 40, 0xFFFFFFFFu, DF_EINVAL, "out of range");
    uint8_t tri_nf[16] = {2 /* triangle */, 0, DF_SECTION_ELEMENTS, 0};
    df_le32_store(tri_nf + 4, 5);
    df_le32_store(tri_nf + 8, 2);
    df_le32_store(tri_nf + 12, 2);
    expect("mesh_chunk_elem", 16, tri_nf, 16, DF_EINVAL, "non-tet");
}

/* devices (HID): device_info at offsets 0 id, 8 class, 9 backend, 10 state, 32 haptics, 33
 * name; device_list = u32 count + items; bind 0 device; view 0 device, 8 session, 16 matrix,
 * 144 viewport */
static void test_device_bodies(void **state)
{
    (void)state;
    u64("device_state", 0, 0, DF_EINVAL, "device_id 0");
    u8("device_state", 8, 4, DF_EINVAL, "class 4");
    u8("device_state", 9, 0, DF_EINVAL, "backend 0");
    u8("device_state", 9, 4, DF_EINVAL, "backend 4");
    u8("device_state", 10, 0, DF_EINVAL, "state 0");
    u8("device_state", 10, 5, DF_EINVAL, "state 5");
    u8("device_state", 32, 2, DF_EINVAL, "haptics 2");
    u8("device_state", 35, 0, DF_EINVAL, "NUL");               /* in the name */
    u16("device_state", 33, DF_MAX_NAME_LEN + 1, DF_ELIMIT, "name");
    u16("device_state", 33, 200, DF_EPROTO_TRUNCATED, NULL);
    u8("device_state", 11, 0xff, DF_OK, NULL);                 /* any bus */
    u32("device_list", 0, DF_MAX_DEVICES + 1, DF_ELIMIT, "limit");
    u32("device_list", 0, 3, DF_EPROTO_TRUNCATED, NULL);
    u32("device_list", 0, 1, DF_EPROTO_TRAILING, NULL);
    u64("device_list", 4, 0, DF_EINVAL, "device_id 0");
    u64("device_bind", 0, 0, DF_EINVAL, "device_id 0");
    u64("device_bind", 8, 0, DF_OK, NULL);                     /* 0 = unbind */
    u64("device_view", 0, 0, DF_EINVAL, "device_id 0");
    u64("device_view", 8, 0, DF_EINVAL, "session_id 0");
    f64("device_view", 16 + 8 * 5, NAN, DF_EINVAL, "view_proj");
    f64("device_view", 144 + 8, INFINITY, DF_EINVAL, "viewport");
    f64("device_view", 144 + 16, 0, DF_EINVAL, "width");
    f64("device_view", 144 + 24, -1, DF_EINVAL, "height");
}

/* per-session access: session_access, join, access_info (PROTOCOL.md 4.35, 4.36) */
static void test_access_bodies(void **state)
{
    (void)state;
    u64("session_access", 0, 0, DF_EINVAL, "session_id 0");
    u8("session_access", 8, 4, DF_EINVAL, "mode 4");
    u8("session_access", 9, 3, DF_EINVAL, "observers 3");
    u8("session_access", 10, 2, DF_EINVAL, "unknown flag bits");
    u8("session_access", 11, 1, DF_EPROTO_RESERVED, NULL);
    u8("session_access", 8, 0, DF_OK, NULL);                   /* 0 = keep */
    u64("join", 0, 0, DF_EINVAL, "session_id 0");
    u64("access_info", 0, 0, DF_EINVAL, "session_id 0");
    u8("access_info", 8, 0, DF_EINVAL, "mode 0");
    u8("access_info", 9, 2, DF_EINVAL, "observers");
    u16("access_info", 10, 1, DF_EPROTO_RESERVED, NULL);
    u16("access_info_key", 16 + 2 + 9, 31, DF_EINVAL, "key_len");
    u16("access_info_key", 16 + 2 + 9, 0, DF_EPROTO_TRAILING, NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_handshake_bodies),
        cmocka_unit_test(test_load_mesh_bodies),
        cmocka_unit_test(test_session_bodies),
        cmocka_unit_test(test_access_bodies),
        cmocka_unit_test(test_brush_bodies),
        cmocka_unit_test(test_brush_state_bodies),
        cmocka_unit_test(test_handle_bodies),
        cmocka_unit_test(test_stream_bodies),
        cmocka_unit_test(test_device_bodies),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

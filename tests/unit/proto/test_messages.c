/* Unit tests for the request/reply bodies of proto/messages.h: byte-exact round trips of every
 * body, explicit field values after decode, truncation at every byte offset, a trailing byte,
 * and the (type, flags) -> body table. Malformed field values are in test_malformed.c. */
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

/* Decodes a heap copy of exactly n bytes so that ASan sees any over-read. */
static int decode_copy(const sample *s, size_t n, df_msg_any *m, df_error *e)
{
    uint8_t *p = malloc(n ? n : 1);
    memcpy(p, s->payload.data, n);
    int rc = df_msg_any_decode(s->type, s->flags, p, n, m, e);
    if (rc == DF_OK)
        df_msg_any_free(m);
    free(p);
    return rc;
}

static void test_reencode_is_byte_identical(void **state)
{
    (void)state;
    sample s[N_SAMPLES];
    build_samples(s);
    for (int i = 0; i < N_SAMPLES; i++) {
        df_msg_any m;
        df_error e;
        int rc = df_msg_any_decode(s[i].type, s[i].flags, s[i].payload.data, s[i].payload.len, &m,
                                   &e);
        if (rc)
            fail_msg("%s: %s", s[i].name, e.msg);
        df_buf again;
        df_buf_init(&again);
        assert_int_equal(df_msg_any_encode(&m, &again, &e), DF_OK);
        assert_int_equal(again.len, s[i].payload.len);
        assert_memory_equal(again.data, s[i].payload.data, again.len);
        df_buf_free(&again);
        df_msg_any_free(&m);
    }
    free_samples(s);
}

static void test_truncation_at_every_offset(void **state)
{
    (void)state;
    sample s[N_SAMPLES];
    build_samples(s);
    size_t checked = 0;
    for (int i = 0; i < N_SAMPLES; i++) {
        if (s[i].type == DF_MSG_PING)
            continue; /* any byte string is a valid ping */
        for (size_t n = 0; n < s[i].payload.len; n++) {
            if (!strcmp(s[i].name, "load_reply") && n == s[i].payload.len - 48)
                continue; /* the 48-byte report is optional: a bare session_info is valid */
            if (!strcmp(s[i].name, "brush_use_session") && n == s[i].payload.len - 2)
                continue; /* use_session is optional: without it, the original brush layout */
            if ((!strcmp(s[i].name, "handles_progress") ||
                 !strcmp(s[i].name, "handle_move_progress") ||
                 !strcmp(s[i].name, "brush_progress")) && n == s[i].payload.len - 4)
                continue; /* options are optional: without them, the original layout */
            if (!strcmp(s[i].name, "brush_progress") && n == s[i].payload.len - 6)
                continue; /* ... and so is use_session before them */
            if (!strcmp(s[i].name, "brush_surface") &&
                (n == s[i].payload.len - 1 || n == s[i].payload.len - 5 ||
                 n == s[i].payload.len - 7))
                continue; /* surface, options and use_session optional: older layouts */
            if ((!strcmp(s[i].name, "hello_stream") ||
                 !strcmp(s[i].name, "hello_reply_stream")) && n == s[i].payload.len - 10)
                continue; /* the stream-encoding trailer is optional: the original layout */
            df_msg_any m;
            df_error e = {0, ""};
            int rc = decode_copy(&s[i], n, &m, &e);
            if (rc != DF_EPROTO_TRUNCATED)
                fail_msg("%s cut at %zu of %zu: rc %d (%s)", s[i].name, n, s[i].payload.len, rc,
                         e.msg);
            assert_int_equal(e.code, DF_EPROTO_TRUNCATED);
            checked++;
        }
    }
    assert_true(checked > 1500); /* every offset of every sample was cut */
    free_samples(s);
}

static void test_trailing_byte_is_rejected(void **state)
{
    (void)state;
    sample s[N_SAMPLES];
    build_samples(s);
    for (int i = 0; i < N_SAMPLES; i++) {
        if (s[i].type == DF_MSG_PING)
            continue;
        df_error e;
        assert_int_equal(df_buf_append(&s[i].payload, "\0", 1, &e), DF_OK);
        df_msg_any m;
        int rc = decode_copy(&s[i], s[i].payload.len, &m, &e);
        if (!strcmp(s[i].name, "brush") && rc == DF_EPROTO_TRUNCATED &&
            strstr(e.msg, "use_session"))
            continue; /* one byte after the pins: the start of a cut optional use_session */
        if ((!strcmp(s[i].name, "handles") || !strcmp(s[i].name, "handle_move") ||
             !strcmp(s[i].name, "handles_reply") || !strcmp(s[i].name, "brush_use_session")) &&
            rc == DF_EPROTO_TRUNCATED && strstr(e.msg, "options"))
            continue; /* one byte after the body: the start of a cut optional options */
        if (!strcmp(s[i].name, "brush_progress") && rc == DF_OK)
            continue; /* one byte after options: the optional surface (0) */
        if ((!strcmp(s[i].name, "hello") || !strcmp(s[i].name, "hello_reply")) &&
            rc == DF_EPROTO_TRUNCATED && strstr(e.msg, "reserved"))
            continue; /* one byte after the name: the start of a cut stream-encoding trailer */
        if (rc != DF_EPROTO_TRAILING)
            fail_msg("%s + 1 byte: rc %d (%s)", s[i].name, rc, e.msg);
    }
    free_samples(s);
}

/* BRUSH_BEGIN's optional trailing use_session (PROTOCOL.md 4.12): a body in the original layout
 * (253 + 24 n bytes, what clients before it send) decodes exactly as before with use_session 0
 * and re-encodes to the same bytes; with the trailer the field is read; an explicit 0 trailer
 * means the same and also re-encodes byte for byte. */
static void test_brush_use_session(void **state)
{
    (void)state;
    df_msg_brush in = sample_brush(), old, zero, with;
    df_buf b, t, r;
    df_buf_init(&b);
    df_buf_init(&t);
    df_buf_init(&r);
    df_error e;
    assert_int_equal(df_msg_brush_encode(&in, &b, &e), DF_OK);
    assert_int_equal(b.len, 253 + 24 * 2); /* use_session 0: no trailer, the old layout */
    assert_int_equal(df_msg_brush_decode(b.data, b.len, &old, &e), DF_OK);
    assert_int_equal(old.use_session, 0);
    assert_int_equal(old.use_session_field, 0);
    assert_true(old.radius == in.radius && old.nu == in.nu && old.n_pinned == 2);
    assert_int_equal(df_msg_brush_encode(&old, &r, &e), DF_OK);
    assert_int_equal(r.len, b.len);
    assert_memory_equal(r.data, b.data, b.len);
    /* the same body with an explicit zero trailer */
    assert_int_equal(df_buf_append(&t, b.data, b.len, &e), DF_OK);
    assert_int_equal(df_buf_append(&t, "\0\0", 2, &e), DF_OK);
    assert_int_equal(df_msg_brush_decode(t.data, t.len, &zero, &e), DF_OK);
    assert_int_equal(zero.use_session, 0);
    assert_int_equal(zero.use_session_field, 1);
    assert_true(zero.radius == old.radius && zero.strength == old.strength &&
                !memcmp(zero.pinned, old.pinned, 6 * sizeof(double)));
    df_buf_reset(&r);
    assert_int_equal(df_msg_brush_encode(&zero, &r, &e), DF_OK);
    assert_int_equal(r.len, t.len);
    assert_memory_equal(r.data, t.data, t.len);
    /* a non-zero trailer */
    in.use_session = DF_BS_RADIUS | DF_BS_MIRROR;
    df_buf_reset(&r);
    assert_int_equal(df_msg_brush_encode(&in, &r, &e), DF_OK);
    assert_int_equal(r.len, b.len + 2);
    assert_int_equal(df_le16_load(r.data + b.len), DF_BS_RADIUS | DF_BS_MIRROR);
    assert_int_equal(df_msg_brush_decode(r.data, r.len, &with, &e), DF_OK);
    assert_int_equal(with.use_session, DF_BS_RADIUS | DF_BS_MIRROR);
    df_msg_brush_free(&old);
    df_msg_brush_free(&zero);
    df_msg_brush_free(&with);
    df_buf_free(&b);
    df_buf_free(&t);
    df_buf_free(&r);
}

/* Session brush bodies: sizes, documented offsets, round trips. */
static void test_brush_state_fields(void **state)
{
    (void)state;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    df_msg_brush_state_set set = {9, DF_BS_RADIUS | DF_BS_NU, {0}}, set2;
    df_msg_brush_values_defaults(&set.v);
    set.v.radius = 0.25;
    set.v.nu = 0.45;
    assert_int_equal(df_msg_brush_state_set_encode(&set, &b, &e), DF_OK);
    assert_int_equal(b.len, 96);
    assert_int_equal(df_le16_load(b.data + 8), DF_BS_RADIUS | DF_BS_NU);
    double radius, nu;
    memcpy(&radius, b.data + 16, 8);
    memcpy(&nu, b.data + 24, 8);
    assert_true(radius == 0.25 && nu == 0.45);
    assert_int_equal(df_msg_brush_state_set_decode(b.data, b.len, &set2, &e), DF_OK);
    assert_true(set2.session_id == 9 && set2.v.radius == 0.25 && set2.v.steps == 1);
    df_msg_brush_state st = {9, 4, DF_BS_NU, DF_ORIGIN_CLIENT, 77, "knobs", set.v}, st2;
    df_buf_reset(&b);
    assert_int_equal(df_msg_brush_state_encode(&st, &b, &e), DF_OK);
    assert_int_equal(b.len, 115 + 5);
    assert_int_equal(b.data[18], DF_ORIGIN_CLIENT);
    assert_int_equal(df_le16_load(b.data + 27), 5);
    assert_int_equal(df_msg_brush_state_decode(b.data, b.len, &st2, &e), DF_OK);
    assert_string_equal(st2.origin_name, "knobs");
    assert_true(st2.seq == 4 && st2.origin_id == 77 && st2.v.nu == 0.45);
    df_msg_brush_cursor c = {9, DF_ORIGIN_DEVICE, 5, DF_CURSOR_STROKE_ACTIVE, {1, 2, 3}, 0.5}, c2;
    df_buf_reset(&b);
    assert_int_equal(df_msg_brush_cursor_encode(&c, &b, &e), DF_OK);
    assert_int_equal(b.len, 50);
    memcpy(&radius, b.data + 42, 8);
    assert_true(radius == 0.5);
    assert_int_equal(df_msg_brush_cursor_decode(b.data, b.len, &c2, &e), DF_OK);
    assert_true(c2.center[2] == 3 && c2.flags == DF_CURSOR_STROKE_ACTIVE && c2.origin_id == 5);
    df_buf_free(&b);
}

static void test_brush_fields(void **state)
{
    (void)state;
    df_msg_brush in = sample_brush(), out;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_brush_encode(&in, &b, &e), DF_OK);
    assert_int_equal(b.len, 253 + 24 * 2);
    /* spot-check documented offsets: radius at 16, nu at 32, n_pinned at 248 */
    double radius, nu;
    memcpy(&radius, b.data + 16, 8);
    memcpy(&nu, b.data + 32, 8);
    assert_true(radius == 0.25 && nu == 0.45);
    assert_int_equal(df_le32_load(b.data + 248), 2);
    assert_int_equal(df_msg_brush_decode(b.data, b.len, &out, &e), DF_OK);
    assert_int_equal(out.session_id, 42);
    assert_int_equal(out.type, DF_BRUSH_AFFINE);
    assert_int_equal(out.dim, 3);
    assert_int_equal(out.falloff, 2);
    assert_int_equal(out.integrator, DF_INTEG_RK4);
    assert_int_equal(out.steps, 8);
    assert_int_equal(out.moving, 1);
    assert_int_equal(out.has_mirror, 1);
    assert_true(out.ratio == 2.5 && out.strength == 1.5 && out.scale == 0.2);
    assert_true(out.center[2] == in.center[2] && out.move[1] == -0.02 && out.twist[2] == 0.6);
    assert_true(out.matrix[4] == 0.1 && out.matrix[5] == 0.05);
    assert_true(out.mirror_normal[0] == 1 && out.mirror_normal[1] == 0);
    assert_int_equal(out.n_pinned, 2);
    assert_int_equal(out.pin_flags, DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT);
    assert_true(out.pinned != sample_pinned);
    assert_memory_equal(out.pinned, sample_pinned, sizeof sample_pinned);
    df_msg_brush_free(&out);
    assert_null(out.pinned);
    /* nu = +inf is legal and survives */
    in.nu = INFINITY;
    in.n_pinned = 0;
    in.pin_flags = 0;
    df_buf_reset(&b);
    assert_int_equal(df_msg_brush_encode(&in, &b, &e), DF_OK);
    assert_int_equal(df_msg_brush_decode(b.data, b.len, &out, &e), DF_OK);
    assert_true(isinf(out.nu) && out.nu > 0);
    assert_null(out.pinned);
    df_msg_brush_free(&out);
    df_buf_free(&b);
}

static void test_handles_and_move_fields(void **state)
{
    (void)state;
    df_msg_affine_set aff;
    df_msg_handles in = sample_handles_msg(&aff), out;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_handles_encode(&in, &b, &e), DF_OK);
    /* 92 fixed + 4 x 4 handles + 4 n_affine + (1 + 2*3*8 + 2*8 + 4 + 3*4) */
    assert_int_equal(b.len, 92 + 16 + 4 + 1 + 48 + 16 + 4 + 12);
    assert_int_equal(df_msg_handles_decode(b.data, b.len, &out, &e), DF_OK);
    assert_int_equal(out.energy, DF_ENERGY_NEOHOOKEAN);
    assert_true(out.w == 1e4 && out.s == 0.01 && out.rho == 0.0 && out.tol == 1e-11); /* rho 0: adaptive */
    assert_true(out.youngs == 1e7 && out.poisson == 0.45 && out.bending == 0.25);
    assert_true(out.strain_min == 0.9 && out.strain_max == 1.1);
    assert_int_equal(out.accelerate, 1);
    assert_int_equal(out.anderson_m, 5);
    assert_int_equal(out.area_weighting, 0);
    assert_int_equal(out.max_iters, 500);
    assert_int_equal(out.n_handles, 4);
    assert_int_equal(out.handles[3], 8000000);
    assert_int_equal(out.n_affine, 1);
    assert_int_equal(out.affine[0].rows, 2);
    assert_true(out.affine[0].A[0] == 1 && out.affine[0].A[4] == 1 && out.affine[0].A[6] == 0);
    assert_true(out.affine[0].b[1] == -0.5);
    assert_int_equal(out.affine[0].n_indices, 3);
    assert_int_equal(out.affine[0].indices[2], 7);
    df_msg_handles_free(&out);
    assert_null(out.handles);

    df_msg_handle_move mv = {7, 0, 250, 10, 4, sample_targets, 0, 0}, mo;
    df_buf_reset(&b);
    assert_int_equal(df_msg_handle_move_encode(&mv, &b, &e), DF_OK);
    assert_int_equal(b.len, 24 + 96);
    assert_int_equal(df_msg_handle_move_decode(b.data, b.len, &mo, &e), DF_OK);
    assert_int_equal(mo.max_ms, 250);
    assert_int_equal(mo.progress_every, 10);
    assert_true(mo.targets[11] == -3.25);
    assert_int_equal(mo.options, 0);
    assert_int_equal(mo.options_field, 0); /* the original layout: no options field */
    df_msg_handle_move_free(&mo);
    /* the optional options (PROTOCOL.md 4.16): PROGRESS read back; an explicit 0 is kept as a
     * field so that the body re-encodes to the same bytes */
    for (uint32_t opt = 0; opt <= (DF_WORK_OPT_PROGRESS | DF_WORK_OPT_KELVINLET_GUESS); opt++) {
        df_msg_handle_move mp = mv;
        mp.options = opt;
        mp.options_field = 1;
        df_buf_reset(&b);
        assert_int_equal(df_msg_handle_move_encode(&mp, &b, &e), DF_OK);
        assert_int_equal(b.len, 24 + 96 + 4);
        assert_int_equal(df_msg_handle_move_decode(b.data, b.len, &mo, &e), DF_OK);
        assert_int_equal(mo.options, opt);
        assert_int_equal(mo.options_field, 1);
        df_buf c;
        df_buf_init(&c);
        assert_int_equal(df_msg_handle_move_encode(&mo, &c, &e), DF_OK);
        assert_int_equal(c.len, b.len);
        assert_memory_equal(c.data, b.data, b.len);
        df_buf_free(&c);
        df_msg_handle_move_free(&mo);
    }
    /* KELVINLET_GUESS is a handle_move bit only: a handles body carrying it is refused */
    df_msg_handles hk;
    memset(&hk, 0, sizeof hk);
    hk.session_id = 7;
    hk.energy = DF_ENERGY_ARAP;
    int32_t one = 0;
    hk.n_handles = 1;
    hk.handles = &one;
    hk.options = DF_WORK_OPT_KELVINLET_GUESS;
    hk.options_field = 1;
    df_buf_reset(&b);
    assert_int_equal(df_msg_handles_encode(&hk, &b, &e), DF_EPROTO_RESERVED);
    df_buf_free(&b);
}

static void test_session_and_load_fields(void **state)
{
    (void)state;
    sample s[N_SAMPLES];
    build_samples(s);
    df_msg_any m;
    df_error e;
    for (int i = 0; i < N_SAMPLES; i++) {
        assert_int_equal(df_msg_any_decode(s[i].type, s[i].flags, s[i].payload.data,
                                           s[i].payload.len, &m, &e), DF_OK);
        if (!strcmp(s[i].name, "load_mesh")) {
            assert_int_equal(m.u.load_mesh.format, DF_FMT_OFF);
            assert_string_equal(m.u.load_mesh.name, "tri");
            assert_null(m.u.load_mesh.path);
            assert_int_equal(m.u.load_mesh.data_len, sizeof sample_blob - 1);
            /* data points into the payload */
            assert_ptr_equal(m.u.load_mesh.data, s[i].payload.data + s[i].payload.len -
                                                     (sizeof sample_blob - 1));
        } else if (!strcmp(s[i].name, "load_path")) {
            assert_int_equal(m.u.load_mesh.source, DF_LOAD_PATH);
            assert_string_equal(m.u.load_mesh.path, "/work/shared/meshes/spot.obj");
            assert_null(m.u.load_mesh.data);
        } else if (!strcmp(s[i].name, "session_list")) {
            assert_int_equal(m.u.session_list.count, 2);
            assert_string_equal(m.u.session_list.items[1].name, "woody");
            assert_int_equal(m.u.session_list.items[1].nv, 694);
            assert_int_equal(m.u.session_list.items[0].ne, 34055);
            assert_true(m.u.session_list.items[0].version == 99);
        } else if (!strcmp(s[i].name, "hello_reply")) {
            assert_int_equal(m.u.hello_reply.max_pending_requests, 64);
            assert_true(m.u.hello_reply.max_client_queue_bytes == 256u << 20);
            assert_string_equal(m.u.hello_reply.server_name, "deformd 0.1");
        } else if (!strcmp(s[i].name, "stats")) {
            assert_int_equal(m.u.stats.count, 3);
            assert_string_equal(m.u.stats.items[1].key, "cache.kelvinlet_lu.hits");
            assert_true(m.u.stats.items[1].value == 17);
        } else if (!strcmp(s[i].name, "session_ref")) {
            assert_true(m.u.session_ref.session_id == 0x1122334455667788ull);
            assert_memory_equal(s[i].payload.data, "\x88\x77\x66\x55\x44\x33\x22\x11", 8);
        } else if (!strcmp(s[i].name, "auth")) {
            assert_int_equal(m.u.auth.method, 2);
            assert_int_equal(m.u.auth.token_len, 4);
            assert_int_equal(m.u.auth.token[3], 6);
        } else if (!strcmp(s[i].name, "brush_param")) {
            assert_true(isinf(m.u.brush_param.value) && m.u.brush_param.value < 0);
        } else if (!strcmp(s[i].name, "handles_get")) {
            assert_int_equal(m.which, DF_BODY_SESSION_REF);
            assert_int_equal(s[i].payload.len, 8);
            assert_true(m.u.session_ref.session_id == 7);
        } else if (!strcmp(s[i].name, "handles_reply")) {
            /* the reply is byte-identical to the handles_set request of the same set */
            const sample *req = NULL;
            for (int k2 = 0; k2 < N_SAMPLES; k2++)
                if (!strcmp(s[k2].name, "handles"))
                    req = &s[k2];
            assert_non_null(req);
            assert_int_equal(s[i].payload.len, req->payload.len);
            assert_memory_equal(s[i].payload.data, req->payload.data, req->payload.len);
            assert_int_equal(m.which, DF_BODY_HANDLES);
            assert_int_equal(m.u.handles.energy, DF_ENERGY_NEOHOOKEAN);
            assert_int_equal(m.u.handles.n_handles, 4);
            assert_int_equal(m.u.handles.handles[3], 8000000);
            assert_true(m.u.handles.w == 1e4 && m.u.handles.bending == 0.25);
            assert_int_equal(m.u.handles.accelerate, 1);
            assert_int_equal(m.u.handles.n_affine, 1);
            assert_int_equal(m.u.handles.affine[0].rows, 2);
            assert_int_equal(m.u.handles.affine[0].indices[2], 7);
            assert_true(m.u.handles.affine[0].b[1] == -0.5);
        } else if (!strcmp(s[i].name, "move_result")) {
            assert_int_equal(s[i].payload.len, 45);
            assert_int_equal(m.u.move_result.iterations, 123);
            assert_true(m.u.move_result.elapsed_ms == 37.5);
        }
        df_msg_any_free(&m);
    }
    free_samples(s);
}

static void test_body_kind_table(void **state)
{
    (void)state;
    df_body_kind k;
    df_error e;
    assert_int_equal(df_msg_body_kind(DF_MSG_HANDLES_MOVE, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_HANDLE_MOVE);
    assert_int_equal(df_msg_body_kind(DF_MSG_HANDLES_MOVE, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_MOVE_RESULT);
    /* handles_get: a session ref in, the handles_set body back; never an event */
    assert_int_equal(df_msg_body_kind(DF_MSG_HANDLES_GET, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_SESSION_REF);
    assert_int_equal(df_msg_body_kind(DF_MSG_HANDLES_GET, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_HANDLES);
    assert_int_equal(df_msg_body_kind(DF_MSG_HANDLES_GET, DF_FLAG_EVENT, &k, &e),
                     DF_EPROTO_BADTYPE);
    assert_non_null(strstr(e.msg, "handles_get"));
    assert_string_equal(df_msg_type_name(DF_MSG_HANDLES_GET), "handles_get");
    assert_int_equal(DF_MSG_HANDLES_GET, 0x0035);
    assert_int_equal(df_msg_body_kind(DF_MSG_SNAPSHOT, DF_FLAG_REPLY | DF_FLAG_MORE, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_DISP);
    assert_int_equal(df_msg_body_kind(DF_MSG_BRUSH_END, DF_FLAG_REPLY | DF_FLAG_ERROR, &k, &e),
                     DF_OK);
    assert_int_equal(k, DF_BODY_ERROR);
    assert_int_equal(df_msg_body_kind(DF_MSG_DISPLACEMENT, 0, &k, &e), DF_EPROTO_BADTYPE);
    assert_non_null(strstr(e.msg, "request"));
    assert_int_equal(df_msg_body_kind(DF_MSG_SESSION_CLOSED, DF_FLAG_REPLY, &k, &e),
                     DF_EPROTO_BADTYPE);
    assert_int_equal(df_msg_body_kind(DF_MSG_UNDO, DF_FLAG_EVENT, &k, &e), DF_EPROTO_BADTYPE);
    assert_int_equal(df_msg_body_kind(0x0777, 0, &k, &e), DF_EPROTO_BADTYPE);
    assert_int_equal(df_msg_body_kind(DF_MSG_ERROR, 0, &k, &e), DF_EPROTO_BADTYPE);
    /* the list sessions request is an empty body; the auth reply an auth body (4.3) */
    assert_int_equal(df_msg_body_kind(DF_MSG_LIST_SESSIONS, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_EMPTY);
    assert_int_equal(df_msg_body_kind(DF_MSG_AUTH, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_AUTH);
    df_msg_any m;
    assert_int_equal(df_msg_any_decode(DF_MSG_AUTH, DF_FLAG_REPLY, NULL, 0, &m, &e),
                     DF_EPROTO_TRUNCATED);
    assert_int_equal(df_msg_any_decode(DF_MSG_LIST_SESSIONS, 0, (const uint8_t *)"x", 1, &m, &e),
                     DF_EPROTO_TRAILING);
    int known = 0;
    for (unsigned t = 0; t <= 0xFFFF; t++)
        known += df_msg_type_valid((uint16_t)t);
    assert_int_equal(known, 33 + 4 + 2 + 1 + 1 + 2); /* + the device (HID), access types,
                                                      * WORK_PROGRESS, SESSION_PEERS, QDISP
                                                      * and ZFRAME */
    /* shared-memory stream: a session ref in, shm_info back; SHM_REF only as an event */
    assert_int_equal(df_msg_body_kind(DF_MSG_STREAM_SHM, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_SESSION_REF);
    assert_int_equal(df_msg_body_kind(DF_MSG_STREAM_SHM, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_SHM_INFO);
    assert_int_equal(df_msg_body_kind(DF_MSG_SHM_REF, DF_FLAG_EVENT, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_SHM_REF);
    assert_int_equal(df_msg_body_kind(DF_MSG_SHM_REF, 0, &k, &e), DF_EPROTO_BADTYPE);
    assert_int_equal(DF_MSG_STREAM_SHM, 0x0016);
    assert_int_equal(DF_MSG_SHM_REF, 0x0083);
    /* a LOAD_MESH reply is a load_reply: session_info, plus the report with options EXT */
    assert_int_equal(df_msg_body_kind(DF_MSG_LOAD_MESH, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_LOAD_REPLY);
}

static void test_defaults_are_valid(void **state)
{
    (void)state;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    df_msg_brush br;
    df_msg_brush_defaults(&br);
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_EINVAL); /* session_id still 0 */
    br.session_id = 1;
    assert_int_equal(df_msg_brush_encode(&br, &b, &e), DF_OK);
    assert_true(br.ratio == 1.1 && br.nu == 0.5 && br.radius == 1 && br.strength == 1);
    assert_int_equal(br.falloff, 1);
    assert_int_equal(br.steps, 1);
    int32_t h[2] = {0, 1};
    for (uint8_t en = 0; en <= DF_ENERGY_MAX + 1; en++) {
        df_msg_handles hs;
        df_msg_handles_defaults(&hs, en);
        hs.session_id = 1;
        hs.n_handles = 2;
        hs.handles = h;
        df_buf_reset(&b);
        assert_int_equal(df_msg_handles_encode(&hs, &b, &e), DF_OK);
        assert_int_equal(b.len, 92 + 8 + 4);
        assert_int_equal(hs.energy, en >= 1 && en <= DF_ENERGY_MAX ? en : DF_ENERGY_ARAP);
        assert_true(hs.rho == 0.0); /* adaptive for every energy (admm.h DF_ADMM_RHO_RULE) */
        assert_true(hs.w == (en == DF_ENERGY_NEOHOOKEAN ? 500 : 1e-4));
        assert_int_equal(hs.max_iters, 500);
    }
    df_buf_free(&b);
}

/* devices (HID): documented offsets of device_info, list/bind/view fields, body kinds */
static void test_device_fields(void **state)
{
    (void)state;
    sample s[N_SAMPLES];
    build_samples(s);
    const sample *info = NULL, *view = NULL;
    for (int i = 0; i < N_SAMPLES; i++) {
        if (!strcmp(s[i].name, "device_state")) info = &s[i];
        if (!strcmp(s[i].name, "device_view")) view = &s[i];
    }
    assert_non_null(info);
    assert_non_null(view);
    const uint8_t *p = info->payload.data;
    assert_true(df_le64_load(p) == ((1ull << 63) | 1));
    assert_int_equal(p[8], DF_DEVCLASS_KNOB);
    assert_int_equal(p[9], DF_DEVBACKEND_REPLAY);
    assert_int_equal(p[10], DF_DEVSTATE_OPEN);
    assert_int_equal(p[11], 5);
    assert_int_equal(df_le16_load(p + 12), 0x045e);
    assert_int_equal(df_le16_load(p + 14), 0x091b);
    assert_int_equal(df_le64_load(p + 24), 5);
    assert_int_equal(p[32], 1);
    assert_int_equal(df_le16_load(p + 33), strlen("Surface Dial System Multi Axis"));
    df_msg_device_info d;
    df_error e;
    assert_int_equal(df_msg_device_info_decode(p, info->payload.len, &d, &e), DF_OK);
    assert_string_equal(d.name, "Surface Dial System Multi Axis");
    assert_string_equal(d.path, "replay:/work/shared/hid/dial.hid#0");
    assert_string_equal(d.error, "");
    assert_int_equal(view->payload.len, 176);
    df_msg_device_view v;
    assert_int_equal(df_msg_device_view_decode(view->payload.data, 176, &v, &e), DF_OK);
    assert_true(v.view_proj[0] == 1 && v.view_proj[11] == -0.5 && v.viewport[2] == 1920);
    df_body_kind k;
    assert_int_equal(df_msg_body_kind(DF_MSG_DEVICES_LIST, 0, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_EMPTY);
    assert_int_equal(df_msg_body_kind(DF_MSG_DEVICE_BIND, DF_FLAG_REPLY, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_EMPTY);
    assert_int_equal(df_msg_body_kind(DF_MSG_DEVICE_STATE, DF_FLAG_EVENT, &k, &e), DF_OK);
    assert_int_equal(k, DF_BODY_DEVICE_INFO);
    assert_int_equal(df_msg_body_kind(DF_MSG_DEVICE_STATE, 0, &k, &e), DF_EPROTO_BADTYPE);
    assert_int_equal(DF_MSG_DEVICE_STATE, 0x0086);
    /* a list over the limit is refused by the encoder */
    df_msg_device_list big = {DF_MAX_DEVICES + 1, &d};
    df_buf b;
    df_buf_init(&b);
    assert_int_equal(df_msg_device_list_encode(&big, &b, &e), DF_ELIMIT);
    assert_int_equal(b.len, 0);
    df_buf_free(&b);
    free_samples(s);
}

/* Stream encodings (PROTOCOL.md 4.2, 4.40): a hello asking for a bad encoding is refused with a
 * message naming the field; a qdisp decodes back to the rows it was built from; a qdisp whose
 * rows leave the mesh or whose rows_bytes disagree is refused. */
static void test_stream_encodings(void **state)
{
    (void)state;
    df_error e;
    df_buf b;
    df_buf_init(&b);
    df_msg_hello h = {1, 1, 0, "x", 1, 0x04, 0};
    assert_int_equal(df_msg_hello_encode(&h, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "stream_encoding"));
    h.stream_encoding = DF_STREAM_ENC_QUANTIZED; /* no error bound */
    assert_int_equal(df_msg_hello_encode(&h, &b, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "error_bound"));
    h.error_bound = NAN;
    assert_int_equal(df_msg_hello_encode(&h, &b, &e), DF_EINVAL);
    h.stream_encoding = DF_STREAM_ENC_ZSTD; /* a bound without QUANTIZED */
    h.error_bound = 1e-3;
    assert_int_equal(df_msg_hello_encode(&h, &b, &e), DF_EINVAL);
    h.stream_encoding = DF_STREAM_ENC_QUANTIZED;
    assert_int_equal(df_msg_hello_encode(&h, &b, &e), DF_OK);
    df_msg_hello back;
    assert_int_equal(df_msg_hello_decode(b.data, b.len, &back, &e), DF_OK);
    assert_int_equal(back.has_stream, 1);
    assert_int_equal(back.stream_encoding, DF_STREAM_ENC_QUANTIZED);
    assert_true(back.error_bound == 1e-3);
    b.data[b.len - 10] = 0x80; /* an unknown bit on the wire */
    assert_int_equal(df_msg_hello_decode(b.data, b.len, &back, &e), DF_EINVAL);
    df_buf_reset(&b);
    int32_t idx[3] = {0, 5, 999};
    int64_t dq[9] = {1, 0, 0, -1, 2, -3, 1ll << 50, -(1ll << 50), 0};
    df_msg_qdisp q = {.session_id = 7, .version = 3, .base_version = 2, .kind = DF_CHANGE_BRUSH,
                      .nv = 1000, .count = 3, .step = 0.5, .idx = idx, .dq = dq}, r;
    assert_int_equal(df_msg_qdisp_encode(&q, &b, &e), DF_OK);
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len, &r, &e), DF_OK);
    assert_int_equal(r.count, 3);
    for (int i = 0; i < 3; i++) assert_int_equal(r.idx[i], idx[i]);
    for (int i = 0; i < 9; i++) assert_true(r.dq[i] == dq[i]);
    df_msg_qdisp_free(&r);
    b.data[28] = 100; /* nv 1000 -> 868: index 999 is outside */
    b.data[29] = 3;
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len, &r, &e), DF_EINVAL);
    df_buf_reset(&b);
    /* the progress trailer (4.40): round trip, bad flag bits, a missing trailer, bad fields */
    df_msg_qdisp qp = q;
    qp.kind = DF_CHANGE_HANDLE_MOVE;
    qp.has_progress = 1;
    qp.status = DF_MOVE_CONVERGED;
    qp.final = 1;
    qp.iteration = 17;
    qp.objective = 0.125;
    qp.residual = 2.5e-7;
    qp.elapsed_ms = 40;
    assert_int_equal(df_msg_qdisp_encode(&qp, &b, &e), DF_OK);
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len, &r, &e), DF_OK);
    assert_true(r.has_progress == 1 && r.status == DF_MOVE_CONVERGED && r.final == 1 &&
                r.iteration == 17 && r.objective == 0.125 && r.residual == 2.5e-7 &&
                r.elapsed_ms == 40 && r.count == 3 && r.idx[2] == 999);
    df_msg_qdisp_free(&r);
    b.data[25] = 3; /* an unknown flag bit */
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len, &r, &e), DF_EINVAL);
    b.data[25] = 1;
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len - 32, &r, &e), DF_EPROTO_TRUNCATED);
    b.data[25] = 0; /* the trailer without the flag: trailing bytes */
    assert_int_equal(df_msg_qdisp_decode(b.data, b.len, &r, &e), DF_EPROTO_TRAILING);
    qp.final = 0; /* final iff status != running */
    assert_int_equal(df_msg_qdisp_encode(&qp, &b, &e), DF_EINVAL);
    qp.final = 1;
    qp.kind = DF_CHANGE_BRUSH; /* only a handle-move iterate has progress */
    assert_int_equal(df_msg_qdisp_encode(&qp, &b, &e), DF_EINVAL);
    df_buf_reset(&b);
    idx[1] = 0; /* not increasing */
    assert_int_equal(df_msg_qdisp_encode(&q, &b, &e), DF_EINVAL);
    df_buf_free(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reencode_is_byte_identical),
        cmocka_unit_test(test_truncation_at_every_offset),
        cmocka_unit_test(test_trailing_byte_is_rejected),
        cmocka_unit_test(test_brush_fields),
        cmocka_unit_test(test_brush_use_session),
        cmocka_unit_test(test_brush_state_fields),
        cmocka_unit_test(test_handles_and_move_fields),
        cmocka_unit_test(test_session_and_load_fields),
        cmocka_unit_test(test_body_kind_table),
        cmocka_unit_test(test_defaults_are_valid),
        cmocka_unit_test(test_device_fields),
        cmocka_unit_test(test_stream_encodings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

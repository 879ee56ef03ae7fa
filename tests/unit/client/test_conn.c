/* Unit tests for libdeformclient's connection core against a scripted fake server on a Unix
 * socket: hello, error replies surfaced as df_error, events dispatched during a request, stray
 * replies dropped, byte-by-byte (partial) writes, get-mesh chunk reassembly and its consistency
 * checks, chunked mesh upload, handles-get decoding and its errors, fatal connection errors. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/dc_net.h"
#include "client/deformclient.h"

/* Smallest max_frame_payload a server may announce: forces chunked uploads. */
#define FAKE_MAX_FRAME 1024u

typedef struct fake {
    char dir[64], path[108];
    int lfd;
    pthread_t th;
    void (*script)(int fd);
    int failures;   /* server-side expectations that did not hold */
} fake;

static fake *g_fake;

static void expect(int ok, const char *what)
{
    if (!ok) {
        fprintf(stderr, "fake server: expectation failed: %s\n", what);
        g_fake->failures++;
    }
}

/* Reads one frame: header into *h, payload into b (reset first). 0 ok, -1 on EOF/error. */
static int srv_read(int fd, df_frame_header *h, df_buf *b)
{
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    if (dc_net_read_exact(fd, raw, sizeof raw, 5000, NULL) ||
        df_frame_header_decode(raw, sizeof raw, h, NULL))
        return -1;
    df_buf_reset(b);
    if (df_buf_reserve(b, h->payload_len + 1, NULL))
        return -1;
    b->len = h->payload_len;
    return dc_net_read_exact(fd, b->data, h->payload_len, 5000, NULL) ? -1 : 0;
}

/* Sends a frame whose payload is p[0..n); `dribble` writes it one byte at a time. */
static void srv_send(int fd, uint16_t type, uint16_t flags, uint64_t id, const void *p, size_t n,
                     int dribble)
{
    df_frame_header h = {DF_FRAME_MAGIC, DF_PROTO_VERSION, type, flags, 0, id, (uint32_t)n};
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    df_frame_header_encode(&h, raw, NULL);
    if (!dribble) {
        dc_net_write2(fd, raw, sizeof raw, p, n, NULL);
        return;
    }
    for (size_t i = 0; i < sizeof raw; i++)
        dc_net_write_all(fd, raw + i, 1, NULL);
    for (size_t i = 0; i < n; i++)
        dc_net_write_all(fd, (const uint8_t *)p + i, 1, NULL);
}

static void srv_hello(int fd)
{
    df_frame_header h;
    df_buf b, o;
    df_buf_init(&b);
    df_buf_init(&o);
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_HELLO, "hello first");
    df_msg_hello m;
    expect(df_msg_hello_decode(b.data, b.len, &m, NULL) == DF_OK, "hello decodes");
    expect(strcmp(m.client_name, "unit") == 0, "client name");
    df_msg_hello_reply r;
    memset(&r, 0, sizeof r);
    r.version = 1;
    r.server_max_version = 1;
    r.features = DF_FEAT_KELVINLET;
    r.max_frame_payload = FAKE_MAX_FRAME;
    r.max_mesh_vertices = 1000;
    r.max_mesh_elements = 1000;
    r.max_pending_requests = 8;
    r.max_sessions = 4;
    r.max_mesh_bytes = 1 << 20;
    r.max_client_queue_bytes = 1 << 20;
    snprintf(r.server_name, sizeof r.server_name, "fake 1");
    df_msg_hello_reply_encode(&r, &o, NULL);
    srv_send(fd, DF_MSG_HELLO, DF_FLAG_REPLY, h.request_id, o.data, o.len, 0);
    df_buf_free(&b);
    df_buf_free(&o);
}

static void *srv_main(void *arg)
{
    fake *f = arg;
    int fd = accept(f->lfd, NULL, NULL);
    if (fd < 0)
        return NULL;
    srv_hello(fd);
    f->script(fd);
    close(fd);
    return NULL;
}

static df_client *start(fake *f, void (*script)(int fd))
{
    memset(f, 0, sizeof *f);
    g_fake = f;
    snprintf(f->dir, sizeof f->dir, "/tmp/dc-test-XXXXXX");
    assert_non_null(mkdtemp(f->dir));
    snprintf(f->path, sizeof f->path, "%s/s", f->dir);
    f->lfd = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    memcpy(sa.sun_path, f->path, strlen(f->path) + 1);
    assert_int_equal(bind(f->lfd, (struct sockaddr *)&sa, sizeof sa), 0);
    assert_int_equal(listen(f->lfd, 1), 0);
    f->script = script;
    pthread_create(&f->th, NULL, srv_main, f);
    df_client *c = NULL;
    df_error e;
    assert_int_equal(df_client_connect_unix(f->path, "unit", &c, &e), DF_OK);
    assert_string_equal(df_client_server_info(c)->server_name, "fake 1");
    assert_int_equal(df_client_server_info(c)->max_frame_payload, FAKE_MAX_FRAME);
    return c;
}

static void finish(fake *f, df_client *c)
{
    df_client_close(c);
    pthread_join(f->th, NULL);
    close(f->lfd);
    unlink(f->path);
    rmdir(f->dir);
    assert_int_equal(f->failures, 0);
}

/* ---- error replies, stray replies, events, partial writes ----------------------------------- */

static void script_errors_events(int fd)
{
    df_frame_header h;
    df_buf b, o;
    df_buf_init(&b);
    df_buf_init(&o);
    /* 1: UNDO -> error reply */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_UNDO, "undo");
    df_msg_error_frame(&o, DF_MSG_UNDO, h.request_id, DF_ENOTFOUND, NULL, "no session %d", 12);
    dc_net_write_all(fd, o.data, o.len, NULL);
    /* 2: REDO -> stray reply, an event, then the ack dribbled byte by byte */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_REDO, "redo");
    df_msg_ack stray = {7, 99};
    df_buf_reset(&o);
    df_msg_ack_encode(&stray, &o, NULL);
    srv_send(fd, DF_MSG_REDO, DF_FLAG_REPLY, h.request_id + 1000, o.data, o.len, 0);
    int32_t idx[1] = {2};
    float xyz[3] = {0.5f, -1, 2};
    df_msg_disp d = {7, 5, 4, DF_CHANGE_REDO, DF_DISP_SPARSE, 3, 1, 0, 1, idx, xyz};
    df_buf_reset(&o);
    df_msg_disp_encode(&d, &o, NULL);
    srv_send(fd, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, 0, o.data, o.len, 0);
    df_msg_ack ack = {7, 5};
    df_buf_reset(&o);
    df_msg_ack_encode(&ack, &o, NULL);
    srv_send(fd, DF_MSG_REDO, DF_FLAG_REPLY, h.request_id, o.data, o.len, 1);
    /* 3: PING -> reply with different bytes */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_PING, "ping");
    srv_send(fd, DF_MSG_PING, DF_FLAG_REPLY, h.request_id, "\x02\x00\x00\x00xy", 6, 0);
    /* 4: STATS -> a fatal connection error frame, then close */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_STATS, "stats");
    df_buf_reset(&o);
    df_msg_error_frame(&o, DF_MSG_ERROR, 0, DF_EPROTO_BADMAGIC, NULL, "bad frame magic");
    dc_net_write_all(fd, o.data, o.len, NULL);
    df_buf_free(&b);
    df_buf_free(&o);
}

typedef struct seen {
    int events;
    uint64_t version;
    uint32_t count;
} seen;

static void on_event(void *user, const df_frame_header *h, const uint8_t *p)
{
    seen *s = user;
    df_msg_disp d;
    if (h->type == DF_MSG_DISPLACEMENT && df_msg_disp_decode(p, h->payload_len, &d, NULL) == 0) {
        s->events++;
        s->version = d.version;
        s->count = d.count;
        df_msg_disp_free(&d);
    }
}

static void test_errors_events_partial_writes(void **state)
{
    (void)state;
    fake f;
    df_client *c = start(&f, script_errors_events);
    seen s = {0, 0, 0};
    df_client_set_event_callback(c, on_event, &s);
    df_error e;
    df_msg_ack ack = {0, 0};
    assert_int_equal(df_client_undo(c, 12, &ack, &e), DF_ENOTFOUND);
    assert_string_equal(e.msg, "no session 12");
    assert_int_equal(df_client_last_error_was_remote(c), 1);
    assert_int_equal(ack.version, 0);
    assert_int_equal(df_client_redo(c, 7, &ack, &e), DF_OK);
    assert_int_equal(df_client_last_error_was_remote(c), 0);
    assert_int_equal(ack.session_id, 7);
    assert_int_equal(ack.version, 5);
    assert_int_equal(s.events, 1);
    assert_int_equal(s.version, 5);
    assert_int_equal(s.count, 1);
    assert_int_equal(df_client_ping(c, "ab", 2, NULL, &e), DF_EFORMAT);
    assert_string_equal(e.msg, "ping echo differs from the 2 bytes sent");
    df_msg_stats st;
    assert_int_equal(df_client_stats(c, 0, &st, &e), DF_EPROTO_BADMAGIC);
    assert_string_equal(e.msg, "bad frame magic");
    assert_int_equal(df_client_undo(c, 1, NULL, &e), DF_EIO); /* connection is now broken */
    finish(&f, c);
}

/* ---- get mesh chunk reassembly -------------------------------------------------------------- */

static void send_chunk(int fd, uint64_t id, uint8_t section, uint32_t off, uint32_t count,
                       float *xyz, int32_t *idx, int more)
{
    df_msg_mesh_chunk k = {7, 3, DF_MESH_TRIANGLE, 0, section, 4, 2, 0, off, count, xyz, idx};
    df_buf o;
    df_buf_init(&o);
    expect(df_msg_mesh_chunk_encode(&k, &o, NULL) == DF_OK, "chunk encodes");
    srv_send(fd, DF_MSG_GET_MESH, DF_FLAG_REPLY | (more ? DF_FLAG_MORE : 0), id, o.data, o.len, 0);
    df_buf_free(&o);
}

static void script_get_mesh(int fd)
{
    df_frame_header h;
    df_buf b;
    df_buf_init(&b);
    float p[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    int32_t t[6] = {0, 1, 2, 0, 2, 3};
    /* good reply: positions in two chunks, elements in one */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_GET_MESH, "get mesh");
    send_chunk(fd, h.request_id, DF_SECTION_POSITIONS, 0, 3, p, NULL, 1);
    send_chunk(fd, h.request_id, DF_SECTION_POSITIONS, 3, 1, p + 9, NULL, 1);
    send_chunk(fd, h.request_id, DF_SECTION_ELEMENTS, 0, 2, NULL, t, 0);
    /* bad reply: positions chunk at row 1 first; then a missing element section */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_GET_MESH, "get mesh 2");
    send_chunk(fd, h.request_id, DF_SECTION_POSITIONS, 1, 3, p + 3, NULL, 1);
    send_chunk(fd, h.request_id, DF_SECTION_ELEMENTS, 0, 2, NULL, t, 0);
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_GET_MESH, "get mesh 3");
    send_chunk(fd, h.request_id, DF_SECTION_POSITIONS, 0, 4, p, NULL, 0);
    df_buf_free(&b);
}

static void test_get_mesh_reassembly(void **state)
{
    (void)state;
    fake f;
    df_client *c = start(&f, script_get_mesh);
    df_error e;
    df_client_mesh m;
    assert_int_equal(df_client_get_mesh(c, 7, 0, &m, &e), DF_OK);
    assert_int_equal(m.nv, 4);
    assert_int_equal(m.ne, 2);
    assert_int_equal(m.version, 3);
    assert_true(m.positions[9] == 0 && m.positions[10] == 1 && m.positions[3] == 1);
    assert_int_equal(m.elements[5], 3);
    assert_null(m.faces);
    df_client_mesh_free(&m);
    assert_int_equal(df_client_get_mesh(c, 7, 0, &m, &e), DF_EFORMAT);
    assert_string_equal(e.msg, "get mesh: section 1 chunk rows [1, +3) out of order");
    assert_int_equal(df_client_get_mesh(c, 7, 0, &m, &e), DF_EFORMAT);
    assert_string_equal(e.msg, "get mesh: reply ended with sections incomplete");
    finish(&f, c);
}

/* ---- chunked upload --------------------------------------------------------------------------- */

#define UPLOAD_BYTES 3000

static void script_upload(int fd)
{
    df_frame_header h;
    df_buf b;
    df_buf_init(&b);
    uint8_t got[UPLOAD_BYTES];
    uint64_t next = 0, id = 0;
    int chunks = 0;
    for (;;) {
        if (srv_read(fd, &h, &b) != 0 || h.type != DF_MSG_LOAD_MESH) {
            expect(0, "load chunk");
            break;
        }
        expect(h.payload_len <= FAKE_MAX_FRAME, "chunk fits max_frame_payload");
        df_msg_load_mesh m;
        expect(df_msg_load_mesh_decode(b.data, b.len, &m, NULL) == DF_OK, "chunk decodes");
        expect(m.offset == next && m.total_size == UPLOAD_BYTES, "consecutive offsets");
        expect(chunks == 0 || h.request_id == id, "same request id");
        expect(strcmp(m.name, "up") == 0 && m.format == DF_FMT_OFF, "name and format repeated");
        id = h.request_id;
        memcpy(got + m.offset, m.data, m.data_len);
        next += m.data_len;
        chunks++;
        df_msg_load_mesh_free(&m);
        if (!(h.flags & DF_FLAG_MORE))
            break;
    }
    expect(next == UPLOAD_BYTES && chunks == 5, "five chunks cover the upload");
    for (int i = 0; i < UPLOAD_BYTES; i++)
        if (got[i] != (uint8_t)(i * 7)) {
            expect(0, "upload bytes intact");
            break;
        }
    df_msg_session_info info;
    memset(&info, 0, sizeof info);
    info.session_id = 9;
    info.kind = DF_MESH_TRIANGLE;
    info.nv = 3;
    info.ne = 1;
    snprintf(info.name, sizeof info.name, "up");
    df_buf_reset(&b);
    df_msg_session_info_encode(&info, &b, NULL);
    srv_send(fd, DF_MSG_LOAD_MESH, DF_FLAG_REPLY, id, b.data, b.len, 0);
    df_buf_free(&b);
}

static void test_chunked_upload(void **state)
{
    (void)state;
    fake f;
    df_client *c = start(&f, script_upload);
    uint8_t data[UPLOAD_BYTES];
    for (int i = 0; i < UPLOAD_BYTES; i++)
        data[i] = (uint8_t)(i * 7);
    df_error e;
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(c, "up", DF_FMT_OFF, data, UPLOAD_BYTES, 0, &info,
                                               &e), DF_OK);
    assert_int_equal(info.session_id, 9);
    assert_string_equal(info.name, "up");
    finish(&f, c);
}

/* ---- handles get: decoded set, remote ENOTFOUND, a reply for another session -------------- */

static int32_t hg_handles[3] = {5, 1, 9};
static int32_t hg_aff_idx[2] = {2, 3};

static df_msg_handles hg_set(uint64_t session_id, df_msg_affine_set *aff)
{
    df_msg_handles m;
    df_msg_handles_defaults(&m, DF_ENERGY_ACAP);
    m.session_id = session_id;
    m.w = 0.5;
    m.s = 0.25;
    m.rho = 3;
    m.accelerate = 1;
    m.anderson_m = 9;
    m.max_iters = 1234;
    m.n_handles = 3;
    m.handles = hg_handles;
    memset(aff, 0, sizeof *aff);
    aff->rows = 1;
    aff->A[2] = 1;
    aff->b[0] = -0.75;
    aff->n_indices = 2;
    aff->indices = hg_aff_idx;
    m.n_affine = 1;
    m.affine = aff;
    return m;
}

static void script_handles_get(int fd)
{
    df_frame_header h;
    df_buf b, o;
    df_buf_init(&b);
    df_buf_init(&o);
    df_msg_session_ref ref;
    df_msg_affine_set aff;
    /* 1: the set of session 7 */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_HANDLES_GET, "handles_get 1");
    expect(df_msg_session_ref_decode(b.data, b.len, &ref, NULL) == DF_OK && ref.session_id == 7,
           "handles_get body is session 7");
    df_msg_handles m = hg_set(7, &aff);
    expect(df_msg_handles_encode(&m, &o, NULL) == DF_OK, "encode set");
    srv_send(fd, DF_MSG_HANDLES_GET, DF_FLAG_REPLY, h.request_id, o.data, o.len, 0);
    /* 2: no handle set */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_HANDLES_GET, "handles_get 2");
    df_buf_reset(&o);
    df_msg_error_frame(&o, DF_MSG_HANDLES_GET, h.request_id, DF_ENOTFOUND, NULL,
                       "handles_get: session 8 has no handle set");
    dc_net_write_all(fd, o.data, o.len, NULL);
    /* 3: a reply naming session 5 instead of 7 */
    expect(srv_read(fd, &h, &b) == 0 && h.type == DF_MSG_HANDLES_GET, "handles_get 3");
    m = hg_set(5, &aff);
    df_buf_reset(&o);
    df_msg_handles_encode(&m, &o, NULL);
    srv_send(fd, DF_MSG_HANDLES_GET, DF_FLAG_REPLY, h.request_id, o.data, o.len, 1);
    df_buf_free(&b);
    df_buf_free(&o);
}

static void test_handles_get(void **state)
{
    (void)state;
    fake f;
    df_client *c = start(&f, script_handles_get);
    df_error e;
    df_msg_handles hs;
    memset(&hs, 0, sizeof hs);
    assert_int_equal(df_client_handles_get(c, 7, &hs, &e), DF_OK);
    assert_true(hs.session_id == 7);
    assert_int_equal(hs.energy, DF_ENERGY_ACAP);
    assert_true(hs.w == 0.5 && hs.s == 0.25 && hs.rho == 3 && hs.tol == 1e-11);
    assert_int_equal(hs.accelerate, 1);
    assert_int_equal(hs.anderson_m, 9);
    assert_int_equal(hs.max_iters, 1234);
    assert_int_equal(hs.n_handles, 3);
    assert_int_equal(hs.handles[0], 5);
    assert_int_equal(hs.handles[1], 1);
    assert_int_equal(hs.handles[2], 9);
    assert_int_equal(hs.n_affine, 1);
    assert_int_equal(hs.affine[0].rows, 1);
    assert_true(hs.affine[0].A[2] == 1 && hs.affine[0].b[0] == -0.75);
    assert_int_equal(hs.affine[0].n_indices, 2);
    assert_int_equal(hs.affine[0].indices[1], 3);
    df_msg_handles_free(&hs);
    assert_null(hs.handles);
    df_msg_handles keep;
    memset(&keep, 0x5A, sizeof keep);
    memcpy(&hs, &keep, sizeof hs);
    assert_int_equal(df_client_handles_get(c, 8, &hs, &e), DF_ENOTFOUND);
    assert_string_equal(e.msg, "handles_get: session 8 has no handle set");
    assert_int_equal(df_client_last_error_was_remote(c), 1);
    assert_memory_equal(&hs, &keep, sizeof hs); /* untouched on error */
    assert_int_equal(df_client_handles_get(c, 7, &hs, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "session 5"));
    assert_memory_equal(&hs, &keep, sizeof hs);
    assert_int_equal(df_client_handles_get(c, 7, NULL, &e), DF_EINVAL);
    finish(&f, c);
}

/* ---- connection lost mid-frame --------------------------------------------------------------- */

static void script_hangup(int fd)
{
    df_frame_header h;
    df_buf b;
    df_buf_init(&b);
    expect(srv_read(fd, &h, &b) == 0, "list");
    uint8_t raw[DF_FRAME_HEADER_SIZE];
    df_frame_header r = {DF_FRAME_MAGIC, 1, DF_MSG_LIST_SESSIONS, DF_FLAG_REPLY, 0, h.request_id, 100};
    df_frame_header_encode(&r, raw, NULL);
    dc_net_write_all(fd, raw, sizeof raw, NULL);
    dc_net_write_all(fd, "\x01\x00", 2, NULL); /* 2 of 100 payload bytes, then close */
    df_buf_free(&b);
}

static void test_connection_lost_mid_frame(void **state)
{
    (void)state;
    fake f;
    df_client *c = start(&f, script_hangup);
    df_error e;
    df_msg_session_list l;
    assert_int_equal(df_client_list_sessions(c, &l, &e), DF_EIO);
    assert_string_equal(e.msg, "connection closed by peer");
    assert_int_equal(df_client_last_error_was_remote(c), 0);
    finish(&f, c);
}

static void test_connect_errors(void **state)
{
    (void)state;
    df_client *c = NULL;
    df_error e;
    assert_int_equal(df_client_connect_unix("/nonexistent/dir/s", NULL, &c, &e), DF_EIO);
    assert_string_equal(e.msg, "cannot connect to /nonexistent/dir/s: No such file or directory");
    char longp[200];
    memset(longp, 'a', sizeof longp - 1);
    longp[sizeof longp - 1] = '\0';
    assert_int_equal(df_client_connect_unix(longp, NULL, &c, &e), DF_EINVAL);
    assert_int_equal(df_client_connect_tcp("127.0.0.1", 0, NULL, &c, &e), DF_EINVAL);
    assert_null(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_errors_events_partial_writes),
        cmocka_unit_test(test_get_mesh_reassembly),
        cmocka_unit_test(test_chunked_upload),
        cmocka_unit_test(test_handles_get),
        cmocka_unit_test(test_connection_lost_mid_frame),
        cmocka_unit_test(test_connect_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

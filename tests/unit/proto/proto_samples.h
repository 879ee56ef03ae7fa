/* proto_samples.h — valid sample messages shared by the proto unit tests (header-only: the
 * Makefile builds one binary per tests/unit/<area>/test_*.c, so helpers live in a header). */
#ifndef DF_TEST_PROTO_SAMPLES_H
#define DF_TEST_PROTO_SAMPLES_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"

typedef struct sample {
    const char *name;
    uint16_t type, flags;
    df_buf payload;
} sample;

enum { N_SAMPLES_BASE = 42, N_SAMPLES_DEVICES = 5, N_SAMPLES_RESYNC = 1, N_SAMPLES_ACCESS = 4,
       N_SAMPLES_WORK = 4, N_SAMPLES_PEERS = 3, N_SAMPLES_STREAM = 6,
       N_SAMPLES = N_SAMPLES_BASE + N_SAMPLES_DEVICES + N_SAMPLES_RESYNC + N_SAMPLES_ACCESS +
                   N_SAMPLES_WORK + N_SAMPLES_PEERS + N_SAMPLES_STREAM };

static const uint8_t sample_blob[] = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
static double sample_pinned[6] = {0.1, 0.2, 0.3, -1.5, 2.5, 1e-3};
static int32_t sample_handles[4] = {0, 17, 4095, 8000000};
static int32_t sample_aff_idx[3] = {5, 6, 7};
static double sample_targets[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, -1, -2, -3.25};
static float sample_dense[15] = {0.5f, 0, 0, 1, 2, 3, -4, -5, -6, 1e-7f, 0, 0, 0, 0, 1e30f};
static int32_t sample_sparse_idx[3] = {2, 40, 99};
static float sample_sparse_xyz[9] = {0.25f, -0.5f, 1, 0, 0, 0, 3, 2, 1};
static float sample_mesh_xyz[6] = {0, 0, 0, 1, 0.5f, -0.5f};
static int32_t sample_tets[8] = {0, 1, 2, 3, 3, 2, 1, 4};

static inline df_msg_brush sample_brush(void)
{
    df_msg_brush m;
    memset(&m, 0, sizeof m);
    m.session_id = 42;
    m.type = DF_BRUSH_AFFINE;
    m.dim = 3;
    m.falloff = 2;
    m.integrator = DF_INTEG_RK4;
    m.steps = 8;
    m.moving = 1;
    m.has_mirror = 1;
    m.radius = 0.25;
    m.ratio = 2.5;
    m.nu = 0.45;
    m.strength = 1.5;
    for (int i = 0; i < 3; i++) {
        m.center[i] = 0.1 * (i + 1);
        m.move[i] = -0.01 * (i + 1);
        m.twist[i] = 0.3 * i;
        m.mirror_point[i] = 0;
        m.mirror_normal[i] = i == 0;
    }
    m.scale = 0.2;
    for (int i = 0; i < 9; i++)
        m.matrix[i] = i % 4 == 0 ? 0.1 : 0.01 * i;
    m.n_pinned = 2;
    m.pin_flags = DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT;
    m.pinned = sample_pinned;
    return m;
}

static inline df_msg_handles sample_handles_msg(df_msg_affine_set *aff)
{
    df_msg_handles m;
    df_msg_handles_defaults(&m, DF_ENERGY_NEOHOOKEAN);
    m.session_id = 7;
    m.w = 1e4;
    m.accelerate = 1;
    m.bending = 0.25;
    m.n_handles = 4;
    m.handles = sample_handles;
    memset(aff, 0, sizeof *aff);
    aff->rows = 2;
    aff->A[0] = 1;
    aff->A[4] = 1;
    aff->b[0] = 0.5;
    aff->b[1] = -0.5;
    aff->n_indices = 3;
    aff->indices = sample_aff_idx;
    m.n_affine = 1;
    m.affine = aff;
    return m;
}

static inline df_msg_disp sample_disp_sparse(void)
{
    df_msg_disp d = {.session_id = 3, .version = 11, .base_version = 10,
                     .kind = DF_CHANGE_BRUSH, .encoding = DF_DISP_SPARSE, .nv = 100, .total = 5,
                     .offset = 2, .count = 3, .idx = sample_sparse_idx, .xyz = sample_sparse_xyz};
    return d;
}

static inline df_msg_disp sample_disp_dense(void)
{
    df_msg_disp d = {.session_id = 3, .version = 12, .base_version = 11, .kind = DF_CHANGE_UNDO,
                     .encoding = DF_DISP_DENSE, .nv = 5, .total = 5, .offset = 0, .count = 5,
                     .idx = NULL, .xyz = sample_dense};
    return d;
}

/* Fills s[0 .. N_SAMPLES) with one valid encoded payload per body kind and direction. */
static inline void build_samples(sample *s)
{
    df_error e;
    int k = 0, rc = 0;
#define ADD(nm, ty, fl, call)                                                                    \
    do {                                                                                         \
        s[k].name = nm;                                                                          \
        s[k].type = ty;                                                                          \
        s[k].flags = fl;                                                                         \
        df_buf_init(&s[k].payload);                                                              \
        df_buf *out = &s[k].payload;                                                             \
        rc = (call);                                                                             \
        if (rc) {                                                                                \
            fprintf(stderr, "sample %s: %s\n", nm, e.msg);                                       \
            abort();                                                                             \
        }                                                                                        \
        k++;                                                                                     \
    } while (0)
    df_msg_hello hello = {1, 3, DF_FEAT_KELVINLET, "deformctl", 0, 0, 0};
    ADD("hello", DF_MSG_HELLO, 0, df_msg_hello_encode(&hello, out, &e));
    df_msg_hello_reply hr = {1, 1, DF_FEAT_KELVINLET | DF_FEAT_ADMM, DF_MAX_FRAME_PAYLOAD,
                             DF_MAX_MESH_VERTICES, DF_MAX_MESH_ELEMENTS, 64, 16,
                             DF_MAX_MESH_BYTES, 256u << 20, 0, "deformd 0.1", 0, 0, 0};
    ADD("hello_reply", DF_MSG_HELLO, DF_FLAG_REPLY, df_msg_hello_reply_encode(&hr, out, &e));
    const uint8_t tok[4] = {9, 8, 7, 6};
    df_msg_auth auth = {2, 4, tok};
    ADD("auth", DF_MSG_AUTH, 0, df_msg_auth_encode(&auth, out, &e));
    df_msg_ping ping = {3, tok};
    ADD("ping", DF_MSG_PING, 0, df_msg_ping_encode(&ping, out, &e));
    df_msg_load_mesh lm = {DF_LOAD_INLINE, DF_FMT_OFF, "tri", NULL, sizeof sample_blob - 1, 0,
                           0, sizeof sample_blob - 1, sample_blob, 0, ""};
    ADD("load_mesh", DF_MSG_LOAD_MESH, 0, df_msg_load_mesh_encode(&lm, out, &e));
    char path[] = "/work/shared/meshes/spot.obj";
    df_msg_load_mesh lp = {DF_LOAD_PATH, DF_FMT_AUTO, "spot", path, 0, 0, 0, 0, NULL, 0, ""};
    ADD("load_path", DF_MSG_LOAD_MESH, 0, df_msg_load_mesh_encode(&lp, out, &e));
    df_msg_load_mesh lx = lm;
    lx.options = DF_LOAD_OPT_EXT;
    snprintf(lx.file_name, sizeof lx.file_name, "tri.off");
    ADD("load_mesh_ext", DF_MSG_LOAD_MESH, 0, df_msg_load_mesh_encode(&lx, out, &e));
    df_msg_session_ref ref = {0x1122334455667788ull};
    ADD("session_ref", DF_MSG_UNDO, 0, df_msg_session_ref_encode(&ref, out, &e));
    df_msg_open_session os = {0, "bunny"};
    ADD("open_session", DF_MSG_OPEN_SESSION, 0, df_msg_open_session_encode(&os, out, &e));
    df_msg_subscribe sub = {5, DF_SUBSCRIBE_SNAPSHOT, 0};
    ADD("subscribe", DF_MSG_SUBSCRIBE, 0, df_msg_subscribe_encode(&sub, out, &e));
    df_msg_session_info si = {5, 99, 3, 0, 2, 5433, 34055, 4, 1, "bunny"};
    ADD("session_info", DF_MSG_OPEN_SESSION, DF_FLAG_REPLY, df_msg_session_info_encode(&si, out, &e));
    df_msg_load_reply lr = {si, 1, {5, 1, 0, 0, 12, 1, 0, 0, 2, 0, 0, 3, 4}};
    ADD("load_reply", DF_MSG_LOAD_MESH, DF_FLAG_REPLY, df_msg_load_reply_encode(&lr, out, &e));
    df_msg_session_info items[2] = {si, {6, 0, 2, 1, 0, 694, 1267, 0, 0, "woody"}};
    df_msg_session_list sl = {2, items};
    ADD("session_list", DF_MSG_LIST_SESSIONS, DF_FLAG_REPLY,
        df_msg_session_list_encode(&sl, out, &e));
    df_msg_ack ack = {5, 100};
    ADD("ack", DF_MSG_UNDO, DF_FLAG_REPLY, df_msg_ack_encode(&ack, out, &e));
    df_msg_brush br = sample_brush();
    ADD("brush", DF_MSG_BRUSH_BEGIN, 0, df_msg_brush_encode(&br, out, &e));
    df_msg_brush_update bu = {42, {1, 2, 3}, {0, 0, 0.5}, -0.25, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    ADD("brush_update", DF_MSG_BRUSH_UPDATE, 0, df_msg_brush_update_encode(&bu, out, &e));
    df_msg_brush_param bp = {42, DF_BP_NU, -INFINITY};
    ADD("brush_param", DF_MSG_SET_BRUSH_PARAM, 0, df_msg_brush_param_encode(&bp, out, &e));
    df_msg_affine_set aff;
    df_msg_handles hs = sample_handles_msg(&aff);
    ADD("handles", DF_MSG_HANDLES_SET, 0, df_msg_handles_encode(&hs, out, &e));
    df_msg_handle_move hm = {7, 0, 250, 10, 4, sample_targets, 0, 0};
    ADD("handle_move", DF_MSG_HANDLES_MOVE, 0, df_msg_handle_move_encode(&hm, out, &e));
    df_msg_move_result mr = {7, 60, DF_MOVE_CONVERGED, 123, 4.5, 1e-12, 37.5};
    ADD("move_result", DF_MSG_HANDLES_MOVE, DF_FLAG_REPLY, df_msg_move_result_encode(&mr, out, &e));
    df_msg_get_mesh gm = {5, DF_GET_MESH_BASE};
    ADD("get_mesh", DF_MSG_GET_MESH, 0, df_msg_get_mesh_encode(&gm, out, &e));
    df_msg_mesh_chunk mcx = {5, 9, 3, 0, DF_SECTION_POSITIONS, 5, 2, 0, 3, 2,
                             sample_mesh_xyz, NULL};
    ADD("mesh_chunk_xyz", DF_MSG_GET_MESH, DF_FLAG_REPLY | DF_FLAG_MORE,
        df_msg_mesh_chunk_encode(&mcx, out, &e));
    df_msg_mesh_chunk mce = {5, 9, 3, 0, DF_SECTION_ELEMENTS, 5, 2, 0, 0, 2, NULL, sample_tets};
    ADD("mesh_chunk_elem", DF_MSG_GET_MESH, DF_FLAG_REPLY, df_msg_mesh_chunk_encode(&mce, out, &e));
    df_msg_snapshot_req sr = {5, 0};
    ADD("snapshot_req", DF_MSG_SNAPSHOT, 0, df_msg_snapshot_req_encode(&sr, out, &e));
    df_msg_disp ds = sample_disp_sparse();
    ADD("disp_sparse", DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, df_msg_disp_encode(&ds, out, &e));
    df_msg_disp dd = sample_disp_dense();
    ADD("disp_dense", DF_MSG_DISPLACEMENT, DF_FLAG_EVENT, df_msg_disp_encode(&dd, out, &e));
    df_msg_progress pr = {DF_MOVE_RUNNING, 0, 20, 3.25, 1e-4, 12.0, sample_disp_sparse()};
    pr.disp.kind = DF_CHANGE_HANDLE_MOVE;
    ADD("progress", DF_MSG_PROGRESS, DF_FLAG_EVENT, df_msg_progress_encode(&pr, out, &e));
    df_msg_stats_req sq = {0};
    ADD("stats_req", DF_MSG_STATS, 0, df_msg_stats_req_encode(&sq, out, &e));
    df_msg_stat st[3] = {{"sessions", 2}, {"cache.kelvinlet_lu.hits", 17}, {"uptime_s", 0.5}};
    df_msg_stats sts = {3, st};
    ADD("stats", DF_MSG_STATS, DF_FLAG_REPLY, df_msg_stats_encode(&sts, out, &e));
    /* appended last so that the request ids (fuzz seeds) of the samples above stay stable */
    df_msg_session_ref hg = {7};
    ADD("handles_get", DF_MSG_HANDLES_GET, 0, df_msg_session_ref_encode(&hg, out, &e));
    ADD("handles_reply", DF_MSG_HANDLES_GET, DF_FLAG_REPLY, df_msg_handles_encode(&hs, out, &e));
    df_msg_session_ref ss = {9};
    ADD("stream_shm", DF_MSG_STREAM_SHM, 0, df_msg_session_ref_encode(&ss, out, &e));
    /* shm_info: session 9, capacity 64 KiB, frames 1024..32768 bytes, path "/run/d.shm-9" */
    df_msg_shm_info shi = {9, 65536, 1024, 32768, "/run/d.shm-9"};
    ADD("shm_info", DF_MSG_STREAM_SHM, DF_FLAG_REPLY, df_msg_shm_info_encode(&shi, out, &e));
    df_msg_shm_ref shr = {9, 131072, 12356};
    ADD("shm_ref", DF_MSG_SHM_REF, DF_FLAG_EVENT, df_msg_shm_ref_encode(&shr, out, &e));
    /* a path load asking for a 2D session (options bit 1, without EXT: no file_name) */
    df_msg_load_mesh l2 = lp;
    l2.options = DF_LOAD_OPT_2D;
    ADD("load_path_2d", DF_MSG_LOAD_MESH, 0, df_msg_load_mesh_encode(&l2, out, &e));
    /* session brush state (issue 11): a begin taking radius and nu from the session brush
     * (the optional trailing use_session), get / set, the reply and both events */
    df_msg_brush bus = sample_brush();
    bus.use_session = DF_BS_RADIUS | DF_BS_NU;
    ADD("brush_use_session", DF_MSG_BRUSH_BEGIN, 0, df_msg_brush_encode(&bus, out, &e));
    /* a surface-aware begin (issue 14: the last optional trailer, after use_session and options 0) */
    df_msg_brush bsf = sample_brush();
    bsf.surface = 1;
    ADD("brush_surface", DF_MSG_BRUSH_BEGIN, 0, df_msg_brush_encode(&bsf, out, &e));
    df_msg_session_ref bg = {42};
    ADD("brush_state_get", DF_MSG_BRUSH_STATE_GET, 0, df_msg_session_ref_encode(&bg, out, &e));
    df_msg_brush_state_set bss = {42, DF_BS_RADIUS | DF_BS_INTEGRATOR | DF_BS_MIRROR,
                                  {DF_BRUSH_GRAB, 1, DF_INTEG_RK4, 1, 4, 0.125, 0.5, 1, 1.1,
                                   {0.5, 0, 0}, {1, 0, 0}}};
    ADD("brush_state_set", DF_MSG_BRUSH_STATE_SET, 0,
        df_msg_brush_state_set_encode(&bss, out, &e));
    df_msg_brush_state bst = {42, 0, 0, DF_ORIGIN_NONE, 0, "",
                              {DF_BRUSH_TWIST, 3, DF_INTEG_EULER, 0, 1, 0.25, 0.45, -2, 1.5,
                               {0, 0, 0}, {1, 0, 0}}};
    ADD("brush_state_reply", DF_MSG_BRUSH_STATE_GET, DF_FLAG_REPLY,
        df_msg_brush_state_encode(&bst, out, &e));
    df_msg_brush_state bev = bst;
    bev.seq = 7;
    bev.changed = DF_BS_RADIUS | DF_BS_NU;
    bev.origin_kind = DF_ORIGIN_DEVICE;
    bev.origin_id = (1ull << 63) | 3;
    snprintf(bev.origin_name, sizeof bev.origin_name, "Surface Dial");
    bev.v.nu = INFINITY;
    ADD("brush_state_event", DF_MSG_BRUSH_STATE, DF_FLAG_EVENT,
        df_msg_brush_state_encode(&bev, out, &e));
    df_msg_brush_cursor bc = {42, DF_ORIGIN_CLIENT, 12, DF_CURSOR_IN_RANGE,
                              {0.5, -0.25, 1e-3}, 0.25};
    ADD("brush_cursor", DF_MSG_BRUSH_CURSOR, DF_FLAG_EVENT,
        df_msg_brush_cursor_encode(&bc, out, &e));
    /* devices (HID): a knob and a pen, their list, a bind and a view */
    static df_msg_device_info dev[2];
    memset(dev, 0, sizeof dev);
    dev[0] = (df_msg_device_info){.device_id = (1ull << 63) | 1, .dev_class = DF_DEVCLASS_KNOB,
                                  .backend = DF_DEVBACKEND_REPLAY, .state = DF_DEVSTATE_OPEN,
                                  .bus = 5, .vid = 0x045e, .pid = 0x091b, .bound_session = 0,
                                  .active_session = 5, .haptics = 1};
    snprintf(dev[0].name, sizeof dev[0].name, "Surface Dial System Multi Axis");
    snprintf(dev[0].path, sizeof dev[0].path, "replay:/work/shared/hid/dial.hid#0");
    dev[1] = (df_msg_device_info){.device_id = (1ull << 63) | 2, .dev_class = DF_DEVCLASS_PEN,
                                  .backend = DF_DEVBACKEND_HIDAPI, .state = DF_DEVSTATE_ERROR,
                                  .bus = 3, .vid = 0x1b96, .pid = 0x1000, .bound_session = 7};
    snprintf(dev[1].name, sizeof dev[1].name, "N-Trig Pen");
    snprintf(dev[1].path, sizeof dev[1].path, "/dev/hidraw3");
    snprintf(dev[1].error, sizeof dev[1].error, "read: Input/output error");
    ADD("device_state", DF_MSG_DEVICE_STATE, DF_FLAG_EVENT,
        df_msg_device_info_encode(&dev[0], out, &e));
    df_msg_device_list dl = {2, dev};
    ADD("device_list", DF_MSG_DEVICES_LIST, DF_FLAG_REPLY, df_msg_device_list_encode(&dl, out, &e));
    df_msg_device_bind db = {(1ull << 63) | 1, 5};
    ADD("device_bind", DF_MSG_DEVICE_BIND, 0, df_msg_device_bind_encode(&db, out, &e));
    df_msg_device_view dv = {(1ull << 63) | 2, 5, {0}, {0, 0, 1920, 1080}};
    for (int i = 0; i < 16; i++) dv.view_proj[i] = i % 5 == 0 ? 1.0 : 0.0;
    dv.view_proj[11] = -0.5;
    ADD("device_view", DF_MSG_DEVICE_VIEW, 0, df_msg_device_view_encode(&dv, out, &e));
    ADD("devices_list", DF_MSG_DEVICES_LIST, 0, ((void)out, DF_OK)); /* empty request */
    /* resync (issue 12): subscribe with the optional trailing from_version */
    df_msg_subscribe subv = {5, DF_SUBSCRIBE_FROM_VERSION, 0x0102030405060708ull};
    ADD("subscribe_from", DF_MSG_SUBSCRIBE, 0, df_msg_subscribe_encode(&subv, out, &e));
    /* per-session access: a policy change, a join, the policy with and without a new key */
    df_msg_session_access sa = {5, DF_ACCESS_MODE_KEY, 1, DF_ACCESS_NEW_KEY};
    ADD("session_access", DF_MSG_SESSION_ACCESS, 0, df_msg_session_access_encode(&sa, out, &e));
    static df_msg_join jn;
    jn.session_id = 5;
    for (int i = 0; i < (int)DF_JOIN_KEY_BYTES; i++) jn.key[i] = (uint8_t)(0xA0 + i);
    ADD("join", DF_MSG_JOIN, 0, df_msg_join_encode(&jn, out, &e));
    static df_msg_access_info ai;
    memset(&ai, 0, sizeof ai);
    ai = (df_msg_access_info){.session_id = 5, .mode = DF_ACCESS_MODE_KEY, .observers = 0,
                              .members = 2, .has_key = 1};
    snprintf(ai.owner, sizeof ai.owner, "key:alice");
    memcpy(ai.key, jn.key, sizeof ai.key);
    ADD("access_info_key", DF_MSG_SESSION_ACCESS, DF_FLAG_REPLY,
        df_msg_access_info_encode(&ai, out, &e));
    ai.has_key = 0;
    ai.mode = DF_ACCESS_MODE_OPEN;
    ai.observers = 1;
    ADD("access_info", DF_MSG_JOIN, DF_FLAG_REPLY, df_msg_access_info_encode(&ai, out, &e));
    /* progress of long work (PROTOCOL.md 4.37): the opt-ins and the event */
    df_msg_handles hsp = sample_handles_msg(&aff);
    hsp.options = DF_WORK_OPT_PROGRESS;
    ADD("handles_progress", DF_MSG_HANDLES_SET, 0, df_msg_handles_encode(&hsp, out, &e));
    df_msg_handle_move hmp = {7, 0, 250, 10, 4, sample_targets, DF_WORK_OPT_PROGRESS, 0};
    ADD("handle_move_progress", DF_MSG_HANDLES_MOVE, 0, df_msg_handle_move_encode(&hmp, out, &e));
    df_msg_brush bpr = sample_brush(); /* pinned points: their LU's progress */
    bpr.options = DF_WORK_OPT_PROGRESS;
    ADD("brush_progress", DF_MSG_BRUSH_BEGIN, 0, df_msg_brush_encode(&bpr, out, &e));
    df_msg_work_progress wp = {0, DF_STAGE_PARSE, 0, 1 << 20, 3 << 20, 12.5};
    ADD("work_progress", DF_MSG_WORK_PROGRESS, DF_FLAG_EVENT,
        df_msg_work_progress_encode(&wp, out, &e));
    /* session peers (PROTOCOL.md 4.38): the request, two rows (one unnamed), an empty list */
    df_msg_session_ref spr = {9};
    ADD("session_peers", DF_MSG_SESSION_PEERS, 0, df_msg_session_ref_encode(&spr, out, &e));
    static df_msg_peer_info peer_rows[2];
    memset(peer_rows, 0, sizeof peer_rows);
    peer_rows[0] = (df_msg_peer_info){.client_id = 3, .flags = DF_PEER_EDIT | DF_PEER_SHM,
                                      .transport = DF_TRANSPORT_UNIX};
    snprintf(peer_rows[0].name, sizeof peer_rows[0].name, "blender");
    snprintf(peer_rows[0].principal, sizeof peer_rows[0].principal, "uid:1000");
    peer_rows[1] = (df_msg_peer_info){.client_id = 41, .flags = DF_PEER_SELF,
                                      .transport = DF_TRANSPORT_TCP};
    snprintf(peer_rows[1].principal, sizeof peer_rows[1].principal, "key:bob");
    df_msg_peer_list pl = {2, peer_rows};
    ADD("peer_list", DF_MSG_SESSION_PEERS, DF_FLAG_REPLY, df_msg_peer_list_encode(&pl, out, &e));
    df_msg_peer_list pl0 = {0, NULL};
    ADD("peer_list_empty", DF_MSG_SESSION_PEERS, DF_FLAG_REPLY,
        df_msg_peer_list_encode(&pl0, out, &e));
    /* negotiated stream encodings: hello / hello_reply with the trailer, qdisp, zframe */
    df_msg_hello hq = {1, 1, 0, "remote", 1, DF_STREAM_ENC_QUANTIZED | DF_STREAM_ENC_ZSTD, 1e-5};
    ADD("hello_stream", DF_MSG_HELLO, 0, df_msg_hello_encode(&hq, out, &e));
    df_msg_hello_reply hrq = hr;
    hrq.has_stream = 1;
    hrq.stream_encoding = DF_STREAM_ENC_ZSTD;
    ADD("hello_reply_stream", DF_MSG_HELLO, DF_FLAG_REPLY,
        df_msg_hello_reply_encode(&hrq, out, &e));
    int64_t qd_dq[9] = {1, -1, 0, 300, -70000, 5, 0, 0, -(1ll << 40)};
    df_msg_qdisp qd = {.session_id = 42, .version = 8, .base_version = 7, .kind = DF_CHANGE_BRUSH,
                       .nv = 100, .count = 3, .step = 2e-5, .idx = sample_sparse_idx,
                       .dq = qd_dq};
    ADD("qdisp", DF_MSG_QDISP, DF_FLAG_EVENT, df_msg_qdisp_encode(&qd, out, &e));
    df_msg_qdisp qe = {.session_id = 42, .version = 9, .base_version = 8,
                       .kind = DF_CHANGE_HANDLE_MOVE, .nv = 100, .count = 0, .step = 1e-3};
    ADD("qdisp_empty", DF_MSG_QDISP, DF_FLAG_EVENT | DF_FLAG_MORE,
        df_msg_qdisp_encode(&qe, out, &e));
    /* a handle-move iterate with the progress trailer (4.40) */
    df_msg_qdisp qp = {.session_id = 42, .version = 10, .base_version = 9,
                       .kind = DF_CHANGE_HANDLE_MOVE, .nv = 100, .count = 3, .step = 2e-5,
                       .idx = sample_sparse_idx, .dq = qd_dq, .has_progress = 1,
                       .status = DF_MOVE_RUNNING, .final = 0, .iteration = 4, .objective = 1.25,
                       .residual = 3e-4, .elapsed_ms = 12.5};
    ADD("qdisp_progress", DF_MSG_QDISP, DF_FLAG_EVENT, df_msg_qdisp_encode(&qp, out, &e));
    /* a real zstd frame of 16 zero bytes (zstd -c of /dev/zero, head -c 16) */
    static const uint8_t zbytes[] = {0x28, 0xb5, 0x2f, 0xfd, 0x04, 0x58, 0x45, 0x00, 0x00,
                                     0x10, 0x00, 0x00, 0x01, 0x00, 0x32, 0xc0, 0x02, 0x32,
                                     0x7c, 0x24, 0x16};
    df_msg_zframe zf = {DF_MSG_DISPLACEMENT, 16, sizeof zbytes, zbytes};
    ADD("zframe", DF_MSG_ZFRAME, DF_FLAG_EVENT, df_msg_zframe_encode(&zf, out, &e));
#undef ADD
    if (k != N_SAMPLES) {
        fprintf(stderr, "built %d samples, expected %d\n", k, N_SAMPLES);
        abort();
    }
}

static inline void free_samples(sample *s)
{
    for (int i = 0; i < N_SAMPLES; i++)
        df_buf_free(&s[i].payload);
}

#endif

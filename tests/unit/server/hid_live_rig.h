/* hid_live_rig.h — the scaffolding the live-HID server unit tests share (header-only): a recorded
 * descriptor loaded from the HID test data, a real libuv loop with a keep-alive tick and a
 * compute pool, a server with the HID manager ops and one tiny-mesh session, the loop run until
 * a predicate holds (no sleeps), and the teardown. Each test keeps its own fake backend (what
 * the fakes answer differs); hid_rig_devinfo fills the device they list. Test thread only. */
#ifndef DF_TEST_SERVER_HID_LIVE_RIG_H
#define DF_TEST_SERVER_HID_LIVE_RIG_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <uv.h>

#include "server/exec/pool.h"
#include "server/hid/hid_manager.h"
#include "server/hid/hid_recording.h"
#include "server/session/session.h"
#include "tests/unit/hid/hid_files.h"
#include "tests/unit/server/tiny_mesh.h"
#include "tests/unit/unit_skip.h"

typedef struct hid_rig {
    uv_loop_t loop;
    uv_timer_t tick;           /* keeps UV_RUN_ONCE blocking in poll */
    df_hid_recording rec;      /* the recording the fake's descriptor points into */
} hid_rig;

static inline void hid_rig_on_tick(uv_timer_t *t) { (void)t; }

/* Parses recording `file` (a name in the HID test data dir, skipped when the dir is absent)
 * into g->rec; fails the test when it cannot be read or parsed. */
static inline void hid_rig_recording(hid_rig *g, const char *file)
{
    char dir[2048];
    unit_hid_dir_or_skip(dir, sizeof dir);
    size_t n = 0;
    char *text = hid_read_file(dir, file, &n);
    assert_non_null(text);
    df_error e;
    assert_int_equal(df_hid_recording_parse(text, n, &g->rec, &e), DF_OK);
    free(text);
}

/* Fills the device a fake backend lists: path, name, vid:pid, the hidapi backend and the first
 * recorded device's descriptor (borrowed from g->rec). */
static inline void hid_rig_devinfo(const hid_rig *g, df_hid_devinfo *info, const char *path,
                                   const char *name, uint16_t vid, uint16_t pid)
{
    snprintf(info->path, sizeof info->path, "%s", path);
    snprintf(info->name, sizeof info->name, "%s", name);
    info->vid = vid;
    info->pid = pid;
    info->backend = DF_HID_BACKEND_HIDAPI;
    info->desc = g->rec.devices[0].desc;
    info->desc_len = g->rec.devices[0].desc_len;
}

/* Starts the loop (50 ms tick), zeroes srv with default config (no periodic enumeration), the
 * HID manager ops, a 2-thread pool, and session "t" on a tiny mesh (*s), made the most recently
 * active session. The HID manager itself is started by the test. */
static inline void hid_rig_start(hid_rig *g, df_server *srv, df_session **s)
{
    df_error e;
    uv_loop_init(&g->loop);
    uv_timer_init(&g->loop, &g->tick);
    uv_timer_start(&g->tick, hid_rig_on_tick, 50, 50);
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
    srv->cfg.hid_enumerate_s = 0;
    srv->loop = &g->loop;
    srv->hid_ops = &df_hid_manager_ops;
    assert_int_equal(df_pool_start(&g->loop, 2, 0, &srv->pool, &e), DF_OK);
    df_mesh m = tiny_mesh();
    assert_int_equal(df_session_create(srv, &m, "t", s, &e), DF_OK);
    srv->last_change_session = (*s)->id;
}

/* Runs the loop until pred(arg) holds; fails after 1200 loop iterations (~60 s of ticks). */
static inline void hid_rig_run_until(hid_rig *g, int (*pred)(void *), void *arg,
                                     const char *what)
{
    for (int i = 0; i < 1200 && !pred(arg); i++) uv_run(&g->loop, UV_RUN_ONCE);
    if (!pred(arg)) fail_msg("never reached: %s", what);
}

/* After the test has stopped and freed the HID manager and closed its sessions: closes the
 * tick and the pool, drains the loop, checks it closes, frees the recording. */
static inline void hid_rig_finish(hid_rig *g, df_server *srv)
{
    uv_close((uv_handle_t *)&g->tick, NULL);
    df_pool_close(srv->pool);
    uv_run(&g->loop, UV_RUN_DEFAULT);
    df_pool_free(srv->pool);
    assert_int_equal(uv_loop_close(&g->loop), 0);
    df_hid_recording_free(&g->rec);
}

#endif

/* hid_manager.h — the daemon's HID devices (issue 11, "Daemon integration").
 *
 * The manager owns a registry of devices found by the configured backends (hid_source.h: hidapi
 * and libusb when `hid = on`, replay files from `hid_replay` / --hid-replay). Each device gets a
 * stable id (1 << 63) | n (never a connection id), a class (hid_class.h) and a mapper
 * (hid_mapper.h). Discovery: at start, on libusb hotplug callbacks and every hid_enumerate_s
 * seconds. Every open device has one reader thread that blocks in the backend's read (100 ms
 * timeout) and posts each report, with its event time, to the loop thread through the compute
 * pool's one completion channel (df_pool_post), so reports of a device arrive in read order.
 *
 * On the loop thread a report goes through the mapper, and its actions become what a client
 * would send (hid_mgr_drive.c): brush-state changes (df_brush_state_apply, origin DEVICE),
 * cursor events (df_brush_cursor_publish), and BRUSH_BEGIN / SET_BRUSH_PARAM / BRUSH_UPDATE /
 * BRUSH_END requests queued through df_job_request with an internal df_req (no connection;
 * origin_id = the device id, which keys the device's stroke), so ordering, undo and broadcast
 * are those of any client. Haptic output reports and PowerMate LED transfers go to the device
 * from the loop thread. The session a device drives: its bound session (DEVICE_BIND /
 * DEVICE_VIEW), else the most recently active one (srv->last_change_session).
 *
 * A device that errors or unplugs (a replay that ends) is closed, logged and reported (state in
 * DEVICES_LIST, a DEVICE_STATE event to the subscribers of the session it drove); its open stroke
 * is ended through the same BRUSH_END path first. Replay devices wait for the first active
 * session before they start: the first subscribe (so a test or demo has something to drive and
 * a subscriber sees every event).
 *
 * Threads: every function here runs on the loop thread. */
#ifndef DF_SERVER_HID_MANAGER_H
#define DF_SERVER_HID_MANAGER_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/messages.h"
#include "server/server.h"

struct df_session;

/* Starts the HID subsystem of srv (srv->hid) per srv->cfg: hid (on/off), hid_replay (files),
 * hid_enumerate_s, hid.* mapping (srv->cfg.hid). With hid off and no replay files it does
 * nothing (srv->hid stays NULL: no feature bit, DEVICES_LIST lists none). Backends that cannot
 * start (no hidraw support, libusb_init failing) are logged and skipped. Errors: a replay file
 * that cannot be read or parsed (DF_EIO / DF_EFORMAT, message names it), DF_ENOMEM. */
int df_hid_manager_start(df_server *srv, df_error *err);

/* The same with the given backends instead of those srv->cfg names (tests: a fake backend; any
 * may be NULL): `live` is enumerated like hidapi (at start, every hid_enumerate_s, on its watch
 * callback), `usb` like libusb, `replay` like the replay backend (devices open at the first
 * subscribe). The manager owns them from here (also on error). DF_OK or DF_ENOMEM. */
struct df_hid_backend;
int df_hid_manager_start_with(df_server *srv, struct df_hid_backend *live,
                              struct df_hid_backend *usb, struct df_hid_backend *replay,
                              df_error *err);

/* Begins shutdown (from df_server_stop): stops enumerating, tells every reader thread to stop
 * and joins it, closes every device and its backend. Posted reports still in flight are dropped
 * when they arrive. Idempotent; NULL-safe for srv->hid. */
void df_hid_manager_stop(df_server *srv);

/* 1 while posted reports have not been delivered yet (shutdown waits for 0). */
int df_hid_manager_busy(const df_server *srv);

/* Frees the manager once the loop has ended (after df_hid_manager_stop). NULL-safe. */
void df_hid_manager_free(df_server *srv);

/* A client subscribed to s (after its reply): replay devices waiting for a session start. */
void df_hid_manager_session_active(df_server *srv, struct df_session *s);

/* Session s is going away: devices bound to it fall back to following the most recent session,
 * its pen ray-cast cache is freed. */
void df_hid_manager_session_gone(df_server *srv, struct df_session *s);

/* Fills out (items malloc'd, free with df_msg_device_list_free) with every device in id order.
 * DF_OK or DF_ENOMEM. An absent manager lists none. */
int df_hid_manager_list(df_server *srv, df_msg_device_list *out, df_error *err);

/* Binds device_id to session_id (0: unbind). Ends the device's stroke on the session it drove
 * when that changes and sends DEVICE_STATE. DF_OK, DF_ENOTFOUND (unknown device or session). */
int df_hid_manager_bind(df_server *srv, uint64_t device_id, uint64_t session_id, df_error *err);

/* Sets the view of a pen (and binds it to v->session_id). DF_OK, DF_ENOTFOUND. */
int df_hid_manager_view(df_server *srv, const df_msg_device_view *v, df_error *err);

/* Appends the stats of device `device_id` as (key, value) through put(ctx, key, value): events,
 * strokes, the last stroke's tip and strength, while a replay device is open `replay.start_us`
 * (CLOCK_MONOTONIC us at its open: its report recorded at r is due at that + r / hid_replay_speed),
 * the replay backend's captured output reports (`out.<seq>.<hex bytes>` = replay time in us;
 * feature reports sent `feat.<seq>.<hex bytes>`; control transfers
 * `ctl.<seq>.<reqtype>_<request>_<value>_<index>`, hex), and force feedback (`force_feedback`
 * 0/1, `ffb.reports` sent). DF_ENOTFOUND for an unknown device. */
int df_hid_manager_device_stats(df_server *srv, uint64_t device_id,
                                void (*put)(void *ctx, const char *key, double v), void *ctx,
                                df_error *err);

/* Daemon-wide figures: devices listed, devices open, reports handled. */
void df_hid_manager_counts(const df_server *srv, uint32_t *devices, uint32_t *open,
                           uint64_t *events);

/* The functions above as srv->hid_ops (server.h) for the layers that may not include this. */
extern const df_hid_ops df_hid_manager_ops;

#endif

/* hid_mgr_ffb.h — force feedback of the HID manager (issue 11, optional part: "Force feedback
 * (PID page 0x0F) for a constant force proportional to the live grab's Kelvinlet force
 * vector"). Off by default.
 *
 * Which device: one whose report descriptor has the PID output reports hid_ffb.h lays out
 * (df_hid_ffb.present: Set Effect and Set Constant Force, e.g. the SideWinder Force Feedback 2)
 * and whose VID:PID section sets `force_feedback = yes` (hid_config.h). Such a joystick has no
 * mapper class (it drives no brush); it is opened for its output reports only (its input
 * reports are read and ignored).
 *
 * Which force: the device follows a session as every device does (bound, else the most
 * recently active one: df_hid_drive_session). While at least one grab stroke (of any client or
 * device) is open on that session, the joystick plays one constant-force effect whose vector
 * is the sum over those strokes of the Kelvinlet grab force f of the stroke's brush at its
 * current tip (server/session/stroke_force.h: the shear modulus is normalized away, so the
 * physical force is 4 pi mu f; ffb_gain absorbs the 4 pi mu). Projection onto the joystick's two axes: the force's mesh x and
 * y components (df_hid_ffb_from_force: magnitude = min(1, ffb_gain |(fx, fy)|), polar
 * direction 0 = +y, clockwise towards +x; the z component is dropped).
 *
 * Reports (all laid out from the descriptor by hid_ffb.h), on the loop thread:
 *   first grab stroke begins: Device Control Enable Actuators (once per open), Create New
 *     Effect (feature, constant force, Byte Count 0 as Linux's pidff), Block Load (feature
 *     GET_REPORT: the effect block; a backend that cannot read feature reports — the replay
 *     backend — gives block 1, the first block of a device with no effect loaded; a status
 *     other than Success stops here until the strokes end), Set Effect (block, infinite
 *     duration, gain 1, no trigger button, X and Y enabled, polar direction), Set Constant
 *     Force (magnitude), Effect Operation Start (loop count 1);
 *   stroke updates / knob changes: Set Effect when the direction's bytes change, Set Constant
 *     Force when the magnitude's bytes change, at most ffb_hz times a second (the latest value
 *     is sent at the end of an interval; ffb_hz 0: every change);
 *   last grab stroke ends or is cancelled, the session goes away, the device follows another
 *     session, or the device closes (unplug, error, shutdown): Effect Operation Stop (loop
 *     count 0), Block Free.
 * Loop thread only. */
#ifndef DF_SERVER_HID_MGR_FFB_H
#define DF_SERVER_HID_MGR_FFB_H

#include <stddef.h>
#include <stdint.h>

struct df_hid_device;
struct df_hid_manager;
struct df_server;
struct df_session;

/* At discovery (after the device was classified): when d's descriptor has PID reports and its
 * config says force_feedback = yes, d->ffb is allocated (else left NULL). A failed allocation
 * is logged; the device then has no force feedback. */
void df_hid_ffb_setup(struct df_hid_device *d);

/* The strokes of session s changed (srv->hid_ops->strokes_changed, after a commit): every
 * force-feedback device following s starts, updates or stops its effect. */
void df_hid_ffb_strokes_changed(struct df_server *srv, struct df_session *s);

/* Stops d's effect if one plays (Effect Operation Stop, Block Free), e.g. before its handle
 * closes; session_id != 0: only when the effect plays for that session. A closing device also
 * forgets that its actuators were enabled (close = 1). */
void df_hid_ffb_stop(struct df_hid_device *d, uint64_t session_id, int close);

/* Manager stop: closes d's rate-limit timer (the loop still runs). */
void df_hid_ffb_close(struct df_hid_device *d);

/* Manager free: frees d->ffb (after df_hid_ffb_close and a loop turn). NULL-safe. */
void df_hid_ffb_free(struct df_hid_device *d);

/* Reports sent by d's force feedback so far (0 without it). */
uint64_t df_hid_ffb_reports(const struct df_hid_device *d);

/* 1 while the latest force waits for the end of the rate-limit interval. */
int df_hid_ffb_pending(const struct df_hid_device *d);

#endif

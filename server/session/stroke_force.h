/* stroke_force.h — the Kelvinlet force of a session's open grab strokes (what HID force
 * feedback plays: server/hid/hid_mgr_ffb.h).
 *
 * A grab stroke's load is a force vector f at its centre (de Goes & James 2017, regularized
 * Kelvinlets): df_kelvinlet_prepare normalizes the brush so that the centre moves by the tip,
 * f = tip / (sum_i w_i kappa(eps_i)) with kappa(eps) = ((a - b) + a / 2) / eps in 3D, a = 1,
 * b = 1 / (4 (1 - nu)) (the shear modulus mu is normalized away: the physical force is
 * 4 pi mu f; length^2 units of the mesh). Pinned points are not taken into account (the
 * unconstrained brush's load). Loop thread (reads s->strokes). */
#ifndef DF_SERVER_STROKE_FORCE_H
#define DF_SERVER_STROKE_FORCE_H

#include "server/session/session.h"

/* The sum of the grab force f of every open grab stroke of s (its brush at its current tip,
 * df_stroke.tip) into f[3]. Returns the number of open grab strokes (0: f = 0). A stroke whose
 * brush the engine refuses (it was validated at begin, so not expected) adds nothing. */
int df_session_grab_force(const df_session *s, double f[3]);

#endif

/* access.h — per-session rights and per-principal quotas (PROTOCOL.md 4.34). Loop thread.
 *
 * A connection acts as a principal (df_conn.principal: Unix "uid:N", TCP "key:NAME" for a
 * peer_key, "admin" for key_file, "tcp" on a server without keys; server/net/peer.h, auth.h).
 * The principal that loads a session owns it (df_session.owner). Rights on a session:
 *   DF_RIGHT_OBSERVE  subscribe, unsubscribe, shared-memory stream, get mesh, snapshot,
 *                     handles get, brush state get, session peers; also open session, a session's stats and
 *                     being listed (checked by their handlers)
 *   DF_RIGHT_EDIT     brush strokes and parameters, brush state set, handles set / move,
 *                     undo / redo, device bind and device view
 *   DF_RIGHT_OWN      close session, reset rest
 *                     and SESSION_ACCESS setting the policy (its plain get needs observe)
 * The owner and admins (key_file, the daemon's own uid or root on the Unix socket, and
 * internal requests of HID devices) hold every right; the others' rights follow the session's
 * policy (df_session.acc, membership.h: open / key / owner mode, observers on or off).
 * A refused request gets DF_EPERM naming the right, the session, the requester, the owner,
 * the mode and how to get the right, and changes nothing.
 * Quotas (quota_sessions, quota_upload_mb, quota_memory_mb; 0 = unlimited) count the live
 * sessions a principal owns; closing a session releases its share at once. A session's memory
 * is its stats memory_bytes (estimate + undo history + shared-memory ring); a new one counts
 * df_session_estimate_bytes of its mesh. */
#ifndef DF_SERVER_ACCESS_H
#define DF_SERVER_ACCESS_H

#include <stdint.h>

#include "server/net/req.h"
#include "server/session/session.h"

enum { DF_RIGHT_OBSERVE = 1, DF_RIGHT_EDIT = 2, DF_RIGHT_OWN = 4 };

/* The right request `type` needs on its session (DF_RIGHT_*), 0 for a request that names no
 * session or needs none. */
int df_access_needed(uint16_t type);

/* The rights (DF_RIGHT_* bits) connection `c` holds on `s`; c NULL (an internal request of a
 * HID device) holds every right. */
int df_access_rights(const df_conn *c, const df_session *s);

/* DF_OK when request `r` (type r->type) may run on `s`, else DF_EPERM with a message such as
 * "close_session: session 'spot' needs the own right (you are key:bob, a member; owner
 * key:alice; key mode): only the owner or an admin key has it". Changes nothing. */
int df_access_check(const df_req *r, const df_session *s, df_error *err);

/* df_access_check for an explicit right `need` (DF_RIGHT_*; SESSION_ACCESS needs observe to
 * read the policy and own to change it). */
int df_access_require(const df_req *r, const df_session *s, int need, df_error *err);

/* DF_OK when principal `who` may own one more session holding `upload_bytes` of uploaded file
 * and `mem_bytes` of session memory, given the live sessions it owns now; else DF_ELIMIT
 * naming the quota, the principal, its use and the limit. Admins are not exempt. */
int df_access_quota_check(df_server *srv, const char *who, uint64_t upload_bytes,
                          uint64_t mem_bytes, df_error *err);

#endif

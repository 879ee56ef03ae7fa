/* peer.h — who is on the other end of a connection (loop thread).
 *
 * Unix socket: the peer's credentials (SO_PEERCRED: uid, gid, pid at connect time, and its
 * supplementary groups through SO_PEERGROUPS where the kernel has it) are recorded in the
 * df_conn (peer_cred, peer_uid, peer_gid, peer_pid) and logged with the connection. When the
 * config restricts the socket (allow_uids / allow_gids, access_config.h) a peer matching neither
 * list gets one ERROR event (type ERROR, request id 0, code EPROTO_AUTH, the message naming its
 * uid, gid and pid and the settings) and is closed; the refusal is logged (warn) with uid and pid
 * and counted in stats (clients_refused_peer). A peer whose credentials cannot be read is
 * refused the same way when the socket is restricted.
 * The principal (df_conn.principal, access control, PROTOCOL.md 4.34): Unix "uid:N", an admin
 * when N is 0 or the daemon's own uid; TCP "tcp" until AUTH names it (auth.h).
 * TCP: the peer's address is recorded (peer_addr "ADDR port P", peer_host "ADDR", peer_loopback)
 * for the key authentication's log lines and rate limit (auth.h). */
#ifndef DF_SERVER_PEER_H
#define DF_SERVER_PEER_H

#include "server/server.h"

/* Records the identity of the freshly accepted connection `c` (Unix or TCP, c->is_tcp) and, for
 * a restricted Unix socket, refuses a peer that is not allowed. Returns 1 when `c` was refused
 * (an ERROR frame is queued and it closes once that is flushed: do not start reading), else 0. */
int df_peer_admit(df_conn *c);

#endif

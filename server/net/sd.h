/* sd.h — the two systemd protocols deformd speaks, implemented directly (no libsystemd).
 *
 * sd_notify: a datagram with "READY=1" / "STOPPING=1" / "STATUS=..." sent to the AF_UNIX socket
 * named by $NOTIFY_SOCKET ('@' prefix = abstract namespace).
 * Socket activation: when $LISTEN_PID equals our pid, fds 3 .. 3 + $LISTEN_FDS - 1 are listening
 * sockets handed over by systemd. */
#ifndef DF_SERVER_SD_H
#define DF_SERVER_SD_H

#define DF_SD_LISTEN_FDS_START 3
#define DF_SD_MAX_LISTEN_FDS 16

/* Sends `state` (e.g. "READY=1") to $NOTIFY_SOCKET. Returns 1 when sent, 0 when NOTIFY_SOCKET is
 * unset (not under systemd), DF_EINVAL for a bad socket name, DF_EIO when sending fails. */
int df_sd_notify(const char *state);

/* Collects socket-activated fds: when $LISTEN_PID is our pid and $LISTEN_FDS = n (1..max), stores
 * fds 3..3+n-1 in fds[], marks them close-on-exec, unsets LISTEN_PID/LISTEN_FDS/LISTEN_FDNAMES
 * and returns n. Returns 0 when not socket-activated, DF_EINVAL for malformed variables. */
int df_sd_listen_fds(int *fds, int max);

#endif

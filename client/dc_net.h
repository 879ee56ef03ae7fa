/* dc_net.h — libdeformclient's socket layer (internal): connecting, and whole-buffer reads and
 * writes that survive partial transfers, EINTR and EAGAIN.
 *
 * All functions take a connected stream socket `fd` (Unix or TCP, blocking or not) and report
 * failures through df_error (code DF_EIO; DF_EINVAL for bad arguments). */
#ifndef DF_CLIENT_DC_NET_H
#define DF_CLIENT_DC_NET_H

#include <stddef.h>

#include "core/common/df_error.h"

/* Longest Unix socket path accepted (sun_path minus the terminating NUL). */
#define DC_UNIX_PATH_MAX 107

/* Connects to the Unix stream socket at `path`. Returns the fd (>= 0) or a negative DF_E* code
 * (DF_EINVAL: path empty or longer than DC_UNIX_PATH_MAX; DF_EIO: socket/connect failed, the
 * message names the path and the errno text). The fd is blocking and close-on-exec. */
int dc_net_connect_unix(const char *path, df_error *err);

/* Connects to `host`:`port` over TCP (host: name or numeric IPv4/IPv6; port 1..65535), trying
 * every address getaddrinfo returns; sets TCP_NODELAY. Returns the fd or a negative DF_E* code. */
int dc_net_connect_tcp(const char *host, int port, df_error *err);

/* Writes all `len` bytes of `buf` to `fd`, retrying partial writes, EINTR, and (for
 * non-blocking fds) EAGAIN by waiting in poll(). Never raises SIGPIPE. Returns DF_OK or DF_EIO
 * ("connection closed by peer" when the peer has gone). */
int dc_net_write_all(int fd, const void *buf, size_t len, df_error *err);

/* Writes two buffers back to back (header + payload) with one writev when possible; same
 * semantics as dc_net_write_all. */
int dc_net_write2(int fd, const void *a, size_t alen, const void *b, size_t blen, df_error *err);

/* Reads exactly `len` bytes into `buf`, retrying partial reads, EINTR and EAGAIN. `timeout_ms`
 * bounds each wait for data (< 0: wait forever). Returns DF_OK, DF_EIO on error or end of
 * stream ("connection closed by peer"), or DF_ESTATE when the timeout expired before the first
 * byte arrived (nothing consumed). A timeout after a partial read is DF_EIO (stream broken). */
int dc_net_read_exact(int fd, void *buf, size_t len, int timeout_ms, df_error *err);

/* Reads up to `cap` bytes that are available now or within `timeout_ms` (< 0: forever) into
 * `buf`. Returns the count (> 0), DF_ESTATE on timeout, DF_EIO on error/end of stream. */
long dc_net_read_some(int fd, void *buf, size_t cap, int timeout_ms, df_error *err);

#endif

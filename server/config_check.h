/* config_check.h — `deformd --check-config`: the start-up checks of a parsed configuration,
 * without binding a socket or opening a device. */
#ifndef DF_SERVER_CONFIG_CHECK_H
#define DF_SERVER_CONFIG_CHECK_H

#include <stddef.h>

#include "server/config.h"

/* Checks `cfg` (parsed by df_config_from_args, so every key and value is already valid on its
 * own) for what start-up would refuse or what cannot work, touching nothing:
 *   - a listener at all (socket or tcp);
 *   - socket: its directory exists and is writable and searchable by this user, and an existing
 *     file there is a socket (skipped when systemd passes sockets: LISTEN_FDS set);
 *   - socket_group: names an existing group (or is a number);
 *   - tcp: the host resolves; a non-loopback address needs key_file and tls_cert/tls_key (or
 *     tcp_insecure);
 *   - tls_cert / tls_key: both set, readable, the key not readable by others and matching;
 *   - allow_paths: each entry exists and is a directory (stricter than start-up, which accepts
 *     a missing one and then refuses every load from it);
 *   - hid_replay: each file parses as a replay file (read, not played);
 *   - cluster: a local store (not none) and an address to advertise (advertise or tcp).
 * Appends one line per problem to `out` (NUL-terminated, truncated to `cap` bytes): "FILE:LINE:
 * message" when the key's line is found in cfg->config_path (the last line setting it to the
 * value in use, or holding the entry for a list key), else "command line: message". Returns the number of
 * problems (0: the configuration is fine). Never fails; any thread. */
int df_config_check(const df_server_config *cfg, char *out, size_t cap);

#endif

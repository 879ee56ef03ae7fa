/* config.h — deformd settings: defaults, the `key = value` config file and the command line.
 *
 * Config file syntax: one `key = value` per line; `#` starts a comment; blank lines ignored.
 * Keys (all optional):
 *   socket             Unix socket path (default $XDG_RUNTIME_DIR/deformd.sock else
 *                      /run/deformd/deformd.sock); "none" disables the Unix listener
 *   tcp                HOST:PORT for a TCP listener (default: off); "none" or "" disables it.
 *                      A non-loopback address needs key_file (authentication) and
 *                      tls_cert / tls_key (TLS 1.3), access_config.h; see tcp_insecure
 *   tcp_insecure       yes | no (default no): also listen on a non-loopback TCP address (0,
 *                      *, [::], a LAN address) without key and TLS (an explicit opt-out)
 *   socket_mode        permission bits of the Unix socket file, octal (default 0660; not
 *                      applied to a socket-activated fd: the unit's SocketMode= decides)
 *   socket_group       group (name or number) of the Unix socket file (default: the daemon's)
 *   handshake_timeout_s a connection that has not completed HELLO after this many seconds
 *                      gets an ERROR frame and is closed (0 = off, default 10)
 *   idle_timeout_s     a connection with no subscription, no unanswered request and no
 *                      upload that sent nothing for this many seconds gets an ERROR frame
 *                      and is closed (0 = off, default 300; subscribers may stay silent)
 *   allow_paths        directories whose files may be loaded by server-side path; a
 *                      colon- or comma-separated list; repeated lines append
 *   max_clients        simultaneous connections (1 .. DF_CONFIG_MAX_CLIENTS_LIMIT)
 *   output_queue_limit bytes a client may have queued before it is dropped (suffix k/m/g ok)
 *   stream_coalesce_start  queued bytes from which a subscriber whose hello carried the stream
 *                      trailer gets coalesced versions (PROTOCOL.md 6.3; suffix k/m/g ok;
 *                      0 .. 1g, default 0 = output_queue_limit / 8; capped at the limit)
 *   stream_coalesce_resume queued bytes at or below which it gets its coalesced version
 *                      (0 .. 1g, default 0 = output_queue_limit / 16; capped at the start)
 *   cache_memory_mb    memory cap of cached factorizations across sessions, MiB (0 = no caching
 *                      beyond the running job)
 *   log_level          error | warn | info | debug
 *   max_mesh_vertices  largest mesh accepted (vertices)
 *   max_sessions       sessions alive at once
 *   threads            worker threads of the compute pool (1 .. DF_CONFIG_MAX_THREADS)
 *   spin_us            microseconds a compute worker keeps polling for the next short job
 *                      before sleeping (0 .. DF_CONFIG_MAX_SPIN_US, default 0; see pool.h:
 *                      lowers stroke latency only when cores are idle)
 *   inline_us          brush updates whose stroke's last update took at most this many
 *                      microseconds run on the loop thread instead of the compute pool
 *                      (0 .. DF_CONFIG_MAX_INLINE_US, default DF_CONFIG_DEFAULT_INLINE_US; 0 =
 *                      never; see job.h)
 *   shm_ring_bytes     data bytes of a session's shared-memory stream ring (PROTOCOL.md 6.1;
 *                      allocated in /dev/shm when its first subscriber attaches; suffix k/m/g
 *                      ok; 0 disables STREAM_SHM, else 64k .. 4g; default 64m). This is the
 *                      cap: a ring is sized to its session's frames (shm.h, df_shm_ring_size)
 *   shm_total_bytes    all rings together (64k .. 1t, default DF_CONFIG_DEFAULT_SHM_TOTAL)
 *   max_upload_mb      largest inline upload (LOAD_MESH total_size), MiB (1 .. 1024, default 1024)
 *   uploads_max_mb     buffers of all uploads in flight together, MiB (default 1024)
 *   history_max_mb     undo history of one session, MiB; the oldest steps are dropped beyond it
 *   history_replay_ms  replay cost between undo checkpoints, ms (history.h; 0 = after every
 *                      recipe step; 0 .. 3600000, default DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS):
 *                      an undo replays about this much at most
 *                      (0 .. 1048576; default physical RAM / 32, clamped to 64 .. 1024)
 *   resync_ring_mb     frames of the versions last broadcast that one session keeps for clients
 *                      resyncing from a version they hold (SUBSCRIBE FROM_VERSION, resync.h),
 *                      MiB; the oldest versions are dropped beyond it (0 .. 1048576, default
 *                      DF_CONFIG_DEFAULT_RESYNC_RING_MB; 0 = keep none: every resync gets a
 *                      snapshot)
 *   cursor_hz          BRUSH_CURSOR events per second at most, per session and origin (a
 *                      device or client moving a brush cursor; brush_state.h): a value within
 *                      1/cursor_hz of the previous event waits for the end of that interval,
 *                      the latest one wins, never lost (0 .. DF_CONFIG_MAX_CURSOR_HZ, default
 *                      DF_CONFIG_DEFAULT_CURSOR_HZ; 0 = unlimited)
 *   memory_max_mb      memory budget of uploads, sessions, rings and history together, MiB
 *                      (16 .. 1073741824; default half the physical RAM, at least 256; see
 *                      membudget.h)
 *   hid                on | off (default on): read HID devices through hidapi (hidraw) and
 *                      libusb (PowerMate); with no device present nothing happens
 *   hid_replay         FILE[,FILE...]: also replay these hid-recorder files (or a PowerMate raw
 *                      file) as devices (server/hid/hid_source.h); they start when a client first
 *                      subscribes to a session; repeated lines append; --hid-replay replaces
 *                      the file's list (repeated options append). Works with hid = off (replay only)
 *   hid_replay_speed   replay speed factor: recorded gaps are divided by it (default 1); 0 =
 *                      deliver every report at once (tests: the recorded timestamps still drive
 *                      the mappers)
 *   hid_replay_end     unplug | hold | loop (default unplug): what a replay device does after its
 *                      last report (unplug; stay open and silent; start again)
 *   hid_enumerate_s    seconds between device enumerations (hotplug without libusb hotplug;
 *                      0 = only at start; default 2, at most 3600)
 *   hid.<class>.<key>, hid.<vvvv:pppp>.<key>   HID device mapping (server/hid/hid_config.h:
 *                      class knob | 3d-mouse | pen, per-device keys override class keys);
 *                      checked for consistency once the whole file is read
 *   allow_uids, allow_gids, key_file, tls_cert, tls_key, auth_fail_burst,
 *   auth_fail_refill_s   access control
 *                      (server/access_config.h)
 *   store              the durable session store (server/store/store.h): a file PATH, or
 *                      none (memory only); default $STATE_DIRECTORY/deformd.db under systemd,
 *                      else $XDG_STATE_HOME/deformd/deformd.db (~/.local/state/deformd/...)
 *   durability         full | normal | off (default full): SQLite synchronous FULL (fsync at
 *                      every acknowledged change), NORMAL (written before the ack, fsync at
 *                      checkpoints: survives kill -9, not a power loss), OFF
 *   store_max_mb       cap of the store file, MiB (0 = none, default): a change beyond it
 *                      fails like a full disk
 *   cluster            redis://HOST:PORT[,HOST:PORT...]: cluster mode (server/cluster/cluster.h):
 *                      sessions are leased, replicated to Redis and failed over; one Redis,
 *                      or seed nodes of a Redis Cluster (server/cluster/redis.h); "": off
 *   advertise          HOST:PORT other daemons redirect clients to (default: the tcp
 *                      listener's address); required with cluster
 *   cluster_lease_ms   session lease ttl, ms (default 3000, 300..600000)
 * Command line (overrides the file): --socket PATH, --store PATH|none, --tcp HOST:PORT,
 * --tcp-insecure, --config FILE, --foreground, --log-level LEVEL, --spin-us N, --inline-us N,
 * --hid-replay FILE[,FILE...], --key-file FILE, --check-config, --help. */
#ifndef DF_SERVER_CONFIG_H
#define DF_SERVER_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "server/access_config.h"
#include "server/hid/hid_config.h"

#define DF_CONFIG_PATH_MAX 4096
#define DF_CONFIG_SOCKET_MAX 108          /* sizeof(sockaddr_un.sun_path) */
#define DF_CONFIG_MAX_ALLOW 16            /* allow_paths entries */
#define DF_CONFIG_LINE_MAX 8192
#define DF_CONFIG_MAX_CLIENTS_LIMIT 100000
#define DF_CONFIG_MAX_THREADS 64
#define DF_CONFIG_MAX_SPIN_US 1000
#define DF_CONFIG_MAX_INLINE_US 1000
#define DF_CONFIG_MAX_CURSOR_HZ 10000

#define DF_CONFIG_DEFAULT_MAX_CLIENTS 256
#define DF_CONFIG_DEFAULT_QUEUE_LIMIT ((size_t)256 << 20) /* 256 MiB per client */
#define DF_CONFIG_DEFAULT_CACHE_MB 1024
#define DF_CONFIG_DEFAULT_MAX_VERTICES 4000000
#define DF_CONFIG_DEFAULT_MAX_SESSIONS 64
#define DF_CONFIG_DEFAULT_THREADS 4
#define DF_CONFIG_DEFAULT_SPIN_US 0
#define DF_CONFIG_DEFAULT_INLINE_US 50 /* ~ two thread hand-offs on the 2-core test machine */
#define DF_CONFIG_DEFAULT_CURSOR_HZ 120 /* BRUSH_CURSOR events per second per (session, origin) */
#define DF_CONFIG_DEFAULT_SHM_RING ((uint64_t)64 << 20) /* 64 MiB: ~5k 1k-vertex versions */
#define DF_CONFIG_MIN_SHM_RING ((uint64_t)64 << 10)
#define DF_CONFIG_DEFAULT_SHM_TOTAL ((uint64_t)256 << 20) /* all rings: 256 MiB */
#define DF_CONFIG_MAX_SHM_TOTAL ((uint64_t)1 << 40)
#define DF_CONFIG_DEFAULT_MAX_UPLOAD_MB 1024  /* = DF_MAX_MESH_BYTES, the protocol's limit */
#define DF_CONFIG_DEFAULT_UPLOADS_MB 1024
#define DF_CONFIG_MAX_UPLOADS_MB (1 << 20)
#define DF_CONFIG_HISTORY_RAM_DIVISOR 32      /* default history_max_mb = RAM / 32 ... */
#define DF_CONFIG_HISTORY_MIN_DEFAULT_MB 64   /* ... at least this ... */
#define DF_CONFIG_HISTORY_MAX_DEFAULT_MB 1024 /* ... at most this */
#define DF_CONFIG_MAX_HISTORY_MB (1 << 20)
#define DF_CONFIG_DEFAULT_RESYNC_RING_MB 32
#define DF_CONFIG_MAX_RESYNC_RING_MB (1 << 20)
/* 1000: at 1M vertices 200 local strokes then hold ~1.3-1.5x the position bytes of undo history
 * (bench_history; 250 gave 2.4x tri-scale, 6.2x single-scale), undo ~0.5 s median, ~1.3 s worst
 * on the 2-core test machine */
#define DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS 1000
#define DF_CONFIG_MAX_HISTORY_REPLAY_MS 3600000
#define DF_CONFIG_MEMORY_RAM_DIVISOR 2        /* default memory_max_mb = RAM / 2 ... */
#define DF_CONFIG_MEMORY_MIN_DEFAULT_MB 256   /* ... at least this */
#define DF_CONFIG_MEMORY_UNKNOWN_RAM_MB 4096  /* when the RAM size is unknown */
#define DF_CONFIG_MIN_MEMORY_MB 16
#define DF_CONFIG_MAX_MEMORY_MB (1 << 30)
#define DF_CONFIG_DEFAULT_SOCKET_MODE 0660
#define DF_CONFIG_DEFAULT_HANDSHAKE_TIMEOUT_S 10
#define DF_CONFIG_DEFAULT_IDLE_TIMEOUT_S 300
#define DF_CONFIG_MAX_TIMEOUT_S 86400    /* one day */
#define DF_CONFIG_GROUP_MAX 64
#define DF_CONFIG_MAX_HID_REPLAY 16       /* replay files */
#define DF_CONFIG_DEFAULT_HID_ENUMERATE_S 2
#define DF_CONFIG_MAX_HID_ENUMERATE_S 3600

typedef struct df_server_config {
    char socket_path[DF_CONFIG_SOCKET_MAX]; /* "" = no Unix listener */
    char tcp_host[256];                     /* "" = no TCP listener */
    int tcp_port;                           /* 0 with a host = any free port */
    int n_allow;
    char allow_paths[DF_CONFIG_MAX_ALLOW][DF_CONFIG_PATH_MAX]; /* normalized, no trailing '/' */
    int max_clients;
    size_t output_queue_limit;   /* bytes */
    int stream_coalesce_start;   /* bytes, 0 = output_queue_limit / 8 (stream_lag.h) */
    int stream_coalesce_resume;  /* bytes, 0 = output_queue_limit / 16 */
    size_t cache_memory_mb;
    int log_level;               /* DF_LOG_* */
    int32_t max_mesh_vertices;
    int max_sessions;
    int threads;
    int spin_us;                 /* compute worker spin after a short job, us (0 = off) */
    int inline_us;               /* loop-thread budget of a cheap brush update, us (0 = off) */
    int cursor_hz;               /* BRUSH_CURSOR rate per (session, origin), Hz (0 = unlimited) */
    uint64_t shm_ring_bytes;     /* shared-memory stream ring per session, bytes (0 = off) */
    uint64_t shm_total_bytes;    /* all rings together, bytes */
    int max_upload_mb;           /* largest inline upload, MiB */
    int uploads_max_mb;          /* all in-flight upload buffers together, MiB */
    int history_max_mb;          /* undo history per session, MiB */
    int resync_ring_mb;          /* resync ring per session, MiB (0 = none) */
    int history_replay_ms;       /* replay cost between undo checkpoints, ms */
    int memory_max_mb;           /* memory budget (membudget.h), MiB */
    int tcp_insecure;            /* 1: a non-loopback TCP address is allowed */
    int socket_mode;             /* Unix socket file permissions (e.g. 0660) */
    char socket_group[DF_CONFIG_GROUP_MAX]; /* "" = the daemon's group */
    int handshake_timeout_s;     /* HELLO deadline after accept, s (0 = off) */
    int idle_timeout_s;          /* silent unsubscribed connection deadline, s (0 = off) */
    int hid_on;                  /* 1: hidapi + libusb backends (config `hid`, default 1) */
    int n_hid_replay;
    char hid_replay[DF_CONFIG_MAX_HID_REPLAY][DF_CONFIG_PATH_MAX]; /* replay files */
    double hid_replay_speed;     /* > 0, or 0 = at once */
    int hid_replay_end;          /* DF_HID_REPLAY_END_* (hid_source.h): unplug (default), loop,
                                    hold (the device stays open and silent: force-feedback demos
                                    and tests that send it output after its last report) */
    int hid_enumerate_s;         /* 0 = at start only */
    int foreground;              /* 1: do not daemonize */
    df_hid_config hid;           /* hid.* keys (zeroed: every device uses the defaults) */
    df_access_config access;     /* allow_uids, allow_gids, key_file, auth_fail_*
                                    (access_config.h) */
    char config_path[DF_CONFIG_PATH_MAX]; /* "" when none */
    char store_path[DF_CONFIG_PATH_MAX];  /* config `store`: "" = the default, "none", a path */
    int durability;              /* 0 full, 1 normal, 2 off (store.h DF_DURABILITY_*) */
    int store_max_mb;            /* store file cap, MiB (0 = none) */
    char cluster[DF_CONFIG_PATH_MAX];   /* config `cluster`: "redis://host:port[,...]", "" = off */
    char advertise[DF_CONFIG_PATH_MAX]; /* config `advertise`: "host:port" ("" = tcp's) */
    int cluster_lease_ms;        /* session lease ttl, ms */
    int admm_active;             /* 1: handle sets solve in the active-set mode (admm.h
                                    DF_ADMM_ACTIVE), 2: the same with the tail test at
                                    DF_ADMM_ACTIVE_TAIL (admm.h "Tail test"), default 0 */
} df_server_config;

/* Fills `cfg` with the defaults; the socket path comes from `xdg_runtime_dir` (may be NULL or "",
 * then /run/deformd/deformd.sock). Never fails. */
void df_config_defaults(df_server_config *cfg, const char *xdg_runtime_dir);

/* Applies one setting `key` = `value` (both NUL-terminated, already trimmed) to `cfg`.
 * Errors: DF_EINVAL for an unknown key or a bad value (message names the key); cfg untouched. */
int df_config_set(df_server_config *cfg, const char *key, const char *value, df_error *err);

/* Parses the text of a config file (`len` bytes, need not be NUL-terminated) into `cfg`.
 * `name` is used in messages ("deformd.conf:3: ..."). On error `cfg` is left untouched
 * (all-or-nothing). Errors: DF_EINVAL / DF_EFORMAT with the line number. */
int df_config_parse(df_server_config *cfg, const char *text, size_t len, const char *name,
                    df_error *err);

/* Reads and parses the file at `path` (see df_config_parse). Errors: DF_EIO when unreadable. */
int df_config_load(df_server_config *cfg, const char *path, df_error *err);

/* What the command line asks for. */
typedef enum df_cli_action {
    DF_CLI_RUN = 0,
    DF_CLI_HELP = 1,
    DF_CLI_CHECK = 2 /* --check-config: check (config_check.h) and exit, start nothing */
} df_cli_action;

/* Parses argv (argc entries, argv[0] is the program name) into `cfg`, starting from the defaults
 * (computed from `xdg_runtime_dir`): first loads --config FILE when given, then applies the other
 * options on top. Sets *action to DF_CLI_HELP for --help/-h (cfg then unspecified), to
 * DF_CLI_CHECK for --check-config (cfg filled as for a run).
 * Errors: DF_EINVAL for an unknown option or a missing/bad value, DF_EIO/DF_EFORMAT from the file. */
int df_config_from_args(df_server_config *cfg, int argc, char **argv, const char *xdg_runtime_dir,
                        df_cli_action *action, df_error *err);

/* The --help text (static string). */
const char *df_config_usage(void);

/* 1 when `path` (absolute, already resolved by realpath) lies inside one of cfg->allow_paths,
 * else 0. */
int df_config_path_allowed(const df_server_config *cfg, const char *path);

#endif

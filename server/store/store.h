/* store.h — the durable session store: one SQLite file in WAL mode (issue 12, "Durable
 * sessions"), its opening, checks and schema.
 *
 * File: `store` in the config (--store PATH); default $STATE_DIRECTORY/deformd.db under systemd
 * (the first entry of that colon-separated list), else $XDG_STATE_HOME/deformd/deformd.db (XDG
 * default ~/.local/state); "none" keeps sessions in memory only. The default's directory is
 * created (0700); the file is created 0600 when missing.
 *
 * Schema (PRAGMA application_id DF_STORE_APP_ID, PRAGMA user_version DF_STORE_SCHEMA):
 *   meta(key TEXT PRIMARY KEY, value INTEGER)      next_session_id: ids are never reused
 *   sessions(id, name, kind, planar, nv, ne, nf, version, brush, brush_seq, log_bytes,
 *            snap_version, replay_ns)              one row per live session: topology sizes,
 *                                                   the last acknowledged version, the session
 *                                                   brush (codec.h), the log's bytes since the
 *                                                   last snapshot (journal.h), that snapshot's
 *                                                   version (0: the base) and the estimated
 *                                                   replay time of the log's recipe records
 *                                                   since (ns, journal.h); small, so that the
 *                                                   per-change update rewrites no mesh
 *   blobs(session, name, data, PRIMARY KEY(session, name))
 *                                                   a session's large values, one row each:
 *                                                   'base' (the exact double BASE positions,
 *                                                   load-time), 'elems', 'faces' (topology),
 *                                                   'handles' (the handle set, codec.h), 'cur',
 *                                                   'rest' (the last snapshot of the positions
 *                                                   and rest shape, 3 x nv doubles; absent: the
 *                                                   base)
 *   changes(id INTEGER PRIMARY KEY, session, version, kind, who, flags, delta, aux, recipe)
 *                                                   the change log, in commit order (journal.h;
 *                                                   recipe: record.h)
 *   access(session INTEGER PRIMARY KEY, owner, mode, observers, key_hash, members)
 *                                                   each session's owner and access policy
 *                                                   (membership.h): mode 1..3, observers 0/1,
 *                                                   the join key's SHA-256 (NULL: none) and
 *                                                   the members, each principal ended by '\n'
 * Versions: 1 (no access table; the large values in the session rows' own columns base, elems,
 * faces, handles, cur, rest; no recipe column, snap_version, replay_ns) and 2 (1 + the access
 * table) are migrated to 3 at open, in one transaction: a session without an access row gets
 * the configured mode and no owner (admins own it), snap_version = the stored version. 3 is
 * current. Any other version is refused, the file untouched.
 * Blobs hold native-endian values: a store moves between machines of the same byte order only.
 *
 * Checks at open (df_store_open): an existing empty file, a file that is not SQLite (a text
 * file), an SQLite database of another application (foreign application_id, or tables without
 * ours), a schema version this build does not know (older ones are migrated), or an integrity
 * failure refuse the open with a message naming the file; nothing is written to such a file.
 * Integrity: PRAGMA integrity_check for files up to DF_STORE_FULL_CHECK_BYTES, PRAGMA
 * quick_check (no index content cross-check) above. The store takes an exclusive lock (locking_mode EXCLUSIVE): a
 * second daemon on the same file is refused ("in use").
 *
 * Durability (config `durability`): full = PRAGMA synchronous FULL (the WAL is fsynced at every
 * commit: an acknowledged change survives a power loss), normal = NORMAL (the WAL commit is
 * written, fsynced at checkpoints: survives kill -9 and crashes of the daemon, not a power loss),
 * off = OFF (no fsync at all).
 *
 * Everything here runs on the loop thread (the SQLite connection is the loop's). */
#ifndef DF_SERVER_STORE_H
#define DF_SERVER_STORE_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

#define DF_STORE_APP_ID 0x44665244            /* "DfRD" */
#define DF_STORE_SCHEMA 3                     /* 1, 2 are migrated at open */
#define DF_STORE_FULL_CHECK_BYTES ((int64_t)256 << 20) /* integrity_check up to 256 MiB */
#define DF_STORE_SNAPSHOT_MIN ((uint64_t)1 << 20) /* journal.h: snapshot once the log since the
                                                   * last one exceeds max(this, 2 x 24 x nv) */
#define DF_STORE_SNAPSHOT_REPLAY_NS ((uint64_t)1000000000) /* journal.h: snapshot also once the
                                                   * log's recipe records would take longer
                                                   * than this to replay at restart (1 s) */
#define DF_STORE_REPLAY_VERTEX_NS 30              /* journal.h: a replayed recipe's restore time
                                                   * beyond its field, per vertex (checksums,
                                                   * base state copy, the undo history's
                                                   * checkpoints: bench_store_delta measured
                                                   * 51 ms per restored stroke, two replays of a
                                                   * 15 ms field, at 1M vertices; 2-3x that on
                                                   * a loaded machine, the field too) */
#define DF_STORE_SNAPSHOT_REPLAY_FORCE 4          /* ... taken between strokes, inside one only
                                                   * past this many times that */

enum { DF_DURABILITY_FULL = 0, DF_DURABILITY_NORMAL = 1, DF_DURABILITY_OFF = 2 };

typedef struct df_store df_store;
struct sqlite3;

/* Resolves the store path of config value `cfg` ("" = the default, "none", or a path) into
 * `out` (cap bytes) from the environment values given (each may be NULL): state_directory
 * ($STATE_DIRECTORY), xdg_state_home ($XDG_STATE_HOME), home ($HOME). Returns 1 with out = ""
 * for "none" (memory only), 0 with the path, or DF_EINVAL (no HOME to derive a default from, or
 * a path longer than cap) with a message. *is_default (may be NULL) = 1 for a derived default.
 * Pure. */
int df_store_resolve_path(const char *cfg, const char *state_directory,
                          const char *xdg_state_home, const char *home, char *out, size_t cap,
                          int *is_default, df_error *err);

/* Opens (creating when missing) the store at `path` with `durability` (DF_DURABILITY_*);
 * max_mb > 0 caps the file's size (PRAGMA max_page_count; a write beyond it fails as a full
 * disk), 0 = no cap. mkdir_parent 1: creates the parent directory (0700) when missing. Runs
 * the checks above; *checked (may be NULL) gets "integrity_check" or "quick_check". On success
 * *out is a new store. Errors (message names the file): DF_EIO (cannot open / create / lock:
 * "in use by another process"), DF_EFORMAT (empty, not SQLite, foreign, corrupt, unknown
 * schema version), DF_ENOMEM. An older schema version is migrated (df_store_migrated_from);
 * a failed migration (DF_EIO) leaves the file as it was. */
int df_store_open(const char *path, int durability, int max_mb, int mkdir_parent,
                  df_store **out, const char **checked, df_error *err);

/* Closes the store (the WAL is checkpointed by SQLite). NULL-safe. */
void df_store_close(df_store *st);

/* The file's path (owned by st). */
const char *df_store_path(const df_store *st);

/* The SQLite connection (for journal.c / restore.c and tests that inject errors, e.g.
 * PRAGMA max_page_count or query_only). */
struct sqlite3 *df_store_db(df_store *st);

/* Fails `err` with `code` and "store FILE: WHAT: <sqlite's message>". Returns code. */
int df_store_fail(df_store *st, int code, const char *what, df_error *err);

/* Runs `sql` (no results) in the store. Errors: DF_EIO via df_store_fail (`what` names it). */
int df_store_exec(df_store *st, const char *sql, const char *what, df_error *err);

/* Bytes appended to the change log since open (blob payloads), and changes appended. */
uint64_t df_store_log_bytes(const df_store *st);
uint64_t df_store_log_changes(const df_store *st);
void df_store_count_change(df_store *st, uint64_t bytes);

/* The lower bound of the snapshot threshold (journal.h; default DF_STORE_SNAPSHOT_MIN): tests
 * lower it to snapshot small meshes. */
uint64_t df_store_snapshot_min(const df_store *st);
void df_store_set_snapshot_min(df_store *st, uint64_t bytes);

/* The replay-time threshold of a snapshot (journal.h; default DF_STORE_SNAPSHOT_REPLAY_NS):
 * tests lower it. */
uint64_t df_store_snapshot_replay_ns(const df_store *st);
void df_store_set_snapshot_replay_ns(df_store *st, uint64_t ns);

/* The schema version df_store_open migrated from, 0 when the file was already current (or
 * new). */
int df_store_migrated_from(const df_store *st);

#endif

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
 *   sessions(id, name, kind, planar, nv, ne, nf, base, elems, faces, version, brush, brush_seq,
 *            handles, cur, rest, log_bytes)        one row per live session: topology and the
 *                                                   exact double BASE positions (load-time), the
 *                                                   version, session brush and brush_seq at
 *                                                   creation or at the last snapshot, the handle
 *                                                   set (codec.h: blob layouts), the last snapshot
 *                                                   of the
 *                                                   positions and rest shape (3 x nv doubles;
 *                                                   NULL: the base); log_bytes is 0 (unused)
 *   changes(id INTEGER PRIMARY KEY, session, version, kind, who, flags, delta, aux)
 *                                                   the change log, in commit order (journal.h)
 * A session's current version is the larger of its row's and its last change row's; its brush
 * is the last brush row's (else the row's), brush_seq the row's plus the brush rows since.
 * Schema 2 stopped updating the session row at every change and brush change (SQLite rewrites a
 * whole row, mesh blobs included, when its size changes, and reads the blobs' overflow pages to
 * reach a column after them or to compare them on an in-place UPDATE); a version 1 file (whose
 * row held the current version, brush, brush_seq and log_bytes) is migrated when opened: its
 * rows' brush_seq lose the brush rows since their snapshot, and it is marked version 2.
 * Blobs hold native-endian values: a store moves between machines of the same byte order only.
 *
 * Checks at open (df_store_open): an existing empty file, a file that is not SQLite (a text
 * file), an SQLite database of another application (foreign application_id, or tables without
 * ours), a schema version this build does not know, or an integrity failure refuse the open with
 * a message naming the file; nothing is written to such a file. Integrity: PRAGMA
 * integrity_check for files up to DF_STORE_FULL_CHECK_BYTES, PRAGMA quick_check (no index
 * content cross-check) above. The store takes an exclusive lock (locking_mode EXCLUSIVE): a
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
#define DF_STORE_SCHEMA 2
#define DF_STORE_SCHEMA_V1 1 /* still opened (and marked 2): its rows mean the same (below) */
#define DF_STORE_FULL_CHECK_BYTES ((int64_t)256 << 20) /* integrity_check up to 256 MiB */
#define DF_STORE_SNAPSHOT_MIN ((uint64_t)1 << 20) /* journal.h: snapshot once the log since the
                                                   * last one exceeds max(this, 2 x 24 x nv) */

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
 * schema version), DF_ENOMEM. */
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

/* The bytes of session `id`'s change log since its last snapshot (journal.h keeps it, the
 * restore sets it from the rows it replays), created at 0 on first use: a pointer into st,
 * valid until the next call of either function; NULL when out of memory.
 * df_store_forget_session drops the entry (a closed session). */
uint64_t *df_store_session_log(df_store *st, uint64_t id);
void df_store_forget_session(df_store *st, uint64_t id);

/* The lower bound of the snapshot threshold (journal.h; default DF_STORE_SNAPSHOT_MIN): tests
 * lower it to snapshot small meshes. */
uint64_t df_store_snapshot_min(const df_store *st);
void df_store_set_snapshot_min(df_store *st, uint64_t bytes);

#endif

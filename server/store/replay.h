/* replay.h — one session's change log replayed at restore (restore.h), recipe records included.
 *
 * Rows are applied in commit order onto the session's positions (the last snapshot or the
 * base): a delta sets the changed vertices' exact doubles, REST_FROM_CUR copies the positions
 * into the rest shape, a history step goes to s->hist (as commit.c applies it: state, then
 * history: a stroke's end marked DF_JOURNAL_HIST_RECIPE commits with its recipe,
 * df_session_history_commit_recipe: a RECIPE undo step as it was live; others an XOR step).
 * A recipe record (DF_JOURNAL_RECIPE, record.h) is recomputed with df_stroke_recipe_replay from
 * the state of its base_version and verified against its checksum. States of base versions are
 * kept (one copy of the positions each) from just before the first row past that version up to
 * the last record that references it. Recomputation is lazy: a recipe record whose positions
 * nothing reads before the next recipe record replaces them (the next version of the same
 * stroke: no delta, rest shape, history step or reference as a base in between) is skipped,
 * so a stroke of many updates costs one replay. A stroke's end carrying a recipe (journal.h) is
 * checked against the checksum it recorded.
 * A mismatch (a checksum not reproduced, a replay the engine refuses, a base state the log does
 * not hold) stops the replay: the session keeps the positions, rest shape and history of the
 * last verified version, and the result says so (restore.c then logs it, counts it and folds
 * that state into a snapshot: never a wrong mesh). A malformed blob is DF_EFORMAT (start-up
 * refused, as for a corrupt delta). Loop thread (start-up). */
#ifndef DF_SERVER_STORE_REPLAY_H
#define DF_SERVER_STORE_REPLAY_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "server/session/session.h"
#include "server/store/store.h"

typedef struct df_replay_result {
    uint64_t rows;              /* rows applied (all of them unless mismatch) */
    uint64_t recipes_replayed;  /* recipe records recomputed and verified */
    uint64_t recipes_skipped;   /* recipe records superseded before anything read them */
    uint64_t bases_kept_max;    /* most base states held at once */
    uint64_t history_recipes;   /* stroke ends committed with their recipe (RECIPE undo steps
                                 * when the replay reproduces them) */
    int mismatch;               /* 1: stopped at the row below */
    uint64_t verified_version;  /* mismatch: the version the session's positions are of */
    uint64_t bad_version;       /* mismatch: the version of the row that did not verify */
    uint64_t rows_dropped;      /* mismatch: rows from that one on, not applied */
    char why[200];              /* mismatch: what did not verify */
} df_replay_result;

/* Replays session s's log (rows of s->id in `st`) onto s->cur / s->rest / s->hist, which hold
 * the state of version `snap_version` (the snapshot, or the base at 0). `threads`: the field
 * evaluation's threads (results do not depend on it). *out describes what happened. Errors:
 * DF_EIO (reading the store), DF_EFORMAT (a malformed delta or recipe record: message names
 * the version), DF_ENOMEM (history or base states); a mismatch is not an error (out->mismatch). */
int df_store_replay(df_store *st, df_session *s, uint64_t snap_version, int threads,
                    df_replay_result *out, df_error *err);

/* Folds session s's current positions and rest shape into its row as a snapshot of `version`
 * (also the row's version) and deletes its log, in one transaction (after a mismatch: the
 * dropped rows must not be replayed onto different positions at the next start). Errors:
 * DF_EIO / DF_ELIMIT (store's message). */
int df_store_replay_cut(df_store *st, const df_session *s, uint64_t version, df_error *err);

#endif

/* stroke_end.h — the undo step that ends a stroke (BRUSH_END), planned off the loop thread. */
#ifndef DF_SERVER_STROKE_END_H
#define DF_SERVER_STROKE_END_H

#include "core/common/df_error.h"
#include "server/session/history.h"
#include "server/session/session.h"

/* Plans the undo step of stroke `st` of session `s` into *plan (history.h, installed later by
 * the commit): a RECIPE step (the stroke's request, stroke_recipe.h) when its last publish is
 * replayable and it began from the history's current state — the plan replays it and keeps it
 * only when the replay is bitwise s->cur — else an XOR step. Reads the session only (the
 * session's running job, or a test with no job running). Errors: those of
 * df_history_plan_commit (DF_ENOMEM, ...); *plan as that function leaves it. */
int df_stroke_end_plan(const df_session *s, const df_stroke *st, df_history_plan *plan,
                       df_error *err);

#endif

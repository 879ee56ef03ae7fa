/* stroke_end.c — the undo step that ends a stroke (see stroke_end.h). */
#include "server/session/stroke_end.h"

#include <stdlib.h>
#include <string.h>

#include "server/session/stroke_recipe.h"

int df_stroke_end_plan(const df_session *s, const df_stroke *st, df_history_plan *plan,
                       df_error *err)
{
    size_t n = 3 * (size_t)s->nv;
    uint8_t *blob = NULL;
    size_t len = 0;
    if (st->last_replayable && memcmp(st->base, s->hist.state, n * sizeof(double)) == 0) {
        df_stroke_recipe r = {.brush = st->last_brush, .strength = st->last_strength,
                              .n_pins = st->n_pins, .pin_flags = st->pin_flags,
                              .pins = st->pins};
        memcpy(r.load, st->last_load, sizeof r.load);
        df_error e;
        if (df_stroke_recipe_encode(&r, &blob, &len, &e) != DF_OK) blob = NULL; /* XOR then */
    }
    int rc = df_history_plan_commit(&s->hist, s->cur, blob, len, plan, err);
    free(blob);
    return rc;
}

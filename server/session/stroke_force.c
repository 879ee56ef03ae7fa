/* stroke_force.c — the Kelvinlet force of a session's open grab strokes: see stroke_force.h. */
#include "server/session/stroke_force.h"

#include <string.h>

#include "core/kelvinlet/kelvinlet.h"

int df_session_grab_force(const df_session *s, double f[3])
{
    int n = 0;
    f[0] = f[1] = f[2] = 0;
    for (const df_stroke *st = s->strokes; st; st = st->next) {
        if (st->brush.type != DF_KELVINLET_GRAB) continue;
        n++;
        df_kelvinlet_brush b = st->brush;
        memcpy(b.tip, st->tip, sizeof b.tip);
        df_kelvinlet_prepared prep;
        df_error err;
        if (df_kelvinlet_prepare(&b, &prep, &err) != DF_OK) continue;
        for (int k = 0; k < 3; k++) f[k] += prep.src[0].f[k];
        df_kelvinlet_prepared_free(&prep);
    }
    return n;
}

/* dc_brush.c — local Kelvinlet validation of a stroke before it is sent (see dc_brush.h). */
#include "client/deformctl/dc_brush.h"

#include <string.h>

#include "proto/wire_core_map.h"

void dc_brush_to_kelvinlet(const df_msg_brush *b, const df_msg_brush_update *u,
                           df_kelvinlet_brush *out)
{
    df_error ignored;
    if (df_wire_brush_to_core(b, out, &ignored) != DF_OK)
        out->type = (df_kelvinlet_type)-1; /* not a wire brush type: the engine refuses it */
    double k = b->strength;
    for (int i = 0; i < 3; i++) {
        out->tip[i] = k * u->move[i];
        out->omega[i] = k * u->twist[i];
    }
    out->s = k * u->scale;
    for (int i = 0; i < 9; i++)
        out->grad[i] = k * u->matrix[i];
}

int dc_brush_check(const df_msg_brush *b, const df_msg_brush_update *u, df_error *err)
{
    df_kelvinlet_brush kb;
    int pin_flags = 0;
    int rc = df_wire_brush_to_core(b, &kb, err); /* a bad wire type / integrator, named */
    if (rc != DF_OK)
        return rc;
    if (df_wire_pin_flags_to_core(b->pin_flags, &pin_flags) != DF_OK)
        return df_error_set(err, DF_EINVAL, "brush: pin_flags 0x%x", b->pin_flags);
    dc_brush_to_kelvinlet(b, u, &kb);
    df_kelvinlet_prepared prep;
    if (b->n_pinned == 0 || b->n_pinned > DC_BRUSH_LOCAL_PIN_CHECK_MAX) {
        rc = df_kelvinlet_prepare(&kb, &prep, err);
        if (rc == DF_OK)
            df_kelvinlet_prepared_free(&prep);
        return rc;
    }
    df_kelvinlet_pins pins = {.n = b->n_pinned, .points = b->pinned,
                              .flags = pin_flags,
                              .radius = kb.radius, .ratio = kb.ratio, .nu = kb.nu,
                              .order = kb.order};
    df_kelvinlet_constraints *cs = NULL;
    rc = df_kelvinlet_constraints_create(&pins, &cs, err);
    if (rc == DF_OK)
        rc = df_kelvinlet_constraints_solve(cs, &kb, &prep, err);
    if (rc == DF_OK)
        df_kelvinlet_prepared_free(&prep);
    df_kelvinlet_constraints_free(cs);
    return rc;
}

/* dc_brush.c — local Kelvinlet validation of a stroke before it is sent (see dc_brush.h). */
#include "client/deformctl/dc_brush.h"

#include <string.h>

void dc_brush_to_kelvinlet(const df_msg_brush *b, const df_msg_brush_update *u,
                           df_kelvinlet_brush *out)
{
    static const df_kelvinlet_type types[] = {DF_KELVINLET_GRAB, DF_KELVINLET_GRAB,
                                              DF_KELVINLET_TWIST, DF_KELVINLET_SCALE,
                                              DF_KELVINLET_PINCH, DF_KELVINLET_AFFINE};
    df_kelvinlet_brush_defaults(out);
    out->type = b->type <= DF_BRUSH_TYPE_MAX ? types[b->type] : (df_kelvinlet_type)-1;
    out->dim = b->dim;
    out->order = b->falloff;
    out->ratio = b->ratio;
    out->radius = b->radius;
    out->nu = b->nu;
    memcpy(out->centre, b->center, sizeof out->centre);
    out->mirror = b->has_mirror;
    memcpy(out->mirror_point, b->mirror_point, sizeof out->mirror_point);
    memcpy(out->mirror_normal, b->mirror_normal, sizeof out->mirror_normal);
    out->integrator = b->integrator == DF_INTEG_RK4 ? DF_KELVINLET_RK4 : DF_KELVINLET_EULER;
    out->steps = b->steps;
    out->moving = b->moving;
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
    dc_brush_to_kelvinlet(b, u, &kb);
    df_kelvinlet_prepared prep;
    int rc;
    if (b->n_pinned == 0 || b->n_pinned > DC_BRUSH_LOCAL_PIN_CHECK_MAX) {
        rc = df_kelvinlet_prepare(&kb, &prep, err);
        if (rc == DF_OK)
            df_kelvinlet_prepared_free(&prep);
        return rc;
    }
    df_kelvinlet_pins pins = {.n = b->n_pinned, .points = b->pinned,
                              .flags = ((b->pin_flags & DF_PIN_DISPLACEMENT)
                                            ? DF_KELVINLET_PIN_DISPLACEMENT : 0) |
                                       ((b->pin_flags & DF_PIN_GRADIENT)
                                            ? DF_KELVINLET_PIN_GRADIENT : 0),
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

/* wire_core_map.h — the one mapping of each wire enum (proto/wire_schema.h, which owns their
 * numbering) to the core engine's enum, bounds-checked: a value outside the wire enum is
 * DF_EINVAL, never an out-of-range table read.
 *
 * Where it lives and who may include it (tests/check_layers.sh enforces both): header-only
 * (static inline), so no library links it; it alone in proto/ may include core solver headers
 * (core/kelvinlet, core/admm), and only the daemon (server/) and deformctl (client/deformctl/)
 * include it. proto's own code and libdeformclient never do, so neither depends on a solver.
 * Wire enums that core/mesh shares (load format, mesh kind) are checked value by value in
 * proto/messages.h, which may see core/mesh. */
#ifndef DF_PROTO_WIRE_CORE_MAP_H
#define DF_PROTO_WIRE_CORE_MAP_H

#include <string.h>

#include "core/admm/admm.h"
#include "core/common/df_error.h"
#include "core/kelvinlet/kelvinlet.h"
#include "proto/messages.h"

/* df_brush_type (1..5) -> df_kelvinlet_type. DF_OK or DF_EINVAL (`*out` untouched). */
static inline int df_wire_brush_type_to_core(unsigned wire, df_kelvinlet_type *out)
{
    switch (wire) {
    case DF_BRUSH_GRAB: *out = DF_KELVINLET_GRAB; return DF_OK;
    case DF_BRUSH_TWIST: *out = DF_KELVINLET_TWIST; return DF_OK;
    case DF_BRUSH_SCALE: *out = DF_KELVINLET_SCALE; return DF_OK;
    case DF_BRUSH_PINCH: *out = DF_KELVINLET_PINCH; return DF_OK;
    case DF_BRUSH_AFFINE: *out = DF_KELVINLET_AFFINE; return DF_OK;
    default: return DF_EINVAL;
    }
}

/* df_integrator (1..2) -> df_kelvinlet_integrator. DF_OK or DF_EINVAL. */
static inline int df_wire_integrator_to_core(unsigned wire, df_kelvinlet_integrator *out)
{
    switch (wire) {
    case DF_INTEG_EULER: *out = DF_KELVINLET_EULER; return DF_OK;
    case DF_INTEG_RK4: *out = DF_KELVINLET_RK4; return DF_OK;
    default: return DF_EINVAL;
    }
}

/* DF_PIN_* bits -> DF_KELVINLET_PIN_* bits. DF_OK, or DF_EINVAL for a bit the wire lacks. */
static inline int df_wire_pin_flags_to_core(unsigned wire, int *out)
{
    if (wire & ~(unsigned)(DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT))
        return DF_EINVAL;
    *out = ((wire & DF_PIN_DISPLACEMENT) ? DF_KELVINLET_PIN_DISPLACEMENT : 0) |
           ((wire & DF_PIN_GRADIENT) ? DF_KELVINLET_PIN_GRADIENT : 0);
    return DF_OK;
}

/* df_energy (1..5) <-> df_admm_energy. DF_OK or DF_EINVAL. */
static inline int df_wire_energy_to_core(unsigned wire, df_admm_energy *out)
{
    switch (wire) {
    case DF_ENERGY_ARAP: *out = DF_ADMM_ARAP; return DF_OK;
    case DF_ENERGY_ACAP: *out = DF_ADMM_ACAP; return DF_OK;
    case DF_ENERGY_NEOHOOKEAN: *out = DF_ADMM_NEOHOOKEAN; return DF_OK;
    case DF_ENERGY_CLOTH: *out = DF_ADMM_CLOTH; return DF_OK;
    case DF_ENERGY_POLYLINE: *out = DF_ADMM_POLYLINE; return DF_OK;
    default: return DF_EINVAL;
    }
}

static inline int df_core_energy_to_wire(df_admm_energy core, uint8_t *out)
{
    switch (core) {
    case DF_ADMM_ARAP: *out = DF_ENERGY_ARAP; return DF_OK;
    case DF_ADMM_ACAP: *out = DF_ENERGY_ACAP; return DF_OK;
    case DF_ADMM_NEOHOOKEAN: *out = DF_ENERGY_NEOHOOKEAN; return DF_OK;
    case DF_ADMM_CLOTH: *out = DF_ENERGY_CLOTH; return DF_OK;
    case DF_ADMM_POLYLINE: *out = DF_ENERGY_POLYLINE; return DF_OK;
    default: return DF_EINVAL;
    }
}

/* The engine's description of the brush a BRUSH_BEGIN `m` asks for, as the daemon runs it and
 * deformctl checks it: df_kelvinlet_brush_defaults, then type, dim, falloff (order), ratio,
 * radius, nu, centre, mirror, integrator, steps, moving. Loads (tip, omega, s, grad) stay 0 and
 * strength is not applied (the caller scales each update's load by m->strength). DF_OK, or
 * DF_EINVAL naming the field when type or integrator is not a wire value. */
static inline int df_wire_brush_to_core(const df_msg_brush *m, df_kelvinlet_brush *b,
                                        df_error *err)
{
    df_kelvinlet_brush_defaults(b);
    if (df_wire_brush_type_to_core(m->type, &b->type) != DF_OK)
        return df_error_set(err, DF_EINVAL, "brush: type %u not in 1..%d", m->type,
                            DF_BRUSH_TYPE_MAX);
    if (df_wire_integrator_to_core(m->integrator, &b->integrator) != DF_OK)
        return df_error_set(err, DF_EINVAL, "brush: integrator %u not %d (Euler) or %d (RK4)",
                            m->integrator, DF_INTEG_EULER, DF_INTEG_RK4);
    b->dim = m->dim;
    b->order = m->falloff;
    b->ratio = m->ratio;
    b->radius = m->radius;
    b->nu = m->nu;
    memcpy(b->centre, m->center, sizeof b->centre);
    b->mirror = m->has_mirror;
    memcpy(b->mirror_point, m->mirror_point, sizeof b->mirror_point);
    memcpy(b->mirror_normal, m->mirror_normal, sizeof b->mirror_normal);
    b->steps = m->steps;
    b->moving = m->moving;
    b->surface = m->surface;
    return DF_OK;
}

#endif

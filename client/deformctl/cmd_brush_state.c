/* cmd_brush_state.c — `deformctl brush-state`: print or set a session's brush (PROTOCOL.md
 * 4.14a); the printing is brush_state_out.c's. */
#include <string.h>

#include "client/deformctl/ctl.h"

enum {
    O_TYPE = CTL_NGLOBAL, O_RADIUS, O_NU, O_STRENGTH, O_FALLOFF, O_RATIO, O_INTEGRATOR, O_STEPS,
    O_MIRROR, O_COUNT
};

static const dc_cli_opt OPTS[O_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"type", 1, "--type grab|twist|scale|pinch|affine   brush kind"},
    {"radius", 1, "--radius R         regularization radius, mesh units, > 0"},
    {"nu", 1, "--nu V             Poisson ratio in [-1, 0.5], or inf"},
    {"strength", 1, "--strength S       load multiplier, |S| <= 1e6"},
    {"falloff", 1, "--falloff N        1 single, 2 bi-scale, 3 tri-scale, up to 8"},
    {"ratio", 1, "--ratio R          multi-scale radius ratio > 1"},
    {"integrator", 1, "--integrator euler|rk4   time integrator"},
    {"steps", 1, "--steps N          integration steps, 1..1024"},
    {"mirror", 1, "--mirror PX,PY,PZ,NX,NY,NZ|off   mirror plane, or none"},
};

static const char *const TYPES[] = {"grab", "twist", "scale", "pinch", "affine", NULL};
static const char *const INTEGRATORS[] = {"euler", "rk4", NULL};

/* The options given, as a brush_state_set over `cur` (the current values: the field partner
 * not given of integrator/steps keeps its value). DF_OK or DF_EINVAL naming the option. */
static int build(const dc_cli_args *a, const df_msg_brush_values *cur, df_msg_brush_state_set *m,
                 df_error *e)
{
    m->v = *cur;
    m->mask = 0;
    long long n;
    int k;
    if (a->val[O_TYPE]) {
        if ((k = dc_cli_choice(a->val[O_TYPE], "--type", TYPES, e)) < 0)
            return k;
        m->v.type = (uint8_t)(k + 1);
        m->mask |= DF_BS_TYPE;
    }
    struct { int opt; const char *name; unsigned bit; double *dst; int inf; } d[] = {
        {O_RADIUS, "--radius", DF_BS_RADIUS, &m->v.radius, 0},
        {O_NU, "--nu", DF_BS_NU, &m->v.nu, 1},
        {O_STRENGTH, "--strength", DF_BS_STRENGTH, &m->v.strength, 0},
        {O_RATIO, "--ratio", DF_BS_RATIO, &m->v.ratio, 0}};
    for (size_t i = 0; i < sizeof d / sizeof d[0]; i++) {
        if (!a->val[d[i].opt])
            continue;
        if (dc_cli_double(a->val[d[i].opt], d[i].name, d[i].inf, d[i].dst, e))
            return DF_EINVAL;
        m->mask |= d[i].bit;
    }
    if (a->val[O_FALLOFF]) {
        if (dc_cli_int(a->val[O_FALLOFF], "--falloff", 1, DF_MAX_FALLOFF, &n, e))
            return DF_EINVAL;
        m->v.falloff = (uint8_t)n;
        m->mask |= DF_BS_FALLOFF;
    }
    if (a->val[O_INTEGRATOR]) {
        if ((k = dc_cli_choice(a->val[O_INTEGRATOR], "--integrator", INTEGRATORS, e)) < 0)
            return k;
        m->v.integrator = (uint8_t)(k + 1);
        m->mask |= DF_BS_INTEGRATOR;
    }
    if (a->val[O_STEPS]) {
        if (dc_cli_int(a->val[O_STEPS], "--steps", 1, DF_MAX_BRUSH_STEPS, &n, e))
            return DF_EINVAL;
        m->v.steps = (uint16_t)n;
        m->mask |= DF_BS_INTEGRATOR;
    }
    if (a->val[O_MIRROR]) {
        double p[6] = {0, 0, 0, 1, 0, 0};
        if (strcmp(a->val[O_MIRROR], "off") != 0 && dc_cli_vec(a->val[O_MIRROR], "--mirror", 6,
                                                                p, e))
            return DF_EINVAL;
        m->v.has_mirror = strcmp(a->val[O_MIRROR], "off") != 0;
        memcpy(m->v.mirror_point, p, sizeof m->v.mirror_point);
        memcpy(m->v.mirror_normal, p + 3, sizeof m->v.mirror_normal);
        m->mask |= DF_BS_MIRROR;
    }
    return DF_OK;
}

static int run_brush_state(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_msg_brush_state_set m;
    df_msg_brush_values defaults;
    df_error e;
    df_msg_brush_values_defaults(&defaults);
    if (build(a, &defaults, &m, &e)) /* the command line alone: usage errors before connecting */
        return ctl_usage_error(ctx, cmd, e.msg);
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_msg_brush_state s;
    uint64_t sid = 0;
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK && (m.mask == 0 || (m.mask & (DF_BS_INTEGRATOR | DF_BS_MIRROR))))
        rc = df_client_brush_state_get(c, sid, &s, &e); /* print it, or the fields' partners */
    if (rc == DF_OK && m.mask) {
        rc = build(a, (m.mask & (DF_BS_INTEGRATOR | DF_BS_MIRROR)) ? &s.v : &defaults, &m, &e);
        m.session_id = sid;
        if (rc == DF_OK)
            rc = df_client_brush_state_set(c, &m, &s, &e);
    }
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    ctl_brush_state_print(ctx, &s, 0);
    df_client_close(c);
    return CTL_EXIT_OK;
}

const ctl_cmd ctl_cmds_brush_state[] = {
    {"brush-state",
     "brush-state SESSION [--type T] [--radius R] [--nu V] [--strength S] [--falloff N]\n"
     "       [--ratio R] [--integrator euler|rk4] [--steps N] [--mirror PX,PY,PZ,NX,NY,NZ|off]",
     "Print the session's brush (the one knobs change and strokes may use), one 'key value' "
     "per line; with options, set those fields first (subscribers see a brush_state event).",
     OPTS, O_COUNT, 1, run_brush_state},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

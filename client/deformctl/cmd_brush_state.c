/* cmd_brush_state.c — `deformctl brush-state`: print or set a session's brush (PROTOCOL.md
 * 4.14a), and the text / JSON form of the BRUSH_STATE and BRUSH_CURSOR events that `watch`
 * prints. Values print in their shortest round-trip form (0.45, not 0.45000000000000001). */
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
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
static const char *const FIELDS[] = {"type", "radius", "nu", "strength", "falloff", "ratio",
                                     "integrator", "mirror", NULL}; /* DF_BS_* bit order */
static const char *const ORIGINS[] = {"none", "client", "device"};

static const char *type_name(unsigned t)
{
    return t >= 1 && t <= 5 ? TYPES[t - 1] : "unknown";
}

static const char *integ_name(unsigned i)
{
    return i >= 1 && i <= 2 ? INTEGRATORS[i - 1] : "unknown";
}

static const char *origin_name(unsigned k)
{
    return k <= DF_ORIGIN_MAX ? ORIGINS[k] : "unknown";
}

/* The shortest %.{15,16,17}g text of v that reads back as v ("inf", "-inf" for infinities). */
static const char *num(double v, char buf[32])
{
    if (isinf(v))
        return v > 0 ? "inf" : "-inf";
    for (int p = 15; p <= 17; p++) {
        snprintf(buf, 32, "%.*g", p, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

/* A number as JSON: the shortest form, infinities as the strings "inf" / "-inf". */
static void json_num(double v)
{
    char b[32];
    if (isinf(v))
        printf("\"%s\"", num(v, b));
    else
        printf("%s", num(v, b));
}

/* "radius,nu" for a DF_BS_* mask ("-" for none). */
static void mask_text(unsigned mask, char *out, size_t cap)
{
    size_t n = 0;
    out[0] = '\0';
    for (int i = 0; FIELDS[i]; i++)
        if (mask & (1u << i))
            n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "%s%s", n ? "," : "", FIELDS[i]);
    if (!n)
        snprintf(out, cap, "-");
}

/* The state's fields as JSON members (no braces). */
static void state_json_members(const df_msg_brush_state *s)
{
    const df_msg_brush_values *v = &s->v;
    printf("\"session\":%" PRIu64 ",\"seq\":%" PRIu64 ",\"type\":\"%s\",\"radius\":",
           s->session_id, s->seq, type_name(v->type));
    json_num(v->radius);
    printf(",\"nu\":");
    json_num(v->nu);
    printf(",\"strength\":");
    json_num(v->strength);
    printf(",\"falloff\":%u,\"ratio\":", v->falloff);
    json_num(v->ratio);
    printf(",\"integrator\":\"%s\",\"steps\":%u,\"mirror\":", integ_name(v->integrator), v->steps);
    if (v->has_mirror) {
        for (int i = 0; i < 6; i++) {
            printf(i ? "," : "[");
            json_num(i < 3 ? v->mirror_point[i] : v->mirror_normal[i - 3]);
        }
        printf("]");
    } else {
        printf("null");
    }
    printf(",\"changed\":[");
    for (int i = 0, k = 0; FIELDS[i]; i++)
        if (s->changed & (1u << i))
            printf("%s\"%s\"", k++ ? "," : "", FIELDS[i]);
    printf("],\"origin\":\"%s\",\"origin_id\":%" PRIu64 ",\"origin_name\":",
           origin_name(s->origin_kind), s->origin_id);
    ctl_json_str(stdout, s->origin_name);
}

/* "px,py,pz,nx,ny,nz" or "off". */
static const char *mirror_text(const df_msg_brush_values *v, char *out, size_t cap)
{
    if (!v->has_mirror)
        return "off";
    size_t n = 0;
    char b[32];
    for (int i = 0; i < 6; i++)
        n += (size_t)snprintf(out + n, n < cap ? cap - n : 0, "%s%s", i ? "," : "",
                              num(i < 3 ? v->mirror_point[i] : v->mirror_normal[i - 3], b));
    return out;
}

void ctl_brush_state_print(const ctl_ctx *ctx, const df_msg_brush_state *s, int event)
{
    const df_msg_brush_values *v = &s->v;
    char b[6][32], mir[200], changed[100];
    mask_text(s->changed, changed, sizeof changed);
    if (ctx->json) {
        printf(event ? "{\"kind\":\"brush_state\"," : "{");
        state_json_members(s);
        printf("}\n");
    } else if (event) {
        printf("brush_state seq %" PRIu64 " changed %s by %s %" PRIu64 " '%s': type %s radius %s "
               "nu %s strength %s falloff %u ratio %s integrator %s steps %u mirror %s\n", s->seq,
               changed, origin_name(s->origin_kind), s->origin_id, s->origin_name,
               type_name(v->type), num(v->radius, b[0]), num(v->nu, b[1]),
               num(v->strength, b[2]), v->falloff, num(v->ratio, b[3]), integ_name(v->integrator),
               v->steps, mirror_text(v, mir, sizeof mir));
    } else {
        printf("session %" PRIu64 "\ntype %s\nradius %s\nnu %s\nstrength %s\nfalloff %u\n"
               "ratio %s\nintegrator %s\nsteps %u\nmirror %s\nseq %" PRIu64 "\nchanged %s\n"
               "origin %s\norigin_id %" PRIu64 "\norigin_name %s\n", s->session_id,
               type_name(v->type), num(v->radius, b[0]), num(v->nu, b[1]),
               num(v->strength, b[2]), v->falloff, num(v->ratio, b[3]), integ_name(v->integrator),
               v->steps, mirror_text(v, mir, sizeof mir), s->seq, changed,
               origin_name(s->origin_kind), s->origin_id, s->origin_name[0] ? s->origin_name : "-");
    }
    fflush(stdout);
}

void ctl_brush_cursor_print(const ctl_ctx *ctx, const df_msg_brush_cursor *m)
{
    char b[4][32];
    int in = (m->flags & DF_CURSOR_IN_RANGE) != 0, st = (m->flags & DF_CURSOR_STROKE_ACTIVE) != 0;
    if (ctx->json) {
        printf("{\"kind\":\"brush_cursor\",\"session\":%" PRIu64 ",\"origin\":\"%s\",\"origin_id\":"
               "%" PRIu64 ",\"center\":[", m->session_id, origin_name(m->origin_kind),
               m->origin_id);
        for (int i = 0; i < 3; i++) {
            printf(i ? "," : "");
            json_num(m->center[i]);
        }
        printf("],\"radius\":");
        json_num(m->radius);
        printf(",\"in_range\":%s,\"stroke_active\":%s}\n", in ? "true" : "false",
               st ? "true" : "false");
    } else {
        printf("brush_cursor %s %" PRIu64 " center %s,%s,%s radius %s%s%s\n",
               origin_name(m->origin_kind), m->origin_id, num(m->center[0], b[0]),
               num(m->center[1], b[1]), num(m->center[2], b[2]), num(m->radius, b[3]),
               in ? " in_range" : "", st ? " stroke_active" : "");
    }
    fflush(stdout);
}

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

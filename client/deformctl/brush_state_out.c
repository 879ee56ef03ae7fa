/* brush_state_out.c — deformctl's text and JSON forms of a session brush (`brush-state`) and of
 * the BRUSH_STATE / BRUSH_CURSOR events (`watch`), see ctl.h. Values print in their shortest
 * round-trip form (0.45, not 0.45000000000000001); infinities as inf / -inf (JSON strings). */
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/deformctl/ctl.h"

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


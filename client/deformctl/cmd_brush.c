/* cmd_brush.c — `deformctl brush`: one whole Kelvinlet stroke (begin with every parameter and
 * a zero load, one update carrying the load, end) committed as one session version.
 *
 * Errors: a bad command line or pin file is a usage error (exit 2). The stroke is then checked
 * locally with the Kelvinlet engine (dc_brush_check: e.g. a pinch matrix that is not symmetric
 * and traceless, nu outside [-1, 0.5], coincident pins): the engine refusing it is a semantic
 * error, reported as "deformctl brush: rejected: CODE: message" with exit 1, as are the
 * daemon's refusals ("deformctl brush: server: CODE: message", exit 1). A stroke the daemon
 * refuses after begin is cancelled, so the session keeps its shape. */
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/deformctl/dc_brush.h"
#include "client/dc_files.h"
#include "client/deformctl/ctl.h"

enum {
    O_TYPE = CTL_NGLOBAL, O_CENTER, O_MOVE, O_TWIST, O_SCALE, O_MATRIX, O_RADIUS, O_NU,
    O_FALLOFF, O_RATIO, O_DIM, O_INTEGRATOR, O_STEPS, O_MIRROR, O_PIN, O_PIN_MODE, O_STRENGTH,
    O_MOVING, O_USE_SESSION, O_SURFACE, O_COUNT
};

static const dc_cli_opt BRUSH_OPTS[O_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"type", 1, "--type grab|twist|scale|pinch|affine   brush kind (required)"},
    {"center", 1, "--center X,Y,Z     brush centre (required)"},
    {"move", 1, "--move DX,DY,DZ    grab: displacement of the centre"},
    {"twist", 1, "--twist WX,WY,WZ   twist: rotation vector at the centre (radians)"},
    {"scale", 1, "--scale S          scale: centre dilation (grad u = S I; needs --nu < 0.5, "
                 "as the default)"},
    {"matrix", 1, "--matrix M00,M01,...,M22   pinch (symmetric, traceless) / affine: centre "
                  "gradient, row-major"},
    {"radius", 1, "--radius R         regularization radius, mesh units (default 1)"},
    {"nu", 1, "--nu NU            Poisson ratio in [-1, 0.5], or inf (default 0.45, where every "
              "--type works;\n                     0.5 = incompressible, where --type scale is "
              "impossible)"},
    {"falloff", 1, "--falloff N        1 single, 2 bi-scale, 3 tri-scale, up to 8 (default 1)"},
    {"ratio", 1, "--ratio Q          multi-scale radius ratio > 1 (default 1.1; for --falloff 3 "
                 "and up\n                     keep it at 1.05 or more, or the radii's weights "
                 "cancel)"},
    {"dim", 1, "--dim 2|3          2: planar brush for z = 0 meshes (default 3)"},
    {"integrator", 1, "--integrator euler|rk4   time integrator (default euler)"},
    {"steps", 1, "--steps N          integration steps (default 1)"},
    {"mirror", 1, "--mirror PX,PY,PZ,NX,NY,NZ   also apply mirrored across this plane"},
    {"pin", 1, "--pin FILE         points held fixed, one 'x y z' per line; pins need a 3D "
               "brush (no --dim 2),\n                     no --mirror and no --moving"},
    {"pin-mode", 1, "--pin-mode displacement|gradient|both   what --pin holds (default "
                    "displacement: u = 0)"},
    {"strength", 1, "--strength S       load multiplier (default 1)"},
    {"moving", 0, "--moving           moving brush: the centre follows the load"},
    {"use-session", 1, "--use-session F,F  take these from the session brush (brush-state) instead:"
                       "\n                     radius, nu, strength, falloff, ratio, integrator"
                       " (with steps),\n                     mirror, or all (not with the "
                       "same option given here)"},
    {"surface", 0, "--surface          surface-aware: attenuate by the distance along the mesh "
                   "from the centre\n                     (parts not connected to it stay at "
                   "rest)"},
};

/* deformctl's default Poisson ratio: below 0.5 so that every brush type works (the scale brush
 * is impossible for an incompressible material); the wire default stays 0.5. */
#define CTL_BRUSH_DEFAULT_NU 0.45

static const char *const TYPES[] = {"grab", "twist", "scale", "pinch", "affine", NULL};
static const char *const INTEGRATORS[] = {"euler", "rk4", NULL};
/* --type / --integrator name i is the wire value i + 1 (the wire enums are 1..MAX, contiguous) */
_Static_assert(sizeof TYPES / sizeof TYPES[0] - 1 == DF_BRUSH_TYPE_MAX, "one name per brush type");
_Static_assert(sizeof INTEGRATORS / sizeof INTEGRATORS[0] - 1 == DF_INTEG_RK4,
               "one name per integrator");
static const char *const PIN_MODES[] = {"displacement", "gradient", "both", NULL};

/* The load option each type needs, indexed by type - 1. */
static const int LOAD_OPT[5] = {O_MOVE, O_TWIST, O_SCALE, O_MATRIX, O_MATRIX};

/* --use-session: the DF_BS_* bits of a comma-separated list of fields (or "all") into
 * b->use_session. The type is not one of them: --type picks the load option. A field also given
 * as its own option is a usage error (which one would apply?). */
static int use_session(const dc_cli_args *a, df_msg_brush *b, df_error *e)
{
    static const struct { const char *name; unsigned bit; int opt, opt2; } F[] = {
        {"radius", DF_BS_RADIUS, O_RADIUS, -1}, {"nu", DF_BS_NU, O_NU, -1},
        {"strength", DF_BS_STRENGTH, O_STRENGTH, -1}, {"falloff", DF_BS_FALLOFF, O_FALLOFF, -1},
        {"ratio", DF_BS_RATIO, O_RATIO, -1},
        {"integrator", DF_BS_INTEGRATOR, O_INTEGRATOR, O_STEPS},
        {"mirror", DF_BS_MIRROR, O_MIRROR, -1}};
    const size_t nf = sizeof F / sizeof F[0];
    char list[256];
    if (strlen(a->val[O_USE_SESSION]) >= sizeof list)
        return df_error_set(e, DF_EINVAL, "--use-session: list too long");
    strcpy(list, a->val[O_USE_SESSION]);
    unsigned mask = 0;
    for (char *save = NULL, *tok = strtok_r(list, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        size_t i = 0;
        while (i < nf && strcmp(tok, F[i].name) != 0)
            i++;
        if (!strcmp(tok, "all")) {
            for (i = 0; i < nf; i++)
                mask |= F[i].bit;
            continue;
        }
        if (i == nf)
            return df_error_set(e, DF_EINVAL, "--use-session: '%s' is not one of radius, nu, "
                                "strength, falloff, ratio, integrator, mirror, all", tok);
        mask |= F[i].bit;
    }
    if (!mask)
        return df_error_set(e, DF_EINVAL, "--use-session: no field named");
    for (size_t i = 0; i < nf; i++)
        if ((mask & F[i].bit) && (a->val[F[i].opt] || (F[i].opt2 >= 0 && a->val[F[i].opt2])))
            return df_error_set(e, DF_EINVAL, "--use-session %s and --%s both given", F[i].name,
                                BRUSH_OPTS[a->val[F[i].opt] ? F[i].opt : F[i].opt2].name);
    b->use_session = (uint16_t)mask;
    return DF_OK;
}

/* Fills the begin message and the update from the options; DF_EINVAL with a message on bad
 * input (the caller reports a usage error). */
static int build(const dc_cli_args *a, df_msg_brush *b, df_msg_brush_update *u, df_error *e)
{
    df_msg_brush_defaults(b);
    b->nu = CTL_BRUSH_DEFAULT_NU;
    memset(u, 0, sizeof *u);
    if (!a->val[O_TYPE] || !a->val[O_CENTER])
        return df_error_set(e, DF_EINVAL, "--type and --center are required");
    int t = dc_cli_choice(a->val[O_TYPE], "--type", TYPES, e);
    if (t < 0)
        return t;
    b->type = (uint8_t)(t + 1);
    int need = LOAD_OPT[t];
    if (!a->val[need])
        return df_error_set(e, DF_EINVAL, "--type %s needs --%s", TYPES[t], BRUSH_OPTS[need].name);
    for (int k = O_MOVE; k <= O_MATRIX; k++)
        if (a->val[k] && k != need)
            return df_error_set(e, DF_EINVAL, "--%s does not apply to --type %s",
                                BRUSH_OPTS[k].name, TYPES[t]);
    int rc = dc_cli_vec(a->val[O_CENTER], "--center", 3, b->center, e);
    if (rc)
        return rc;
    if (need == O_MOVE)
        rc = dc_cli_vec(a->val[O_MOVE], "--move", 3, u->move, e);
    else if (need == O_TWIST)
        rc = dc_cli_vec(a->val[O_TWIST], "--twist", 3, u->twist, e);
    else if (need == O_SCALE)
        rc = dc_cli_double(a->val[O_SCALE], "--scale", 0, &u->scale, e);
    else
        rc = dc_cli_vec(a->val[O_MATRIX], "--matrix", 9, u->matrix, e);
    if (rc)
        return rc;
    long long v;
    if (a->val[O_RADIUS] && (rc = dc_cli_double(a->val[O_RADIUS], "--radius", 0, &b->radius, e)))
        return rc;
    if (b->radius <= 0)
        return df_error_set(e, DF_EINVAL, "--radius: %g must be > 0", b->radius);
    if (a->val[O_NU] && (rc = dc_cli_double(a->val[O_NU], "--nu", 1, &b->nu, e)))
        return rc;
    if (a->val[O_RATIO] && (rc = dc_cli_double(a->val[O_RATIO], "--ratio", 0, &b->ratio, e)))
        return rc;
    if (b->ratio <= 1)
        return df_error_set(e, DF_EINVAL, "--ratio: %g must be > 1", b->ratio);
    if (a->val[O_STRENGTH] &&
        (rc = dc_cli_double(a->val[O_STRENGTH], "--strength", 0, &b->strength, e)))
        return rc;
    if (a->val[O_FALLOFF]) {
        if ((rc = dc_cli_int(a->val[O_FALLOFF], "--falloff", 1, DF_MAX_FALLOFF, &v, e)))
            return rc;
        b->falloff = (uint8_t)v;
    }
    if (a->val[O_DIM]) {
        if ((rc = dc_cli_int(a->val[O_DIM], "--dim", 2, 3, &v, e)))
            return rc;
        b->dim = (uint8_t)v;
    }
    if (a->val[O_INTEGRATOR]) {
        int k = dc_cli_choice(a->val[O_INTEGRATOR], "--integrator", INTEGRATORS, e);
        if (k < 0)
            return k;
        b->integrator = (uint8_t)(k + 1);
    }
    if (a->val[O_STEPS]) {
        if ((rc = dc_cli_int(a->val[O_STEPS], "--steps", 1, DF_MAX_BRUSH_STEPS, &v, e)))
            return rc;
        b->steps = (uint16_t)v;
    }
    if (a->val[O_MIRROR]) {
        double m[6];
        if ((rc = dc_cli_vec(a->val[O_MIRROR], "--mirror", 6, m, e)))
            return rc;
        if (m[3] == 0 && m[4] == 0 && m[5] == 0)
            return df_error_set(e, DF_EINVAL, "--mirror: the plane normal is zero");
        b->has_mirror = 1;
        memcpy(b->mirror_point, m, sizeof b->mirror_point);
        memcpy(b->mirror_normal, m + 3, sizeof b->mirror_normal);
    }
    if (a->val[O_PIN_MODE] && !a->val[O_PIN])
        return df_error_set(e, DF_EINVAL, "--pin-mode needs --pin FILE");
    b->pin_flags = DF_PIN_DISPLACEMENT;
    if (a->val[O_PIN_MODE]) {
        int k = dc_cli_choice(a->val[O_PIN_MODE], "--pin-mode", PIN_MODES, e);
        if (k < 0)
            return k;
        b->pin_flags = (uint8_t)(k + 1); /* 1 displacement, 2 gradient, 3 both */
    }
    b->moving = a->val[O_MOVING] ? 1 : 0;
    b->surface = a->val[O_SURFACE] ? 1 : 0;
    if (a->val[O_USE_SESSION] && (rc = use_session(a, b, e)))
        return rc;
    return DF_OK; /* the begin keeps zero loads: the update carries the whole load */
}

static int run_brush(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_msg_brush b;
    df_msg_brush_update u;
    df_error e;
    df_error_clear(&e);
    if (build(a, &b, &u, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    double *pins = NULL;
    int32_t npins = 0;
    if (a->val[O_PIN]) {
        if (dc_load_points_file(a->val[O_PIN], &pins, &npins, &e))
            return ctl_usage_error(ctx, cmd, e.msg);
        if ((uint32_t)npins > DF_MAX_PINNED_POINTS) {
            free(pins);
            return ctl_usage_error(ctx, cmd, "--pin: more points than DF_MAX_PINNED_POINTS");
        }
        b.n_pinned = (uint32_t)npins;
        b.pinned = pins;
    } else {
        b.pin_flags = 0;
    }
    if (dc_brush_check(&b, &u, &e)) {
        free(pins);
        if (b.type == DF_BRUSH_SCALE && e.code == DF_ESINGULAR && b.nu == 0.5) {
            char m[sizeof e.msg + 80];
            snprintf(m, sizeof m, "%s; pass --nu below 0.5 (e.g. --nu 0.45, the default)", e.msg);
            return ctl_error(ctx, cmd, "rejected", e.code, m, CTL_EXIT_SERVER);
        }
        return ctl_error(ctx, cmd, "rejected", e.code, e.msg, CTL_EXIT_SERVER);
    }
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) {
        free(pins);
        return CTL_EXIT_SERVER;
    }
    df_msg_ack ack = {0, 0};
    int rc = ctl_session_id(c, a->pos[0], &b.session_id, &e);
    u.session_id = b.session_id;
    int remote = 0; /* whether the failure was the daemon's (before the cancel resets it) */
    if (rc == DF_OK)
        rc = df_client_brush_begin(c, &b, NULL, &e);
    if (rc == DF_OK) {
        rc = df_client_brush_update(c, &u, NULL, &e);
        if (rc == DF_OK) {
            rc = df_client_brush_end(c, b.session_id, &ack, &e);
        } else if ((remote = df_client_last_error_was_remote(c))) {
            df_error e2;
            df_client_brush_cancel(c, b.session_id, NULL, &e2);
        }
    }
    free(pins);
    if (rc) {
        rc = remote ? ctl_error(ctx, cmd, "server", e.code, e.msg, CTL_EXIT_SERVER)
                    : ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (ctx->json)
        printf("{\"session\":%" PRIu64 ",\"version\":%" PRIu64 "}\n", ack.session_id, ack.version);
    else
        printf("session %" PRIu64 " version %" PRIu64 "\n", ack.session_id, ack.version);
    df_client_close(c);
    return CTL_EXIT_OK;
}

const ctl_cmd ctl_cmds_brush[] = {
    {"brush",
     "brush SESSION --type grab|twist|scale|pinch|affine --center X,Y,Z [--move DX,DY,DZ]\n"
     "       [--twist WX,WY,WZ] [--scale S] [--matrix M00,M01,...,M22] [--radius R] [--nu NU]\n"
     "       [--falloff N] [--ratio Q] [--dim 2|3] [--integrator euler|rk4] [--steps N]\n"
     "       [--mirror PX,PY,PZ,NX,NY,NZ] [--pin FILE [--pin-mode MODE]] [--strength S]\n"
     "       [--moving] [--use-session FIELD,...|all] [--surface]",
     "Apply one whole Kelvinlet brush stroke (begin, update, end) as one new version.",
     BRUSH_OPTS, O_COUNT, 1, run_brush},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

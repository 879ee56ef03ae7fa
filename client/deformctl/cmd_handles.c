/* cmd_handles.c — `deformctl handles` (define a session's SC-L1 handle set) and `deformctl move`
 * (move the handles to targets and wait for the final ADMM iterate). */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "client/dc_files.h"
#include "core/admm/admm_defaults.h"
#include "client/deformctl/ctl.h"
#include "client/deformctl/progress_out.h"

enum {
    H_ENERGY = CTL_NGLOBAL, H_HANDLES, H_W, H_S, H_RHO, H_ITERS, H_TOL, H_YOUNGS, H_POISSON,
    H_ACCEL, H_AREA, H_PROGRESS, H_COUNT
};

/* Defaults in the help text come from core/admm/admm_defaults.h (the values themselves from
 * df_msg_handles_defaults). */
#define S_(x) #x
#define S(x) S_(x)
static const dc_cli_opt HANDLES_OPTS[H_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"energy", 1, "--energy arap|acap|neohookean|cloth|polyline   elastic energy (required)"},
    {"handles", 1, "--handles FILE     handle vertices, one 0-based index per line (required)"},
    {"w", 1, "--w W              SC-L1 locality weight >= 0 (default " S(DF_ADMM_DEFAULT_W) "; neohookean " S(DF_ADMM_DEFAULT_NH_W) ")"},
    {"s", 1, "--s S              SC-L1 threshold distance > 0, mesh units (default " S(DF_ADMM_DEFAULT_S) ")"},
    {"rho", 1, "--rho RHO          fixed ADMM penalty > w/s (default: adaptive, chosen and tuned by the solver)"},
    {"iters", 1, "--iters N          default iteration budget of a move (default " S(DF_ADMM_DEFAULT_MAX_ITERS) ")"},
    {"tol", 1, "--tol T            residual tolerance >= 0 (default " S(DF_ADMM_DEFAULT_TOL) ")"},
    {"youngs", 1, "--youngs E         neohookean Young's modulus, Pa (default " S(DF_ADMM_DEFAULT_YOUNGS) ")"},
    {"poisson", 1, "--poisson NU       neohookean Poisson ratio in (-1, 0.5) (default " S(DF_ADMM_DEFAULT_POISSON) ")"},
    {"accelerate", 0, "--accelerate       Anderson-accelerated ADMM"},
    {"area-weighting", 0, "--area-weighting   weight the locality term by vertex area/volume"},
    {"progress", 1, CTL_PROGRESS_HELP},
};

static const char *const ENERGIES[] = {"arap", "acap", "neohookean", "cloth", "polyline", NULL};
/* --energy name i is the wire value i + 1 (df_energy is 1..DF_ENERGY_MAX, contiguous) */
_Static_assert(sizeof ENERGIES / sizeof ENERGIES[0] - 1 == DF_ENERGY_MAX, "one name per energy");

/* Each numeric option in its range; the message names the option and the value given. */
static int check_ranges(const dc_cli_args *a, const df_msg_handles *h, df_error *e)
{
    if (h->w < 0)
        return df_error_set(e, DF_EINVAL, "--w: %s must be >= 0", a->val[H_W]);
    if (h->s <= 0)
        return df_error_set(e, DF_EINVAL, "--s: %s must be > 0", a->val[H_S]);
    if (a->val[H_RHO] && h->rho <= 0)
        return df_error_set(e, DF_EINVAL, "--rho: %s must be > 0 (and above w/s); omit it for the adaptive penalty", a->val[H_RHO]);
    if (h->tol < 0)
        return df_error_set(e, DF_EINVAL, "--tol: %s must be >= 0", a->val[H_TOL]);
    if (a->val[H_YOUNGS] && h->youngs <= 0)
        return df_error_set(e, DF_EINVAL, "--youngs: %s must be > 0", a->val[H_YOUNGS]);
    if (a->val[H_POISSON] && !(h->poisson > -1 && h->poisson < 0.5))
        return df_error_set(e, DF_EINVAL, "--poisson: %s must be in (-1, 0.5)",
                            a->val[H_POISSON]);
    return DF_OK;
}

static int run_handles(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_error e;
    df_error_clear(&e);
    if (!a->val[H_ENERGY] || !a->val[H_HANDLES])
        return ctl_usage_error(ctx, cmd, "--energy and --handles are required");
    int en = dc_cli_choice(a->val[H_ENERGY], "--energy", ENERGIES, &e);
    if (en < 0)
        return ctl_usage_error(ctx, cmd, e.msg);
    df_msg_handles h;
    df_msg_handles_defaults(&h, (uint8_t)(en + 1));
    long long it;
    if ((a->val[H_W] && dc_cli_double(a->val[H_W], "--w", 0, &h.w, &e)) ||
        (a->val[H_S] && dc_cli_double(a->val[H_S], "--s", 0, &h.s, &e)) ||
        (a->val[H_RHO] && dc_cli_double(a->val[H_RHO], "--rho", 0, &h.rho, &e)) ||
        (a->val[H_TOL] && dc_cli_double(a->val[H_TOL], "--tol", 0, &h.tol, &e)) ||
        (a->val[H_YOUNGS] && dc_cli_double(a->val[H_YOUNGS], "--youngs", 0, &h.youngs, &e)) ||
        (a->val[H_POISSON] && dc_cli_double(a->val[H_POISSON], "--poisson", 0, &h.poisson, &e)))
        return ctl_usage_error(ctx, cmd, e.msg);
    h.accelerate = a->val[H_ACCEL] ? 1 : 0;
    h.area_weighting = a->val[H_AREA] ? 1 : 0;
    if (a->val[H_ITERS]) {
        if (dc_cli_int(a->val[H_ITERS], "--iters", 1, DF_MAX_MOVE_ITERS, &it, &e))
            return ctl_usage_error(ctx, cmd, e.msg);
        h.max_iters = (uint32_t)it;
    }
    if (check_ranges(a, &h, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    int pmode = CTL_PROGRESS_AUTO;
    if (a->val[H_PROGRESS] &&
        (pmode = dc_cli_choice(a->val[H_PROGRESS], "--progress", ctl_progress_modes, &e)) < 0)
        return ctl_usage_error(ctx, cmd, e.msg);
    int32_t *idx = NULL, n = 0;
    if (dc_load_index_file(a->val[H_HANDLES], &idx, &n, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    h.n_handles = (uint32_t)n;
    h.handles = idx;
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) {
        free(idx);
        return CTL_EXIT_SERVER;
    }
    ctl_progress pr;
    ctl_progress_init(&pr, ctx->prog, cmd->name, pmode, stderr);
    df_client_set_event_callback(c, ctl_progress_event, &pr);
    h.options = ctl_progress_wanted(&pr) ? DF_WORK_OPT_PROGRESS : 0;
    int rc = ctl_session_id(c, a->pos[0], &h.session_id, &e);
    if (rc == DF_OK)
        rc = df_client_handles_set(c, &h, &e);
    ctl_progress_finish(&pr);
    free(idx);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (ctx->json)
        printf("{\"session\":%" PRIu64 ",\"handles\":%d,\"energy\":\"%s\"}\n", h.session_id, n,
               ENERGIES[en]);
    else
        printf("session %" PRIu64 ": %d handles, %s\n", h.session_id, n, ENERGIES[en]);
    df_client_close(c);
    return CTL_EXIT_OK;
}

enum { M_TARGETS = CTL_NGLOBAL, M_HANDLES, M_ITERS, M_MS, M_EVERY, M_PROGRESS, M_KGUESS, M_POLISH,
       M_COUNT };

static const dc_cli_opt MOVE_OPTS[M_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"targets", 1, "--targets FILE     'x y z' per handle in handle order, or a .node file "
                   "whose rows at the handle indices are the targets (required)"},
    {"handles", 1, "--handles FILE     handle index file picking the rows of a .node targets "
                   "file (default: the session's handle set, fetched from the daemon)"},
    {"max-iters", 1, "--max-iters N      iteration budget (default: the handle set's --iters)"},
    {"max-ms", 1, "--max-ms MS        wall-clock budget in ms (default: none)"},
    {"progress-every", 1, "--progress-every N progress event every N iterations (default 10)"},
    {"progress", 1, CTL_PROGRESS_HELP},
    {"kelvinlet-guess", 0, "--kelvinlet-guess  start the solver from the Kelvinlet field of the "
                           "handles' move (line-searched; never a higher starting objective)"},
    {"polish", 0, "--polish           after ADMM, polish by projected Newton to a relative KKT "
                  "residual of 1e-9 (tet meshes: arap, acap, neohookean)"},
};

static const char *status_name(unsigned s)
{
    return s == DF_MOVE_CONVERGED    ? "converged"
           : s == DF_MOVE_BUDGET     ? "budget"
           : s == DF_MOVE_SUPERSEDED ? "superseded"
           : s == DF_MOVE_FAILED     ? "failed"
                                     : "running";
}

static int run_move(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_error e;
    df_error_clear(&e);
    const char *tf = a->val[M_TARGETS];
    if (!tf)
        return ctl_usage_error(ctx, cmd, "--targets is required");
    df_msg_handle_move m;
    memset(&m, 0, sizeof m);
    m.progress_every = 10;
    long long v;
    if (a->val[M_ITERS]) {
        if (dc_cli_int(a->val[M_ITERS], "--max-iters", 1, DF_MAX_MOVE_ITERS, &v, &e))
            return ctl_usage_error(ctx, cmd, e.msg);
        m.max_iters = (uint32_t)v;
    }
    if (a->val[M_MS]) {
        if (dc_cli_int(a->val[M_MS], "--max-ms", 1, UINT32_MAX, &v, &e))
            return ctl_usage_error(ctx, cmd, e.msg);
        m.max_ms = (uint32_t)v;
    }
    if (a->val[M_EVERY]) {
        if (dc_cli_int(a->val[M_EVERY], "--progress-every", 0, DF_MAX_MOVE_ITERS, &v, &e))
            return ctl_usage_error(ctx, cmd, e.msg);
        m.progress_every = (uint32_t)v;
    }
    int pmode = CTL_PROGRESS_AUTO;
    if (a->val[M_PROGRESS] &&
        (pmode = dc_cli_choice(a->val[M_PROGRESS], "--progress", ctl_progress_modes, &e)) < 0)
        return ctl_usage_error(ctx, cmd, e.msg);
    size_t tl = strlen(tf);
    int is_node = tl >= 5 && strcasecmp(tf + tl - 5, ".node") == 0;
    if (!is_node && a->val[M_HANDLES])
        return ctl_usage_error(ctx, cmd, "--handles FILE only applies to a .node targets file "
                               "(an 'x y z' targets file lists the handles in order)");
    /* Read every local file before connecting: a missing file is a usage error either way. */
    char *node_text = NULL;
    int32_t *hidx = NULL, nh = 0;
    double *targets = NULL;
    int rc;
    if (is_node)
        rc = dc_read_file(tf, &node_text, NULL, &e);
    else
        rc = dc_load_points_file(tf, &targets, &nh, &e);
    if (rc == DF_OK && is_node && a->val[M_HANDLES])
        rc = dc_load_index_file(a->val[M_HANDLES], &hidx, &nh, &e);
    if (rc) {
        free(node_text);
        free(targets);
        return ctl_usage_error(ctx, cmd, e.msg);
    }
    df_client *c = ctl_connect(ctx, cmd);
    if (!c) {
        free(node_text);
        free(hidx);
        free(targets);
        return CTL_EXIT_SERVER;
    }
    rc = ctl_session_id(c, a->pos[0], &m.session_id, &e);
    df_msg_handles hs;
    memset(&hs, 0, sizeof hs);
    if (rc == DF_OK && is_node && !hidx) {
        /* No --handles: the rows of the .node file at the session's own handle indices. */
        rc = df_client_handles_get(c, m.session_id, &hs, &e);
        if (rc == DF_OK) {
            hidx = hs.handles;
            hs.handles = NULL;
            nh = (int32_t)hs.n_handles;
        }
        df_msg_handles_free(&hs);
    }
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        free(node_text);
        free(hidx);
        free(targets);
        df_client_close(c);
        return rc;
    }
    if (is_node) {
        rc = dc_parse_targets_text(node_text, tf, 1, hidx, nh, &targets, &e);
        free(node_text);
        free(hidx);
        if (rc) {
            df_client_close(c);
            return ctl_usage_error(ctx, cmd, e.msg);
        }
    }
    m.n_targets = (uint32_t)nh;
    m.targets = targets;
    df_msg_move_result r;
    memset(&r, 0, sizeof r);
    ctl_progress pr;
    ctl_progress_init(&pr, ctx->prog, cmd->name, pmode, stderr);
    df_client_set_event_callback(c, ctl_progress_event, &pr);
    m.options = (ctl_progress_wanted(&pr) ? DF_WORK_OPT_PROGRESS : 0) |
                (a->val[M_KGUESS] ? DF_WORK_OPT_KELVINLET_GUESS : 0) |
                (a->val[M_POLISH] ? DF_WORK_OPT_POLISH : 0);
    rc = df_client_handles_move(c, &m, &r, &e);
    ctl_progress_finish(&pr);
    free(targets);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (r.status == DF_MOVE_FAILED) { /* the solver failed on the daemon: an error, exit 1 */
        char msg[200];
        snprintf(msg, sizeof msg, "the move failed after %u iterations (solver error; see the "
                 "daemon's log), version %" PRIu64, r.iterations, r.version);
        df_client_close(c);
        return ctl_error(ctx, cmd, "server", DF_EINTERNAL, msg, CTL_EXIT_SERVER);
    }
    if (ctx->json) {
        printf("{\"session\":%" PRIu64 ",\"version\":%" PRIu64 ",\"status\":\"%s\",\"iterations\":%u,"
               "\"residual\":", r.session_id, r.version, status_name(r.status), r.iterations);
        ctl_json_num(stdout, r.residual);
        printf(",\"objective\":");
        ctl_json_num(stdout, r.objective);
        printf(",\"elapsed_ms\":");
        ctl_json_num(stdout, r.elapsed_ms);
        printf("}\n");
    } else {
        printf("iterations %u residual %.6g objective %.12g (%s, version %" PRIu64 ", %.1f ms)\n",
               r.iterations, r.residual, r.objective, status_name(r.status), r.version,
               r.elapsed_ms);
    }
    df_client_close(c);
    return CTL_EXIT_OK;
}

const ctl_cmd ctl_cmds_handles[] = {
    {"handles",
     "handles SESSION --energy arap|acap|neohookean|cloth|polyline --handles FILE [--w W]\n"
     "       [--s S] [--rho RHO] [--iters N] [--tol T] [--youngs E] [--poisson NU]\n"
     "       [--accelerate] [--area-weighting] [--progress MODE]",
     "Define the session's handle set for SC-L1 local deformation (ADMM).", HANDLES_OPTS, H_COUNT,
     1, run_handles},
    {"move",
     "move SESSION --targets FILE [--handles FILE] [--max-iters N] [--max-ms MS]\n"
     "       [--progress-every N] [--progress MODE] [--kelvinlet-guess] [--polish]",
     "Move the handles to their targets; waits for the final iterate and prints iterations, "
     "residual, objective.",
     MOVE_OPTS, M_COUNT, 1, run_move},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

/* cmd_session.c — deformctl commands about the daemon and its sessions: ping, load, list,
 * close, stats (watch: cmd_watch.c). */
#include <inttypes.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "client/deformctl/ctl.h"
#include "client/deformctl/progress_out.h"
#include "core/mesh/mesh_io.h"

static const char *kind_name(unsigned k)
{
    return k == 1 ? "polyline" : k == 2 ? "triangle" : k == 3 ? "tet" : "unknown";
}

/* ---- ping ---------------------------------------------------------------------------- */
static int run_ping(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    (void)a;
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    double rtt = 0;
    int rc = df_client_ping(c, "deformctl-ping", 14, &rtt, &e);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    const df_msg_hello_reply *s = df_client_server_info(c);
    if (ctx->json) {
        printf("{\"ok\":true,\"rtt_us\":%.1f,\"protocol\":%u,\"server\":", rtt, s->version);
        ctl_json_str(stdout, s->server_name);
        printf(",\"features\":%u}\n", s->features);
    } else {
        printf("pong from %s (protocol %u): %.1f us\n", s->server_name, s->version, rtt);
    }
    df_client_close(c);
    return CTL_EXIT_OK;
}

/* ---- load ---------------------------------------------------------------------------- */
/* The load report as JSON members (no braces). */
static void load_report_json(const df_msg_load_report *r)
{
    printf("\"format\":\"%s\",\"dropped_elements\":%u,\"duplicate_elements\":%u,"
           "\"degenerate_elements\":%u,\"inverted_elements\":%u,\"nonmanifold_edges\":%u,"
           "\"nonmanifold_faces\":%u,\"boundary_edges\":%u,\"boundary_faces\":%u,"
           "\"unused_vertices\":%u,\"input_polygons\":%u,\"polygons_triangulated\":%u",
           df_mesh_format_name((df_mesh_format)r->format), r->dropped_elements,
           r->duplicate_elements, r->degenerate_elements, r->inverted_elements,
           r->nonmanifold_edges, r->nonmanifold_faces, r->boundary_edges, r->boundary_faces,
           r->unused_vertices, r->input_polygons, r->polygons_triangulated);
}

/* One stderr line per finding worth a warning (stdout keeps just the session id). */
static void load_report_text(const ctl_ctx *ctx, const char *file, const df_msg_load_report *r)
{
    const struct { uint32_t n; const char *what; } w[] = {
        {r->dropped_elements, "lower-dimensional elements dropped (e.g. OBJ 'l' lines beside "
                              "faces, MEDIT Edges in a tet mesh; the session keeps one kind)"},
        {r->duplicate_elements, "duplicate elements (same vertices as an earlier one)"},
        {r->degenerate_elements, "degenerate elements (zero or near-zero measure, or a repeated "
                                 "vertex): excluded from the solver's energies"},
        {r->inverted_elements, "inverted elements"},
        {r->nonmanifold_edges, "non-manifold edges"},
        {r->nonmanifold_faces, "non-manifold faces"},
        {r->unused_vertices, "unused vertices (no element uses them)"},
    };
    for (size_t i = 0; i < sizeof w / sizeof w[0]; i++)
        if (w[i].n)
            fprintf(stderr, "%s load: %s: warning: %u %s\n", ctx->prog, file, w[i].n, w[i].what);
}

static int run_load(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    const char *file = a->pos[0], *name = a->val[CTL_NGLOBAL];
    char m[700];
    if (df_mesh_format_from_path(file) == DF_FMT_AUTO) {
        snprintf(m, sizeof m, "%.400s: %s", file, DF_CLIENT_FORMATS_MSG);
        return ctl_usage_error(ctx, cmd, m);
    }
    if (access(file, R_OK) != 0) {
        snprintf(m, sizeof m, "cannot read %.400s", file);
        return ctl_usage_error(ctx, cmd, m);
    }
    df_error pe;
    int pmode = CTL_PROGRESS_AUTO;
    if (a->val[CTL_NGLOBAL + 2] &&
        (pmode = dc_cli_choice(a->val[CTL_NGLOBAL + 2], "--progress", ctl_progress_modes, &pe)) < 0)
        return ctl_usage_error(ctx, cmd, pe.msg);
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    df_msg_load_reply r;
    ctl_progress pr;
    ctl_progress_init(&pr, ctx->prog, cmd->name, pmode, stderr);
    df_client_set_event_callback(c, ctl_progress_event, &pr);
    df_client_set_load_flags(c, (uint16_t)((a->val[CTL_NGLOBAL + 1] ? DF_LOAD_OPT_2D : 0) |
                                           (ctl_progress_wanted(&pr) ? DF_LOAD_OPT_PROGRESS : 0)));
    int rc = df_client_load_mesh_file_ex(c, file, name, &r, &e);
    ctl_progress_finish(&pr);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    const df_msg_session_info *info = &r.info;
    if (ctx->json) {
        printf("{\"session\":%" PRIu64 ",\"name\":", info->session_id);
        ctl_json_str(stdout, info->name);
        printf(",\"kind\":\"%s\",\"nv\":%u,\"ne\":%u,\"version\":%" PRIu64,
               kind_name(info->kind), info->nv, info->ne, info->version);
        if (r.has_report) {
            printf(",\"report\":{");
            load_report_json(&r.report);
            printf("}");
        }
        printf("}\n");
    } else {
        printf("%" PRIu64 "\n", info->session_id);
    }
    if (r.has_report)
        load_report_text(ctx, file, &r.report);
    df_client_close(c);
    return CTL_EXIT_OK;
}

/* ---- list ---------------------------------------------------------------------------- */
static int run_list(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    (void)a;
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    df_msg_session_list l;
    int rc = df_client_list_sessions(c, &l, &e);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (ctx->json)
        printf("{\"sessions\":[");
    else
        printf("%-6s %-24s %-8s %9s %9s %8s %4s\n", "ID", "NAME", "KIND", "VERTICES", "ELEMENTS",
               "VERSION", "SUBS");
    for (uint32_t i = 0; i < l.count; i++) {
        const df_msg_session_info *s = &l.items[i];
        if (ctx->json) {
            printf("%s{\"session\":%" PRIu64 ",\"name\":", i ? "," : "", s->session_id);
            ctl_json_str(stdout, s->name);
            printf(",\"kind\":\"%s\",\"nv\":%u,\"ne\":%u,\"version\":%" PRIu64
                   ",\"subscribers\":%u,\"undo_depth\":%u,\"redo_depth\":%u}",
                   kind_name(s->kind), s->nv, s->ne, s->version, s->subscribers, s->undo_depth,
                   s->redo_depth);
        } else {
            printf("%-6" PRIu64 " %-24s %-8s %9u %9u %8" PRIu64 " %4u\n", s->session_id,
                   s->name[0] ? s->name : "-", kind_name(s->kind), s->nv, s->ne, s->version,
                   s->subscribers);
        }
    }
    if (ctx->json)
        printf("]}\n");
    df_msg_session_list_free(&l);
    df_client_close(c);
    return CTL_EXIT_OK;
}

/* ---- close --------------------------------------------------------------------------- */
static int run_close(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    uint64_t sid = 0;
    df_msg_ack ack = {0, 0};
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK)
        rc = df_client_close_session(c, sid, &ack, &e);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (ctx->json)
        printf("{\"session\":%" PRIu64 ",\"closed\":true}\n", sid);
    else
        printf("closed session %" PRIu64 "\n", sid);
    df_client_close(c);
    return CTL_EXIT_OK;
}

/* ---- stats --------------------------------------------------------------------------- */
/* One closing line "memory: USED of MAX MiB (P%)" when the daemon reports its memory budget. */
static void print_memory_summary(const df_msg_stats *st)
{
    double used = -1, max = -1;
    for (uint32_t i = 0; i < st->count; i++) {
        if (strcmp(st->items[i].key, "memory_used_bytes") == 0) used = st->items[i].value;
        if (strcmp(st->items[i].key, "memory_max_bytes") == 0) max = st->items[i].value;
    }
    if (used < 0 || max <= 0)
        return;
    printf("memory: %.1f of %.1f MiB (%.1f%% of memory_max_mb)\n", used / 1048576.0,
           max / 1048576.0, 100.0 * used / max);
}

static int run_stats(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    uint64_t sid = 0;
    int rc = a->val[CTL_NGLOBAL] ? ctl_session_id(c, a->val[CTL_NGLOBAL], &sid, &e) : DF_OK;
    df_msg_stats st;
    memset(&st, 0, sizeof st);
    if (rc == DF_OK)
        rc = df_client_stats(c, sid, &st, &e);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    if (ctx->json)
        printf("{");
    for (uint32_t i = 0; i < st.count; i++) {
        if (ctx->json) {
            printf("%s", i ? "," : "");
            ctl_json_str(stdout, st.items[i].key);
            printf(":");
            ctl_json_num(stdout, st.items[i].value);
        } else {
            printf("%-40s %.17g\n", st.items[i].key, st.items[i].value);
        }
    }
    if (ctx->json)
        printf("}\n");
    else
        print_memory_summary(&st);
    df_msg_stats_free(&st);
    df_client_close(c);
    return CTL_EXIT_OK;
}

static const dc_cli_opt PLAIN_OPTS[] = {CTL_GLOBAL_OPTS};
static const dc_cli_opt LOAD_OPTS[] = {
    CTL_GLOBAL_OPTS,
    {"name", 1, "--name NAME        session name (default: the file name without extension: "
                "spot, spot-2, ...)"},
    {"2d", 0, "--2d               a 2D session even if the file gives z (every z must be 0); "
              "else 2D only when the file is (OBJ `v x y`, MEDIT Dimension 2, 2D .node, PLY "
              "without z)"},
    {"progress", 1, CTL_PROGRESS_HELP},
};
static const dc_cli_opt STATS_OPTS[] = {
    CTL_GLOBAL_OPTS,
    {"session", 1, "--session SESSION  stats of one session (id or name) instead of the daemon"},
};
#define N(x) ((int)(sizeof x / sizeof x[0]))

const ctl_cmd ctl_cmds_session[] = {
    {"ping", "ping", "Check that the daemon answers; prints the round trip.", PLAIN_OPTS,
     N(PLAIN_OPTS), 0, run_ping},
    {"load", "load FILE [--name NAME] [--2d] [--progress MODE]",
     "Upload a mesh (.obj .off .ply .mesh, or X.node with X.ele); prints the new session id "
     "(--json: also the load report); warnings about the mesh (dropped elements, duplicates, "
     "non-manifold edges, unused vertices) go to stderr.",
     LOAD_OPTS, N(LOAD_OPTS), 1, run_load},
    {"list", "list", "List the sessions: id, name, kind, sizes, version, subscribers.", PLAIN_OPTS,
     N(PLAIN_OPTS), 0, run_list},
    {"close", "close SESSION",
     "Close a session (id or name): its mesh, history and handle set are freed and every "
     "subscriber is told.", PLAIN_OPTS, N(PLAIN_OPTS), 1, run_close},
    {"stats", "stats [--session SESSION]",
     "Print the daemon's (or one session's) counters, one 'key value' per line.", STATS_OPTS,
     N(STATS_OPTS), 0, run_stats},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

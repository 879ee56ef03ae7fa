/* cmd_mesh.c — deformctl commands on a session's mesh and history: get (write the current mesh
 * to a file), undo, redo, reset-rest. */
#include <inttypes.h>
#include <string.h>
#include <strings.h>

#include "client/dc_meshout.h"
#include "client/deformctl/ctl.h"

enum { G_OUT = CTL_NGLOBAL, G_COUNT };

static const dc_cli_opt GET_OPTS[G_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"out", 1, "--out FILE         output mesh; format from the extension: .obj .off .ply .node "
               ".mesh (required).\n                     A tet mesh written as .obj .off .ply "
               "becomes its boundary surface\n                     over all vertices (a note on "
               "stderr)"},
};

static const char *const OUT_EXTS[] = {".obj", ".off", ".ply", ".node", ".mesh", NULL};

static int run_get(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    const char *out = a->val[G_OUT];
    if (!out)
        return ctl_usage_error(ctx, cmd, "--out FILE is required");
    size_t ol = strlen(out);
    int ok = 0;
    for (int i = 0; OUT_EXTS[i]; i++) {
        size_t el = strlen(OUT_EXTS[i]);
        ok |= ol > el && strcasecmp(out + ol - el, OUT_EXTS[i]) == 0;
    }
    if (!ok)
        return ctl_usage_error(ctx, cmd, "--out: extension must be .obj .off .ply .node or .mesh");
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    df_client_mesh m;
    memset(&m, 0, sizeof m);
    uint64_t sid = 0;
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK)
        rc = df_client_get_mesh(c, sid, 0, &m, &e);
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        return rc;
    }
    df_client_close(c);
    int32_t surf = -1;
    rc = dc_meshout_write(out, m.kind, m.planar, m.nv, m.positions, m.ne, m.elements, m.nf,
                          m.faces, &surf, &e);
    if (rc) {
        df_client_mesh_free(&m);
        /* A local failure after the command line was accepted (the file cannot be written, or
         * its format cannot hold this session's mesh, e.g. a polyline as .off): exit 1. */
        return ctl_error(ctx, cmd, "client", e.code, e.msg, CTL_EXIT_SERVER);
    }
    if (surf >= 0)
        fprintf(stderr, "%s %s: note: %s cannot hold tetrahedra; wrote the boundary surface of "
                "the tet mesh (%d triangles over all %u vertices)\n", ctx->prog, cmd->name, out,
                (int)surf, m.nv);
    if (ctx->json) {
        printf("{\"session\":%" PRIu64 ",\"version\":%" PRIu64 ",\"nv\":%u,\"ne\":%u,",
               m.session_id, m.version, m.nv, m.ne);
        if (surf >= 0)
            printf("\"boundary_faces\":%d,", (int)surf);
        printf("\"out\":");
        ctl_json_str(stdout, out);
        printf("}\n");
    } else {
        if (surf >= 0)
            printf("wrote %s: %u vertices, %d boundary triangles of %u tets (session %" PRIu64
                   " version %" PRIu64 ")\n", out, m.nv, (int)surf, m.ne, m.session_id, m.version);
        else
            printf("wrote %s: %u vertices, %u elements (session %" PRIu64 " version %" PRIu64
                   ")\n", out, m.nv, m.ne, m.session_id, m.version);
    }
    df_client_mesh_free(&m);
    return CTL_EXIT_OK;
}

/* undo / redo / reset-rest: one session id in, the new version out. */
static int run_history(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_error e;
    df_msg_ack ack = {0, 0};
    uint64_t sid = 0;
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK) {
        if (strcmp(cmd->name, "undo") == 0)
            rc = df_client_undo(c, sid, &ack, &e);
        else if (strcmp(cmd->name, "redo") == 0)
            rc = df_client_redo(c, sid, &ack, &e);
        else
            rc = df_client_reset_rest(c, sid, &ack, &e);
    }
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
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

static const dc_cli_opt PLAIN_OPTS[] = {CTL_GLOBAL_OPTS};
#define NPLAIN ((int)(sizeof PLAIN_OPTS / sizeof PLAIN_OPTS[0]))

const ctl_cmd ctl_cmds_mesh[] = {
    {"get", "get SESSION --out FILE",
     "Write the session's current mesh to FILE (.obj .off .ply .node .mesh).", GET_OPTS, G_COUNT,
     1, run_get},
    {"undo", "undo SESSION", "Revert the session's last change (a new version).", PLAIN_OPTS,
     NPLAIN, 1, run_history},
    {"redo", "redo SESSION", "Re-apply the last undone change (a new version).", PLAIN_OPTS,
     NPLAIN, 1, run_history},
    {"reset-rest", "reset-rest SESSION",
     "Make the current positions the rest shape of the handle solver (sculpting).", PLAIN_OPTS,
     NPLAIN, 1, run_history},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

/* cmd_preview.c — deformctl preview: a PNG picture of a session, rest and current shapes side
 * by side shaded by displacement magnitude with a colour bar (client/dc_preview.h renders it,
 * png_out.h writes it). */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "client/dc_preview.h"
#include "client/deformctl/ctl.h"
#include "client/deformctl/png_out.h"

enum { P_OUT = CTL_NGLOBAL, P_VIEW, P_SIZE, P_COUNT };

#define PREVIEW_DEFAULT_W 800
#define PREVIEW_DEFAULT_H 400

static const dc_cli_opt PREVIEW_OPTS[P_COUNT] = {
    CTL_GLOBAL_OPTS,
    {"out", 1, "--out FILE.png     the picture to write (required; .png)"},
    {"view", 1, "--view VIEW        front (default), side, top or iso; a 2D session is always "
                "drawn flat\n                     (its top view)"},
    {"size", 1, "--size WxH         picture size in pixels (default 800x400; each side "
                "64..8192)"},
};

/* Parses "WxH" into w, h within the preview's bounds (DF_EINVAL naming --size otherwise). */
static int parse_size(const char *s, int *w, int *h, df_error *e)
{
    const char *x = strpbrk(s, "xX");
    char a[32];
    if (!x || (size_t)(x - s) >= sizeof a || x == s)
        return df_error_set(e, DF_EINVAL, "--size: '%s' is not WxH (e.g. 800x400)", s);
    memcpy(a, s, (size_t)(x - s));
    a[x - s] = '\0';
    long long lw, lh;
    if (dc_cli_int(a, "--size width", DC_PREVIEW_MIN_SIDE, DC_RENDER_MAX_SIDE, &lw, e) ||
        dc_cli_int(x + 1, "--size height", DC_PREVIEW_MIN_SIDE, DC_RENDER_MAX_SIDE, &lh, e))
        return DF_EINVAL;
    *w = (int)lw;
    *h = (int)lh;
    return DF_OK;
}

static void print_result(const ctl_ctx *ctx, const char *out, int w, int h,
                         const df_client_mesh *m, const dc_preview_info *in)
{
    if (!ctx->json) {
        printf("wrote %s: %dx%d, %s view, rest | current, displacement %.6g..%.6g (session %"
               PRIu64 " version %" PRIu64 ")\n", out, w, h, dc_view_names[in->view],
               (double)in->vmin, (double)in->vmax, m->session_id, m->version);
        return;
    }
    printf("{\"session\":%" PRIu64 ",\"version\":%" PRIu64 ",\"out\":", m->session_id,
           m->version);
    ctl_json_str(stdout, out);
    printf(",\"width\":%d,\"height\":%d,\"view\":\"%s\",\"min\":", w, h,
           dc_view_names[in->view]);
    ctl_json_num(stdout, in->vmin);
    printf(",\"max\":");
    ctl_json_num(stdout, in->vmax);
    printf(",\"triangles\":%u,\"segments\":%u,\"panels\":[[%d,%d,%d,%d],[%d,%d,%d,%d]],"
           "\"bar\":[%d,%d,%d,%d]}\n", in->ntri, in->nseg, in->panel[0][0], in->panel[0][1],
           in->panel[0][2], in->panel[0][3], in->panel[1][0], in->panel[1][1], in->panel[1][2],
           in->panel[1][3], in->bar[0], in->bar[1], in->bar[2], in->bar[3]);
}

static int run_preview(ctl_ctx *ctx, const ctl_cmd *cmd, const dc_cli_args *a)
{
    const char *out = a->val[P_OUT];
    if (!out)
        return ctl_usage_error(ctx, cmd, "--out FILE.png is required");
    size_t ol = strlen(out);
    if (ol <= 4 || strcasecmp(out + ol - 4, ".png") != 0)
        return ctl_usage_error(ctx, cmd, "--out: the file name must end in .png");
    df_error e;
    df_error_clear(&e);
    int view = DC_VIEW_FRONT;
    if (a->val[P_VIEW] && (view = dc_cli_choice(a->val[P_VIEW], "--view", dc_view_names, &e)) < 0)
        return ctl_usage_error(ctx, cmd, e.msg);
    int w = PREVIEW_DEFAULT_W, h = PREVIEW_DEFAULT_H;
    if (a->val[P_SIZE] && parse_size(a->val[P_SIZE], &w, &h, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    df_client *c = ctl_connect(ctx, cmd);
    if (!c)
        return CTL_EXIT_SERVER;
    df_client_mesh m;
    memset(&m, 0, sizeof m);
    uint64_t sid = 0;
    int rc = ctl_session_id(c, a->pos[0], &sid, &e);
    if (rc == DF_OK)
        rc = df_client_get_mesh(c, sid, DF_GET_MESH_REST, &m, &e);
    if (rc == DF_OK && !m.rest)
        rc = df_error_set(&e, DF_EFORMAT, "the daemon sent no REST section");
    if (rc) {
        rc = ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
        df_client_mesh_free(&m);
        return rc;
    }
    df_client_close(c);
    dc_preview_mesh pm = {m.kind, m.planar, m.nv, m.positions, m.rest, m.ne, m.elements, m.nf,
                          m.faces};
    dc_image im;
    dc_preview_info in;
    rc = dc_preview_render(&pm, (dc_view)view, w, h, &im, &in, &e);
    if (rc == DF_OK)
        rc = ctl_png_write(out, im.w, im.h, im.rgb, &e);
    dc_image_free(&im);
    if (rc) {
        df_client_mesh_free(&m);
        return ctl_error(ctx, cmd, "client", e.code, e.msg, CTL_EXIT_SERVER);
    }
    if (m.planar && a->val[P_VIEW] && view != DC_VIEW_FRONT)
        fprintf(stderr, "%s %s: note: session %" PRIu64 " is 2D: drawn flat (front view)\n",
                ctx->prog, cmd->name, m.session_id);
    print_result(ctx, out, w, h, &m, &in);
    df_client_mesh_free(&m);
    return CTL_EXIT_OK;
}

const ctl_cmd ctl_cmds_preview[] = {
    {"preview", "preview SESSION --out FILE.png [--view front|side|top|iso] [--size WxH]",
     "Write a PNG of the session: rest and current shape side by side, shaded by displacement.",
     PREVIEW_OPTS, P_COUNT, 1, run_preview},
    {NULL, NULL, NULL, NULL, 0, 0, NULL},
};

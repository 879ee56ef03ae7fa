/* dc_preview.c — rest and current side by side with a colour bar (see dc_preview.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client/dc_preview.h"

static const uint8_t BG[3] = {32, 32, 36};
static const uint8_t FG[3] = {230, 230, 230};
static const uint8_t SEP[3] = {90, 90, 96};

/* Triangles and segments of the mesh (malloc'd; NULL when there are none). */
static int primitives(const dc_preview_mesh *m, int32_t **tris, uint32_t *ntri, int32_t **segs,
                      uint32_t *nseg, df_error *err)
{
    *tris = *segs = NULL;
    *ntri = *nseg = 0;
    if (m->kind == 1) {
        *segs = malloc(((size_t)m->ne + 1) * 2 * sizeof **segs);
        if (!*segs) return df_error_set(err, DF_ENOMEM, "out of memory for the segments");
        memcpy(*segs, m->elements, (size_t)m->ne * 2 * sizeof **segs);
        *nseg = m->ne;
    } else if (m->kind == 2 || (m->kind == 3 && m->nf > 0)) {
        uint32_t n = m->kind == 2 ? m->ne : m->nf;
        *tris = malloc(((size_t)n + 1) * 3 * sizeof **tris);
        if (!*tris) return df_error_set(err, DF_ENOMEM, "out of memory for the triangles");
        memcpy(*tris, m->kind == 2 ? m->elements : m->faces, (size_t)n * 3 * sizeof **tris);
        *ntri = n;
    } else { /* tets without boundary faces: every face of every tet */
        static const int F[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
        *tris = malloc(((size_t)m->ne * 4 + 1) * 3 * sizeof **tris);
        if (!*tris) return df_error_set(err, DF_ENOMEM, "out of memory for the triangles");
        for (size_t e = 0; e < m->ne; e++)
            for (int f = 0; f < 4; f++)
                for (int k = 0; k < 3; k++)
                    (*tris)[3 * (4 * e + (size_t)f) + (size_t)k] = m->elements[4 * e + (size_t)F[f][k]];
        *ntri = m->ne * 4;
    }
    return DF_OK;
}

static void label_value(char *buf, size_t n, float v)
{
    snprintf(buf, n, "%.4g", (double)v);
    for (char *p = buf; *p; p++) /* "1e+03", "inf": the font is lower case */
        if (*p >= 'A' && *p <= 'Z') *p = (char)(*p - 'A' + 'a');
}

static void draw_bar(dc_image *im, int s, const dc_preview_info *in)
{
    const int *b = in->bar;
    for (int x = 0; x < b[2]; x++) {
        uint8_t c[3];
        dc_colormap(b[2] > 1 ? (double)x / (b[2] - 1) : 0, c);
        dc_image_fill(im, b[0] + x, b[1], 1, b[3], c);
    }
    int ly = b[1] + b[3] + 3;
    char lo[32], hi[32];
    label_value(lo, sizeof lo, in->vmin);
    label_value(hi, sizeof hi, in->vmax);
    dc_draw_text(im, b[0], ly, s, lo, FG);
    dc_draw_text(im, b[0] + b[2] - dc_text_width(hi, s), ly, s, hi, FG);
    const char *mid = "displacement";
    int mw = dc_text_width(mid, s);
    int lw = dc_text_width(lo, s), hw = dc_text_width(hi, s);
    int mx = b[0] + (b[2] - mw) / 2;
    if (mx > b[0] + lw + 2 * s && mx + mw < b[0] + b[2] - hw - 2 * s) /* only where it fits */
        dc_draw_text(im, mx, ly, s, mid, FG);
}

int dc_preview_render(const dc_preview_mesh *m, dc_view view, int w, int h, dc_image *out,
                      dc_preview_info *info, df_error *err)
{
    memset(out, 0, sizeof *out);
    if (w < DC_PREVIEW_MIN_SIDE || h < DC_PREVIEW_MIN_SIDE || w > DC_RENDER_MAX_SIDE ||
        h > DC_RENDER_MAX_SIDE)
        return df_error_set(err, DF_EINVAL, "preview size %dx%d outside %d..%d per side", w, h,
                            DC_PREVIEW_MIN_SIDE, DC_RENDER_MAX_SIDE);
    if (m->kind < 1 || m->kind > 3)
        return df_error_set(err, DF_EINVAL, "mesh kind %u is not 1..3", m->kind);
    if (m->nv == 0 || !m->pos || !m->rest || (m->ne && !m->elements) || (m->nf && !m->faces))
        return df_error_set(err, DF_EINVAL, "preview needs vertices, current and rest positions "
                            "and the elements");
    dc_preview_info in;
    memset(&in, 0, sizeof in);
    in.view = m->planar ? DC_VIEW_FRONT : view;
    float *val = malloc((size_t)m->nv * sizeof *val);
    if (!val) return df_error_set(err, DF_ENOMEM, "out of memory for %u displacements", m->nv);
    in.vmin = INFINITY;
    in.vmax = -INFINITY;
    for (size_t i = 0; i < m->nv; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double d = (double)m->pos[3 * i + (size_t)k] - m->rest[3 * i + (size_t)k];
            d2 += d * d;
        }
        val[i] = (float)sqrt(d2);
        if (!isfinite(val[i])) continue;
        if (val[i] < in.vmin) in.vmin = val[i];
        if (val[i] > in.vmax) in.vmax = val[i];
    }
    if (!(in.vmin <= in.vmax)) in.vmin = in.vmax = 0;
    int32_t *tris, *segs;
    int rc = primitives(m, &tris, &in.ntri, &segs, &in.nseg, err);
    if (rc == DF_OK) rc = dc_image_init(out, w, h, BG, err);
    if (rc != DF_OK) {
        free(val);
        free(tris);
        free(segs);
        return rc;
    }
    int s = h >= 400 ? 2 : 1;
    int th = 7 * s + 8, barh = 8 * s + 4, bh = 4 + barh + 3 + 7 * s + 4;
    int pw = w / 2 - 1, ph = h - th - bh;
    int p0[4] = {0, th, pw, ph}, p1[4] = {w / 2, th, pw, ph};
    memcpy(in.panel[0], p0, sizeof p0);
    memcpy(in.panel[1], p1, sizeof p1);
    in.bar[0] = w / 8;
    in.bar[1] = h - bh + 4;
    in.bar[2] = 7 * w / 8 - w / 8;
    in.bar[3] = barh;
    dc_image_fill(out, w / 2 - 1, th, 1, ph, SEP);
    dc_camera cam;
    const float *sets[2] = {m->rest, m->pos};
    dc_camera_fit(&cam, in.view, sets, 2, m->nv, p0[0], p0[1], p0[2], p0[3], 8 * s);
    int line_px = s + 1;
    dc_render_mesh rm = {m->nv, m->rest, NULL, in.ntri, tris, in.nseg, segs};
    float *zero = calloc(m->nv, sizeof *zero); /* the rest is at distance 0 from itself */
    rm.value = zero;
    if (zero) {
        dc_render_draw(out, p0, &cam, &rm, in.vmin, in.vmax, line_px);
        dc_image_clear_depth(out);
        cam.cx += p1[0] - p0[0];
        rm.pos = m->pos;
        rm.value = val;
        dc_render_draw(out, p1, &cam, &rm, in.vmin, in.vmax, line_px);
        const char *t0 = "rest", *t1 = "current";
        dc_draw_text(out, p0[0] + (pw - dc_text_width(t0, s)) / 2, 4, s, t0, FG);
        dc_draw_text(out, p1[0] + (pw - dc_text_width(t1, s)) / 2, 4, s, t1, FG);
        draw_bar(out, s, &in);
    }
    free(zero);
    free(val);
    free(tris);
    free(segs);
    if (!zero) {
        dc_image_free(out);
        return df_error_set(err, DF_ENOMEM, "out of memory for %u displacements", m->nv);
    }
    if (info) *info = in;
    return DF_OK;
}

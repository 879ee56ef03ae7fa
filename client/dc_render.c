/* dc_render.c — the preview renderer (see dc_render.h): image, camera, triangle and line
 * rasterizers with a depth buffer, Lambert shading, colour map and a 5x7 bitmap font. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/dc_render.h"

const char *const dc_view_names[] = {"front", "side", "top", "iso", NULL};

int dc_image_init(dc_image *im, int w, int h, const uint8_t bg[3], df_error *err)
{
    memset(im, 0, sizeof *im);
    if (w < 1 || h < 1 || w > DC_RENDER_MAX_SIDE || h > DC_RENDER_MAX_SIDE)
        return df_error_set(err, DF_EINVAL, "image size %dx%d outside 1..%d per side", w, h,
                            DC_RENDER_MAX_SIDE);
    size_t n = (size_t)w * (size_t)h;
    im->rgb = malloc(n * 3);
    im->depth = malloc(n * sizeof *im->depth);
    if (!im->rgb || !im->depth) {
        dc_image_free(im);
        return df_error_set(err, DF_ENOMEM, "out of memory for a %dx%d image", w, h);
    }
    im->w = w;
    im->h = h;
    for (size_t i = 0; i < n; i++)
        memcpy(im->rgb + 3 * i, bg, 3);
    dc_image_clear_depth(im);
    return DF_OK;
}

void dc_image_free(dc_image *im)
{
    if (!im) return;
    free(im->rgb);
    free(im->depth);
    memset(im, 0, sizeof *im);
}

void dc_image_clear_depth(dc_image *im)
{
    size_t n = (size_t)im->w * (size_t)im->h;
    for (size_t i = 0; i < n; i++)
        im->depth[i] = -INFINITY;
}

void dc_image_put(dc_image *im, int x, int y, const uint8_t c[3])
{
    if (x < 0 || y < 0 || x >= im->w || y >= im->h) return;
    memcpy(im->rgb + 3 * ((size_t)y * (size_t)im->w + (size_t)x), c, 3);
}

void dc_image_fill(dc_image *im, int x, int y, int w, int h, const uint8_t c[3])
{
    for (int j = y; j < y + h; j++)
        for (int i = x; i < x + w; i++)
            dc_image_put(im, i, j, c);
}

void dc_view_rotation(dc_view v, double R[9])
{
    static const double FRONT[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const double SIDE[9] = {0, 0, -1, 0, 1, 0, 1, 0, 0};
    static const double TOP[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0};
    switch (v) {
    case DC_VIEW_SIDE: memcpy(R, SIDE, sizeof SIDE); return;
    case DC_VIEW_TOP: memcpy(R, TOP, sizeof TOP); return;
    case DC_VIEW_ISO: {
        /* yaw -45 degrees about y (so +x and +z both come forward), then pitch by
         * a = atan(1/sqrt 2) about the screen x axis (so +y comes forward too). */
        double c = sqrt(0.5), s = sqrt(0.5);
        double Y[9] = {c, 0, -s, 0, 1, 0, s, 0, c};
        double a = atan(1.0 / sqrt(2.0)), ca = cos(a), sa = sin(a);
        double P[9] = {1, 0, 0, 0, ca, -sa, 0, sa, ca};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                R[3 * i + j] = P[3 * i] * Y[j] + P[3 * i + 1] * Y[3 + j] + P[3 * i + 2] * Y[6 + j];
        return;
    }
    case DC_VIEW_FRONT:
    default: memcpy(R, FRONT, sizeof FRONT); return;
    }
}

static void view_coords(const double R[9], const float p[3], double v[3])
{
    for (int i = 0; i < 3; i++)
        v[i] = R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2];
}

void dc_camera_fit(dc_camera *cam, dc_view v, const float *const *sets, int nsets, uint32_t nv,
                   int x, int y, int w, int h, int margin)
{
    dc_view_rotation(v, cam->R);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int k = 0; k < nsets; k++)
        for (uint32_t i = 0; sets[k] && i < nv; i++) {
            const float *p = sets[k] + 3 * (size_t)i;
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) continue;
            double q[3];
            view_coords(cam->R, p, q);
            for (int a = 0; a < 2; a++) {
                if (q[a] < lo[a]) lo[a] = q[a];
                if (q[a] > hi[a]) hi[a] = q[a];
            }
        }
    if (!(lo[0] <= hi[0])) lo[0] = hi[0] = lo[1] = hi[1] = 0;
    cam->c0 = 0.5 * (lo[0] + hi[0]);
    cam->c1 = 0.5 * (lo[1] + hi[1]);
    cam->cx = x + 0.5 * w;
    cam->cy = y + 0.5 * h;
    double aw = w - 2.0 * margin, ah = h - 2.0 * margin, scale = INFINITY;
    if (aw < 1) aw = 1;
    if (ah < 1) ah = 1;
    if (hi[0] > lo[0]) scale = aw / (hi[0] - lo[0]);
    if (hi[1] > lo[1] && ah / (hi[1] - lo[1]) < scale) scale = ah / (hi[1] - lo[1]);
    cam->scale = isfinite(scale) && scale > 0 ? scale : 1.0;
}

void dc_camera_project(const dc_camera *cam, const float p[3], double *sx, double *sy,
                       double *sz)
{
    double v[3];
    view_coords(cam->R, p, v);
    *sx = cam->cx + cam->scale * (v[0] - cam->c0);
    *sy = cam->cy - cam->scale * (v[1] - cam->c1);
    *sz = v[2];
}

void dc_colormap(double t, uint8_t out[3])
{
    static const double STOPS[5][3] = {
        {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    double f = t * 4;
    int i = (int)f;
    if (i > 3) i = 3;
    f -= i;
    for (int c = 0; c < 3; c++)
        out[c] = (uint8_t)lround(STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c]));
}

/* Pixel bounds of a screen box intersected with the clip rectangle and the image: 0 if empty. */
static int pixel_bounds(const dc_image *im, const int clip[4], double minx, double maxx,
                        double miny, double maxy, int b[4])
{
    double cx0 = clip[0] > 0 ? clip[0] : 0, cy0 = clip[1] > 0 ? clip[1] : 0;
    double cx1 = clip[0] + clip[2] < im->w ? clip[0] + clip[2] : im->w;
    double cy1 = clip[1] + clip[3] < im->h ? clip[1] + clip[3] : im->h;
    if (minx < cx0) minx = cx0;
    if (miny < cy0) miny = cy0;
    if (maxx > cx1 - 0.5) maxx = cx1 - 0.5;
    if (maxy > cy1 - 0.5) maxy = cy1 - 0.5;
    if (!(minx <= maxx) || !(miny <= maxy)) return 0;
    b[0] = (int)floor(minx - 0.5);
    b[1] = (int)floor(miny - 0.5);
    b[2] = (int)ceil(maxx - 0.5);
    b[3] = (int)ceil(maxy - 0.5);
    if (b[0] < (int)cx0) b[0] = (int)cx0;
    if (b[1] < (int)cy0) b[1] = (int)cy0;
    if (b[2] > (int)cx1 - 1) b[2] = (int)cx1 - 1;
    if (b[3] > (int)cy1 - 1) b[3] = (int)cy1 - 1;
    return b[0] <= b[2] && b[1] <= b[3];
}

static int plot(dc_image *im, int x, int y, double z, double t, double shade)
{
    size_t i = (size_t)y * (size_t)im->w + (size_t)x;
    if (!(z > im->depth[i])) return 0;
    im->depth[i] = (float)z;
    uint8_t c[3];
    dc_colormap(t, c);
    for (int k = 0; k < 3; k++)
        im->rgb[3 * i + (size_t)k] = (uint8_t)lround(c[k] * shade);
    return 1;
}

long dc_raster_triangle(dc_image *im, const int clip[4], const double sx[3], const double sy[3],
                        const double sz[3], const double t[3], double shade)
{
    for (int k = 0; k < 3; k++)
        if (!isfinite(sx[k]) || !isfinite(sy[k]) || !isfinite(sz[k])) return 0;
    double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sy[1] - sy[0]) * (sx[2] - sx[0]);
    if (area == 0 || !isfinite(area)) return 0;
    double sgn = area > 0 ? 1 : -1;
    area *= sgn;
    double minx = fmin(sx[0], fmin(sx[1], sx[2])), maxx = fmax(sx[0], fmax(sx[1], sx[2]));
    double miny = fmin(sy[0], fmin(sy[1], sy[2])), maxy = fmax(sy[0], fmax(sy[1], sy[2]));
    int b[4];
    if (!pixel_bounds(im, clip, minx, maxx, miny, maxy, b)) return 0;
    if (!(shade >= 0)) shade = 0;
    if (shade > 1) shade = 1;
    long n = 0;
    for (int y = b[1]; y <= b[3]; y++)
        for (int x = b[0]; x <= b[2]; x++) {
            double px = x + 0.5, py = y + 0.5, w[3];
            for (int k = 0; k < 3; k++) { /* w[k]: edge opposite vertex k */
                int a = (k + 1) % 3, c = (k + 2) % 3;
                w[k] = sgn * ((sx[c] - sx[a]) * (py - sy[a]) - (sy[c] - sy[a]) * (px - sx[a]));
            }
            if (w[0] < 0 || w[1] < 0 || w[2] < 0) continue;
            double l0 = w[0] / area, l1 = w[1] / area, l2 = w[2] / area;
            n += plot(im, x, y, l0 * sz[0] + l1 * sz[1] + l2 * sz[2],
                      l0 * t[0] + l1 * t[1] + l2 * t[2], shade);
        }
    return n;
}

long dc_raster_line(dc_image *im, const int clip[4], const double sx[2], const double sy[2],
                    const double sz[2], const double t[2], int thick)
{
    for (int k = 0; k < 2; k++)
        if (!isfinite(sx[k]) || !isfinite(sy[k]) || !isfinite(sz[k])) return 0;
    if (thick < 1) thick = 1;
    if (thick > 4) thick = 4;
    double dx = sx[1] - sx[0], dy = sy[1] - sy[0];
    double len = fmax(fabs(dx), fabs(dy));
    if (len > 4.0 * DC_RENDER_MAX_SIDE) return 0; /* far outside: not worth stepping */
    int steps = (int)ceil(len);
    int x0 = clip[0] > 0 ? clip[0] : 0, y0 = clip[1] > 0 ? clip[1] : 0;
    int x1 = clip[0] + clip[2] < im->w ? clip[0] + clip[2] : im->w;
    int y1 = clip[1] + clip[3] < im->h ? clip[1] + clip[3] : im->h;
    long n = 0;
    for (int i = 0; i <= steps; i++) {
        double f = steps ? (double)i / steps : 0;
        int px = (int)floor(sx[0] + f * dx), py = (int)floor(sy[0] + f * dy);
        double z = sz[0] + f * (sz[1] - sz[0]), tt = t[0] + f * (t[1] - t[0]);
        for (int oy = -(thick - 1) / 2; oy <= thick / 2; oy++)
            for (int ox = -(thick - 1) / 2; ox <= thick / 2; ox++) {
                int x = px + ox, y = py + oy;
                if (x < x0 || y < y0 || x >= x1 || y >= y1) continue;
                n += plot(im, x, y, z, tt, 1.0);
            }
    }
    return n;
}

static double norm_value(const dc_render_mesh *m, int32_t i, float vmin, float vmax)
{
    if (!m->value || !(vmax > vmin)) return 0;
    return ((double)m->value[i] - vmin) / ((double)vmax - vmin);
}

long dc_render_draw(dc_image *im, const int clip[4], const dc_camera *cam,
                    const dc_render_mesh *m, float vmin, float vmax, int line_px)
{
    const double L[3] = {0.3 / sqrt(1.25), 0.4 / sqrt(1.25), 1.0 / sqrt(1.25)};
    long n = 0;
    for (uint32_t f = 0; f < m->ntri; f++) {
        const int32_t *tri = m->tris + 3 * (size_t)f;
        double sx[3], sy[3], sz[3], t[3], v[3][3];
        int ok = 1;
        for (int k = 0; k < 3 && ok; k++) {
            if (tri[k] < 0 || (uint32_t)tri[k] >= m->nv) { ok = 0; break; }
            const float *p = m->pos + 3 * (size_t)tri[k];
            dc_camera_project(cam, p, &sx[k], &sy[k], &sz[k]);
            view_coords(cam->R, p, v[k]);
            t[k] = norm_value(m, tri[k], vmin, vmax);
        }
        if (!ok) continue;
        double e1[3], e2[3], nn[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = v[1][a] - v[0][a];
            e2[a] = v[2][a] - v[0][a];
        }
        nn[0] = e1[1] * e2[2] - e1[2] * e2[1];
        nn[1] = e1[2] * e2[0] - e1[0] * e2[2];
        nn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double nl = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
        double d = nl > 0 ? fabs(nn[0] * L[0] + nn[1] * L[1] + nn[2] * L[2]) / nl : 0;
        n += dc_raster_triangle(im, clip, sx, sy, sz, t, 0.25 + 0.75 * d);
    }
    for (uint32_t s = 0; s < m->nseg; s++) {
        const int32_t *seg = m->segs + 2 * (size_t)s;
        if (seg[0] < 0 || seg[1] < 0 || (uint32_t)seg[0] >= m->nv || (uint32_t)seg[1] >= m->nv)
            continue;
        double sx[2], sy[2], sz[2], t[2];
        for (int k = 0; k < 2; k++) {
            dc_camera_project(cam, m->pos + 3 * (size_t)seg[k], &sx[k], &sy[k], &sz[k]);
            t[k] = norm_value(m, seg[k], vmin, vmax);
        }
        n += dc_raster_line(im, clip, sx, sy, sz, t, line_px);
    }
    return n;
}

/* 5x7 glyphs: 7 rows, bit 4 the leftmost column. */
static const char FONT_CHARS[] = "0123456789.-+:|()/ abcdefghijklmnopqrstuvwxyz";
static const uint8_t FONT[][7] = {
    {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}, {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E},
    {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}, {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E},
    {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}, {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E},
    {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08},
    {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}, {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C},
    {0, 0, 0, 0, 0, 0x0C, 0x0C},                {0, 0, 0, 0x1F, 0, 0, 0},
    {0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0},       {0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0},
    {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}, {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02},
    {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}, {0x01, 0x01, 0x02, 0x04, 0x08, 0x10, 0x10},
    {0, 0, 0, 0, 0, 0, 0},
    {0, 0, 0x0E, 0x01, 0x0F, 0x11, 0x0F},       {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E},
    {0, 0, 0x0E, 0x10, 0x10, 0x11, 0x0E},       {0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F},
    {0, 0, 0x0E, 0x11, 0x1F, 0x10, 0x0E},       {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08},
    {0, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E},    {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11},
    {0x04, 0, 0x0C, 0x04, 0x04, 0x04, 0x0E},    {0x02, 0, 0x06, 0x02, 0x02, 0x12, 0x0C},
    {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}, {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E},
    {0, 0, 0x1A, 0x15, 0x15, 0x11, 0x11},       {0, 0, 0x16, 0x19, 0x11, 0x11, 0x11},
    {0, 0, 0x0E, 0x11, 0x11, 0x11, 0x0E},       {0, 0, 0x1E, 0x11, 0x1E, 0x10, 0x10},
    {0, 0, 0x0D, 0x13, 0x0F, 0x01, 0x01},       {0, 0, 0x16, 0x19, 0x10, 0x10, 0x10},
    {0, 0, 0x0E, 0x10, 0x0E, 0x01, 0x1E},       {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06},
    {0, 0, 0x11, 0x11, 0x11, 0x13, 0x0D},       {0, 0, 0x11, 0x11, 0x11, 0x0A, 0x04},
    {0, 0, 0x11, 0x11, 0x15, 0x15, 0x0A},       {0, 0, 0x11, 0x0A, 0x04, 0x0A, 0x11},
    {0, 0, 0x11, 0x11, 0x0F, 0x01, 0x0E},       {0, 0, 0x1F, 0x02, 0x04, 0x08, 0x1F},
};
static const uint8_t BOX[7] = {0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F};

_Static_assert(sizeof FONT / sizeof FONT[0] == sizeof FONT_CHARS - 1, "one glyph per char");

static const uint8_t *glyph(char c)
{
    const char *p = c ? strchr(FONT_CHARS, c) : NULL;
    return p ? FONT[p - FONT_CHARS] : NULL;
}

int dc_font_has(char c)
{
    return glyph(c) != NULL;
}

int dc_text_width(const char *text, int scale)
{
    return (int)strlen(text) * DC_FONT_ADVANCE * scale;
}

int dc_draw_text(dc_image *im, int x, int y, int scale, const char *text, const uint8_t c[3])
{
    if (scale < 1) scale = 1;
    if (scale > 8) scale = 8;
    int cx = x;
    for (const char *s = text; *s; s++, cx += DC_FONT_ADVANCE * scale) {
        const uint8_t *g = glyph(*s);
        if (!g) g = BOX;
        for (int r = 0; r < DC_FONT_H; r++)
            for (int col = 0; col < DC_FONT_W; col++)
                if (g[r] & (0x10 >> col))
                    dc_image_fill(im, cx + col * scale, y + r * scale, scale, scale, c);
    }
    return cx - x;
}

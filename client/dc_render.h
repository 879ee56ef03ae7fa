/* dc_render.h — a small software renderer for mesh previews (deformctl preview): an RGB image,
 * an orthographic camera for a few fixed views, a z-buffered triangle rasterizer with Lambert
 * shading tinted by a per-vertex scalar through a colour map, depth-tested lines (polylines),
 * a colour bar and a tiny built-in 5x7 bitmap font for labels. Pure computation: no file I/O
 * (the PNG writer lives in deformctl), no globals, thread-safe on distinct images.
 *
 * Conventions. Pixel (x, y) covers [x, x+1) x [y, y+1), y down; its centre is (x+0.5, y+0.5).
 * Screen coordinates are pixels with that orientation. View space: a view rotation R (rows:
 * screen right, screen up, towards the viewer) applied to mesh coordinates; depth = the third
 * view coordinate, larger is nearer. Colours are 8-bit sRGB triples, stored row-major RGB. */
#ifndef DF_CLIENT_DC_RENDER_H
#define DF_CLIENT_DC_RENDER_H

#include <stdint.h>

#include "core/common/df_error.h"

#define DC_RENDER_MAX_SIDE 8192 /* largest image width or height */

/* An RGB image with a depth buffer. rgb: w*h*3 bytes; depth: w*h floats (-INFINITY = empty). */
typedef struct dc_image {
    int w, h;
    uint8_t *rgb;
    float *depth;
} dc_image;

/* Allocates a w x h image (1..DC_RENDER_MAX_SIDE each) filled with `bg` and an empty depth
 * buffer. Errors: DF_EINVAL (size), DF_ENOMEM; *im zeroed then. Caller frees with
 * dc_image_free. */
int dc_image_init(dc_image *im, int w, int h, const uint8_t bg[3], df_error *err);

/* Frees the image's buffers (NULL-safe) and zeroes it. */
void dc_image_free(dc_image *im);

/* Empties the depth buffer (every pixel -INFINITY) so a new panel can be drawn. */
void dc_image_clear_depth(dc_image *im);

/* Sets pixel (x, y) to c; outside the image: nothing. */
void dc_image_put(dc_image *im, int x, int y, const uint8_t c[3]);

/* Fills the rectangle [x, x+w) x [y, y+h) (clipped to the image) with c. */
void dc_image_fill(dc_image *im, int x, int y, int w, int h, const uint8_t c[3]);

/* The fixed views. FRONT looks along -z (x right, y up); SIDE looks from +x (-z right, y up);
 * TOP looks down from +y (x right, -z up); ISO turns FRONT 45 degrees about y, then tilts it
 * down by atan(1/sqrt(2)) (35.26 degrees) about the screen's x axis: the (1, 1, 1) diagonal
 * points at the viewer. A 2D (planar, z = 0) mesh is drawn with FRONT: its flat top view. */
typedef enum dc_view { DC_VIEW_FRONT = 0, DC_VIEW_SIDE, DC_VIEW_TOP, DC_VIEW_ISO } dc_view;

/* Names "front", "side", "top", "iso" (index = dc_view), NULL-terminated, for option parsing. */
extern const char *const dc_view_names[];

/* Orthographic camera: screen x = cx + scale * (v0 - c0), screen y = cy - scale * (v1 - c1),
 * depth = v2, where v = R p (R: row-major 3x3 view rotation, rows right/up/towards viewer),
 * c the view-space point at the screen point (cx, cy), `scale` pixels per mesh unit (> 0). */
typedef struct dc_camera {
    double R[9];
    double c0, c1;
    double cx, cy;
    double scale;
} dc_camera;

/* Fills R with view `v`'s rotation (see dc_view). Unknown v: FRONT. */
void dc_view_rotation(dc_view v, double R[9]);

/* A camera for view `v` that fits every point of the `nsets` position arrays sets[k] (nv x 3
 * floats each, same nv) into the pixel rectangle (x, y, w, h) with `margin` pixels free on each
 * side: the view-space bounding box of all the points is centred in the rectangle and scaled
 * uniformly so its larger extent fills (w or h) - 2 margin. A box of zero extent (one point)
 * gets scale 1. Non-finite coordinates are skipped. Output in *cam. */
void dc_camera_fit(dc_camera *cam, dc_view v, const float *const *sets, int nsets, uint32_t nv,
                   int x, int y, int w, int h, int margin);

/* Projects mesh point p to screen (sx, sy) and depth sz with camera `cam`. */
void dc_camera_project(const dc_camera *cam, const float p[3], double *sx, double *sy,
                       double *sz);

/* Colour map: t in [0, 1] (clamped; NaN -> 0) to a viridis-like colour (dark purple at 0,
 * teal at 0.5, yellow at 1), piecewise linear through 5 stops. */
void dc_colormap(double t, uint8_t out[3]);

/* Rasterizes one screen-space triangle into `im`, clipped to the clip rectangle (clip[0..3] =
 * x, y, w, h) and the image: every pixel whose centre lies inside the triangle (or on an edge:
 * edge function >= 0 for either winding) and whose interpolated depth is greater than the depth
 * buffer's gets the colour colormap(t) * shade (t interpolated linearly from t[0..2],
 * shade in [0, 1] constant for the triangle) and its depth. A degenerate (zero area) or
 * non-finite triangle draws nothing. Returns the number of pixels written. */
long dc_raster_triangle(dc_image *im, const int clip[4], const double sx[3], const double sy[3],
                        const double sz[3], const double t[3], double shade);

/* Draws a depth-tested line from screen point 0 to 1 (DDA, one sample per pixel step along
 * the major axis, `thick` (1..4) pixels wide) coloured colormap(t interpolated), clipped like
 * dc_raster_triangle. Returns the number of pixels written. */
long dc_raster_line(dc_image *im, const int clip[4], const double sx[2], const double sy[2],
                    const double sz[2], const double t[2], int thick);

/* A mesh to draw: nv positions (x,y,z floats), a per-vertex scalar `value` (may be NULL: 0
 * everywhere), mapped to colour by (value - vmin) / (vmax - vmin) (0 when vmax <= vmin).
 * Triangles `tris` (ntri x 3 vertex indices) are shaded; segments `segs` (nseg x 2) are drawn
 * as lines. Indices outside 0..nv-1 are skipped. */
typedef struct dc_render_mesh {
    uint32_t nv;
    const float *pos;
    const float *value;
    uint32_t ntri;
    const int32_t *tris;
    uint32_t nseg;
    const int32_t *segs;
} dc_render_mesh;

/* Draws `m` with camera `cam` into the clip rectangle clip[] = (x, y, w, h) of `im` (the depth
 * buffer should be clear for the panel: dc_image_clear_depth). Each triangle is shaded
 * flat with Lambert lighting, two-sided: shade = 0.25 + 0.75 |n . l|, n its unit view-space
 * normal and l the unit light direction (0.3, 0.4, 1) in view space (from the viewer, a little
 * up and right); a triangle with n . l = 0 exactly (edge-on) has shade 0.25. Segments are lines
 * `line_px` pixels thick, unshaded. Returns the number of pixels written (all primitives). */
long dc_render_draw(dc_image *im, const int clip[4], const dc_camera *cam,
                    const dc_render_mesh *m, float vmin, float vmax, int line_px);

/* Font: glyph width and height in font pixels (each drawn as a `scale` x `scale` square), and
 * the advance of one character (glyph + 1 column). */
#define DC_FONT_W 5
#define DC_FONT_H 7
#define DC_FONT_ADVANCE 6

/* 1 when the built-in font has a glyph for c: digits, '.', '-', '+', ':', '|', '(', ')', '/',
 * ' ', and the lower-case letters a-z. */
int dc_font_has(char c);

/* Draws `text` with its top-left corner at (x, y), glyph pixels `scale` (1..8) image pixels,
 * in colour c (only set pixels are written; characters without a glyph are drawn as a box).
 * Returns the width drawn in pixels (strlen * DC_FONT_ADVANCE * scale). */
int dc_draw_text(dc_image *im, int x, int y, int scale, const char *text, const uint8_t c[3]);

/* Width in pixels that dc_draw_text would use for `text` at `scale`. */
int dc_text_width(const char *text, int scale);

#endif

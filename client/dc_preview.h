/* dc_preview.h — a preview picture of a session (deformctl preview): the rest shape and the
 * current shape side by side, both shaded by the displacement magnitude |current - rest| of each
 * vertex through the colour map of dc_render.h, with titles and a labelled colour bar. Pure
 * computation on arrays the caller fetched (df_client_get_mesh with DF_GET_MESH_REST); no I/O.
 *
 * Layout of a w x h picture (s = 2 when h >= 400, else 1: the font's pixel size):
 *   a title strip of 7 s + 8 pixels at the top ("rest" over the left panel, "current" over the
 *   right one); two panels of equal size (w / 2 - 1) x ph below it, the left at x 0, the right at
 *   x w / 2 (a 1-pixel separator column between them); a colour-bar strip at the bottom (the bar
 *   spans x from w / 8 to 7 w / 8, colormap(0) at its left end, colormap(1) at its right end;
 *   the minimum displacement is written under its left end, the maximum under its right end,
 *   "displacement" in the middle). Both panels use the same camera (dc_camera_fit over the rest
 *   and current positions together, margin 8 s), so they differ only where the shape or the
 *   colours do; with current == rest both panels hold the same pixels. */
#ifndef DF_CLIENT_DC_PREVIEW_H
#define DF_CLIENT_DC_PREVIEW_H

#include <stdint.h>

#include "client/dc_render.h"
#include "core/common/df_error.h"

#define DC_PREVIEW_MIN_SIDE 64 /* smallest width and height accepted */

/* The mesh: kind 1 polyline (elements are segments), 2 triangle (elements are triangles), 3 tet
 * (the nf boundary triangles `faces` are drawn; without faces every tet face is drawn); planar
 * 1 for a 2D session (drawn in the FRONT view, its flat top view, whatever view is asked).
 * pos and rest: nv x 3 floats (current and rest positions). */
typedef struct dc_preview_mesh {
    uint8_t kind;
    int planar;
    uint32_t nv;
    const float *pos;
    const float *rest;
    uint32_t ne;
    const int32_t *elements;
    uint32_t nf;
    const int32_t *faces;
} dc_preview_mesh;

/* What was drawn: panel rectangles (x, y, w, h) of rest [0] and current [1], the colour bar's
 * rectangle, the displacement range (mesh units), the view used and the primitive counts. */
typedef struct dc_preview_info {
    int panel[2][4];
    int bar[4];
    float vmin, vmax;
    dc_view view;
    uint32_t ntri, nseg;
} dc_preview_info;

/* Renders `m` in view `view` into a new w x h image *out (DC_PREVIEW_MIN_SIDE..
 * DC_RENDER_MAX_SIDE per side) and fills *info (may be NULL). Errors: DF_EINVAL (size, kind not
 * 1..3, nv 0, NULL arrays), DF_ENOMEM; *out is then empty. The caller frees *out with
 * dc_image_free. */
int dc_preview_render(const dc_preview_mesh *m, dc_view view, int w, int h, dc_image *out,
                      dc_preview_info *info, df_error *err);

#endif

/* Unit tests for the preview renderer (client/dc_render, client/dc_preview) and deformctl's PNG
 * writer (client/deformctl/png_out): expected pixels are computed here from the geometry with an
 * independent point-in-triangle test (barycentric coordinates by Cramer's rule), and PNG files
 * are read back through libpng. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/dc_preview.h"
#include "client/dc_render.h"
#include "client/deformctl/png_out.h"

static const uint8_t BLACK[3] = {0, 0, 0};

/* 1 when the pixel centre (px, py) is inside triangle (ax..cy); *margin receives the smallest
 * barycentric coordinate (how far inside; negative outside). */
static int inside(double ax, double ay, double bx, double by, double cx, double cy, double px,
                  double py, double *margin)
{
    double d = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
    double u = ((px - ax) * (cy - ay) - (cx - ax) * (py - ay)) / d;
    double v = ((bx - ax) * (py - ay) - (px - ax) * (by - ay)) / d;
    double w = 1 - u - v;
    *margin = fmin(u, fmin(v, w));
    return u >= 0 && v >= 0 && w >= 0;
}

static int is_bg(const dc_image *im, int x, int y)
{
    const uint8_t *p = im->rgb + 3 * ((size_t)y * (size_t)im->w + (size_t)x);
    return p[0] == 0 && p[1] == 0 && p[2] == 0;
}

static void test_triangle_covers_exactly_its_pixel_centres(void **state)
{
    (void)state;
    dc_image im;
    df_error e;
    assert_int_equal(dc_image_init(&im, 40, 30, BLACK, &e), DF_OK);
    int clip[4] = {0, 0, 40, 30};
    const double sx[3] = {3.3, 31.2, 12.7}, sy[3] = {4.7, 8.1, 25.4}, sz[3] = {1, 1, 1};
    const double t[3] = {0.5, 0.5, 0.5};
    long n = dc_raster_triangle(&im, clip, sx, sy, sz, t, 1.0);
    uint8_t teal[3];
    dc_colormap(0.5, teal);
    assert_int_equal(teal[0], 33); /* the contract's teal stop at 0.5 */
    assert_int_equal(teal[1], 145);
    assert_int_equal(teal[2], 140);
    long expect = 0;
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 40; x++) {
            double m;
            int in = inside(sx[0], sy[0], sx[1], sy[1], sx[2], sy[2], x + 0.5, y + 0.5, &m);
            assert_true(fabs(m) > 1e-6); /* no centre on an edge: the test is unambiguous */
            expect += in;
            assert_int_equal(!is_bg(&im, x, y), in);
            if (in)
                assert_memory_equal(im.rgb + 3 * (y * 40 + x), teal, 3);
        }
    assert_int_equal(n, expect);
    assert_true(expect > 150); /* area ~ 260 px^2 */
    /* The same triangle wound the other way covers the same pixels; behind it (lower depth)
     * nothing is drawn, in front of it everything is. */
    const double rx[3] = {sx[2], sx[1], sx[0]}, ry[3] = {sy[2], sy[1], sy[0]};
    const double back[3] = {0, 0, 0}, front[3] = {2, 2, 2};
    assert_int_equal(dc_raster_triangle(&im, clip, rx, ry, back, t, 1.0), 0);
    assert_int_equal(dc_raster_triangle(&im, clip, rx, ry, front, t, 0.5), expect);
    /* clipped to the left half: only the centres with x < 20 */
    dc_image_clear_depth(&im);
    int half[4] = {0, 0, 20, 30};
    long left = 0;
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 20; x++) {
            double m;
            left += inside(sx[0], sy[0], sx[1], sy[1], sx[2], sy[2], x + 0.5, y + 0.5, &m);
        }
    assert_int_equal(dc_raster_triangle(&im, half, sx, sy, sz, t, 1.0), left);
    dc_image_free(&im);
}

static void test_mesh_through_camera_lands_where_the_geometry_says(void **state)
{
    (void)state;
    dc_image im;
    df_error e;
    assert_int_equal(dc_image_init(&im, 64, 48, BLACK, &e), DF_OK);
    const float P[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const int32_t T[3] = {0, 1, 2};
    dc_camera cam;
    dc_view_rotation(DC_VIEW_FRONT, cam.R);
    cam.c0 = cam.c1 = 0;
    cam.cx = 5.3;
    cam.cy = 40.2;
    cam.scale = 30.1;
    dc_render_mesh m = {3, P, NULL, 1, T, 0, NULL};
    int clip[4] = {0, 0, 64, 48};
    long n = dc_render_draw(&im, clip, &cam, &m, 0, 1, 1);
    /* expected screen triangle: x = cx + scale px, y = cy - scale py */
    double ax = 5.3, ay = 40.2, bx = 5.3 + 30.1, by = 40.2, cx = 5.3, cy = 40.2 - 30.1;
    /* Lambert: n = (0,0,1), l = (0.3,0.4,1)/|.|: shade 0.25 + 0.75 / sqrt(1.25) on colormap(0)
     * = (68, 1, 84), the contract's dark purple */
    double shade = 0.25 + 0.75 / sqrt(1.25);
    uint8_t want[3] = {(uint8_t)lround(68 * shade), (uint8_t)lround(1 * shade),
                       (uint8_t)lround(84 * shade)};
    long expect = 0;
    for (int y = 0; y < 48; y++)
        for (int x = 0; x < 64; x++) {
            double mg;
            int in = inside(ax, ay, bx, by, cx, cy, x + 0.5, y + 0.5, &mg);
            assert_true(fabs(mg) > 1e-6);
            expect += in;
            assert_int_equal(!is_bg(&im, x, y), in);
            if (in)
                assert_memory_equal(im.rgb + 3 * (y * 64 + x), want, 3);
        }
    assert_int_equal(n, expect);
    assert_true(expect > 300);
    dc_image_free(&im);
}

static long draw_count(dc_view v, const float *P, const int32_t *T, uint32_t ntri, dc_image *im)
{
    uint8_t bg[3] = {0, 0, 0};
    df_error e;
    assert_int_equal(dc_image_init(im, 80, 80, bg, &e), DF_OK);
    dc_camera cam;
    const float *sets[1] = {P};
    dc_camera_fit(&cam, v, sets, 1, 4, 0, 0, 80, 80, 4);
    dc_render_mesh m = {4, P, NULL, ntri, T, 0, NULL};
    int clip[4] = {0, 0, 80, 80};
    return dc_render_draw(im, clip, &cam, &m, 0, 1, 1);
}

static void test_views_differ(void **state)
{
    (void)state;
    /* A triangle in the z = 0 plane is seen face-on from the front and edge-on from the side and
     * the top; one in the y = 0 plane is face-on only from the top. */
    const float XY[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0};
    const float XZ[12] = {0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0};
    const int32_t T[3] = {0, 1, 2};
    dc_image im;
    assert_true(draw_count(DC_VIEW_FRONT, XY, T, 1, &im) > 1000);
    dc_image_free(&im);
    assert_int_equal(draw_count(DC_VIEW_SIDE, XY, T, 1, &im), 0);
    dc_image_free(&im);
    assert_int_equal(draw_count(DC_VIEW_TOP, XY, T, 1, &im), 0);
    dc_image_free(&im);
    assert_true(draw_count(DC_VIEW_ISO, XY, T, 1, &im) > 100);
    dc_image_free(&im);
    assert_true(draw_count(DC_VIEW_TOP, XZ, T, 1, &im) > 1000);
    dc_image_free(&im);
    assert_int_equal(draw_count(DC_VIEW_FRONT, XZ, T, 1, &im), 0);
    dc_image_free(&im);
    /* Orientation: FRONT +x right, +y up; SIDE +z left; TOP +z down; ISO (1,1,1) at the viewer. */
    dc_camera c;
    c.c0 = c.c1 = c.cx = c.cy = 0;
    c.scale = 1;
    double x, y, z;
    const float px[3] = {1, 0, 0}, py[3] = {0, 1, 0}, pz[3] = {0, 0, 1}, d[3] = {1, 1, 1};
    dc_view_rotation(DC_VIEW_FRONT, c.R);
    dc_camera_project(&c, px, &x, &y, &z);
    assert_true(x > 0.99 && fabs(y) < 1e-12);
    dc_camera_project(&c, py, &x, &y, &z);
    assert_true(y < -0.99); /* up on screen: smaller pixel row */
    dc_view_rotation(DC_VIEW_SIDE, c.R);
    dc_camera_project(&c, pz, &x, &y, &z);
    assert_true(x < -0.99);
    dc_view_rotation(DC_VIEW_TOP, c.R);
    dc_camera_project(&c, pz, &x, &y, &z);
    assert_true(y > 0.99);
    dc_view_rotation(DC_VIEW_ISO, c.R);
    dc_camera_project(&c, d, &x, &y, &z);
    assert_true(fabs(x) < 1e-12 && fabs(y) < 1e-12 && fabs(z - sqrt(3.0)) < 1e-12);
    /* An asymmetric solid (a tetrahedron's 4 faces) gives four different pictures. */
    const float TET[12] = {0, 0, 0, 2, 0, 0, 0, 1, 0, 0.3f, 0.2f, 1.5f};
    const int32_t F[12] = {0, 1, 2, 0, 1, 3, 0, 2, 3, 1, 2, 3};
    dc_image v[4];
    for (int k = 0; k < 4; k++)
        assert_true(draw_count((dc_view)k, TET, F, 4, &v[k]) > 500);
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++)
            assert_true(memcmp(v[a].rgb, v[b].rgb, 80 * 80 * 3) != 0);
    for (int k = 0; k < 4; k++)
        dc_image_free(&v[k]);
}

static void test_line_and_font(void **state)
{
    (void)state;
    dc_image im;
    df_error e;
    assert_int_equal(dc_image_init(&im, 50, 20, BLACK, &e), DF_OK);
    int clip[4] = {0, 0, 50, 20};
    const double sx[2] = {2.5, 40.5}, sy[2] = {10.5, 10.5}, sz[2] = {0, 0}, t[2] = {0, 1};
    assert_int_equal(dc_raster_line(&im, clip, sx, sy, sz, t, 1), 39); /* x 2..40, row 10 */
    for (int x = 0; x < 50; x++)
        assert_int_equal(!is_bg(&im, x, 10), x >= 2 && x <= 40);
    uint8_t hi[3];
    dc_colormap(1, hi);
    assert_memory_equal(im.rgb + 3 * (10 * 50 + 40), hi, 3);
    dc_image_free(&im);
    /* glyph "1" of the 5x7 font (rows .#..., ##..., four .#..., ###..): 10 set cells; at
     * scale 2 each is 2x2 pixels */
    assert_int_equal(dc_image_init(&im, 30, 20, BLACK, &e), DF_OK);
    const uint8_t W[3] = {255, 255, 255};
    assert_int_equal(dc_draw_text(&im, 1, 1, 2, "1", W), DC_FONT_ADVANCE * 2);
    int set = 0;
    for (int y = 0; y < 20; y++)
        for (int x = 0; x < 30; x++)
            set += !is_bg(&im, x, y);
    assert_int_equal(set, 10 * 4);
    assert_true(dc_font_has('7') && dc_font_has('e') && dc_font_has('.') && !dc_font_has('#'));
    dc_image_free(&im);
}

static void test_png_round_trip(void **state)
{
    (void)state;
    dc_image im;
    df_error e;
    assert_int_equal(dc_image_init(&im, 37, 23, BLACK, &e), DF_OK);
    for (int y = 0; y < 23; y++)
        for (int x = 0; x < 37; x++) {
            uint8_t c[3] = {(uint8_t)(7 * x), (uint8_t)(11 * y), (uint8_t)(x ^ y)};
            dc_image_put(&im, x, y, c);
        }
    char path[] = "/tmp/df_test_png_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    assert_int_equal(ctl_png_write(path, im.w, im.h, im.rgb, &e), DF_OK);
    png_image r;
    memset(&r, 0, sizeof r);
    r.version = PNG_IMAGE_VERSION;
    assert_true(png_image_begin_read_from_file(&r, path));
    assert_int_equal(r.width, 37);
    assert_int_equal(r.height, 23);
    r.format = PNG_FORMAT_RGB;
    uint8_t *buf = malloc(PNG_IMAGE_SIZE(r));
    assert_non_null(buf);
    assert_true(png_image_finish_read(&r, NULL, buf, 0, NULL));
    assert_memory_equal(buf, im.rgb, 37 * 23 * 3);
    assert_int_equal(buf[3 * (5 * 37 + 9) + 0], 63); /* pixel (9, 5) = (7*9, 11*5, 9^5) */
    assert_int_equal(buf[3 * (5 * 37 + 9) + 1], 55);
    assert_int_equal(buf[3 * (5 * 37 + 9) + 2], 12);
    free(buf);
    unlink(path);
    /* an unwritable path: DF_EIO naming it, and no file (nor temporary) left */
    assert_int_equal(ctl_png_write("/nonexistent-dir/x.png", im.w, im.h, im.rgb, &e), DF_EIO);
    assert_non_null(strstr(e.msg, "/nonexistent-dir/x.png"));
    assert_int_equal(ctl_png_write(path, 0, 5, im.rgb, &e), DF_EINVAL);
    assert_int_not_equal(access(path, F_OK), 0);
    dc_image_free(&im);
}

/* The left and right panels of a preview hold the same pixels. */
static int panels_equal(const dc_image *im, const dc_preview_info *in)
{
    for (int y = 0; y < in->panel[0][3]; y++)
        if (memcmp(im->rgb + 3 * ((size_t)(in->panel[0][1] + y) * im->w + in->panel[0][0]),
                   im->rgb + 3 * ((size_t)(in->panel[1][1] + y) * im->w + in->panel[1][0]),
                   3 * (size_t)in->panel[0][2]) != 0)
            return 0;
    return 1;
}

static void test_preview_side_by_side(void **state)
{
    (void)state;
    float rest[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0.2f};
    float cur[12];
    memcpy(cur, rest, sizeof cur);
    const int32_t T[6] = {0, 1, 2, 1, 3, 2};
    dc_preview_mesh m = {2, 0, 4, cur, rest, 2, T, 0, NULL};
    dc_image im;
    dc_preview_info in;
    df_error e;
    assert_int_equal(dc_preview_render(&m, DC_VIEW_ISO, 200, 120, &im, &in, &e), DF_OK);
    assert_int_equal(in.panel[0][2], in.panel[1][2]);
    assert_int_equal(in.panel[1][0], 100);
    assert_true(panels_equal(&im, &in)); /* nothing moved: the same picture twice */
    assert_true(in.vmin == 0 && in.vmax == 0);
    dc_image_free(&im);
    cur[3 * 3 + 2] += 0.5f; /* vertex 3 up by 0.5 */
    assert_int_equal(dc_preview_render(&m, DC_VIEW_ISO, 200, 120, &im, &in, &e), DF_OK);
    assert_false(panels_equal(&im, &in));
    assert_true(in.vmin == 0);
    assert_true(fabsf(in.vmax - 0.5f) < 1e-6f);
    assert_int_equal(in.ntri, 2);
    uint8_t lo[3], hi[3];
    dc_colormap(0, lo);
    dc_colormap(1, hi);
    int by = in.bar[1] + in.bar[3] / 2;
    assert_memory_equal(im.rgb + 3 * ((size_t)by * 200 + in.bar[0]), lo, 3);
    assert_memory_equal(im.rgb + 3 * ((size_t)by * 200 + in.bar[0] + in.bar[2] - 1), hi, 3);
    dc_image_free(&im);
    /* a 2D session is drawn flat whatever the view */
    m.planar = 1;
    assert_int_equal(dc_preview_render(&m, DC_VIEW_SIDE, 200, 120, &im, &in, &e), DF_OK);
    assert_int_equal(in.view, DC_VIEW_FRONT);
    dc_image_free(&im);
    /* polylines are lines; bad sizes and kinds are refused */
    const int32_t S[4] = {0, 1, 1, 3};
    dc_preview_mesh pl = {1, 0, 4, cur, rest, 2, S, 0, NULL};
    assert_int_equal(dc_preview_render(&pl, DC_VIEW_FRONT, 100, 80, &im, &in, &e), DF_OK);
    assert_int_equal(in.nseg, 2);
    assert_int_equal(in.ntri, 0);
    dc_image_free(&im);
    assert_int_equal(dc_preview_render(&m, DC_VIEW_FRONT, 63, 80, &im, &in, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "63x80"));
    assert_null(im.rgb);
    m.kind = 7;
    assert_int_equal(dc_preview_render(&m, DC_VIEW_FRONT, 100, 80, &im, &in, &e), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_covers_exactly_its_pixel_centres),
        cmocka_unit_test(test_mesh_through_camera_lands_where_the_geometry_says),
        cmocka_unit_test(test_views_differ),
        cmocka_unit_test(test_line_and_font),
        cmocka_unit_test(test_png_round_trip),
        cmocka_unit_test(test_preview_side_by_side),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

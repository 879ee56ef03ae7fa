/* kelvinlet_test_brush.h — the test brush shared by the SIMD and arithmetic-version tests
 * (header-only). */
#ifndef DF_TESTS_KELVINLET_TEST_BRUSH_H
#define DF_TESTS_KELVINLET_TEST_BRUSH_H

#include <string.h>

#include "core/kelvinlet/kelvinlet.h"

/* A brush of `type` (df_kelvinlet_type), `dim` 2 or 3, falloff `order`, radius `ratio`, `nu` and
 * `radius`, centred near the origin, with every load non-zero: tip, omega, s and a general
 * gradient (in 2D its upper-left 2x2, traceless for pinch; z of centre and tip 0). */
static inline df_kelvinlet_brush tk_brush(int type, int dim, int order, double ratio, double nu,
                                          double radius)
{
    static const double G[9] = {0.1, 0.02, 0, 0.02, -0.05, 0.01, 0, 0.01, -0.05};
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.type = (df_kelvinlet_type)type;
    b.dim = dim;
    b.order = order;
    b.ratio = ratio;
    b.radius = radius;
    b.nu = nu;
    b.centre[0] = 0.1;
    b.centre[1] = -0.05;
    b.centre[2] = dim == 3 ? 0.02 : 0.0;
    b.tip[0] = 0.01;
    b.tip[1] = -0.004;
    b.tip[2] = dim == 3 ? 0.02 : 0.0;
    b.omega[0] = dim == 3 ? 0.1 : 0.0;
    b.omega[2] = 0.3;
    b.s = 0.1;
    memcpy(b.grad, G, sizeof G);
    if (dim == 2) {
        b.grad[2] = b.grad[5] = b.grad[6] = b.grad[7] = b.grad[8] = 0.0;
        b.grad[4] = -b.grad[0];
    }
    return b;
}

#endif

/* Parity of the daemon with the core engines (real $BUILD/bin/deformd, skipped when not built):
 *  - every brush kind applied through the daemon (begin with a zero load, one update, end, the
 *    way deformctl strokes) equals core/kelvinlet run on the float32 positions the way
 *    server/handlers/h_brush.c runs it (df_kelvinlet_prepare or the pinned solver, then
 *    df_kelvinlet_displacements at the stroke-start floats; positions = base + the float32 motion),
 *    to 1e-6 absolute on unit-size meshes, and to the double reference df_kelvinlet_apply_ref to
 *    PARITY_REF_TOL;
 *  - handle moves through the daemon equal df_admm_create / set_targets / run on the same parsed
 *    mesh with the same parameters and iteration count (tol 0: exactly max_iters iterations),
 *    including a warm-started second move.
 * Meshes are generated with dyadic coordinates (exact in float32 and double) so the daemon's
 * double base and the floats it returns hold the same numbers. Any mismatch prints the case, the
 * worst vertex and both values, then fails. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "client/deformclient.h"
#include "tests/unit/client/live_daemon.h"
#include "tests/unit/unit_skip.h"
#include "core/admm/admm.h"
#include "core/kelvinlet/kelvinlet.h"
#include "core/mesh/mesh_io.h"

#define PARITY_TOL 1e-6      /* daemon vs core on the float path, absolute, unit-size meshes */
#define PARITY_REF_TOL 1e-6  /* daemon vs the double reference integrator (measured 7e-8) */
#define PARITY_MIN_MOTION 1e-3 /* every case must move some coordinate at least this much */
#define PARITY_GRID 33       /* grid vertices per side (coordinates k / 32: dyadic) */
#define PARITY_ADMM_ITERS 30 /* ADMM iterations per move */

typedef live_daemon daemon_proc;

/* Starts the daemon and connects, or skips the test when deformd is not built. */
static df_client *setup(daemon_proc *d)
{
    char exe[PATH_MAX];
    if (live_daemon_path(exe, sizeof exe) != 0)
        unit_skip("deformd is not built next to this test (make -j2 builds it)");
    memset(d, 0, sizeof *d);
    assert_int_equal(live_daemon_start(d, exe, "parity"), 0);
    df_client *c = NULL;
    df_error e;
    assert_int_equal(df_client_connect_unix(d->sock, "parity", &c, &e), DF_OK);
    return c;
}

/* PARITY_GRID^2 grid over [0,1]^2 as OFF text; z = (i % 3) / 16 - (j % 2) / 32 (curved, dyadic)
 * or 0 when planar. */
static char *grid_off(int planar, size_t *len)
{
    int n = PARITY_GRID;
    size_t cap = (size_t)n * n * 96 + 64;
    char *t = malloc(cap);
    size_t o = (size_t)snprintf(t, cap, "OFF\n%d %d 0\n", n * n, 2 * (n - 1) * (n - 1));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            o += (size_t)snprintf(t + o, cap - o, "%.17g %.17g %.17g\n", i / (n - 1.0),
                                  j / (n - 1.0), planar ? 0.0 : (i % 3) / 16.0 - (j % 2) / 32.0);
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            int a = j * n + i;
            o += (size_t)snprintf(t + o, cap - o, "3 %d %d %d\n3 %d %d %d\n", a, a + 1, a + n + 1,
                                  a, a + n + 1, a + n);
        }
    *len = o;
    return t;
}

/* One brush case: the wire messages and the engine description built independently by hand. */
typedef struct bcase {
    const char *name;
    df_msg_brush b;          /* begin (zero load) */
    df_msg_brush_update u;   /* the load */
    df_kelvinlet_brush k;    /* what the daemon must run: loads already times strength */
    int planar;
    double pins[9];
    int npins, pin_flags;    /* DF_KELVINLET_PIN_* */
} bcase;

static void wire_defaults(bcase *c, const char *name, uint8_t type, double nu)
{
    memset(c, 0, sizeof *c);
    c->name = name;
    df_msg_brush_defaults(&c->b);
    c->b.type = type;
    c->b.radius = 0.3;
    c->b.nu = nu;
    c->b.center[0] = 0.5;
    c->b.center[1] = 0.5;
    c->b.center[2] = 0.0625;
    df_kelvinlet_brush_defaults(&c->k);
    c->k.radius = 0.3;
    c->k.nu = nu;
    memcpy(c->k.centre, c->b.center, sizeof c->k.centre);
}

static void set_grab(bcase *c, double x, double y, double z)
{
    c->u.move[0] = x, c->u.move[1] = y, c->u.move[2] = z;
    c->k.type = DF_KELVINLET_GRAB;
    c->k.tip[0] = x, c->k.tip[1] = y, c->k.tip[2] = z;
}

/* Fills cases[]; returns their count. */
static int make_cases(bcase *cs)
{
    int n = 0;
    static const char *grab_names[6] = {"grab 1-scale euler", "grab 1-scale rk4",
                                        "grab 2-scale euler", "grab 2-scale rk4",
                                        "grab 3-scale euler", "grab 3-scale rk4"};
    for (int g = 0; g < 6; g++) {
        bcase *c = &cs[n++];
        wire_defaults(c, grab_names[g], DF_BRUSH_GRAB, 0.4);
        set_grab(c, 0.06, 0.03, -0.04);
        c->b.falloff = (uint8_t)(1 + g / 2);
        c->k.order = 1 + g / 2;
        c->b.ratio = c->k.ratio = 1.5;
        if (g % 2) {
            c->b.integrator = DF_INTEG_RK4;
            c->k.integrator = DF_KELVINLET_RK4;
            c->b.steps = 5;
            c->k.steps = 5;
        }
    }
    bcase *c = &cs[n++];
    wire_defaults(c, "twist", DF_BRUSH_TWIST, 0.45);
    c->u.twist[2] = c->k.omega[2] = 0.6;
    c->u.twist[0] = c->k.omega[0] = 0.1;
    c->k.type = DF_KELVINLET_TWIST;
    c = &cs[n++];
    wire_defaults(c, "scale", DF_BRUSH_SCALE, 0.3);
    c->u.scale = c->k.s = 0.25;
    c->k.type = DF_KELVINLET_SCALE;
    c = &cs[n++];
    wire_defaults(c, "pinch", DF_BRUSH_PINCH, 0.5);
    static const double pinch[9] = {0.2, 0.05, 0, 0.05, -0.15, 0.02, 0, 0.02, -0.05};
    memcpy(c->u.matrix, pinch, sizeof pinch);
    memcpy(c->k.grad, pinch, sizeof pinch);
    c->k.type = DF_KELVINLET_PINCH;
    c = &cs[n++];
    wire_defaults(c, "affine", DF_BRUSH_AFFINE, 0.3);
    static const double aff[9] = {0.1, 0.2, 0, 0, 0.1, 0, 0.05, 0, 0.3};
    memcpy(c->u.matrix, aff, sizeof aff);
    memcpy(c->k.grad, aff, sizeof aff);
    c->k.type = DF_KELVINLET_AFFINE;
    c = &cs[n++];
    wire_defaults(c, "moving grab rk4 x8, strength 2", DF_BRUSH_GRAB, 0.45);
    set_grab(c, 0.1, -0.05, 0.02);
    c->b.moving = 1;
    c->k.moving = 1;
    c->b.integrator = DF_INTEG_RK4;
    c->k.integrator = DF_KELVINLET_RK4;
    c->b.steps = 8;
    c->k.steps = 8;
    c->b.strength = 2;
    for (int i = 0; i < 3; i++)
        c->k.tip[i] *= 2;
    c = &cs[n++];
    wire_defaults(c, "mirrored grab", DF_BRUSH_GRAB, 0.45);
    set_grab(c, 0.05, 0.02, 0.04);
    c->b.center[0] = c->k.centre[0] = 0.3;
    c->b.has_mirror = 1;
    c->k.mirror = 1;
    c->b.mirror_point[0] = c->k.mirror_point[0] = 0.5;
    c->b.mirror_normal[0] = c->k.mirror_normal[0] = 1;
    c = &cs[n++];
    wire_defaults(c, "2D grab, planar grid", DF_BRUSH_GRAB, 0.45);
    set_grab(c, 0.05, -0.03, 0);
    c->b.center[2] = c->k.centre[2] = 0;
    c->b.dim = 2;
    c->k.dim = 2;
    c->planar = 1;
    c = &cs[n++];
    wire_defaults(c, "grab nu = -inf", DF_BRUSH_GRAB, -INFINITY);
    set_grab(c, 0, 0.05, 0.05);
    static const double pins[9] = {0.75, 0.5, 0.0625, 0.5, 0.8125, 0, 0.25, 0.25, 0.125};
    c = &cs[n++];
    wire_defaults(c, "3 pinned points (displacement)", DF_BRUSH_GRAB, 0.45);
    set_grab(c, 0.04, 0.04, 0.08);
    memcpy(c->pins, pins, sizeof pins);
    c->npins = 3;
    c->pin_flags = DF_KELVINLET_PIN_DISPLACEMENT;
    c->b.pin_flags = DF_PIN_DISPLACEMENT;
    c = &cs[n++];
    wire_defaults(c, "3 pinned points (both), twist", DF_BRUSH_TWIST, 0.4);
    c->u.twist[2] = c->k.omega[2] = 0.5;
    c->k.type = DF_KELVINLET_TWIST;
    memcpy(c->pins, pins, sizeof pins);
    c->npins = 3;
    c->pin_flags = DF_KELVINLET_PIN_DISPLACEMENT | DF_KELVINLET_PIN_GRADIENT;
    c->b.pin_flags = DF_PIN_DISPLACEMENT | DF_PIN_GRADIENT;
    return n;
}

/* The engine's field for case `c` (prepare, or the pinned solver with the brush's kernel). */
static void engine_field(const bcase *c, df_kelvinlet_prepared *prep,
                         df_kelvinlet_constraints **cs)
{
    df_error e;
    *cs = NULL;
    if (!c->npins) {
        assert_int_equal(df_kelvinlet_prepare(&c->k, prep, &e), DF_OK);
        return;
    }
    df_kelvinlet_pins p = {.n = (size_t)c->npins, .points = c->pins, .flags = c->pin_flags,
                           .radius = c->k.radius, .ratio = c->k.ratio, .nu = c->k.nu,
                           .order = c->k.order};
    assert_int_equal(df_kelvinlet_constraints_create(&p, cs, &e), DF_OK);
    assert_int_equal(df_kelvinlet_constraints_solve(*cs, &c->k, prep, &e), DF_OK);
}

/* Runs one case through the daemon and the core; returns the worst float-path difference. */
static double run_case(df_client *cl, const bcase *c, double *worst_ref)
{
    df_error e;
    size_t len;
    char *off = grid_off(c->planar, &len);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(cl, c->name, DF_FMT_OFF, off, len, 0, &info, &e),
                     DF_OK);
    free(off);
    uint64_t sid = info.session_id;
    df_client_mesh m0, m1;
    assert_int_equal(df_client_get_mesh(cl, sid, 0, &m0, &e), DF_OK);
    df_msg_brush b = c->b;
    df_msg_brush_update u = c->u;
    b.session_id = u.session_id = sid;
    b.n_pinned = (uint32_t)c->npins;
    b.pinned = c->npins ? (double *)c->pins : NULL;
    df_msg_ack ack;
    if (df_client_brush_begin(cl, &b, NULL, &e) || df_client_brush_update(cl, &u, NULL, &e) ||
        df_client_brush_end(cl, sid, &ack, &e))
        fail_msg("%s: the daemon refused the stroke: %s", c->name, e.msg);
    assert_int_equal(df_client_get_mesh(cl, sid, 0, &m1, &e), DF_OK);
    assert_int_equal(m1.version, ack.version);
    size_t n = m0.nv, n3 = 3 * n;
    df_kelvinlet_prepared prep;
    df_kelvinlet_constraints *cs;
    engine_field(c, &prep, &cs);
    float *disp = malloc(n3 * sizeof *disp);
    double *ref = malloc(n3 * sizeof *ref);
    assert_int_equal(df_kelvinlet_displacements(&prep, m0.positions, n, disp, &e), DF_OK);
    for (size_t i = 0; i < n3; i++)
        ref[i] = m0.positions[i];
    assert_int_equal(df_kelvinlet_apply_ref(&prep, ref, n, &e), DF_OK);
    double worst = 0, motion = 0;
    size_t at = 0;
    *worst_ref = 0;
    for (size_t i = 0; i < n3; i++) {
        float x0 = m0.positions[i];
        float mv = (x0 + disp[i]) - x0; /* the daemon's float32 motion of the stroke */
        float want = (float)((double)x0 + (double)mv);
        double d = fabs((double)m1.positions[i] - (double)want);
        if (d > worst || isnan(d)) {
            worst = isnan(d) ? INFINITY : d;
            at = i;
        }
        double dr = fabs((double)m1.positions[i] - ref[i]);
        *worst_ref = dr > *worst_ref || isnan(dr) ? (isnan(dr) ? INFINITY : dr) : *worst_ref;
        motion = fmax(motion, fabs((double)m1.positions[i] - (double)x0));
    }
    if (!(worst <= PARITY_TOL) || !(*worst_ref <= PARITY_REF_TOL) || !(motion > PARITY_MIN_MOTION))
        fail_msg("brush parity FAILED for '%s': max |daemon - core float path| = %.3g (tol %g) at "
                 "vertex %zu coord %zu: daemon %.9g, core %.9g; max |daemon - double ref| = "
                 "%.3g (tol %g); largest motion %.3g (must exceed %g)", c->name, worst,
                 PARITY_TOL, at / 3, at % 3, (double)m1.positions[at],
                 (double)((float)((double)m0.positions[at] +
                                  (double)((m0.positions[at] + disp[at]) - m0.positions[at]))),
                 *worst_ref, PARITY_REF_TOL, motion, PARITY_MIN_MOTION);
    if (c->planar)
        for (size_t i = 0; i < n; i++)
            assert_true(m1.positions[3 * i + 2] == 0.0f);
    printf("  %-34s max|daemon-core| %.2g  max|daemon-ref| %.2g  motion %.3f\n", c->name, worst,
           *worst_ref, motion);
    free(disp);
    free(ref);
    df_kelvinlet_prepared_free(&prep);
    df_kelvinlet_constraints_free(cs);
    df_client_mesh_free(&m0);
    df_client_mesh_free(&m1);
    assert_int_equal(df_client_close_session(cl, sid, NULL, &e), DF_OK);
    return worst;
}

static void test_every_brush_matches_the_core(void **state)
{
    (void)state;
    daemon_proc d;
    df_client *cl = setup(&d);
    bcase cases[24];
    int n = make_cases(cases);
    assert_true(n >= 16);
    double worst = 0, worst_ref = 0;
    for (int i = 0; i < n; i++) {
        double r;
        worst = fmax(worst, run_case(cl, &cases[i], &r));
        worst_ref = fmax(worst_ref, r);
    }
    printf("parity: %d brush cases, worst |daemon - core| %.3g, worst |daemon - double ref| %.3g\n",
           n, worst, worst_ref);
    df_client_close(cl);
    live_daemon_stop(&d);
}

/* An n^3-vertex cube [0,1]^3 (coordinates k / (n-1), n - 1 a power of two) of 6 tets per cell as
 * MEDIT text, every tet positively oriented. */
static char *tet_cube_medit(int n, size_t *len)
{
    size_t cap = (size_t)n * n * n * (80 + 6 * 48) + 256;
    char *t = malloc(cap);
    size_t o = (size_t)snprintf(t, cap, "MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n",
                                n * n * n);
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                o += (size_t)snprintf(t + o, cap - o, "%.17g %.17g %.17g 0\n", i / (n - 1.0),
                                      j / (n - 1.0), k / (n - 1.0));
    o += (size_t)snprintf(t + o, cap - o, "Tetrahedra\n%d\n", 6 * (n - 1) * (n - 1) * (n - 1));
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int k = 0; k + 1 < n; k++)
        for (int j = 0; j + 1 < n; j++)
            for (int i = 0; i + 1 < n; i++)
                for (int p = 0; p < 6; p++) {
                    int c[3] = {i, j, k}, v[4];
                    v[0] = (c[2] * n + c[1]) * n + c[0];
                    for (int s = 0; s < 3; s++) {
                        c[perm[p][s]]++;
                        v[s + 1] = (c[2] * n + c[1]) * n + c[0];
                    }
                    /* Kuhn tets of an even permutation are positive, odd ones need a swap */
                    int odd = p == 1 || p == 2 || p == 5;
                    if (odd) {
                        int tmp = v[1];
                        v[1] = v[2];
                        v[2] = tmp;
                    }
                    o += (size_t)snprintf(t + o, cap - o, "%d %d %d %d 0\n", v[0] + 1, v[1] + 1,
                                          v[2] + 1, v[3] + 1);
                }
    o += (size_t)snprintf(t + o, cap - o, "End\n");
    *len = o;
    return t;
}

/* Max |daemon float positions - core double positions| over every coordinate. */
static double move_diff(const float *P, const double *V, size_t n3)
{
    double w = 0;
    for (size_t i = 0; i < n3; i++) {
        double d = fabs((double)P[i] - V[i]);
        w = isnan(d) ? INFINITY : fmax(w, d);
    }
    return w;
}

static void test_handle_moves_match_the_core(void **state)
{
    (void)state;
    daemon_proc d;
    df_client *cl = setup(&d);
    df_error e;
    size_t len;
    char *txt = tet_cube_medit(9, &len);
    df_mesh mesh;
    df_mesh_init(&mesh);
    assert_int_equal(df_mesh_read_memory(txt, len, DF_FMT_MEDIT, "cube", NULL, &mesh, NULL, &e),
                     DF_OK);
    df_msg_session_info info;
    assert_int_equal(df_client_load_mesh_bytes(cl, "cube", DF_FMT_MEDIT, txt, len, 0, &info, &e),
                     DF_OK);
    free(txt);
    assert_int_equal(info.nv, mesh.nv);
    uint64_t sid = info.session_id;
    /* handles: the bottom face (z = 0) fixed and the top corner (1,1,1) pulled */
    int32_t handles[128];
    int32_t nh = 0;
    for (int32_t i = 0; i < mesh.nv; i++)
        if (mesh.V[3 * i + 2] == 0.0)
            handles[nh++] = i;
    handles[nh++] = mesh.nv - 1;
    df_msg_handles h;
    df_msg_handles_defaults(&h, DF_ADMM_ARAP);
    h.session_id = sid;
    h.tol = 0; /* run exactly max_iters iterations on both sides */
    h.max_iters = PARITY_ADMM_ITERS;
    h.w = 1e-3;
    h.s = 0.05;
    h.rho = 1.0;
    h.n_handles = (uint32_t)nh;
    h.handles = handles;
    assert_int_equal(df_client_handles_set(cl, &h, &e), DF_OK);
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.w = h.w, p.s = h.s, p.rho = h.rho, p.tol = h.tol, p.max_iters = (int)h.max_iters;
    p.youngs = h.youngs, p.poisson = h.poisson, p.area_weighting = h.area_weighting;
    p.accelerate = h.accelerate, p.anderson_m = h.anderson_m;
    p.strain_min = h.strain_min, p.strain_max = h.strain_max, p.bending = h.bending;
    df_admm *s = NULL;
    assert_int_equal(df_admm_create(&mesh, &p, handles, nh, NULL, 0, &s, &e), DF_OK);
    double targets[3 * 128];
    for (int round = 0; round < 2; round++) {
        for (int32_t k = 0; k < nh; k++)
            memcpy(&targets[3 * k], &mesh.V[3 * handles[k]], 3 * sizeof(double));
        double pull = round == 0 ? 0.25 : -0.1;
        targets[3 * (nh - 1) + 0] += pull;
        targets[3 * (nh - 1) + 2] += 0.5 * pull;
        df_msg_handle_move mv = {.session_id = sid, .max_iters = 0, .max_ms = 0,
                                 .progress_every = 0, .n_targets = (uint32_t)nh,
                                 .targets = targets};
        df_msg_move_result res;
        assert_int_equal(df_client_handles_move(cl, &mv, &res, &e), DF_OK);
        assert_int_equal(df_admm_set_targets(s, targets, &e), DF_OK);
        df_admm_result cr;
        df_admm_budget bud = {.max_iters = PARITY_ADMM_ITERS};
        assert_int_equal(df_admm_run(s, &bud, &cr, &e), DF_OK);
        df_client_mesh m;
        assert_int_equal(df_client_get_mesh(cl, sid, 0, &m, &e), DF_OK);
        double diff = move_diff(m.positions, df_admm_positions(s), 3 * (size_t)mesh.nv);
        double moved = move_diff(m.positions, mesh.V, 3 * (size_t)mesh.nv);
        double derr = fabs(res.objective - cr.objective) / fmax(1e-300, fabs(cr.objective));
        printf("  handle move %d: %u vs %d iterations, max|daemon-core| %.2g, objective %.9g vs "
               "%.9g, largest motion %.3f\n", round + 1, res.iterations, cr.iterations, diff,
               res.objective, cr.objective, moved);
        if ((int)res.iterations != cr.iterations || !(diff <= PARITY_TOL) || !(derr < 1e-6) ||
            !(moved > 0.05))
            fail_msg("handle-move parity FAILED (move %d): iterations %u vs %d, max |daemon - "
                     "core| %.3g (tol %g), objective %.12g vs %.12g, motion %.3g",
                     round + 1, res.iterations, cr.iterations, diff, PARITY_TOL, res.objective,
                     cr.objective, moved);
        assert_int_equal(cr.iterations, PARITY_ADMM_ITERS);
        df_client_mesh_free(&m);
    }
    df_admm_free(s);
    df_mesh_free(&mesh);
    df_client_close(cl);
    live_daemon_stop(&d);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_brush_matches_the_core),
        cmocka_unit_test(test_handle_moves_match_the_core),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

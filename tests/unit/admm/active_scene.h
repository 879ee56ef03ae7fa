/* active_scene.h — the drag scenes of the active-set unit tests (test_admm_active.c,
 * test_admm_active_reuse.c): a tet grid with its bottom face pinned and a 3 x 3 top patch dragged
 * up, a planar triangle grid with its left column pinned and a 3 x 3 centre patch dragged in the
 * plane, ARAP parameters scaled by the grid spacing, and cmocka-asserting wrappers of create,
 * set_targets and run. Header-only (static inline); include after <cmocka.h>. */
#ifndef ACTIVE_SCENE_H
#define ACTIVE_SCENE_H

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

typedef struct scene {
    df_mesh m;
    int32_t *h;
    int nh;
    double *tg;     /* rest positions of the handles */
    uint8_t *drag;  /* per handle: 1 when dragged */
    double hsp;     /* grid spacing */
    double dir[3];  /* drag direction per unit of `amount` */
} scene;

/* Fills *sc from grid mesh m of n cells per side over the unit square or cube: each vertex whose
 * grid indices (i, j) lie within one cell of the centre, and on the top face for a tet grid, is a
 * dragged handle; each on the bottom face (tets) or the left column (triangles) a pinned one. */
static inline void scene_fill(scene *sc, df_mesh m, int n)
{
    memset(sc, 0, sizeof(*sc));
    sc->m = m;
    sc->hsp = 1.0 / n;
    sc->h = malloc((size_t)m.nv * sizeof(int32_t));
    sc->tg = malloc((size_t)m.nv * 3 * sizeof(double));
    sc->drag = calloc((size_t)m.nv, 1);
    int tet = m.kind == DF_MESH_TET;
    for (int32_t i = 0; i < m.nv; i++) {
        const double *x = m.V + 3 * (size_t)i;
        long ii = lround(x[0] * n), jj = lround(x[1] * n);
        int mid = labs(ii - n / 2) <= 1 && labs(jj - n / 2) <= 1;
        int dragged = tet ? mid && x[2] == 1.0 : mid, pinned = tet ? x[2] == 0.0 : ii == 0;
        if (dragged || pinned) {
            sc->drag[sc->nh] = (uint8_t)dragged;
            memcpy(sc->tg + 3 * (size_t)sc->nh, x, 3 * sizeof(double));
            sc->h[sc->nh++] = i;
        }
    }
}

/* tet grid n^3 over [0,1]^3: bottom face pinned, 3 x 3 patch at the top centre dragged up */
static inline void tet_scene(scene *sc, int n)
{
    scene_fill(sc, tu_bar3d(n, n, n, 1.0, 1.0, 1.0), n);
    sc->dir[2] = 1.0;
}

/* planar triangle grid n x n over [0,1]^2: left column pinned, 3 x 3 centre patch dragged in x, y */
static inline void tri_scene(scene *sc, int n)
{
    scene_fill(sc, tu_grid2d(n, n, 1.0, 1.0), n);
    sc->dir[0] = 0.8;
    sc->dir[1] = 0.6;
}

static inline void scene_free(scene *sc)
{
    tu_free(&sc->m);
    free(sc->h); free(sc->tg); free(sc->drag);
}

/* ARAP with w, s, rho scaled by the grid spacing (a support of a few rings) */
static inline df_admm_params arap_params(const scene *sc, int active)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    double h = sc->hsp;
    if (sc->m.kind == DF_MESH_TET) { /* per-vertex stiffness ~ h: w ~ h^2 keeps the support in rings */
        p.w = 0.5 * h * h;
        p.rho = 6.0 * h;
    } else { /* spokes and rims: stiffness ~ 1, w ~ h */
        p.w = 0.5 * h;
        p.rho = 6.0;
    }
    p.s = 0.25 * h;
    p.tol = 1e-13;
    p.max_iters = 20000;
    p.threads = 1;
    p.active = active;
    return p;
}

static inline df_admm *make(const scene *sc, const df_admm_params *p)
{
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&sc->m, p, sc->h, sc->nh, NULL, 0, &s, &err), DF_OK);
    return s;
}

/* targets: dragged handles moved by amount * hsp along dir */
static inline void set_drag(df_admm *s, const scene *sc, double amount)
{
    double *t = malloc((size_t)sc->nh * 3 * sizeof(double));
    memcpy(t, sc->tg, (size_t)sc->nh * 3 * sizeof(double));
    for (int k = 0; k < sc->nh; k++)
        if (sc->drag[k])
            for (int c = 0; c < 3; c++) t[3 * k + c] += amount * sc->hsp * sc->dir[c];
    df_error err;
    assert_int_equal(df_admm_set_targets(s, t, &err), DF_OK);
    free(t);
}

static inline df_admm_result run(df_admm *s, int iters)
{
    df_admm_budget b = {.max_iters = iters};
    df_admm_result r;
    df_error err;
    assert_int_equal(df_admm_run(s, &b, &r, &err), DF_OK);
    return r;
}

static inline int32_t count_moved(const df_admm *s, const df_mesh *m)
{
    const double *V = df_admm_positions(s);
    int32_t n = 0;
    for (int32_t i = 0; i < m->nv; i++)
        if (memcmp(V + 3 * (size_t)i, m->V + 3 * (size_t)i, 3 * sizeof(double))) n++;
    return n;
}

#endif

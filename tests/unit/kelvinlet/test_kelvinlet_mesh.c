/* Unit tests of core/kelvinlet brushes on a real mesh ($MESHES/bunny.off; skipped with a
 * message when the folder is missing): an incompressible (nu = 0.5, divergence-free) tri-scale
 * grab integrated with RK4 keeps the enclosed volume far better than a compressible (nu = 0)
 * one, the grabbed vertex lands on its target, and the twist brush keeps the volume too. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"
#include "tests/unit/unit_skip.h"

static const char *meshes_dir(void)
{
    const char *d = getenv("MESHES");
    return d && *d ? d : "../shared/meshes";
}

typedef struct {
    int nv, nf;
    float *v;
    int *f;
} tri_mesh;

/* Minimal triangle-OFF reader (the test must not depend on the mesh module's evolving API). */
static int read_off(const char *path, tri_mesh *m)
{
    FILE *fp = fopen(path, "r");
    char tag[8];
    int ne;
    if (!fp)
        return -1;
    if (fscanf(fp, "%7s %d %d %d", tag, &m->nv, &m->nf, &ne) != 4 || strcmp(tag, "OFF") != 0) {
        fclose(fp);
        return -1;
    }
    m->v = malloc(3 * (size_t)m->nv * sizeof *m->v);
    m->f = malloc(3 * (size_t)m->nf * sizeof *m->f);
    for (int i = 0; i < 3 * m->nv; i++)
        if (fscanf(fp, "%f", &m->v[i]) != 1)
            return fclose(fp), -1;
    for (int i = 0; i < m->nf; i++) {
        int k;
        if (fscanf(fp, "%d %d %d %d", &k, &m->f[3 * i], &m->f[3 * i + 1], &m->f[3 * i + 2]) != 4
            || k != 3)
            return fclose(fp), -1;
    }
    fclose(fp);
    return 0;
}

static double volume(const tri_mesh *m, const float *v)
{
    double vol = 0.0;
    for (int i = 0; i < m->nf; i++) {
        const float *a = v + 3 * m->f[3 * i], *b = v + 3 * m->f[3 * i + 1];
        const float *c = v + 3 * m->f[3 * i + 2];
        vol += (a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1])
                - a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0])
                + a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6.0;
    }
    return vol;
}

static void test_bunny_volume(void **state)
{
    (void)state;
    char path[1024];
    struct stat st;
    snprintf(path, sizeof path, "%s/bunny.off", meshes_dir());
    if (stat(path, &st) != 0)
        unit_skip("%s not found (set MESHES to the shared mesh folder)", path);
    tri_mesh m;
    assert_int_equal(read_off(path, &m), 0);
    assert_int_equal(m.nv, 3485);
    float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
    int top = 0;
    for (int i = 0; i < m.nv; i++) {
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], m.v[3 * i + k]);
            hi[k] = fmaxf(hi[k], m.v[3 * i + k]);
        }
        if (m.v[3 * i + 1] > m.v[3 * top + 1])
            top = i;                                   /* an ear tip */
    }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1])
                       + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double v0 = volume(&m, m.v);
    float *w = malloc(3 * (size_t)m.nv * sizeof *w);
    double dv[2];
    const double nus[2] = {0.0, 0.5};
    for (int k = 0; k < 2; k++) {
        df_kelvinlet_brush b;
        df_kelvinlet_brush_defaults(&b);
        b.order = 3;
        b.nu = nus[k];
        b.radius = 0.15 * diag;
        for (int i = 0; i < 3; i++)
            b.centre[i] = m.v[3 * top + i];
        b.tip[0] = 0.08 * diag;
        b.tip[1] = 0.05 * diag;
        b.integrator = DF_KELVINLET_EULER;
        df_kelvinlet_prepared p;
        df_error e;
        assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
        memcpy(w, m.v, 3 * (size_t)m.nv * sizeof *w);
        assert_int_equal(df_kelvinlet_apply(&p, w, (size_t)m.nv, &e), DF_OK);
        for (int i = 0; i < 3; i++)               /* Euler, 1 step: the ear tip is exact */
            assert_true(fabs(w[3 * top + i] - (b.centre[i] + b.tip[i])) < 1e-6 * diag);
        b.integrator = DF_KELVINLET_RK4;
        b.steps = 8;
        assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
        memcpy(w, m.v, 3 * (size_t)m.nv * sizeof *w);
        assert_int_equal(df_kelvinlet_apply(&p, w, (size_t)m.nv, &e), DF_OK);
        dv[k] = (volume(&m, w) - v0) / v0;
        printf("# bunny tri-scale grab nu %.1f, RK4 x 8: volume change %+.3e\n", nus[k], dv[k]);
    }
    assert_true(fabs(dv[1]) < 2e-4);
    assert_true(fabs(dv[1]) < 0.2 * fabs(dv[0]));
    /* twist: divergence-free for every nu */
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.type = DF_KELVINLET_TWIST;
    b.order = 2;
    b.nu = 0.3;
    b.radius = 0.25 * diag;
    for (int i = 0; i < 3; i++)
        b.centre[i] = 0.5 * (lo[i] + hi[i]);
    b.omega[1] = 1.2;
    b.integrator = DF_KELVINLET_RK4;
    b.steps = 8;
    df_kelvinlet_prepared p;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
    memcpy(w, m.v, 3 * (size_t)m.nv * sizeof *w);
    assert_int_equal(df_kelvinlet_apply(&p, w, (size_t)m.nv, NULL), DF_OK);
    double dt = (volume(&m, w) - v0) / v0, moved = 0.0;
    for (int i = 0; i < 3 * m.nv; i++)
        moved = fmax(moved, fabs(w[i] - m.v[i]));
    printf("# bunny bi-scale twist nu 0.3: max move %.3f diag, volume change %+.3e\n",
           moved / diag, dt);
    assert_true(moved > 0.01 * diag);
    assert_true(fabs(dt) < 5e-4);
    free(w);
    free(m.v);
    free(m.f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bunny_volume),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* bench_raycast — the pen's ray cast (core/geom, Embree 3, one thread) on a ~140k-vertex mesh
 * (`make bench`).
 *
 * $MESHES/stanford-bunny.obj (35,947 v / 69,451 f) split once at its edge midpoints (each
 * triangle into 4: ~140k v / ~278k f). Figures: the scene build (create), the refit after every
 * vertex moved (a smooth bump, as a brush update would), per-query cast time for random rays from
 * a sphere around the mesh towards its bounding box (hits and misses counted and printed: a miss
 * leaves the BVH early and costs less), and the pen path (view ray from a pixel + cast) through a
 * perspective view. Targets: cast <= 10 us per query, refit <= 5 ms. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/geom/raycast.h"
#include "core/geom/view_ray.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/operators.h"

#define TARGET_CAST_US 10.0
#define TARGET_REFIT_MS 5.0
#define NRAYS 200000
#define NREFIT 20

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static uint64_t rs = 0x2545F4914F6CDD1Dull;
static double rnd(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 7;
    rs ^= rs << 17;
    return (double)(rs >> 11) * 0x1.0p-53;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Index of edge (i, j) in the sorted unique edge list (keys i * nv + j, i < j). */
static int32_t edge_index(const int64_t *keys, int32_t ne, int64_t nv, int32_t i, int32_t j)
{
    int64_t k = i < j ? (int64_t)i * nv + j : (int64_t)j * nv + i;
    const int64_t *p = bsearch(&k, keys, (size_t)ne, sizeof *keys, cmp_i64);
    return p ? (int32_t)(p - keys) : -1;
}

/* Midpoint subdivision of m into V2 / F2 (malloc'd). 0 on success. */
static int subdivide(const df_mesh *m, double **V2, int32_t *nv2, int32_t **F2, int32_t *nf2)
{
    int32_t *E = NULL, ne = 0;
    df_error e;
    if (df_mesh_edges(m, &E, &ne, &e) != DF_OK) {
        fprintf(stderr, "bench_raycast: edges: %s\n", e.msg);
        return 1;
    }
    int64_t *keys = malloc((size_t)ne * sizeof *keys);
    *nv2 = m->nv + ne;
    *nf2 = 4 * m->ne;
    *V2 = malloc(3 * (size_t)*nv2 * sizeof **V2);
    *F2 = malloc(3 * (size_t)*nf2 * sizeof **F2);
    if (!keys || !*V2 || !*F2)
        return 1;
    memcpy(*V2, m->V, 3 * (size_t)m->nv * sizeof **V2);
    for (int32_t k = 0; k < ne; k++) {
        keys[k] = (int64_t)E[2 * k] * m->nv + E[2 * k + 1];
        for (int c = 0; c < 3; c++)
            (*V2)[3 * (size_t)(m->nv + k) + c] = 0.5 * (m->V[3 * (size_t)E[2 * k] + c]
                                                        + m->V[3 * (size_t)E[2 * k + 1] + c]);
    }
    qsort(keys, (size_t)ne, sizeof *keys, cmp_i64);   /* df_mesh_edges sorts already */
    for (int32_t f = 0; f < m->ne; f++) {
        const int32_t *t = m->E + 3 * (size_t)f;
        int32_t a = edge_index(keys, ne, m->nv, t[0], t[1]);
        int32_t b = edge_index(keys, ne, m->nv, t[1], t[2]);
        int32_t c = edge_index(keys, ne, m->nv, t[2], t[0]);
        if (a < 0 || b < 0 || c < 0)
            return 1;
        a += m->nv, b += m->nv, c += m->nv;
        int32_t q[12] = {t[0], a, c, a, t[1], b, c, b, t[2], a, b, c};
        memcpy(*F2 + 12 * (size_t)f, q, sizeof q);
    }
    free(keys);
    free(E);
    return 0;
}

static void look_at_persp(const double eye[3], const double at[3], double fovy, double aspect,
                          double n, double f, double vp[16])
{
    double fw[3], s[3], u[3], up[3] = {0, 1, 0};
    double fn = 0;
    for (int k = 0; k < 3; k++)
        fw[k] = at[k] - eye[k], fn += fw[k] * fw[k];
    for (int k = 0; k < 3; k++)
        fw[k] /= sqrt(fn);
    s[0] = fw[1] * up[2] - fw[2] * up[1];
    s[1] = fw[2] * up[0] - fw[0] * up[2];
    s[2] = fw[0] * up[1] - fw[1] * up[0];
    double sn = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int k = 0; k < 3; k++)
        s[k] /= sn;
    u[0] = s[1] * fw[2] - s[2] * fw[1];
    u[1] = s[2] * fw[0] - s[0] * fw[2];
    u[2] = s[0] * fw[1] - s[1] * fw[0];
    double view[16] = {s[0], s[1], s[2], -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]),
                       u[0], u[1], u[2], -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]),
                       -fw[0], -fw[1], -fw[2], fw[0] * eye[0] + fw[1] * eye[1] + fw[2] * eye[2],
                       0, 0, 0, 1};
    double g = 1 / tan(fovy / 2);
    double proj[16] = {g / aspect, 0, 0, 0, 0, g, 0, 0, 0, 0, (f + n) / (n - f),
                       2 * f * n / (n - f), 0, 0, -1, 0};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double acc = 0;
            for (int k = 0; k < 4; k++)
                acc += proj[4 * i + k] * view[4 * k + j];
            vp[4 * i + j] = acc;
        }
}

int main(void)
{
    const char *dir = getenv("MESHES");
    char path[1024];
    snprintf(path, sizeof path, "%s/stanford-bunny.obj", dir && *dir ? dir : "../shared/meshes");
    df_mesh m;
    df_mesh_init(&m);
    df_error e;
    if (df_mesh_read_file(path, NULL, &m, NULL, &e) != DF_OK) {
        printf("bench_raycast: %s (set MESHES to the shared meshes folder). Skipping.\n", e.msg);
        return 0;
    }
    double *V = NULL;
    int32_t *F = NULL, nv = 0, nf = 0;
    if (subdivide(&m, &V, &nv, &F, &nf)) {
        fprintf(stderr, "bench_raycast: subdivision failed\n");
        return 1;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], V[3 * i + k]), hi[k] = fmax(hi[k], V[3 * i + k]);
    double c[3], diag = 0;
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (lo[k] + hi[k]), diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    diag = sqrt(diag);
    printf("bench_raycast: stanford-bunny.obj split at edge midpoints: %d vertices, %d faces; "
           "Embree 3, 1 thread\n", (int)nv, (int)nf);

    /* Build. */
    double tb = 1e30;
    df_raycast *rc = NULL;
    for (int r = 0; r < 3; r++) {
        df_raycast_free(rc);
        rc = NULL;
        double t0 = now();
        if (df_raycast_create(V, nv, F, nf, &rc, &e) != DF_OK) {
            fprintf(stderr, "bench_raycast: create: %s\n", e.msg);
            return 1;
        }
        tb = fmin(tb, now() - t0);
    }
    printf("  build (create): %.2f ms (best of 3)\n", tb * 1e3);

    /* Refit: a moving smooth bump displaces every vertex (like a brush update). */
    double *W = malloc(3 * (size_t)nv * sizeof *W), tr[NREFIT];
    if (!W)
        return 1;
    for (int r = 0; r < NREFIT; r++) {
        double a = 2 * M_PI * r / NREFIT;
        for (int32_t i = 0; i < nv; i++) {
            const double *p = V + 3 * (size_t)i;
            double dx = p[0] - c[0] - 0.2 * diag * cos(a), dy = p[1] - c[1];
            double w = 0.02 * diag * exp(-(dx * dx + dy * dy) / (0.05 * diag * diag));
            W[3 * (size_t)i] = p[0];
            W[3 * (size_t)i + 1] = p[1] + w;
            W[3 * (size_t)i + 2] = p[2];
        }
        double t0 = now();
        if (df_raycast_refit(rc, W, &e) != DF_OK) {
            fprintf(stderr, "bench_raycast: refit: %s\n", e.msg);
            return 1;
        }
        tr[r] = now() - t0;
    }
    qsort(tr, NREFIT, sizeof tr[0], cmp_d);
    double refit_med = tr[NREFIT / 2];
    printf("  refit (all %d vertices moved): median %.2f ms, best %.2f ms, worst %.2f ms of %d "
           "(%.0f%% of a build)\n", (int)nv, refit_med * 1e3, tr[0] * 1e3, tr[NREFIT - 1] * 1e3,
           NREFIT, 100 * refit_med / tb);

    /* Casts: random rays from a sphere of radius 1.5 diag towards the bounding box. */
    double *rays = malloc(6 * (size_t)NRAYS * sizeof *rays);
    if (!rays)
        return 1;
    for (int r = 0; r < NRAYS; r++) {
        double z = 2 * rnd() - 1, ph = 2 * M_PI * rnd(), s = sqrt(1 - z * z);
        double d[3] = {s * cos(ph), s * sin(ph), z};
        for (int k = 0; k < 3; k++) {
            rays[6 * (size_t)r + k] = c[k] + 1.5 * diag * d[k];
            rays[6 * (size_t)r + 3 + k] = lo[k] + rnd() * (hi[k] - lo[k]) - rays[6 * (size_t)r + k];
        }
    }
    double tc = 1e30;
    int hits = 0;
    double sink = 0;
    for (int rep = 0; rep < 3; rep++) {
        hits = 0;
        double t0 = now();
        for (int r = 0; r < NRAYS; r++) {
            df_ray_hit h;
            if (df_raycast_hit(rc, rays + 6 * (size_t)r, rays + 6 * (size_t)r + 3, &h)) {
                hits++;
                sink += h.t;
            }
        }
        tc = fmin(tc, now() - t0);
    }
    double cast_us = tc * 1e6 / NRAYS;
    printf("  cast: %.2f us per query (best of 3 x %d rays: %d hit, %d missed)\n", cast_us, NRAYS,
           hits, NRAYS - hits);

    /* Pen path: pixel -> view ray -> cast, over a 400 x 300 grid of a 1600 x 1200 viewport. */
    double vp[16], viewport[4] = {0, 0, 1600, 1200};
    double eye[3] = {c[0] + 0.3 * diag, c[1] + 0.2 * diag, c[2] + 1.2 * diag};
    look_at_persp(eye, c, 0.7, 4.0 / 3.0, 0.01 * diag, 10 * diag, vp);
    int pen_hits = 0, npen = 400 * 300;
    double t0 = now();
    for (int j = 0; j < 300; j++)
        for (int i = 0; i < 400; i++) {
            double px, py, o[3], d[3];
            df_ray_hit h;
            if (df_view_pen_pixel(viewport, (i + 0.5) / 400, (j + 0.5) / 300, &px, &py, &e) != DF_OK
                || df_view_ray(vp, viewport, px, py, o, d, &e) != DF_OK) {
                fprintf(stderr, "bench_raycast: view ray: %s\n", e.msg);
                return 1;
            }
            if (df_raycast_hit(rc, o, d, &h))
                pen_hits++, sink += h.point[0];
        }
    double pen_us = (now() - t0) * 1e6 / npen;
    printf("  pen path (pixel -> view ray -> cast): %.2f us per query (%d pixels: %d hit, %d "
           "missed)\n", pen_us, npen, pen_hits, npen - pen_hits);

    int t1 = cast_us <= TARGET_CAST_US, t2 = refit_med * 1e3 <= TARGET_REFIT_MS;
    printf("  target cast <= %.0f us: %s (%.2f us, ratio to target %.2f)\n", TARGET_CAST_US,
           t1 ? "MET" : "MISSED", cast_us, cast_us / TARGET_CAST_US);
    printf("  target refit <= %.0f ms: %s (median %.2f ms, ratio to target %.2f)\n",
           TARGET_REFIT_MS, t2 ? "MET" : "MISSED", refit_med * 1e3,
           refit_med * 1e3 / TARGET_REFIT_MS);
    printf("bench_raycast: targets %s%s\n", t1 && t2 ? "MET" : "MISSED (see ratios above)",
           sink == 12345.678 ? " " : "");
    df_raycast_free(rc);
    free(rays);
    free(W);
    free(V);
    free(F);
    df_mesh_free(&m);
    return 0;
}

/* bench_local.c — cost proportional to the edit (issue 14 item 4): the region-bounded update
 * table. Meshes: generated tet grids of n^3 cubes (6 tets each) over [0,1]^3 at ~10k, ~100k and
 * ~1M elements (n = 12, 26, 55). The edit is the same in grid units on every mesh: a 5 x 5 vertex
 * patch at the centre of the top face dragged up in 10 warm-started updates of 20 iterations
 * (0.3 grid spacings each), the bottom face pinned; ARAP with w, s and rho scaled with the grid
 * spacing h (w = W0 h^2, s = S0 h, rho = R0 h), which makes the discrete problem identical in grid
 * units on every mesh, so the support (vertices that move) has the same size while the mesh grows.
 * For each mesh: the full solve (params.active = 0) against the active-set mode (params.active =
 * 1) with the default band (3 rings) and twice that: mean and largest update time (wall and CPU),
 * the region and support, the largest relative objective difference per update (the restricted
 * and the full ADMM iterates differ until converged; the wider band narrows it), and after the
 * drag both solves converged (tol 1e-12) and compared.
 * The full solve on the 1M mesh is not run by default (its whole-mesh factorization alone takes
 * about a minute and 1.7 GB on this machine); BENCH_LOCAL_FULL1M=1 runs it.
 * Target (issue 14): a 20-iteration warm update on the 1M mesh moving <= 2% of the vertices in
 * <= 33 ms on 2 threads, final objective equal to the full solve's within 1e-8 relative. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/admm/admm.h"
#include "tests/bench/bench_util.h"

#define UPDATES 10
#define ITERS 20
#define W0 0.5      /* w / h^2 */
#define S0 0.25     /* s / h */
#define R0 6.0      /* rho / h (> W0 / S0 = 2) */
#define STEP 0.3    /* drag per update, grid spacings */
#define TARGET_MS 33.0
#define TARGET_REL 1e-8

/* CPU seconds of the process (all threads): the work, whatever the machine's load */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct grid {
    df_mesh m;
    int32_t *h, nh;
    double *tg;
    int32_t *drag;  /* 1 for the dragged handles (index into h) */
    double hsp;
} grid;

static void make_grid(int n, grid *g)
{
    memset(g, 0, sizeof(*g));
    df_mesh *m = &g->m;
    m->kind = DF_MESH_TET;
    m->nv = (n + 1) * (n + 1) * (n + 1);
    m->ne = 6 * n * n * n;
    m->V = malloc((size_t)m->nv * 3 * sizeof(double));
    m->E = malloc((size_t)m->ne * 4 * sizeof(int32_t));
    g->hsp = 1.0 / n;
#define ID(i, j, k) ((int32_t)(((k) * (n + 1) + (j)) * (n + 1) + (i)))
    for (int k = 0; k <= n; k++)
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                double *p = m->V + 3 * (size_t)ID(i, j, k);
                p[0] = (double)i / n; p[1] = (double)j / n; p[2] = (double)k / n;
            }
    static const int c6[6][4] = {{0, 1, 3, 7}, {0, 1, 7, 5}, {0, 5, 7, 4}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}};
    size_t e = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                int32_t c[8];
                for (int b = 0; b < 8; b++) c[b] = ID(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                for (int t = 0; t < 6; t++, e++) {
                    int32_t *el = m->E + 4 * e;
                    for (int q = 0; q < 4; q++) el[q] = c[c6[t][q]];
                    const double *x0 = m->V + 3 * (size_t)el[0], *x1 = m->V + 3 * (size_t)el[1];
                    const double *x2 = m->V + 3 * (size_t)el[2], *x3 = m->V + 3 * (size_t)el[3];
                    double u[3], v[3], w[3];
                    for (int d = 0; d < 3; d++) { u[d] = x1[d] - x0[d]; v[d] = x2[d] - x0[d]; w[d] = x3[d] - x0[d]; }
                    double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                                 u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if (det < 0) { int32_t tmp = el[2]; el[2] = el[3]; el[3] = tmp; }
                }
            }
    /* handles: bottom face pinned, 5 x 5 patch at the centre of the top face dragged */
    int32_t cap = (n + 1) * (n + 1) + 25;
    g->h = malloc((size_t)cap * sizeof(int32_t));
    g->drag = malloc((size_t)cap * sizeof(int32_t));
    g->tg = malloc((size_t)cap * 3 * sizeof(double));
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            g->drag[g->nh] = 0;
            g->h[g->nh++] = ID(i, j, 0);
        }
    for (int j = n / 2 - 2; j <= n / 2 + 2; j++)
        for (int i = n / 2 - 2; i <= n / 2 + 2; i++) {
            g->drag[g->nh] = 1;
            g->h[g->nh++] = ID(i, j, n);
        }
#undef ID
    for (int32_t k = 0; k < g->nh; k++) memcpy(g->tg + 3 * (size_t)k, m->V + 3 * (size_t)g->h[k], 3 * sizeof(double));
}

static void free_grid(grid *g)
{
    free(g->m.V); free(g->m.E); free(g->h); free(g->tg); free(g->drag);
}

typedef struct outcome {
    int ran;
    double create_s, mean_ms, max_ms, cpu_ms, E[UPDATES], E_conv;
    int updates, conv_iters, converged;
    df_admm_active_stats st;
    int32_t moved;
} outcome;

static int drag(const grid *g, int active, int band, int updates, outcome *o)
{
    memset(o, 0, sizeof(*o));
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 2;
    p.w = W0 * g->hsp * g->hsp;
    p.s = S0 * g->hsp;
    p.rho = R0 * g->hsp;
    p.tol = 1e-12;
    p.active = active;
    p.active_band = band;
    df_admm *s = NULL;
    df_error err;
    double t0 = bench_now();
    if (df_admm_create(&g->m, &p, g->h, g->nh, NULL, 0, &s, &err)) { printf("  create: %s\n", err.msg); return -1; }
    o->create_s = bench_now() - t0;
    double *tg = malloc((size_t)g->nh * 3 * sizeof(double));
    memcpy(tg, g->tg, (size_t)g->nh * 3 * sizeof(double));
    for (int u = 0; u < updates; u++) {
        for (int32_t k = 0; k < g->nh; k++)
            if (g->drag[k]) tg[3 * (size_t)k + 2] = g->tg[3 * (size_t)k + 2] + STEP * g->hsp * (u + 1);
        df_admm_budget b = {.max_iters = ITERS};
        df_admm_result r;
        double t = bench_now(), c = cpu_now();
        if (df_admm_set_targets(s, tg, &err) || df_admm_run(s, &b, &r, &err)) { printf("  run: %s\n", err.msg); break; }
        double ms = (bench_now() - t) * 1e3;
        o->cpu_ms += (cpu_now() - c) * 1e3 / updates;
        o->mean_ms += ms / updates;
        if (ms > o->max_ms) o->max_ms = ms;
        o->E[u] = r.objective;
        o->updates++;
    }
    df_admm_budget b = {.max_iters = 3000};
    df_admm_result r;
    if (o->updates == UPDATES && !df_admm_run(s, &b, &r, &err)) {
        o->E_conv = r.objective;
        o->conv_iters = r.iterations;
        o->converged = r.converged;
    }
    const double *V = df_admm_positions(s);
    for (int32_t i = 0; i < g->m.nv; i++)
        if (memcmp(V + 3 * (size_t)i, g->m.V + 3 * (size_t)i, 3 * sizeof(double))) o->moved++;
    df_admm_get_active_stats(s, &o->st);
    o->ran = o->updates == updates;
    if (updates < UPDATES) o->E_conv = NAN; /* a partial drag: no convergence run */
    free(tg);
    df_admm_free(s);
    return o->ran ? 0 : -1;
}

int main(int argc, char **argv)
{
    (void)argc;
    /* as bench_admm: on a shared machine OpenMP threads spinning at barriers while their partner
     * is descheduled cost more than they save; re-run once with the passive policy unless the
     * caller chose one (libgomp reads it at load) */
    if (!getenv("OMP_WAIT_POLICY")) {
        setenv("OMP_WAIT_POLICY", "passive", 1);
        execv("/proc/self/exe", argv);
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    static const int sizes[3] = {12, 26, 55};
    const char *f1m = getenv("BENCH_LOCAL_FULL1M");
    int full1m = f1m && atoi(f1m) > 0;
    printf("region-bounded updates: tet grid n^3 x 6 over [0,1]^3, 5x5 top patch dragged %d x %.1f h, bottom pinned,\n"
           "ARAP w %.2g h^2, s %.2g h, rho %.2g h; %d warm updates of %d iterations, 2 threads (timings under whatever load the machine has)\n",
           UPDATES, STEP, W0, S0, R0, UPDATES, ITERS);
    printf("active bK: active-set mode with a band of K rings; CPU ms: process CPU per update (both threads); upd dE:\n"
           "largest relative objective difference to the full solve after an update; conv dE: after both converged\n");
    printf("%9s %8s  %-10s | %-17s | %7s | %7s %7s %7s %6s | %9s %9s\n", "elements", "vertices", "solve",
           "wall mean/max ms", "CPU ms", "region", "support", "moved%", "grows", "upd dE", "conv dE");
    int met_time = 0, met_exact = -1, have1m = 0;
    double upd100k[2] = {NAN, NAN};
    for (int k = 0; k < 3; k++) {
        grid g;
        make_grid(sizes[k], &g);
        /* the full solve: every update and the convergence run at 10k (and at 1M on request),
         * the first 2 updates at 100k (one update there takes seconds on this machine), none at
         * 1M by default (header comment) */
        int full_updates = k == 0 || full1m ? UPDATES : k == 1 ? 2 : 0;
        outcome full, act[2];
        memset(&full, 0, sizeof(full));
        int have_full = full_updates > 0 && drag(&g, 0, 0, full_updates, &full) == 0;
        static const int bands[2] = {DF_ADMM_ACTIVE_BAND, 2 * DF_ADMM_ACTIVE_BAND};
        for (int b = 0; b < 2; b++)
            if (drag(&g, 1, bands[b], UPDATES, &act[b])) act[b].ran = 0;
        if (have_full)
            printf("%9d %8d  %-10s | %7.1f / %7.1f | %7.1f | %7s %7s %6.2f%% %6s | %9s %9s%s\n", g.m.ne, g.m.nv, "full",
                   full.mean_ms, full.max_ms, full.cpu_ms, "all", "-", 100.0 * full.moved / g.m.nv, "-", "", "",
                   full_updates < UPDATES ? "  (first 2 updates only)" : "");
        else
            printf("%9d %8d  %-10s | not run (whole-mesh factorization ~1 min, 1.7 GB; BENCH_LOCAL_FULL1M=1)\n", g.m.ne,
                   g.m.nv, "full");
        for (int b = 0; b < 2; b++) {
            const outcome *a = &act[b];
            if (!a->ran) { printf("%9s %8s  active b%-2d | failed\n", "", "", bands[b]); continue; }
            double dE = NAN, dC = NAN;
            if (have_full) {
                dE = 0;
                for (int u = 0; u < full.updates; u++) dE = fmax(dE, fabs(a->E[u] - full.E[u]) / fabs(full.E[u]));
                if (isfinite(full.E_conv) && full.E_conv != 0) dC = fabs(a->E_conv - full.E_conv) / fabs(full.E_conv);
            }
            char upd[16], conv[16], name[16];
            if (isfinite(dE)) snprintf(upd, sizeof upd, "%9.1e", dE);
            else snprintf(upd, sizeof upd, "%9s", "-");
            if (isfinite(dC)) snprintf(conv, sizeof conv, "%9.1e", dC);
            else snprintf(conv, sizeof conv, "%9s", "-");
            snprintf(name, sizeof name, "active b%d", bands[b]);
            printf("%9s %8s  %-10s | %7.1f / %7.1f | %7.1f | %7d %7d %6.2f%% %6ld | %s %s\n", "", "", name, a->mean_ms,
                   a->max_ms, a->cpu_ms, a->st.region_vertices, a->st.support, 100.0 * a->moved / g.m.nv, a->st.grows,
                   upd, conv);
            char fc[32];
            if (have_full) snprintf(fc, sizeof fc, "%.2f s", full.create_s);
            else snprintf(fc, sizeof fc, "not run");
            printf("%9s %8s  %-10s   create %.2f s (full %s); converged %s in %d its; certificates %ld, check "
                   "grows %ld, fallbacks %ld\n", "", "", "", a->create_s, fc, a->converged ? "yes" : "NO",
                   a->conv_iters, a->st.checks, a->st.check_grows, a->st.fallbacks);
            if (k == 1) upd100k[b] = dE;
            if (k == 2 && b == 0) {
                have1m = 1;
                met_time = a->mean_ms <= TARGET_MS && a->moved <= 0.02 * g.m.nv;
                if (isfinite(dC)) met_exact = dC <= TARGET_REL;
            }
        }
        free_grid(&g);
    }
    for (int b = 0; b < 2; b++)
        if (isfinite(upd100k[b]))
            printf("per-update objective (20 iterations, not converged) within 1e-8 of the full solve's at 100k, band %d: "
                   "%.1e: %s\n", (b + 1) * DF_ADMM_ACTIVE_BAND, upd100k[b], upd100k[b] <= TARGET_REL ? "MET" : "MISS");
    if (have1m) {
        printf("target 1M elements, <= 2%% moved: mean 20-iteration update <= %.0f ms wall on 2 threads: %s\n",
               TARGET_MS, met_time ? "MET" : "MISS");
        if (met_exact >= 0)
            printf("target 1M: converged objective equal to the full solve's within 1e-8 relative: %s\n", met_exact ? "MET" : "MISS");
        else
            printf("target 1M: converged objective equal to the full solve's within 1e-8: not measured at 1M (full solve "
                   "not run; 10k row: conv dE; BENCH_LOCAL_FULL1M=1 measures it)\n");
    }
    return 0;
}

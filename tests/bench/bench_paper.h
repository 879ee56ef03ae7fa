/* bench_paper.h — the local-deformation paper's experiments on the shared meshes, shared by the
 * ADMM benches (bench_admm, bench_admm_ttq, bench_kguess, bench_newton; header-only): the mesh
 * folder, the experiment record and the paper's rows, loading a case (rest mesh, handles, the
 * handles' init targets), building a solver for it, and the "objective within QUALITY_REL of a
 * reference" progress callback. Every function prints its own failure ("  cannot read ...") to
 * stdout and returns an error value; none is thread-safe beyond what the solver itself is. */
#ifndef DF_BENCH_PAPER_H
#define DF_BENCH_PAPER_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm.h"
#include "core/mesh/mesh_io.h"
#include "bench_util.h"

#define QUALITY_REL 1e-6

/* The shared mesh folder: $MESHES when set and non-empty, else ../shared/meshes. */
static inline const char *mesh_dir(void)
{
    const char *d = getenv("MESHES");
    return d && *d ? d : "../shared/meshes";
}

/* 1 when the shared meshes are there (mesh_dir()/pig_rest.node opens); else prints
 * "<bench>: ... not found; ... Skipping." and returns 0. */
static inline int paper_meshes_present(const char *bench)
{
    char probe[1024];
    snprintf(probe, sizeof(probe), "%s/pig_rest.node", mesh_dir());
    FILE *f = fopen(probe, "r");
    if (!f) {
        printf("%s: %s not found; set MESHES to the shared meshes folder. Skipping.\n", bench, probe);
        return 0;
    }
    fclose(f);
    return 1;
}

typedef struct experiment {
    const char *label, *stem, *init; /* stem: <stem>_rest.node, <stem>_handles.txt; init: targets file */
    df_admm_energy energy;
    double rho, s;
    double w;      /* 0: the paper's w = rho s / 10 */
    int unit;      /* 1: mesh and targets scaled to a unit bounding box (largest side 1) */
    double scale;  /* > 0 and != 1: mesh and targets then multiplied by it (after `unit`); 0: none */
} experiment;

/* The paper's rows (supplement Table 2 and the teaser), as experiment initializers. */
#define PAPER_PIG_ARAP {"pig ARAP", "pig", "pig_init0.4.node", DF_ADMM_ARAP, 0.1, 0.01, 0, 0, 0}
#define PAPER_PIG_NH {"pig Neo-Hookean", "pig", "pig_init0.4.node", DF_ADMM_NEOHOOKEAN, 5e5, 0.01, 0, 0, 0}
#define PAPER_PIG_TEASER_NH \
    {"pig teaser Neo-Hookean", "pig", "pig_init_teaser.node", DF_ADMM_NEOHOOKEAN, 5e5, 0.01, 0, 0, 0}
#define PAPER_BAR3_ARAP {"bar3 ARAP", "bar3", "bar3_init1.node", DF_ADMM_ARAP, 0.1, 0.1, 0, 0, 0}
#define PAPER_APPLE_NH \
    {"apple Neo-Hookean", "teaser_apple", "teaser_apple_init1.node", DF_ADMM_NEOHOOKEAN, 1e3, 0.01, 0, 0, 0}

/* the SC-L1 weight of an experiment */
static inline double exp_w(const experiment *x) { return x->w > 0 ? x->w : x->rho * x->s / 10.0; }

typedef struct loaded {
    df_mesh m;
    int32_t nh;
    int32_t *h;
    double *tg;    /* nh x 3 targets */
} loaded;

/* Loads x's rest mesh, handles and the handles' targets (from x->init) into *L (owned by the
 * caller: free with unload); scales to a unit box when x->unit, then by x->scale when set. Returns
 * 0, or -1 (printed). */
static inline int load(const experiment *x, loaded *L)
{
    char p[1024];
    df_error err;
    df_mesh_init(&L->m);
    snprintf(p, sizeof(p), "%s/%s_rest.node", mesh_dir(), x->stem);
    if (df_mesh_read_file(p, NULL, &L->m, NULL, &err)) { printf("  cannot read %s: %s\n", p, err.msg); return -1; }
    snprintf(p, sizeof(p), "%s/%s_handles.txt", mesh_dir(), x->stem);
    FILE *f = fopen(p, "r");
    if (!f) { printf("  cannot read %s\n", p); return -1; }
    L->h = malloc((size_t)L->m.nv * sizeof(int32_t));
    L->nh = 0;
    while (L->nh < L->m.nv && fscanf(f, "%d", &L->h[L->nh]) == 1) L->nh++;
    fclose(f);
    snprintf(p, sizeof(p), "%s/%s", mesh_dir(), x->init);
    double *T;
    int32_t nt;
    if (df_mesh_read_tetgen_nodes(p, &T, &nt, &err) || nt != L->m.nv) { printf("  cannot read %s\n", p); return -1; }
    L->tg = malloc((size_t)L->nh * 3 * sizeof(double));
    for (int k = 0; k < L->nh; k++) memcpy(L->tg + 3 * k, T + 3 * (size_t)L->h[k], 24);
    free(T);
    if (x->unit) { /* largest bounding-box side 1, about the origin of the box's corner */
        double lo[3], hi[3];
        for (int d = 0; d < 3; d++) lo[d] = hi[d] = L->m.V[d];
        for (int32_t i = 0; i < L->m.nv; i++)
            for (int d = 0; d < 3; d++) { lo[d] = fmin(lo[d], L->m.V[3 * (size_t)i + d]); hi[d] = fmax(hi[d], L->m.V[3 * (size_t)i + d]); }
        double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
        for (int32_t i = 0; i < L->m.nv; i++)
            for (int d = 0; d < 3; d++) L->m.V[3 * (size_t)i + d] = (L->m.V[3 * (size_t)i + d] - lo[d]) / ext;
        for (int k = 0; k < L->nh; k++)
            for (int d = 0; d < 3; d++) L->tg[3 * k + d] = (L->tg[3 * k + d] - lo[d]) / ext;
    }
    if (x->scale > 0 && x->scale != 1.0) {
        for (int64_t i = 0; i < 3 * (int64_t)L->m.nv; i++) L->m.V[i] *= x->scale;
        for (int k = 0; k < 3 * L->nh; k++) L->tg[k] *= x->scale;
    }
    return 0;
}

static inline void unload(loaded *L)
{
    df_mesh_free(&L->m);
    free(L->h);
    free(L->tg);
}

/* A solver for x on L with the targets set: w = exp_w(x), ADMM penalty rho (0: the paper's rho;
 * < 0: the default, i.e. the adaptive penalty), Anderson acceleration when accelerate. Caller
 * frees it (df_admm_free); NULL on an error (printed). */
static inline df_admm *make(const experiment *x, const loaded *L, int accelerate, double rho)
{
    df_admm_params p;
    df_admm_params_default(&p, x->energy);
    p.rho = rho > 0 ? rho : rho < 0 ? p.rho : x->rho; p.s = x->s; p.w = exp_w(x);
    p.accelerate = accelerate;
    df_admm *s = NULL;
    df_error err;
    if (df_admm_create(&L->m, &p, L->h, L->nh, NULL, 0, &s, &err)) { printf("  create: %s\n", err.msg); return NULL; }
    if (df_admm_set_targets(s, L->tg, &err)) { printf("  targets: %s\n", err.msg); df_admm_free(s); return NULL; }
    return s;
}

typedef struct quality {
    double target, t0, t_hit;
    int it_hit;
    const loaded *L; /* when set: the handles must also be at their targets (Neo-Hookean damping
                        lags them, with a lower objective meanwhile) */
} quality;

/* 1 when every handle of L is at its target in V (to 1e-9 of the coordinate's size) */
static inline int handles_at(const loaded *L, const double *V)
{
    for (int k = 0; k < L->nh; k++)
        for (int d = 0; d < 3; d++) {
            double t = L->tg[3 * k + d];
            if (fabs(V[3 * (size_t)L->h[k] + d] - t) > 1e-9 * (1.0 + fabs(t))) return 0;
        }
    return 1;
}

/* df_admm progress callback (user: quality): stops the run (returns 1) at the first iteration
 * whose objective is within QUALITY_REL of q->target (and, when q->L, with the handles at their
 * targets), recording its iteration and seconds since q->t0. */
static inline int quality_cb(void *user, const df_admm_progress *pr)
{
    quality *q = user;
    if (pr->objective <= q->target * (1.0 + QUALITY_REL) && (!q->L || handles_at(q->L, pr->V))) {
        q->t_hit = bench_now() - q->t0;
        q->it_hit = pr->iteration;
        return 1;
    }
    return 0;
}

#endif

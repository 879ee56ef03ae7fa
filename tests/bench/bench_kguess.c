/* bench_kguess — the Kelvinlet initial guess of a handle move (core/kelvinlet/kelvinlet_guess.h,
 * seeded through core/admm/admm_seed.h's line search) against the plain start, as time to
 * quality and final objective. Cases: pig and bar3 (the shared meshes; the paper's targets) and
 * the table built by bench_table.h, ARAP, and the apple Neo-Hookean (small); Neo-Hookean for pig
 * and bar3 and the pig teaser on request (cases 1, 3, 5: ~45 s each on this machine). Every start runs
 * PLAIN_ITERS iterations at the case's fixed penalty; the quality is E_plain, the plain start's
 * objective after them. Printed per start: the first iteration (and seconds, the guess's own cost
 * included) whose objective is within QUALITY_REL (1e-6) of E_plain with the handles on target,
 * and the objective after the PLAIN_ITERS iterations. Target (MET/MISS): the seeded start's final
 * objective is no worse than E_plain (within QUALITY_REL). Weights as bench_admm: w = rho s / 10
 * (bar3 Neo-Hookean, not in the paper: pig's rho 5e5 with bar3's s 0.1; table ARAP: bar3's rho
 * with s = the lattice cell). Arguments: [case index 0..6] [full] [shrink=X]: one case only; `full`
 * also runs the guess as the option used it before (whole field, alpha = 1) for comparison;
 * shrink=X: df_admm_seed's support restriction fixed at X (default: searched,
 * DF_ADMM_SEED_SHRINK_AUTO, as the daemon does). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/admm/admm_seed.h"
#include "core/kelvinlet/kelvinlet_guess.h"
#include "bench_paper.h"
#include "bench_table.h"

#define PLAIN_ITERS 500 /* iterations of every start; the plain start's objective is the quality */

static double shrink = DF_ADMM_SEED_SHRINK_AUTO; /* argument shrink=X */

enum { START_PLAIN, START_FULL, START_SEARCH };
static const char *start_name[] = {"plain start", "guess, alpha 1", "guess, line search"};

typedef struct trace {
    const loaded *L;
    double t0, E[PLAIN_ITERS + 1], t[PLAIN_ITERS + 1];
    unsigned char on[PLAIN_ITERS + 1]; /* handles on their targets */
} trace;

static int trace_cb(void *user, const df_admm_progress *p)
{
    trace *tr = user;
    if (p->iteration >= 1 && p->iteration <= PLAIN_ITERS) {
        tr->E[p->iteration] = p->objective;
        tr->t[p->iteration] = bench_now() - tr->t0;
        tr->on[p->iteration] = (unsigned char)handles_at(tr->L, p->V);
    }
    return 0;
}

typedef struct outcome {
    int ok, iters;
    double secs, guess_secs, objective;
    df_admm_seed_report rep;
    trace tr;
} outcome;

/* first iteration within QUALITY_REL of target with the handles on target (0: none) */
static int hit(const outcome *o, double target)
{
    for (int i = 1; i <= o->iters; i++)
        if (o->tr.on[i] && o->tr.E[i] <= target * (1.0 + QUALITY_REL)) return i;
    return 0;
}

/* One start of x on L, PLAIN_ITERS iterations. */
static int solve(const experiment *x, const loaded *L, int start, outcome *o)
{
    memset(o, 0, sizeof *o);
    df_admm *s = make(x, L, 0, 0.0);
    if (!s) return -1;
    df_error err;
    size_t n = 3 * (size_t)L->m.nv;
    double *V0 = malloc(n * sizeof *V0), *G = malloc(n * sizeof *G);
    memcpy(V0, df_admm_positions(s), n * sizeof *V0);
    o->tr.L = L;
    o->tr.t0 = bench_now();
    int rc = DF_OK;
    if (start != START_PLAIN) {
        double nu = x->energy == DF_ADMM_NEOHOOKEAN ? 0.45 : 0.5;
        rc = df_kelvinlet_guess(V0, L->m.nv, L->h, L->nh, L->tg, 0.0, nu, G, NULL, NULL, &err);
        if (rc == DF_OK && start == START_FULL) {
            rc = df_admm_set_positions(s, G, NULL, &err);
            o->rep.alpha = 1.0;
        } else if (rc == DF_OK) {
            rc = df_admm_seed(s, V0, G, shrink, &o->rep, &err);
        }
        o->guess_secs = bench_now() - o->tr.t0;
    }
    df_admm_budget b = {PLAIN_ITERS, 0, 1, trace_cb, &o->tr};
    df_admm_result r;
    if (rc == DF_OK) rc = df_admm_run(s, &b, &r, &err);
    if (rc != DF_OK) printf("  %s: %s\n", start_name[start], err.msg);
    else {
        o->ok = 1;
        o->iters = r.iterations;
        o->secs = bench_now() - o->tr.t0;
        o->objective = r.objective;
    }
    free(V0); free(G);
    df_admm_free(s);
    return o->ok ? 0 : -1;
}

static outcome runs[3];

static void report(int start, double target)
{
    const outcome *o = &runs[start];
    int h = hit(o, target);
    printf("  %-19s", start_name[start]);
    if (start == START_SEARCH)
        printf(" shrink %.2f%s (tau %.3g), alpha %.3f (start E %.4g; plain start with the handles on target %.4g, "
               "alpha 1 %.4g; %d evaluations; %.3f s with the field),", o->rep.shrink,
               shrink == DF_ADMM_SEED_SHRINK_AUTO ? " searched" : "", o->rep.tau, o->rep.alpha,
               o->rep.e_seed, o->rep.e_plain, o->rep.e_one, o->rep.evaluations, o->guess_secs);
    else if (start == START_FULL)
        printf(" (%.3f s for the field),", o->guess_secs);
    if (h) printf(" reached E_plain in %3d iterations, %.3f s;", h, o->tr.t[h]);
    else printf(" never reached E_plain in %d iterations;", o->iters);
    printf(" final objective %.9g (%+.2e relative) after %d iterations, %.3f s\n", o->objective,
           (o->objective - target) / target, o->iters, o->secs);
}

static int row(const experiment *x, int full)
{
    loaded L;
    if (strcmp(x->stem, "table") == 0 ? table_load(&L) : load(x, &L)) return 1;
    printf("%s (%d vertices, %d tets, %d handles, rho %g, w %g):\n", x->label, (int)L.m.nv, (int)L.m.ne,
           (int)L.nh, x->rho, exp_w(x));
    int bad = solve(x, &L, START_PLAIN, &runs[START_PLAIN]) || solve(x, &L, START_SEARCH, &runs[START_SEARCH]) ||
              (full && solve(x, &L, START_FULL, &runs[START_FULL]));
    unload(&L);
    if (bad) return 1;
    double target = runs[START_PLAIN].objective;
    for (int st = START_PLAIN; st <= START_SEARCH; st++)
        if (st != START_FULL || full) report(st, target);
    const outcome *g = &runs[START_SEARCH], *p = &runs[START_PLAIN];
    int hg = hit(g, target), hp = hit(p, target);
    printf("  target: the guess's final objective no worse than the plain start's (within %g): %s\n",
           QUALITY_REL, g->objective <= target * (1.0 + QUALITY_REL) ? "MET" : "MISS");
    if (g->rep.alpha == 0)
        printf("  saved by the guess: nothing (no candidate lowered the start's objective: the plain start)\n");
    else if (hg && hp)
        printf("  saved by the guess: %d iterations, %.3f s (the guess's cost included; timings under load)\n",
               hp - hg, p->tr.t[hp] - g->tr.t[hg]);
    return 0;
}

int main(int argc, char **argv)
{
    if (!getenv("OMP_WAIT_POLICY")) {   /* as bench_admm: passive waits on a shared machine */
        setenv("OMP_WAIT_POLICY", "passive", 1);
        execv("/proc/self/exe", argv);
    }
    if (!paper_meshes_present("bench_kguess")) return 0;
    setvbuf(stdout, NULL, _IOLBF, 0);
    printf("bench_kguess: Kelvinlet initial guess (line-searched) vs plain start: %d iterations each; "
           "iterations and seconds to the plain start's final objective (within %g) and final objectives\n",
           PLAIN_ITERS, QUALITY_REL);
    experiment ex[7] = {
        PAPER_PIG_ARAP,
        PAPER_PIG_NH,
        PAPER_BAR3_ARAP,
        {"bar3 Neo-Hookean", "bar3", "bar3_init1.node", DF_ADMM_NEOHOOKEAN, 5e5, 0.1, 0, 0, 0},
        {"table ARAP", "table", NULL, DF_ADMM_ARAP, 0.1, TABLE_H, 0, 0, 0},
        PAPER_PIG_TEASER_NH,
        PAPER_APPLE_NH,
    };
    int only = -1, full = 0, bad = 0;
    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "full") == 0) full = 1;
        else if (strncmp(argv[a], "shrink=", 7) == 0) shrink = atof(argv[a] + 7);
        else only = atoi(argv[a]);
    }
    for (int i = 0; i < 7; i++) /* pig and bar3 Neo-Hookean (1, 3, 5) on request: ~45 s each here */
        if (only == i || (only < 0 && (ex[i].energy != DF_ADMM_NEOHOOKEAN || i == 6))) bad |= row(&ex[i], full);
    return bad;
}

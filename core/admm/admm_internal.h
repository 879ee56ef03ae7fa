/* admm_internal.h — private state of the SC-L1 ADMM solver shared by the files of core/admm.
 * Not part of the public API (see admm.h). */
#ifndef DF_ADMM_INTERNAL_H
#define DF_ADMM_INTERNAL_H

#include <cholmod.h>
#include <stdint.h>

#include "core/admm/admm.h"

enum { ADMM_FAM_VERTEX = 1, ADMM_FAM_ELEMENT = 2 };

/* Anderson acceleration history (Walker & Ni type II, Zhang et al. 2019 safeguard). */
typedef struct admm_anderson {
    int m, count, head;      /* capacity, stored columns, next slot */
    int64_t n;               /* state length */
    double *dF, *dG;         /* m columns of length n: differences of f = G(x) - x and of G(x) */
    double *f_prev, *g_prev; /* last accepted f and G(x) */
    double *gram;            /* m x m dF^T dF (symmetric, slot-indexed) */
    double *g_fallback;      /* plain ADMM iterate to revert to when a step is rejected */
    double r_prev;           /* |f| of the last accepted iterate, +inf when none */
    int have_prev, pending;  /* pending: the current state is an extrapolated (unverified) one */
    int nthreads;
} admm_anderson;

struct df_admm {
    df_admm_params p;
    df_mesh_kind kind;
    int planar;
    int32_t nv, ne, esz;
    int32_t *E;              /* ne x esz: the non-degenerate elements (admm_degen.c) */
    int32_t ne_in, *E_in;    /* the mesh's elements as given (reset_rest rebuilds from them) */
    int32_t *e_map;          /* ne: index of each kept element in E_in */
    df_admm_degenerate deg;  /* excluded elements and followers */
    int32_t *fo_v, *fo_ptr, *fo_src; /* followers in placement order, their source vertices */
    uint8_t *fo_flag;        /* nv (NULL without degenerate elements): 1 for a vertex of degenerate
                                elements only (follower or kept at rest): a_i = 0 */
    double *Vrest;           /* nv x 3 */
    int64_t n_state;         /* 6 nv (+ 9 ne for the element family) */
    double *state;           /* V | U | W (W only for the element family) */
    double *V, *U, *W;       /* views into state */
    double *Vout;            /* positions produced by the last global step (reported) */
    double *Z;               /* nv x 3 */
    double *a;               /* nv locality weights a_i */
    double max_a;
    int family;
    int nthreads;            /* OpenMP threads of the kernels */
    /* element family */
    int q;                   /* columns of F_e: 3 (tets), 2 (cloth triangles) */
    double *grad;            /* ne x esz x 3: g_{e,a}, F_e = sum_a V_a g_{e,a}^T (first q used) */
    double *vol;             /* ne rest measures */
    double *gam;             /* ne element penalty weights */
    double *RX;              /* ne x 9: R_e X_e (3 x q, row stride 3) */
    double *Ce;              /* ne x esz x 3: gam_e (R_e X_e - W_e) g_{e,a}, the global RHS pieces */
    double mu, lambda;
    double *nhQ, *nhx;       /* Neo-Hookean warm starts: ne x 9 eigenvectors, ne x 3 prox answers */
    int32_t *ve_ptr, *ve_ent;/* vertex -> (element * esz + corner) incidence */
    /* vertex family (spokes and rims) */
    int32_t *sr_ptr;         /* nv + 1: entries of vertex i's cell */
    int32_t *sr_a, *sr_b;    /* edge endpoints (d = V_b - V_a) */
    int32_t *sr_own;         /* entry -> vertex whose cell holds it */
    double *sr_w;            /* weights */
    double *sr_d;            /* rest edge vectors, 3 per entry */
    double *Rv;              /* nv x 9: s_i R_i of the last local step */
    int32_t *in_ptr, *in_ent;/* vertex -> signed entries (+(t+1): vertex is b, -(t+1): is a) */
    /* cloth bending: rows of the cotangent Laplacian at interior vertices, scaled by M^-1/2 */
    int32_t *bl_ptr, *bl_idx;
    double *bl_val;
    /* handles */
    int32_t nh;
    int32_t *hidx;
    double *target;          /* nh x 3: the targets the global step applies */
    double *target_req;      /* nh x 3: the targets set by df_admm_set_targets */
    int damp;                /* Neo-Hookean: damped handle steps (admm_damp.c) */
    int tgt_pending;         /* target != target_req */
    int damp_stall;          /* consecutive damped steps that could not move the handles */
    double *damp_va, *damp_dp; /* nv x 3 undamped global solution, nh x 3 pending handle step */
    int32_t nfree;
    int32_t *fidx;           /* nv -> free index or -1 */
    int32_t *fvert;          /* nfree -> vertex */
    int64_t ncpl;            /* K_fh entries */
    int32_t *cpl_f, *cpl_h;
    double *cpl_v;
    double *KfhP;            /* nfree x 3 (column-major like the RHS) */
    /* CHOLMOD */
    cholmod_common cc;
    int cc_started;
    cholmod_factor *L;
    cholmod_factor *Lsym;    /* adaptive penalties: copy of the supernodal symbolic analysis */
    struct admm_kcache *kcache; /* adaptive penalties: K split by part for refactorizations
                                (admm_system.c), NULL until the first one */
    cholmod_dense *rhs;      /* nfree x 3 column-major */
    cholmod_dense *sol, *sol_y, *sol_e; /* cholmod_solve2 result and workspaces, reused */
    /* affine constraints: Schur complement on top of the factorization */
    int n_arows;             /* scalar rows M */
    int32_t *ar_col;         /* row -> column of Y (distinct constrained vertex) */
    double *ar_A, *ar_b;     /* M x 3, M */
    int n_ycols;
    int32_t *yc_free;        /* Y column -> free index */
    double *Y;               /* nfree x n_ycols column-major: K_ff^-1 e_t */
    double *Sch;             /* M x M Cholesky factor (lower, column-major) */
    double *lam;             /* M work */
    df_admm_affine *aff;     /* copies of the affine sets (own verts arrays) */
    int naff;
    df_admm_stats st;
    double E_last;           /* objective of Vout, NAN when unknown */
    double el_last, lo_last; /* its elastic and locality parts, NAN when unknown */
    admm_anderson aa;
    struct admm_polish_cache *polish; /* df_admm_polish's CHOLMOD pattern/analysis (admm_newton.c) */
    struct admm_active *act; /* active-set mode state (admm_active.h), NULL until first used */
    int act_dirty;           /* the state outside the active region may be off rest (a full run or
                                set_positions since create / the last region build) */
    /* adaptive penalty (admm_rho.c); p.rho is the penalty in use */
    double rho_req;          /* params.rho as given (<= 0: adaptive) */
    int rho_adaptive;        /* 1: residual balancing changes p.rho */
    double rho_floor;        /* smallest penalty the balancing may choose (> w max(a_i) / s) */
    double rho_ceil;         /* largest one */
    int win_n, stall_pending;/* stall watch: iterations in the current window; a stall seen */
    double win_best, win_prev; /* best stop residual of the current / previous window (-1: none) */
    int rho_gap;             /* iterations between two penalty changes (refactorization cost) */
    int rho_wait;            /* iterations left before the next change may happen */
    int held_run;            /* consecutive held (inverted Neo-Hookean) iterates */
    int gam_locked;          /* 1: a lowering of the element penalties was undone (inverted
                                iterates); Neo-Hookean keeps g = 1 from then on */
    double best_since_change;/* best stop residual since the last penalty change */
    int g_trial;             /* iterations left in the trial of lowered element penalties (0: none) */
    double g_trial_ref, g_trial_best; /* best residual before the lowering / during the trial */
    double gscale;           /* element penalties: current gamma_e over the operators' gamma_e */
    int broken;              /* a failed refactorization could not restore the affine system */
};

/* admm_setup.c: operators for the current Vrest (element gradients, spokes and rims, a_i,
 * bending rows, incidence). Frees previous ones. */
int admm_build_operators(df_admm *s, df_error *err);
void admm_free_operators(df_admm *s);

/* admm_degen.c: sets s->E, s->ne (kept elements), s->E_in, s->e_map, s->deg and the follower
 * plan from mesh m (indices already checked), the handles and the affine sets. Errors: DF_EINVAL
 * (every element degenerate), DF_ENOMEM. admm_place_followers: V_f = Vrest_f + the mean
 * displacement V - Vrest of its sources (its neighbours in degenerate elements placed before it,
 * or only those at its very rest position when there are some), for every follower in order. */
int admm_filter_degenerate(df_admm *s, const df_mesh *m, const int32_t *handles, int32_t nh,
                           const df_admm_affine *aff, int naff, df_error *err);
void admm_place_followers(const df_admm *s, double *V);
void admm_free_degenerate(df_admm *s);

/* admm_system.c: assembles K, eliminates handles, analyzes + factorizes, affine Schur.
 * admm_solve: rhs (nfree x 3, already holding B + rho(...)) -> V (free rows, affine corrected). */
int admm_build_system_affine(df_admm *s, const df_admm_affine *aff, int naff, df_error *err);
void admm_free_system(df_admm *s);
void admm_update_kfhp(df_admm *s);
int admm_global_solve(df_admm *s, df_error *err);
/* solves K_ff x = rhs (s->rhs) with the affine correction towards A x = b (with_b = 1) or A x = 0;
 * *x points to the nfree x 3 column-major answer (valid until the next solve) */
int admm_solve_rhs(df_admm *s, int with_b, const double **x, df_error *err);

/* admm_system.c: a growing list of (i, j, v) entries, for the sparse assembly of the whole-mesh
 * system and of the active region's sub-system. Start from {0}; admm_trip_push appends one entry
 * (capacity doubled as needed; -1 when out of memory, the list kept as it was); admm_trip_free
 * frees the arrays and zeroes the list. */
typedef struct admm_trip {
    int64_t n, cap;
    int32_t *i, *j;
    double *v;
} admm_trip;
int admm_trip_push(admm_trip *t, int32_t i, int32_t j, double v);
void admm_trip_free(admm_trip *t);

/* admm_system.c: p.rho = rho_new and every gamma_e multiplied by gscale, K_ff reassembled (same
 * pattern) and refactored numerically (supernodal, from the kept symbolic copy Lsym), K_fh P and the affine Schur complement
 * rebuilt; on error the old weights are restored (s->broken if even that fails) */
int admm_system_refactor(df_admm *s, double rho_new, double gscale, df_error *err);
/* admm_system.c: frees the refactorizations' assembly cache (NULL-safe; admm_free_system calls it) */
void admm_kcache_free(df_admm *s);

/* admm_rho.c: the adaptive penalty (admm.h, DF_ADMM_RHO_RULE). admm_rho_init: at create, after the
 * operators, before the system is built: chooses p.rho when params.rho <= 0 (else keeps it) and
 * the floor. admm_rho_adapt: after an iteration with relative Z-block residuals pri_z, dual_z: may
 * change p.rho (numeric refactorization, U rescaled); *changed = 1 then. */
void admm_rho_init(df_admm *s);
void admm_rho_set_gap(df_admm *s);
struct admm_resid;
int admm_rho_adapt(df_admm *s, const struct admm_resid *rs, int held, double resid, int *changed,
                   df_error *err);

/* admm_damp.c: the global step; for Neo-Hookean moves the applied handle targets towards the
 * requested ones by the largest step (1, 1/2, ...) that leaves no element of V inverted */
int admm_global_step(df_admm *s, df_error *err);
/* the damped handle step shared by admm_global_step and the active-set run (admm_active_run.c),
 * which try t = 1, 1/2, ..., 2^-ADMM_DAMP_HALVINGS on their own vertex sets first.
 * admm_damp_choose: when no trial step avoids an inversion: t_min the smallest trial step, va_bad
 * 1 when V_a (t = 0) has an inverted element; returns the step to take: 0 (hold still, at most
 * ADMM_DAMP_MAX_STALL times in a row, counted in s->damp_stall) when V_a is fine, else t_min, or 1
 * when V_a is inverted (damping cannot help); resets the count when not holding.
 * admm_damp_apply: moves the applied targets by t dp (t = 1: exactly to target_req, nothing
 * pending). */
#define ADMM_DAMP_HALVINGS 7 /* smallest trial step 2^-7 */
double admm_damp_choose(df_admm *s, double t_min, int va_bad);
void admm_damp_apply(df_admm *s, double t);

/* admm_local.c: local steps and the global right-hand side. admm_local_x_one: local step 1 of
 * element e (R_e X_e) and its right-hand side pieces Ce (element family only). */
void admm_local_x_one(df_admm *s, int32_t e);
/* the same from G = F_e(V) + W_e computed by the caller (the active-set run keeps it from its
 * dual update, admm_active_run.c): bit-identical to admm_local_x_one when G holds exactly
 * admm_element_F(V, e) + W_e summed in that order; G is scratch afterwards */
void admm_local_x_one_G(df_admm *s, int32_t e, double G[9]);
/* admm_tet4.c: dual update of the tet elements ae[0..n) (s->esz 4, s->q 3; any energy) four at
 * a time, bit-identical to admm_active_elem.c's per-element update: W_e += F_e(V) - R_e X_e, F_e(V)
 * into fb row k (n x 9, ae order), element k's terms gam |dW|^2, gam |F|^2, gam |W new|^2 and its
 * energy (0 when lazy) into t[4k .. 4k + 3]. No threads of its own. */
void admm_dual_tet4(df_admm *s, const int32_t *ae, double *fb, int32_t n, int lazy, double *t);
/* admm_tet4.c: elastic energies (ARAP / ACAP tets) of the elements ae[0..n) from their F rows fb
 * (n x 9, ae order) into out[0..n), bit-identical to admm_element_energy_F. No threads. */
void admm_energy_tet4(const df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *out);
/* admm_tet4.c: |grad_i E_elastic| at positions V for vertex i of an ARAP / ACAP tet mesh (the
 * active-set certificate's force norm: the moved elements around i, four at a time), bit-identical
 * to the per-element sum in admm_active.c. No threads. */
double admm_force_tet4(const df_admm *s, const double *V, int32_t i);
/* admm_tet4.c: local step 1 of the ARAP / ACAP tet elements ae[0..n) (s->q 3, s->esz 4)
 * four at a time, G_k = fb row k (F_e(V), n x 9 in ae order) + W_e, writing RX and Ce of each,
 * bit-identical to admm_local_x_one_G per element; *s2 += sum gam_e |RX_e new - old|^2 and
 * *z2 += sum gam_e |RX_e new|^2, summed in ae order within the call. No threads of its own. */
void admm_local_tet4(df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *s2, double *z2);
void admm_local_x(df_admm *s);
void admm_local_z(df_admm *s);
void admm_assemble_rhs(df_admm *s);
/* the global right-hand side rows of the nf vertices verts (free vertices, no handles): for row f,
 * vertex v = verts[f], column k: the element (cell) pieces gathered at v + rho (Vrest + Z - U)_v,k
 * - sub[f + k nf], written to rhs[f + k nf] (both nf x 3 column-major). par: fork OpenMP threads.
 * admm_assemble_rhs is this over the whole mesh's free vertices (sub = K_fh P); the active-set run
 * over its region's (sub = the outside couplings). */
void admm_rhs_rows(const df_admm *s, const int32_t *verts, int32_t nf, const double *sub, double *rhs,
                   int par);
/* row f of admm_rhs_rows (no threads of its own: for callers' own parallel loops) */
void admm_rhs_row(const df_admm *s, const int32_t *verts, int32_t nf, const double *sub, double *rhs, int32_t f);
/* dual updates; for the element family also returns sum_e E_e(F_e(V)) (the elastic energy of V
 * without bending, from the same F_e), else 0 */
double admm_dual_update(df_admm *s);

/* admm_active.c: the active-set mode (admm.h DF_ADMM_ACTIVE). admm_active_run runs df_admm_run
 * in active mode and sets *handled = 1, or sets *handled = 0 (then the caller runs the full solve,
 * after which the active state is marked stale); admm_active_stale marks the state outside the
 * region as possibly not at rest (df_admm_set_positions); admm_active_free frees it (before
 * cholmod_finish). */
int admm_active_run(df_admm *s, const df_admm_budget *budget, df_admm_result *res, int *handled,
                    df_error *err);
void admm_active_stale(df_admm *s);
/* 1 when df_admm_create may skip the whole-mesh factorization (params.active and the features
 * the active mode covers); the full system is then built by the first full run */
int admm_active_defers(const df_admm *s);
/* builds the active mode's mesh-sized tables (vertex graph, maps) at create: O(mesh), once.
 * Errors: DF_ENOMEM. */
int admm_active_prepare(df_admm *s, df_error *err);
void admm_active_free(df_admm *s);

/* admm_energy.c: objective pieces at positions V; elastic is +inf for inverted NH elements.
 * admm_fit_vertex: best s_i R_i (row-major 3x3) of vertex i's cell at V (ACAP: s_i analytic). */
void admm_fit_vertex(const df_admm *s, const double *V, int32_t i, double SR[9]);
double admm_elastic(const df_admm *s, const double *V);
double admm_locality(const df_admm *s, const double *V);
double admm_bending(const df_admm *s, const double *V);
double admm_element_energy_F(const df_admm *s, int32_t e, const double F[9]);
/* the ARAP / ACAP stress direction P = F - sc R (row-major 3 x 3; R the polar rotation of F, by
 * the SVD where the closed form fails; sc = 1 for ARAP, tr(R^T F) / 3 for ACAP): the elastic
 * gradient of an element is vol_e P g_{e,a} at corner a */
void admm_rot_stress(const df_admm *s, const double F[9], double P[9]);
/* elastic energy of vertex i's spokes-and-rims cell at V (vertex family): sum over its entries t
 * of sr_w[t] / 2 |s_i R_i d_t - (V_b - V_a)|^2 with s_i R_i = admm_fit_vertex(V, i) */
double admm_vertex_energy(const df_admm *s, const double *V, int32_t i);

/* F_e(V) = sum_a V_a g_{e,a}^T of kept element e (3 x q, row stride 3, unused columns 0); inline
 * for the per-element loops of the full and the active-set paths (one summation order for both) */
static inline __attribute__((always_inline)) void admm_element_F(const df_admm *s, const double *V, int32_t e, double F[9])
{
    const int32_t *el = s->E + (size_t)e * s->esz;
    const double *g = s->grad + (size_t)e * s->esz * 3;
    for (int k = 0; k < 9; k++) F[k] = 0.0;
    if (s->esz == 4 && s->q == 3) { /* tets: the same sums with constant bounds (unrolled) */
        for (int a = 0; a < 4; a++) {
            const double *x = V + 3 * (size_t)el[a];
            const double *ga = g + 3 * a;
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) F[3 * r + c] += x[r] * ga[c];
        }
        return;
    }
    for (int a = 0; a < s->esz; a++) {
        const double *x = V + 3 * (size_t)el[a];
        const double *ga = g + 3 * a;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < s->q; c++) F[3 * r + c] += x[r] * ga[c];
    }
}

/* det of a row-major 3 x 3 matrix */
static inline double admm_det3(const double F[9])
{
    return F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
           F[2] * (F[3] * F[7] - F[4] * F[6]);
}

/* admm_anderson.c */
int admm_aa_init(admm_anderson *aa, int m, int64_t n);
void admm_aa_free(admm_anderson *aa);
void admm_aa_reset(admm_anderson *aa);
int admm_aa_step(admm_anderson *aa, const double *x_before, double *state);

/* admm_newton.c: frees the polish cache (NULL-safe) */
void admm_polish_free(df_admm *s);

/* admm_params.c */
int admm_validate_params(const df_admm_params *p, df_error *err);

/* helpers */
double admm_now(void);

#endif

/* admm_active.h — private state of the active-set mode (admm.h DF_ADMM_ACTIVE), shared by
 * admm_active.c (region, sub-system, certificate) and admm_active_run.c (restricted iterations).
 * Not part of the public API. */
#ifndef DF_ADMM_ACTIVE_H
#define DF_ADMM_ACTIVE_H

#include <cholmod.h>
#include <stdint.h>

#include "core/admm/admm_internal.h"

/* a region's loops fork threads only when they have this much work: an OpenMP fork/join (a futex
 * wake-up with the passive wait policy) costs tens of microseconds, a whole light loop over a
 * small region less */
#define ACT_PAR_HEAVY 1024      /* elements / cells with a local solve (polar, SVD, prox) */
#define ACT_PAR_LIGHT 16384     /* a few dozen flops per item */
/* elements per work item of the 4-lane tet kernels (admm_tet4.c) in the region's loops */
#define ACT_TET4_CHUNK 256

typedef struct admm_active {
    int valid;               /* region built and every vertex outside it exactly at rest */
    int band, check_every;
    /* vertex graph (CSR, built once): vertices sharing an element / a spokes-and-rims entry */
    int32_t *adj_ptr, *adj;
    int32_t *hmap;           /* nv: handle index or -1 */
    /* region */
    uint8_t *in;             /* nv: 1 in the region */
    int32_t *depth;          /* nv: hops to the nearest outside vertex (region), 0 outside */
    int32_t nr, *rv;         /* region vertices */
    int32_t nfr, *fr;        /* fringe: outside vertices next to the region */
    int32_t nedge, *edge;    /* edge: region vertices next to the fringe (depth 1) */
    int32_t tail_added;      /* vertices the tail test added since the last fresh build */
    int32_t nae, *ae, *ae2;  /* elements touching the region (vertex family: cells of region and
                                fringe vertices); ae2: scratch of the same size */
    uint8_t *emark;          /* ne (element family) or nv (cells): 1 when in ae */
    int32_t *work;           /* nv scratch (BFS queue, the certificate's verdicts) */
    int32_t *tbud;           /* nv scratch: the tail test's ring budget per vertex */
    uint32_t *stamp, gen;    /* nv visit stamps (no clearing per pass) */
    uint32_t *tstamp, tgen;  /* spokes-and-rims entry stamps (vertex family) */
    int kfhp_dirty;          /* handle targets moved by a damped step: the full system's K_fh P is
                                stale (refreshed before any full run) */
    int bypass;              /* set while the active run finishes with the full solve */
    int32_t nsup, *sup;      /* support (scratch list, nv) */
    int32_t nhs, *hs;        /* handles off rest (nh capacity): admm_act_support's handle scan */
    int hs_ok;               /* hs holds this run's list (steady within a run: see admm_act_support) */
    /* sub-system on the region's free vertices (region minus handles) */
    int32_t nrf, *rfv;       /* free region vertex list */
    int32_t *rfidx;          /* nv: index in rfv or -1 */
    int64_t ncp;             /* couplings K(free region vertex, handle) */
    int32_t *cp_f, *cp_v;    /* free index, handle vertex */
    double *cp_val;
    double *kout;            /* nrf x 3 (column-major): K(free, outside) Vrest(outside) */
    cholmod_factor *L;
    cholmod_dense *rhs, *sol, *sol_y, *sol_e;
    double rho_fact;         /* rho of the factor */
    /* residual scale of the elements outside (constant 3 sum gam_e |I|^2 of the far field) */
    double gam3_all, gam3_ae; /* over all elements, over the region's elements */
    /* damped steps: the undamped global solution on the region (nr x 3, capacity cap_v) */
    int64_t cap_v;
    double *va;
    /* the tail test's probe (admm_active_tail.c): the region's state at the start of a run on a
     * fresh region */
    int32_t pr_nr, *pr_rv, pr_nae, *pr_ae;
    int64_t pr_cap_v, pr_cap_e;
    double *pr_v, *pr_e;     /* per vertex V U Z Vout (12), per element W R X (18) */
    uint8_t *pr_mark;        /* ne scratch */
    double pr_E, pr_el, pr_lo;
    df_admm_active_stats st;
    /* element family: two buffers (capacity cap_gc elements each) of F_e(V) of the region's
     * elements (nae x 9, in ae order), written by the dual updates in turn, read by the next local
     * step (G = F + W) and the lazy energy (admm_active_run.c); gc_ok 1 while buffer gc_buf
     * matches V and ae (cleared at a run's start and by every region build) */
    double *gc;              /* also the partial sums of admm_active_elem.c after the two buffers:
                                cap_gc x 4 doubles at gc + 18 cap_gc */
    int64_t cap_gc;
    int gc_ok, gc_buf;
} admm_active;

/* admm_active.c */
int admm_act_init(df_admm *s, df_error *err);                 /* allocates s->act (once) */
/* (re)builds the region: fresh (from the support only; vertices leaving it are snapped to rest)
 * or grown (union with the current region); refactors. extra (n_extra vertices) join the region
 * themselves, without rings around them (the tail test's one-ring growth). */
int admm_act_build(df_admm *s, int fresh, const int32_t *extra, int32_t n_extra, df_error *err);
/* support scan over the region (or, stale, the whole mesh) into act->sup: the vertices with
 * Z != 0 and the handles off rest (target, requested target, V or Vout). iter: a call after an
 * iteration's global step, which reuses the handle list of the run's first such call (hs_ok;
 * without damped handle steps, targets, V and Vout of the handles stay put within a run: V =
 * target after every global step); admm_active_run.c clears hs_ok at a run's start, a region
 * build and the probe's restore */
void admm_act_support(df_admm *s, int whole, int iter);
/* size of the region a fresh build from act->sup would have (support grown by band rings) */
int32_t admm_act_fresh_size(df_admm *s);
/* 1 when a support vertex lies within band - 1 rings of the region's edge or outside it */
int admm_act_needs_grow(const df_admm *s);
/* far-field certificate: appends the failing fringe vertices to act->sup after its nsup entries
 * (nsup unchanged, fringe order) and returns their number; the fringe scan on the solver's team
 * from ACT_CERT_PAR fringe vertices (admm_active.c), act->work as scratch */
int32_t admm_act_certify(df_admm *s);
/* sub-system solve: rhs already in act->rhs; *x the nrf x 3 column-major answer */
int admm_act_solve(df_admm *s, const double **x, df_error *err);
int admm_act_buffers(df_admm *s, df_error *err);

/* next generation of a stamp array (a->stamp: nv entries, a->tstamp: spokes-and-rims entries) */
uint32_t admm_act_stamp(admm_active *a, uint32_t *arr, size_t n);

/* admm_active_tail.c. Tail test (admm.h DF_ADMM_ACTIVE, "Tail test"): when the summed SC-L1
 * charge w a_i |Vout_i - Vrest_i| of the edge exceeds tol |E|, appends to act->sup after its nsup
 * entries (nsup unchanged) the outside vertices within the predicted number of rings of each edge
 * vertex whose charge exceeds tol |E| / nedge, and returns their number (0: no growth). Probe:
 * admm_act_probe_save saves the region's state (and the objective) / puts it back after the
 * region grew (elements that entered get their local step from the restored positions) / frees */
int32_t admm_act_tail(df_admm *s, double E, double tol);
int admm_act_probe_save(df_admm *s, df_error *err);
void admm_act_probe_restore(df_admm *s);
void admm_act_probe_free(admm_active *a);

/* admm_active_elem.c: the region's element sums (element family), threaded from ACT_PAR_HEAVY
 * elements with sums bit-identical to one thread's below ACT_PAR_LIGHT (file header).
 * admm_act_dual_elems: W_e += F_e(V) - R_e X_e for the region's elements (s->V, s->RX, s->W),
 * F_e(V) into fb (nae x 9, ae order) when fb is not NULL; *r2, *ax2, *y2: the sums of gam_e
 * |F - R X|^2, gam_e |F|^2, gam_e |W_e|^2 (new W); returns the elastic energy sum_e E_e(F_e(V)),
 * 0 when lazy. admm_act_energy: the elastic energy of the region's elements from fb (nae x 9, ae
 * order) or, fb NULL, from F_e(V). Called from the solver's thread; no allocation, no errors. */
double admm_act_dual_elems(df_admm *s, double *fb, int lazy, double *r2, double *ax2, double *y2);
double admm_act_energy(const df_admm *s, const double *fb, const double *V);

#endif

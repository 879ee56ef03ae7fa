/* admm_active.c — the active region of the active-set mode (admm.h DF_ADMM_ACTIVE): the vertex
 * graph, the support, the region (support grown by `band` rings) with its fringe, depths and
 * elements, the snap of everything outside to rest, the principal sub-system of the global matrix
 * on the region's free vertices (CHOLMOD analysis + factorization, cached while the region and
 * rho are unchanged), the far-field certificate and the tail test's edge charge. The restricted
 * iterations are in admm_active_run.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_active.h"

/* the far-field certificate's fringe scan forks threads from this many fringe vertices (each
 * costs a dozen element stresses) */
#define ACT_CERT_PAR 128

void admm_active_stale(df_admm *s)
{
    if (!s) return;
    s->act_dirty = 1;
    if (s->act) s->act->valid = 0;
}

static void free_factor(df_admm *s)
{
    admm_active *a = s->act;
    if (!s->cc_started) return;
    if (a->L) cholmod_free_factor(&a->L, &s->cc);
    if (a->rhs) cholmod_free_dense(&a->rhs, &s->cc);
    if (a->sol) cholmod_free_dense(&a->sol, &s->cc);
    if (a->sol_y) cholmod_free_dense(&a->sol_y, &s->cc);
    if (a->sol_e) cholmod_free_dense(&a->sol_e, &s->cc);
}

void admm_active_free(df_admm *s)
{
    if (!s || !s->act) return;
    admm_active *a = s->act;
    free_factor(s);
    free(a->adj_ptr); free(a->adj); free(a->hmap); free(a->in); free(a->depth); free(a->rv);
    free(a->fr); free(a->edge); free(a->ae); free(a->ae2); free(a->emark); free(a->work); free(a->sup); free(a->rfv);
    free(a->rfidx); free(a->cp_f); free(a->cp_v); free(a->cp_val); free(a->kout); free(a->stamp); free(a->tstamp); free(a->tbud); free(a->hs);
    free(a->va); free(a->gc);
    admm_act_probe_free(a);
    free(a);
    s->act = NULL;
}

/* neighbours of every vertex: vertices sharing an element (element family) or a spokes-and-rims
 * entry (vertex family), deduplicated with a stamp array */
static int build_graph(df_admm *s, admm_active *a)
{
    int32_t nv = s->nv;
    int32_t *last = malloc((size_t)nv * sizeof(int32_t));
    a->adj_ptr = calloc((size_t)nv + 1, sizeof(int32_t));
    if (!last || !a->adj_ptr) { free(last); return -1; }
    for (int pass = 0; pass < 2; pass++) {
        for (int32_t i = 0; i < nv; i++) last[i] = -1;
        for (int32_t v = 0; v < nv; v++) {
            int32_t cnt = 0, base = pass ? a->adj_ptr[v] : 0;
            last[v] = v;
            if (s->family == ADMM_FAM_ELEMENT) {
                for (int32_t p = s->ve_ptr[v]; p < s->ve_ptr[v + 1]; p++) {
                    const int32_t *el = s->E + (size_t)(s->ve_ent[p] / s->esz) * s->esz;
                    for (int c = 0; c < s->esz; c++)
                        if (last[el[c]] != v) {
                            last[el[c]] = v;
                            if (pass) a->adj[base + cnt] = el[c];
                            cnt++;
                        }
                }
            } else {
                for (int32_t p = s->in_ptr[v]; p < s->in_ptr[v + 1]; p++) {
                    int32_t se = s->in_ent[p], t = (se > 0 ? se : -se) - 1;
                    int32_t ends[3] = {s->sr_a[t], s->sr_b[t], s->sr_own[t]};
                    for (int c = 0; c < 3; c++)
                        if (last[ends[c]] != v) {
                            last[ends[c]] = v;
                            if (pass) a->adj[base + cnt] = ends[c];
                            cnt++;
                        }
                }
            }
            if (!pass) a->adj_ptr[v + 1] = cnt;
        }
        if (!pass) {
            for (int32_t v = 0; v < nv; v++) a->adj_ptr[v + 1] += a->adj_ptr[v];
            a->adj = malloc(((size_t)a->adj_ptr[nv] + 1) * sizeof(int32_t));
            if (!a->adj) { free(last); return -1; }
        }
    }
    free(last);
    return 0;
}

int admm_act_init(df_admm *s, df_error *err)
{
    if (s->act && s->act->adj) return DF_OK;
    if (!s->act) {
        s->act = calloc(1, sizeof(admm_active));
        if (!s->act) return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (active set)");
    }
    admm_active *a = s->act;
    if (!s->cc_started) { /* the whole-mesh system was deferred (admm_active_defers) */
        cholmod_start(&s->cc);
        s->cc.print = 0;
        s->cc_started = 1;
    }
    a->band = s->p.active_band > 0 ? s->p.active_band : DF_ADMM_ACTIVE_BAND;
    a->check_every = s->p.active_check_every > 0 ? s->p.active_check_every : DF_ADMM_ACTIVE_CHECK;
    size_t nv = (size_t)s->nv, nm = s->family == ADMM_FAM_ELEMENT ? (size_t)s->ne : nv;
    a->hmap = malloc(nv * sizeof(int32_t));
    a->in = calloc(nv, 1);
    a->depth = calloc(nv, sizeof(int32_t));
    a->rv = malloc(nv * sizeof(int32_t));
    a->fr = malloc(nv * sizeof(int32_t));
    a->edge = malloc(nv * sizeof(int32_t));
    a->ae = malloc(nm * sizeof(int32_t));
    a->ae2 = malloc(nm * sizeof(int32_t));
    a->emark = calloc(nm, 1);
    a->work = malloc(nv * sizeof(int32_t));
    a->sup = malloc(nv * sizeof(int32_t));
    a->rfv = malloc(nv * sizeof(int32_t));
    a->rfidx = malloc(nv * sizeof(int32_t));
    a->stamp = calloc(nv, sizeof(uint32_t));
    a->tbud = malloc(nv * sizeof(int32_t));
    a->hs = malloc(((size_t)s->nh + 1) * sizeof(int32_t));
    if (s->family == ADMM_FAM_VERTEX) a->tstamp = calloc((size_t)s->sr_ptr[s->nv] + 1, sizeof(uint32_t));
    if (!a->hmap || !a->in || !a->depth || !a->rv || !a->fr || !a->edge || !a->ae || !a->ae2 || !a->emark || !a->work || !a->sup ||
        !a->rfv || !a->rfidx || !a->stamp || !a->tbud || !a->hs || (s->family == ADMM_FAM_VERTEX && !a->tstamp) || build_graph(s, a)) {
        df_admm_active_stats keep = a->st;
        admm_active_free(s);
        s->act = calloc(1, sizeof(admm_active));
        if (s->act) s->act->st = keep;
        return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (active set)");
    }
    for (size_t i = 0; i < nv; i++) { a->hmap[i] = -1; a->rfidx[i] = -1; }
    for (int32_t h = 0; h < s->nh; h++) a->hmap[s->hidx[h]] = h;
    a->gam3_all = 0;
    if (s->family == ADMM_FAM_ELEMENT)
        for (int32_t e = 0; e < s->ne; e++) a->gam3_all += 3.0 * s->gam[e];
    return DF_OK;
}

int admm_active_prepare(df_admm *s, df_error *err) { return admm_act_init(s, err); }

uint32_t admm_act_stamp(admm_active *a, uint32_t *arr, size_t n)
{
    uint32_t *gen = arr == a->stamp ? &a->gen : &a->tgen;
    if (++*gen == 0) { /* wrapped: clear */
        memset(arr, 0, n * sizeof(uint32_t));
        *gen = 1;
    }
    return *gen;
}

static int differs3(const double *x, const double *y) { return x[0] != y[0] || x[1] != y[1] || x[2] != y[2]; }

void admm_act_support(df_admm *s, int whole, int iter)
{
    admm_active *a = s->act;
    int32_t n = 0;
    uint32_t g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    const double zero[3] = {0, 0, 0};
    if (whole) {
        for (int32_t i = 0; i < s->nv; i++)
            if (differs3(s->Z + 3 * (size_t)i, zero)) { a->sup[n++] = i; a->stamp[i] = g; }
    } else {
        for (int32_t k = 0; k < a->nr; k++) {
            int32_t i = a->rv[k];
            if (differs3(s->Z + 3 * (size_t)i, zero)) { a->sup[n++] = i; a->stamp[i] = g; }
        }
    }
    /* the handles off rest: from the run's list (iter: no damped steps, list made this run), or
     * by a scan over all handles, kept as the run's list when iter */
    int cache = iter && !s->damp && a->hs;
    if (!(cache && a->hs_ok)) {
        a->nhs = 0;
        for (int32_t h = 0; h < s->nh; h++) {
            int32_t v = s->hidx[h];
            const double *r = s->Vrest + 3 * (size_t)v;
            if (differs3(s->target + 3 * (size_t)h, r) || differs3(s->target_req + 3 * (size_t)h, r) ||
                differs3(s->V + 3 * (size_t)v, r) || differs3(s->Vout + 3 * (size_t)v, r))
                a->hs[a->nhs++] = v;
        }
        a->hs_ok = cache;
    }
    for (int32_t k = 0; k < a->nhs; k++) {
        int32_t v = a->hs[k];
        if (a->stamp[v] != g) {
            a->sup[n++] = v;
            a->stamp[v] = g;
        }
    }
    a->nsup = n;
}

int admm_act_needs_grow(const df_admm *s)
{
    const admm_active *a = s->act;
    for (int32_t k = 0; k < a->nsup; k++) {
        int32_t v = a->sup[k];
        if (!a->in[v] || a->depth[v] <= a->band - 1) return 1;
    }
    return 0;
}

int32_t admm_act_fresh_size(df_admm *s)
{
    admm_active *a = s->act;
    uint32_t g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    int32_t qh = 0, qt = 0;
    for (int32_t k = 0; k < a->nsup; k++)
        if (a->stamp[a->sup[k]] != g) { a->stamp[a->sup[k]] = g; a->work[qt++] = a->sup[k]; }
    for (int lev = 0; lev < a->band; lev++) { /* level by level: no distance array needed */
        int32_t end = qt;
        for (; qh < end; qh++) {
            int32_t v = a->work[qh];
            for (int32_t p = a->adj_ptr[v]; p < a->adj_ptr[v + 1]; p++)
                if (a->stamp[a->adj[p]] != g) { a->stamp[a->adj[p]] = g; a->work[qt++] = a->adj[p]; }
        }
    }
    return qt;
}

static int cmp_i32(const void *x, const void *y)
{
    int32_t u = *(const int32_t *)x, v = *(const int32_t *)y;
    return (u > v) - (u < v);
}

static void snap_vertex(df_admm *s, int32_t i)
{
    size_t o = 3 * (size_t)i;
    memcpy(s->V + o, s->Vrest + o, 3 * sizeof(double));
    memcpy(s->Vout + o, s->Vrest + o, 3 * sizeof(double));
    memset(s->U + o, 0, 3 * sizeof(double));
    memset(s->Z + o, 0, 3 * sizeof(double));
}

/* the region's lists after in[] changed: fringe, depths, elements / cells (entering ones get their
 * local step so the residual snapshot sees current values, elements on the team from
 * ACT_PAR_HEAVY region elements; leaving ones W = 0) */
static void region_lists(df_admm *s, admm_active *a)
{
    qsort(a->rv, (size_t)a->nr, sizeof(int32_t), cmp_i32); /* memory order (as ae below) */
    uint32_t g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    a->nfr = 0;
    for (int32_t k = 0; k < a->nr; k++) {
        int32_t v = a->rv[k];
        a->stamp[v] = g;
        for (int32_t p = a->adj_ptr[v]; p < a->adj_ptr[v + 1]; p++) {
            int32_t u = a->adj[p];
            if (!a->in[u] && a->stamp[u] != g) { a->stamp[u] = g; a->fr[a->nfr++] = u; }
        }
    }
    /* depths: multi-source BFS from the fringe into the region */
    g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    int32_t qh = 0, qt = 0;
    for (int32_t k = 0; k < a->nfr; k++) { a->work[qt++] = a->fr[k]; a->stamp[a->fr[k]] = g; a->depth[a->fr[k]] = 0; }
    while (qh < qt) {
        int32_t v = a->work[qh++];
        for (int32_t p = a->adj_ptr[v]; p < a->adj_ptr[v + 1]; p++) {
            int32_t u = a->adj[p];
            if (a->in[u] && a->stamp[u] != g) { a->stamp[u] = g; a->depth[u] = a->depth[v] + 1; a->work[qt++] = u; }
        }
    }
    a->nedge = 0;
    for (int32_t k = 0; k < a->nr; k++) { /* a region component with no fringe (the whole mesh) */
        if (a->stamp[a->rv[k]] != g) a->depth[a->rv[k]] = INT32_MAX;
        else if (a->depth[a->rv[k]] == 1) a->edge[a->nedge++] = a->rv[k];
    }
    /* elements (cells): previous marks 1 -> 2; this pass marks 1 (new) or 3 (kept) into ae2 */
    for (int32_t k = 0; k < a->nae; k++) a->emark[a->ae[k]] = 2;
    int32_t n = 0;
    double gsum = 0;
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t k = 0; k < a->nr; k++) {
            int32_t v = a->rv[k];
            for (int32_t p = s->ve_ptr[v]; p < s->ve_ptr[v + 1]; p++) {
                int32_t e = s->ve_ent[p] / s->esz;
                if (a->emark[e] & 1) continue;
                a->emark[e] = a->emark[e] == 2 ? 3 : 1;
                a->ae2[n++] = e;
                gsum += 3.0 * s->gam[e];
            }
        }
    } else {
        for (int pass = 0; pass < 2; pass++) {
            const int32_t *list = pass ? a->fr : a->rv;
            int32_t cnt = pass ? a->nfr : a->nr;
            for (int32_t k = 0; k < cnt; k++) {
                int32_t v = list[k];
                if (a->emark[v] == 0) admm_fit_vertex(s, s->V, v, s->Rv + 9 * (size_t)v);
                a->emark[v] = a->emark[v] == 2 ? 3 : 1;
                a->ae2[n++] = v;
            }
        }
    }
    if (s->family == ADMM_FAM_ELEMENT) { /* entering elements (mark 1): their local step, on the team */
        #pragma omp parallel for schedule(dynamic, 256) num_threads(s->nthreads) if (n >= ACT_PAR_HEAVY)
        for (int32_t k = 0; k < n; k++)
            if (a->emark[a->ae2[k]] == 1) admm_local_x_one(s, a->ae2[k]);
    }
    for (int32_t k = 0; k < a->nae; k++) { /* leaving: still 2; their vertices are at rest now */
        int32_t e = a->ae[k];
        if (a->emark[e] != 2) continue;
        a->emark[e] = 0;
        if (s->W) memset(s->W + 9 * (size_t)e, 0, 9 * sizeof(double));
    }
    for (int32_t k = 0; k < n; k++) a->emark[a->ae2[k]] = 1;
    int32_t *tmp = a->ae;
    a->ae = a->ae2;
    a->ae2 = tmp;
    a->nae = n;
    a->gam3_ae = gsum;
    /* memory order: the element loops of every iteration then walk the per-element arrays
     * (RX, W, grad, gam, vol) and the vertex rows forward instead of in BFS order */
    qsort(a->ae, (size_t)n, sizeof(int32_t), cmp_i32);
}

/* one entry K(i, j) of the global matrix into the sub-system (free row i) or its couplings */
static int emit(const admm_active *a, admm_trip *kff, admm_trip *cpl, int32_t i, int32_t j, double v)
{
    int32_t fi = a->rfidx[i], fj = a->rfidx[j];
    if (fi < 0) return 0;
    if (fj >= 0) return fi <= fj ? admm_trip_push(kff, fi, fj, v) : 0;
    return admm_trip_push(cpl, fi, j, v);
}

/* the principal submatrix of K on the region's free vertices, its couplings to fixed vertices
 * (handles and the outside), analysis + factorization */
static int factor_sub(df_admm *s, admm_active *a, df_error *err)
{
    for (int32_t k = 0; k < a->nrf; k++) a->rfidx[a->rfv[k]] = -1;
    a->nrf = 0;
    for (int32_t k = 0; k < a->nr; k++) {
        int32_t v = a->rv[k];
        if (a->hmap[v] < 0) { a->rfidx[v] = a->nrf; a->rfv[a->nrf++] = v; }
    }
    free_factor(s);
    free(a->cp_f); free(a->cp_v); free(a->cp_val);
    a->cp_f = a->cp_v = NULL;
    a->cp_val = NULL;
    a->ncp = 0;
    a->rho_fact = s->p.rho;
    if (a->nrf == 0) return DF_OK;
    admm_trip kff = {0}, cpl = {0};
    int rc = 0;
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t k = 0; k < a->nae && !rc; k++) {
            int32_t e = a->ae[k];
            const int32_t *el = s->E + (size_t)e * s->esz;
            const double *g = s->grad + (size_t)e * s->esz * 3;
            for (int x = 0; x < s->esz; x++)
                for (int y = 0; y < s->esz; y++) {
                    double d = 0;
                    for (int c = 0; c < s->q; c++) d += g[3 * x + c] * g[3 * y + c];
                    rc |= emit(a, &kff, &cpl, el[x], el[y], s->gam[e] * d);
                }
        }
    } else {
        uint32_t tg = admm_act_stamp(a, a->tstamp, (size_t)s->sr_ptr[s->nv] + 1);
        for (int32_t k = 0; k < a->nr && !rc; k++) {
            int32_t v = a->rv[k];
            for (int32_t p = s->in_ptr[v]; p < s->in_ptr[v + 1] && !rc; p++) {
                int32_t se = s->in_ent[p], t = (se > 0 ? se : -se) - 1;
                if (a->tstamp[t] == tg) continue;
                a->tstamp[t] = tg;
                int32_t x = s->sr_a[t], y = s->sr_b[t];
                double w = s->sr_w[t];
                rc |= emit(a, &kff, &cpl, x, x, w);
                rc |= emit(a, &kff, &cpl, y, y, w);
                rc |= emit(a, &kff, &cpl, x, y, -w);
                rc |= emit(a, &kff, &cpl, y, x, -w);
            }
        }
    }
    for (int32_t f = 0; f < a->nrf && !rc; f++) rc |= admm_trip_push(&kff, f, f, s->p.rho);
    /* couplings to the outside (at rest, constant while the region stands) summed into kout;
     * those to handles (targets change) kept in the cp list */
    free(a->kout);
    a->kout = rc ? NULL : calloc((size_t)a->nrf * 3, sizeof(double));
    if (!a->kout) rc = 1;
    int64_t nh = 0;
    for (int64_t t = 0; t < cpl.n && !rc; t++) {
        int32_t v = cpl.j[t];
        if (a->hmap[v] >= 0) {
            cpl.i[nh] = cpl.i[t]; cpl.j[nh] = v; cpl.v[nh] = cpl.v[t]; nh++;
            continue;
        }
        for (int c = 0; c < 3; c++) a->kout[cpl.i[t] + (size_t)c * a->nrf] += cpl.v[t] * s->Vrest[3 * (size_t)v + c];
    }
    a->ncp = nh;
    a->cp_f = cpl.i; a->cp_v = cpl.j; a->cp_val = cpl.v;
    if (rc) {
        admm_trip_free(&kff);
        return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (active sub-system)");
    }
    cholmod_triplet *T = cholmod_allocate_triplet(a->nrf, a->nrf, (size_t)kff.n, 1, CHOLMOD_REAL, &s->cc);
    if (!T) { admm_trip_free(&kff); return df_error_set(err, DF_ENOMEM, "admm_run: CHOLMOD out of memory"); }
    memcpy(T->i, kff.i, (size_t)kff.n * sizeof(int32_t));
    memcpy(T->j, kff.j, (size_t)kff.n * sizeof(int32_t));
    memcpy(T->x, kff.v, (size_t)kff.n * sizeof(double));
    T->nnz = (size_t)kff.n;
    admm_trip_free(&kff);
    cholmod_sparse *K = cholmod_triplet_to_sparse(T, (size_t)T->nnz, &s->cc);
    cholmod_free_triplet(&T, &s->cc);
    if (!K) return df_error_set(err, DF_ENOMEM, "admm_run: CHOLMOD out of memory");
    /* a region is small and refactored as it grows: AMD only (no METIS / nested-dissection
     * trials) and a simplicial factor (solved with 3 right-hand sides, like the full system's);
     * the common's settings are restored for the whole-mesh system */
    int nm = s->cc.nmethods, sn = s->cc.supernodal, ord = s->cc.method[0].ordering;
    s->cc.nmethods = 1;
    s->cc.method[0].ordering = CHOLMOD_AMD;
    s->cc.supernodal = CHOLMOD_SIMPLICIAL;
    a->L = cholmod_analyze(K, &s->cc);
    s->st.analyses++;
    int ok = a->L && cholmod_factorize(K, a->L, &s->cc);
    s->cc.nmethods = nm;
    s->cc.supernodal = sn;
    s->cc.method[0].ordering = ord;
    if (!a->L) { cholmod_free_sparse(&K, &s->cc); return df_error_set(err, DF_EINTERNAL, "admm_run: cholmod_analyze failed (status %d)", s->cc.status); }
    s->st.factorizations++;
    cholmod_free_sparse(&K, &s->cc);
    if (!ok || s->cc.status == CHOLMOD_NOT_POSDEF || a->L->minor < a->L->n)
        return df_error_set(err, DF_ESINGULAR, "admm_run: active sub-system is not positive definite");
    if (a->L->is_super && !cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, a->L, &s->cc))
        return df_error_set(err, DF_EINTERNAL, "admm_run: cholmod_change_factor failed (status %d)", s->cc.status);
    a->rhs = cholmod_zeros(a->nrf, 3, CHOLMOD_REAL, &s->cc);
    if (!a->rhs) return df_error_set(err, DF_ENOMEM, "admm_run: CHOLMOD out of memory");
    return DF_OK;
}

int admm_act_build(df_admm *s, int fresh, const int32_t *extra, int32_t n_extra, df_error *err)
{
    admm_active *a = s->act;
    /* stale: no region yet or the state may be off rest outside it (act_dirty): then everything
     * outside the new region is put at rest (O(mesh), once); a pristine solver is at rest already */
    if (!a->valid) fresh = 1;
    int stale = !a->valid && s->act_dirty;
    int32_t old_n = 0;
    if (fresh) { /* keep the old region in fr (rebuilt below) to snap the vertices leaving it */
        old_n = a->nr;
        memcpy(a->fr, a->rv, (size_t)old_n * sizeof(int32_t));
        for (int32_t k = 0; k < old_n; k++) a->in[a->rv[k]] = 0;
        a->nr = 0;
        a->tail_added = 0;
    }
    /* BFS `band` rings from the seeds (support and extra); depth[] holds the hop count here */
    uint32_t g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    int32_t qh = 0, qt = 0;
    for (int pass = 0; pass < 2; pass++) {
        const int32_t *list = pass ? extra : a->sup;
        int32_t cnt = pass ? n_extra : a->nsup;
        for (int32_t k = 0; k < cnt; k++) {
            int32_t v = list[k];
            if (a->stamp[v] == g) continue;
            a->stamp[v] = g;
            a->depth[v] = pass ? a->band : 0; /* extra: no rings around it */
            a->work[qt++] = v;
            if (!a->in[v]) { a->in[v] = 1; a->rv[a->nr++] = v; a->tail_added += pass; }
        }
    }
    while (qh < qt) {
        int32_t v = a->work[qh++];
        if (a->depth[v] >= a->band) continue;
        for (int32_t p = a->adj_ptr[v]; p < a->adj_ptr[v + 1]; p++) {
            int32_t u = a->adj[p];
            if (a->stamp[u] == g) continue;
            a->stamp[u] = g;
            a->depth[u] = a->depth[v] + 1;
            a->work[qt++] = u;
            if (!a->in[u]) { a->in[u] = 1; a->rv[a->nr++] = u; }
        }
    }
    if (fresh)
        for (int32_t k = 0; k < old_n; k++)
            if (!a->in[a->fr[k]]) snap_vertex(s, a->fr[k]);
    if (stale) /* a full run or set_positions: put everything outside at rest */
        for (int32_t i = 0; i < s->nv; i++)
            if (!a->in[i]) snap_vertex(s, i);
    region_lists(s, a);
    if (stale && s->W)
        for (int32_t e = 0; e < s->ne; e++)
            if (!a->emark[e]) memset(s->W + 9 * (size_t)e, 0, 9 * sizeof(double));
    if (stale || fresh) { s->E_last = NAN; s->el_last = s->lo_last = NAN; }
    a->valid = 1;
    s->act_dirty = 0;
    int rc = factor_sub(s, a, err);
    if (rc) { admm_active_stale(s); return rc; }
    a->st.region_vertices = a->nr;
    a->st.region_elements = a->nae;
    return admm_act_buffers(s, err);
}

int admm_act_buffers(df_admm *s, df_error *err)
{
    admm_active *a = s->act;
    if (a->nr > a->cap_v) {
        int64_t c = a->nr + a->nr / 2;
        free(a->va);
        a->va = malloc((size_t)c * 3 * sizeof(double));
        a->cap_v = a->va ? c : 0;
        if (!a->va) return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (active buffers)");
    }
    return DF_OK;
}

int admm_act_solve(df_admm *s, const double **x, df_error *err)
{
    admm_active *a = s->act;
    int ok = cholmod_solve2(CHOLMOD_A, a->L, a->rhs, NULL, &a->sol, NULL, &a->sol_y, &a->sol_e, &s->cc);
    s->st.solves++;
    if (!ok || !a->sol) return df_error_set(err, DF_EINTERNAL, "admm: cholmod_solve failed (status %d)", s->cc.status);
    *x = a->sol->x;
    return DF_OK;
}

/* |grad_i E_elastic| at Vout for vertex i (elements or cells touching it) */
static double force_norm(const df_admm *s, int32_t i)
{
    const double *V = s->Vout;
    double f[3] = {0, 0, 0};
    if (s->family == ADMM_FAM_ELEMENT && s->esz == 4 && s->q == 3 && s->p.energy != DF_ADMM_NEOHOOKEAN)
        return admm_force_tet4(s, V, i); /* the same sums, four elements at a time */
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t p = s->ve_ptr[i]; p < s->ve_ptr[i + 1]; p++) {
            int32_t e = s->ve_ent[p] / s->esz, corner = s->ve_ent[p] % s->esz;
            const int32_t *el = s->E + (size_t)e * s->esz;
            const double *g = s->grad + (size_t)e * s->esz * 3;
            int moved = 0;
            for (int c = 0; c < s->esz; c++) moved |= differs3(V + 3 * (size_t)el[c], s->Vrest + 3 * (size_t)el[c]);
            if (!moved) continue; /* exactly the rest element: zero gradient */
            double F[9] = {0}, P[9];
            for (int c = 0; c < s->esz; c++)
                for (int r = 0; r < 3; r++)
                    for (int k = 0; k < 3; k++) F[3 * r + k] += V[3 * (size_t)el[c] + r] * g[3 * c + k];
            if (s->p.energy == DF_ADMM_NEOHOOKEAN) {
                double C[9] = {F[4] * F[8] - F[5] * F[7], F[5] * F[6] - F[3] * F[8], F[3] * F[7] - F[4] * F[6],
                               F[2] * F[7] - F[1] * F[8], F[0] * F[8] - F[2] * F[6], F[1] * F[6] - F[0] * F[7],
                               F[1] * F[5] - F[2] * F[4], F[2] * F[3] - F[0] * F[5], F[0] * F[4] - F[1] * F[3]};
                double J = F[0] * C[0] + F[1] * C[1] + F[2] * C[2];
                if (!(J > 0)) return INFINITY;
                double lJ = log(J);
                for (int k = 0; k < 9; k++) { /* F^-T = cofactor / J */
                    double fit = C[k] / J;
                    P[k] = s->mu * (F[k] - fit) + s->lambda * lJ * fit;
                }
            } else {
                admm_rot_stress(s, F, P);
            }
            const double *gc = g + 3 * corner;
            for (int r = 0; r < 3; r++) f[r] += s->vol[e] * (P[3 * r] * gc[0] + P[3 * r + 1] * gc[1] + P[3 * r + 2] * gc[2]);
        }
    } else {
        for (int32_t p = s->in_ptr[i]; p < s->in_ptr[i + 1]; p++) {
            int32_t se = s->in_ent[p], t = (se > 0 ? se : -se) - 1;
            double SR[9];
            admm_fit_vertex(s, V, s->sr_own[t], SR);
            const double *xa = V + 3 * (size_t)s->sr_a[t], *xb = V + 3 * (size_t)s->sr_b[t], *d = s->sr_d + 3 * (size_t)t;
            double sign = se > 0 ? -1.0 : 1.0; /* i = b: -w r; i = a: +w r */
            for (int r = 0; r < 3; r++) {
                double res = SR[3 * r] * d[0] + SR[3 * r + 1] * d[1] + SR[3 * r + 2] * d[2] - (xb[r] - xa[r]);
                f[r] += sign * s->sr_w[t] * res;
            }
        }
    }
    return sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}

int32_t admm_act_certify(df_admm *s)
{
    admm_active *a = s->act;
    a->st.checks++;
    /* the fringe's force norms (independent, read-only: each an element gather and a polar
     * decomposition or Neo-Hookean stress per moved element around it) on the team, their
     * verdicts in work[]; the failing vertices listed afterwards in fringe order */
    int32_t *bad = a->work;
    #pragma omp parallel for schedule(dynamic, 64) num_threads(s->nthreads) if (a->nfr >= ACT_CERT_PAR)
    for (int32_t k = 0; k < a->nfr; k++) {
        int32_t v = a->fr[k];
        bad[k] = a->hmap[v] < 0 && !(force_norm(s, v) <= s->p.w * s->a[v]); /* a handle is constrained, not optimal */
    }
    int32_t n = 0;
    for (int32_t k = 0; k < a->nfr; k++)
        if (bad[k]) a->sup[a->nsup + n++] = a->fr[k];
    return n;
}

void df_admm_get_active_stats(const df_admm *s, df_admm_active_stats *out)
{
    if (!out) return;
    if (!s || !s->act) { memset(out, 0, sizeof(*out)); return; }
    *out = s->act->st;
}

/* admm_system.c — the global step's linear system: assembly of K = sum_e gamma_e D_e^T D_e
 * (+ spokes-and-rims Laplacian, + cloth bending) + rho I, elimination of the handle DoFs, one
 * CHOLMOD analysis + factorization per (mesh, weights, rho, handle set), the affine constraints as a
 * dense Schur complement on top of the factorization, and the n_free x 3 solve. */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"

int admm_trip_push(admm_trip *t, int32_t i, int32_t j, double v)
{
    if (t->n == t->cap) {
        int64_t nc = t->cap ? 2 * t->cap : 1024;
        int32_t *ni = realloc(t->i, (size_t)nc * sizeof(int32_t));
        if (ni) t->i = ni;
        int32_t *nj = realloc(t->j, (size_t)nc * sizeof(int32_t));
        if (nj) t->j = nj;
        double *nvv = realloc(t->v, (size_t)nc * sizeof(double));
        if (nvv) t->v = nvv;
        if (!ni || !nj || !nvv) return -1;
        t->cap = nc;
    }
    t->i[t->n] = i; t->j[t->n] = j; t->v[t->n] = v; t->n++;
    return 0;
}

void admm_trip_free(admm_trip *t) { free(t->i); free(t->j); free(t->v); memset(t, 0, sizeof(*t)); }

void admm_free_system(df_admm *s)
{
    if (s->cc_started) {
        admm_kcache_free(s);
        if (s->L) cholmod_free_factor(&s->L, &s->cc);
        if (s->Lsym) cholmod_free_factor(&s->Lsym, &s->cc);
        if (s->rhs) cholmod_free_dense(&s->rhs, &s->cc);
        if (s->sol) cholmod_free_dense(&s->sol, &s->cc);
        if (s->sol_y) cholmod_free_dense(&s->sol_y, &s->cc);
        if (s->sol_e) cholmod_free_dense(&s->sol_e, &s->cc);
    }
    free(s->fidx); free(s->fvert); free(s->cpl_f); free(s->cpl_h); free(s->cpl_v); free(s->KfhP);
    free(s->ar_col); free(s->ar_A); free(s->ar_b); free(s->yc_free); free(s->Y); free(s->Sch); free(s->lam);
    s->fidx = s->fvert = s->cpl_f = s->cpl_h = s->ar_col = s->yc_free = NULL;
    s->cpl_v = s->KfhP = s->ar_A = s->ar_b = s->Y = s->Sch = s->lam = NULL;
    s->ncpl = 0;
    s->n_ycols = 0;
}

/* emits K entries (both triangles of the symmetric matrix) into the free/coupling containers */
static int emit(df_admm *s, admm_trip *kff, admm_trip *cpl, const int32_t *hmap, int32_t i, int32_t j, double v)
{
    int32_t fi = s->fidx[i], fj = s->fidx[j];
    if (fi >= 0 && fj >= 0) return fi <= fj ? admm_trip_push(kff, fi, fj, v) : 0;
    if (fi >= 0 && fj < 0) return admm_trip_push(cpl, fi, hmap[j], v);
    return 0;
}

/* K's entries, each part times its weight: wt[0] the element (or spokes-and-rims) part, wt[1]
 * cloth bending, wt[2] rho I; the same entry sequence for any weights (zeros included) */
static int assemble(df_admm *s, admm_trip *kff, admm_trip *cpl, const int32_t *hmap, const double wt[3])
{
    int rc = 0;
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t e = 0; e < s->ne && !rc; e++) {
            const int32_t *el = s->E + (size_t)e * s->esz;
            const double *g = s->grad + (size_t)e * s->esz * 3;
            for (int a = 0; a < s->esz; a++)
                for (int b = 0; b < s->esz; b++) {
                    double d = 0;
                    for (int k = 0; k < s->q; k++) d += g[3 * a + k] * g[3 * b + k];
                    rc |= emit(s, kff, cpl, hmap, el[a], el[b], wt[0] * (s->gam[e] * d));
                }
        }
    } else {
        for (int64_t t = 0; t < s->sr_ptr[s->nv] && !rc; t++) {
            int32_t a = s->sr_a[t], b = s->sr_b[t];
            double w = wt[0] * s->sr_w[t];
            rc |= emit(s, kff, cpl, hmap, a, a, w);
            rc |= emit(s, kff, cpl, hmap, b, b, w);
            rc |= emit(s, kff, cpl, hmap, a, b, -w);
            rc |= emit(s, kff, cpl, hmap, b, a, -w);
        }
    }
    if (s->bl_ptr) {
        double kb = wt[1] * s->p.bending;
        for (int32_t k = 0; k < s->nv && !rc; k++)
            for (int32_t p = s->bl_ptr[k]; p < s->bl_ptr[k + 1]; p++)
                for (int32_t q = s->bl_ptr[k]; q < s->bl_ptr[k + 1]; q++)
                    rc |= emit(s, kff, cpl, hmap, s->bl_idx[p], s->bl_idx[q], kb * s->bl_val[p] * s->bl_val[q]);
    }
    for (int32_t i = 0; i < s->nv && !rc; i++) rc |= emit(s, kff, cpl, hmap, i, i, wt[2] * s->p.rho);
    return rc;
}

void admm_update_kfhp(df_admm *s)
{
    if (!s->KfhP) return; /* not built yet (active-set mode builds it before a full run) */
    int32_t nf = s->nfree;
    memset(s->KfhP, 0, (size_t)nf * 3 * sizeof(double));
    for (int64_t t = 0; t < s->ncpl; t++) {
        const double *p = s->target + 3 * (size_t)s->cpl_h[t];
        for (int k = 0; k < 3; k++) s->KfhP[s->cpl_f[t] + (size_t)k * nf] += s->cpl_v[t] * p[k];
    }
}

/* affine constraints: Y = K^-1 E_T (one multi-column solve) and the Cholesky of the Schur
 * complement S = C K^-1 C^T */
static int build_affine(df_admm *s, const df_admm_affine *aff, int naff, df_error *err)
{
    int M = 0;
    for (int k = 0; k < naff; k++) M += aff[k].n * aff[k].m;
    s->n_arows = M;
    if (M == 0) return DF_OK;
    int32_t *col_of = malloc((size_t)s->nv * sizeof(int32_t));
    s->ar_col = malloc((size_t)M * sizeof(int32_t));
    s->ar_A = malloc((size_t)M * 3 * sizeof(double));
    s->ar_b = malloc((size_t)M * sizeof(double));
    s->yc_free = malloc((size_t)M * sizeof(int32_t));
    s->lam = malloc((size_t)M * sizeof(double));
    if (!col_of || !s->ar_col || !s->ar_A || !s->ar_b || !s->yc_free || !s->lam) {
        free(col_of);
        return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    }
    for (int32_t i = 0; i < s->nv; i++) col_of[i] = -1;
    int r = 0;
    s->n_ycols = 0;
    for (int k = 0; k < naff; k++)
        for (int32_t t = 0; t < aff[k].n; t++) {
            int32_t v = aff[k].verts[t];
            if (col_of[v] < 0) { col_of[v] = s->n_ycols; s->yc_free[s->n_ycols++] = s->fidx[v]; }
            for (int m = 0; m < aff[k].m; m++, r++) {
                s->ar_col[r] = col_of[v];
                memcpy(s->ar_A + 3 * (size_t)r, aff[k].A + 3 * m, 3 * sizeof(double));
                s->ar_b[r] = aff[k].b[m];
            }
        }
    free(col_of);
    int32_t nf = s->nfree, nc = s->n_ycols;
    cholmod_dense *Eb = cholmod_zeros(nf, nc, CHOLMOD_REAL, &s->cc);
    if (!Eb) return df_error_set(err, DF_ENOMEM, "admm: out of memory (affine)");
    for (int c = 0; c < nc; c++) ((double *)Eb->x)[(size_t)c * nf + s->yc_free[c]] = 1.0;
    cholmod_dense *Yd = cholmod_solve(CHOLMOD_A, s->L, Eb, &s->cc);
    cholmod_free_dense(&Eb, &s->cc);
    s->st.solves++;
    if (!Yd) return df_error_set(err, DF_EINTERNAL, "admm: CHOLMOD solve failed (affine)");
    s->Y = malloc((size_t)nf * nc * sizeof(double));
    s->Sch = malloc((size_t)M * M * sizeof(double));
    if (!s->Y || !s->Sch) { cholmod_free_dense(&Yd, &s->cc); return df_error_set(err, DF_ENOMEM, "admm: out of memory (affine)"); }
    memcpy(s->Y, Yd->x, (size_t)nf * nc * sizeof(double));
    cholmod_free_dense(&Yd, &s->cc);
    for (int i = 0; i < M; i++)
        for (int j = 0; j < M; j++) {
            const double *ai = s->ar_A + 3 * (size_t)i, *aj = s->ar_A + 3 * (size_t)j;
            double kij = s->Y[(size_t)s->ar_col[j] * nf + s->yc_free[s->ar_col[i]]];
            s->Sch[(size_t)j * M + i] = (ai[0] * aj[0] + ai[1] * aj[1] + ai[2] * aj[2]) * kij;
        }
    double *dg = malloc((size_t)M * sizeof(double));
    if (!dg) return df_error_set(err, DF_ENOMEM, "admm: out of memory (affine)");
    for (int i = 0; i < M; i++) dg[i] = s->Sch[(size_t)i * M + i];
    lapack_int info = LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'L', M, s->Sch, M);
    /* a pivot that lost all but 1e-10 of its row's weight means (numerically) dependent rows */
    for (int i = 0; i < M && info == 0; i++) {
        double l = s->Sch[(size_t)i * M + i];
        if (!(l * l > 1e-10 * dg[i])) info = i + 1;
    }
    free(dg);
    if (info != 0)
        return df_error_set(err, DF_ESINGULAR,
                            "admm: affine constraints are linearly dependent or contradictory (Schur pivot %d)", (int)info);
    return DF_OK;
}

static void free_affine(df_admm *s)
{
    free(s->ar_col); free(s->ar_A); free(s->ar_b); free(s->yc_free); free(s->Y); free(s->Sch); free(s->lam);
    s->ar_col = s->yc_free = NULL;
    s->ar_A = s->ar_b = s->Y = s->Sch = s->lam = NULL;
    s->n_ycols = 0;
    s->n_arows = 0;
}

/* K_ff (upper triangle, CHOLMOD sparse) and the K_fh coupling triplets for the current weights,
 * rho and handle set (s->fidx set); the same entry sequence every time, so the same pattern */
static const double ADMM_ALL_PARTS[3] = {1.0, 1.0, 1.0};

static int assemble_sparse(df_admm *s, cholmod_sparse **Ko, admm_trip *cpl, const double wt[3], df_error *err)
{
    int32_t nv = s->nv, nf = s->nfree;
    int32_t *hmap = malloc((size_t)nv * sizeof(int32_t));
    if (!hmap) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    for (int32_t i = 0; i < nv; i++) hmap[i] = -1;
    for (int32_t h = 0; h < s->nh; h++) hmap[s->hidx[h]] = h;
    admm_trip kff = {0};
    memset(cpl, 0, sizeof(*cpl));
    int rc = assemble(s, &kff, cpl, hmap, wt);
    free(hmap);
    if (rc) { admm_trip_free(&kff); admm_trip_free(cpl); return df_error_set(err, DF_ENOMEM, "admm: out of memory (assembly)"); }
    cholmod_triplet *T = cholmod_allocate_triplet(nf, nf, (size_t)kff.n, 1, CHOLMOD_REAL, &s->cc);
    if (!T) { admm_trip_free(&kff); admm_trip_free(cpl); return df_error_set(err, DF_ENOMEM, "admm: CHOLMOD out of memory"); }
    memcpy(T->i, kff.i, (size_t)kff.n * sizeof(int32_t));
    memcpy(T->j, kff.j, (size_t)kff.n * sizeof(int32_t));
    memcpy(T->x, kff.v, (size_t)kff.n * sizeof(double));
    T->nnz = (size_t)kff.n;
    admm_trip_free(&kff);
    *Ko = cholmod_triplet_to_sparse(T, (size_t)T->nnz, &s->cc);
    cholmod_free_triplet(&T, &s->cc);
    if (!*Ko) { admm_trip_free(cpl); return df_error_set(err, DF_ENOMEM, "admm: CHOLMOD out of memory"); }
    return DF_OK;
}

/* numeric-only factorization of K into the analyzed L (which keeps its symbolic analysis; after
 * the first factorization L is simplicial LL^T and cholmod_factorize refactors it in place) */
static int factor_numeric(df_admm *s, cholmod_sparse *K)
{
    if (!s->Lsym) { /* in place: cholmod_factorize refactors a simplicial L with cholmod_rowfac */
        int ok = cholmod_factorize(K, s->L, &s->cc);
        s->st.factorizations++;
        return ok && s->cc.status != CHOLMOD_NOT_POSDEF && s->L->minor >= s->L->n ? 0 : -1;
    }
    /* from a copy of the kept supernodal symbolic analysis: a supernodal (BLAS) numeric
     * factorization, then the same simplicial LL^T conversion as at build */
    cholmod_factor *Ln = cholmod_copy_factor(s->Lsym, &s->cc);
    if (!Ln) return -1;
    int ok = cholmod_factorize(K, Ln, &s->cc);
    s->st.factorizations++;
    if (!ok || s->cc.status == CHOLMOD_NOT_POSDEF || Ln->minor < Ln->n ||
        (Ln->is_super && !cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, Ln, &s->cc))) {
        cholmod_free_factor(&Ln, &s->cc);
        return -1;
    }
    cholmod_free_factor(&s->L, &s->cc);
    s->L = Ln;
    return 0;
}

/* The refactorizations' assembly cache (adaptive penalties, no cloth bending): K_ff and the K_fh
 * coupling values as assembled at create, K0 = g0 E + rho0 I (E the element or spokes-and-rims part,
 * g0 = gam[0] then), so that a new (rho, g) costs one pass over the values,
 * K = (g / g0) (K0 - rho0 I) + rho I, instead of a triplet assembly and sort (~40% of a
 * refactorization on the pig); round-off apart the same matrix. Freed with the system. */
struct admm_kcache {
    cholmod_sparse *K0;       /* the create-time K_ff (upper triangle, packed, sorted) */
    double *cpl0;             /* its coupling values (rows s->cpl_f, handles s->cpl_h: unchanged) */
    int64_t ncpl;
    double gam0, rho0;        /* gam[0] (element family; 1 otherwise) and rho at create */
};

void admm_kcache_free(df_admm *s)
{
    struct admm_kcache *kc = s->kcache;
    if (!kc) return;
    if (kc->K0) cholmod_free_sparse(&kc->K0, &s->cc);
    free(kc->cpl0);
    free(kc);
    s->kcache = NULL;
}

/* keeps K (taking it: *K becomes NULL) and the coupling values as the cache; without memory, or
 * with cloth bending (not scaled with the element part), no cache and K is left to the caller */
static void kcache_keep(df_admm *s, cholmod_sparse **K)
{
    if (!s->rho_adaptive || s->bl_ptr || !(*K)->packed || !(*K)->sorted) return;
    struct admm_kcache *kc = calloc(1, sizeof(*kc));
    double *c = malloc((size_t)(s->ncpl ? s->ncpl : 1) * sizeof(double));
    if (!kc || !c) { free(kc); free(c); return; }
    memcpy(c, s->cpl_v, (size_t)s->ncpl * sizeof(double));
    kc->K0 = *K;
    *K = NULL;
    kc->cpl0 = c;
    kc->ncpl = s->ncpl;
    kc->gam0 = s->family == ADMM_FAM_ELEMENT ? s->gam[0] : 1.0;
    kc->rho0 = s->p.rho;
    s->kcache = kc;
    if (!(kc->gam0 > 0)) admm_kcache_free(s);
}

/* K_ff and the coupling for the current rho and gam from the cache (every gam_e is scaled alike,
 * so g / g0 = gam[0] / gam0); DF_ENOMEM when out of memory */
static int kcache_assemble(df_admm *s, cholmod_sparse **Ko, admm_trip *cpl, df_error *err)
{
    struct admm_kcache *kc = s->kcache;
    double g = s->family == ADMM_FAM_ELEMENT ? s->gam[0] / kc->gam0 : 1.0, rho = s->p.rho;
    cholmod_sparse *K = cholmod_copy_sparse(kc->K0, &s->cc);
    memset(cpl, 0, sizeof(*cpl));
    int64_t n = kc->ncpl;
    cpl->i = malloc((size_t)(n ? n : 1) * sizeof(int32_t));
    cpl->j = malloc((size_t)(n ? n : 1) * sizeof(int32_t));
    cpl->v = malloc((size_t)(n ? n : 1) * sizeof(double));
    if (!K || !cpl->i || !cpl->j || !cpl->v) {
        if (K) cholmod_free_sparse(&K, &s->cc);
        admm_trip_free(cpl);
        return df_error_set(err, DF_ENOMEM, "admm: out of memory (refactorization)");
    }
    const int32_t *Kp = K->p, *Ki = K->i;
    double *x = K->x;
    for (size_t j = 0; j < K->ncol; j++)
        for (int32_t k = Kp[j]; k < Kp[j + 1]; k++)
            x[k] = (size_t)Ki[k] == j ? g * (x[k] - kc->rho0) + rho : g * x[k];
    memcpy(cpl->i, s->cpl_f, (size_t)n * sizeof(int32_t));
    memcpy(cpl->j, s->cpl_h, (size_t)n * sizeof(int32_t));
    for (int64_t k = 0; k < n; k++) cpl->v[k] = g * kc->cpl0[k];
    cpl->n = cpl->cap = n;
    *Ko = K;
    return DF_OK;
}

/* reassembles K with p.rho and gam, refactors numerically, replaces the coupling and K_fh P and
 * rebuilds the affine Schur complement */
static int refactor_current(df_admm *s, df_error *err)
{
    cholmod_sparse *K = NULL;
    admm_trip cpl;
    int rc = s->kcache ? kcache_assemble(s, &K, &cpl, err) : assemble_sparse(s, &K, &cpl, ADMM_ALL_PARTS, err);
    if (rc) return rc;
    int bad = factor_numeric(s, K);
    cholmod_free_sparse(&K, &s->cc);
    if (bad) {
        admm_trip_free(&cpl);
        return df_error_set(err, DF_ESINGULAR, "admm: refactorization with rho = %g failed (status %d)", s->p.rho, s->cc.status);
    }
    free(s->cpl_f); free(s->cpl_h); free(s->cpl_v);
    s->ncpl = cpl.n;
    s->cpl_f = cpl.i; s->cpl_h = cpl.j; s->cpl_v = cpl.v;
    admm_update_kfhp(s);
    if (s->naff > 0) {
        free_affine(s);
        rc = build_affine(s, s->aff, s->naff, err);
    }
    return rc;
}

int admm_system_refactor(df_admm *s, double rho_new, double gscale, df_error *err)
{
    if (!s->L) return df_error_set(err, DF_EINTERNAL, "admm: no factorization to refactor");
    double rho_old = s->p.rho, *gam_old = NULL;
    if (gscale != 1.0) {
        gam_old = malloc((size_t)s->ne * sizeof(double));
        if (!gam_old) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
        memcpy(gam_old, s->gam, (size_t)s->ne * sizeof(double));
        for (int32_t e = 0; e < s->ne; e++) s->gam[e] *= gscale;
    }
    s->p.rho = rho_new;
    int rc = refactor_current(s, err);
    if (rc == DF_OK) {
        s->st.refactorizations++;
        free(gam_old);
        return DF_OK;
    }
    /* back to the old weights (the matrix factorized before: cannot fail but for memory) */
    s->p.rho = rho_old;
    if (gam_old) memcpy(s->gam, gam_old, (size_t)s->ne * sizeof(double));
    free(gam_old);
    df_error e2;
    if (refactor_current(s, &e2)) s->broken = 1;
    return rc;
}

int admm_build_system_affine(df_admm *s, const df_admm_affine *aff, int naff, df_error *err)
{
    admm_free_system(s);
    if (!s->cc_started) {
        cholmod_start(&s->cc);
        s->cc.print = 0;
        s->cc_started = 1;
    }
    int32_t nv = s->nv;
    s->fidx = malloc((size_t)nv * sizeof(int32_t));
    int32_t *hmap = malloc((size_t)nv * sizeof(int32_t));
    if (!s->fidx || !hmap) { free(hmap); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    for (int32_t i = 0; i < nv; i++) hmap[i] = -1;
    for (int32_t h = 0; h < s->nh; h++) hmap[s->hidx[h]] = h;
    s->nfree = 0;
    for (int32_t i = 0; i < nv; i++) s->fidx[i] = hmap[i] >= 0 ? -1 : s->nfree++;
    int32_t nf = s->nfree;
    if (nf == 0) { free(hmap); return df_error_set(err, DF_EINVAL, "admm: every vertex is a handle"); }
    s->fvert = malloc((size_t)nf * sizeof(int32_t));
    s->KfhP = malloc((size_t)nf * 3 * sizeof(double));
    if (!s->fvert || !s->KfhP) { free(hmap); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    for (int32_t i = 0; i < nv; i++) if (s->fidx[i] >= 0) s->fvert[s->fidx[i]] = i;
    free(hmap);
    cholmod_sparse *K = NULL;
    admm_trip cpl;
    int rc = assemble_sparse(s, &K, &cpl, ADMM_ALL_PARTS, err);
    if (rc) return rc;
    s->ncpl = cpl.n;
    s->cpl_f = cpl.i; s->cpl_h = cpl.j; s->cpl_v = cpl.v;
    s->L = cholmod_analyze(K, &s->cc);
    s->st.analyses++;
    if (!s->L) { cholmod_free_sparse(&K, &s->cc); return df_error_set(err, DF_EINTERNAL, "admm: cholmod_analyze failed (status %d)", s->cc.status); }
    /* adaptive penalties: the symbolic analysis kept for the numeric refactorizations */
    if (s->rho_adaptive && s->L->is_super && !(s->Lsym = cholmod_copy_factor(s->L, &s->cc))) {
        cholmod_free_sparse(&K, &s->cc);
        return df_error_set(err, DF_ENOMEM, "admm: CHOLMOD out of memory");
    }
    int ok = cholmod_factorize(K, s->L, &s->cc);
    s->st.factorizations++;
    kcache_keep(s, &K);
    if (K) cholmod_free_sparse(&K, &s->cc);
    if (!ok || s->cc.status == CHOLMOD_NOT_POSDEF || s->L->minor < s->L->n)
        return df_error_set(err, DF_ESINGULAR, "admm: global matrix is not positive definite (pivot %d of %d)",
                            (int)s->L->minor, (int)nf);
    /* solves with 3 right-hand sides: a simplicial LL^T factor solves without BLAS calls (no
     * BLAS thread pool competing with the OpenMP kernels every iteration); same numbers */
    if (s->L->is_super && !cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, s->L, &s->cc))
        return df_error_set(err, DF_EINTERNAL, "admm: cholmod_change_factor failed (status %d)", s->cc.status);
    s->rhs = cholmod_zeros(nf, 3, CHOLMOD_REAL, &s->cc);
    if (!s->rhs) return df_error_set(err, DF_ENOMEM, "admm: CHOLMOD out of memory");
    admm_update_kfhp(s);
    return build_affine(s, aff, naff, err);
}

int admm_solve_rhs(df_admm *s, int with_b, const double **xo, df_error *err)
{
    /* cholmod_solve2 reuses the solution and its workspaces across iterations (no allocation) */
    int ok = cholmod_solve2(CHOLMOD_A, s->L, s->rhs, NULL, &s->sol, NULL, &s->sol_y, &s->sol_e, &s->cc);
    s->st.solves++;
    cholmod_dense *X = s->sol;
    if (!ok || !X) return df_error_set(err, DF_EINTERNAL, "admm: cholmod_solve failed (status %d)", s->cc.status);
    int32_t nf = s->nfree;
    double *x = X->x;
    if (s->n_arows > 0) {
        int M = s->n_arows;
        for (int r = 0; r < M; r++) {
            const double *A = s->ar_A + 3 * (size_t)r;
            size_t f = (size_t)s->yc_free[s->ar_col[r]];
            s->lam[r] = A[0] * x[f] + A[1] * x[f + nf] + A[2] * x[f + 2 * (size_t)nf] - (with_b ? s->ar_b[r] : 0.0);
        }
        LAPACKE_dpotrs(LAPACK_COL_MAJOR, 'L', M, 1, s->Sch, M, s->lam, M);
        for (int k = 0; k < 3; k++) {
            double *xk = x + (size_t)k * nf;
            for (int r = 0; r < M; r++) {
                double c = s->lam[r] * s->ar_A[3 * (size_t)r + k];
                if (c == 0.0) continue;
                const double *y = s->Y + (size_t)s->ar_col[r] * nf;
                for (int32_t i = 0; i < nf; i++) xk[i] -= c * y[i];
            }
        }
    }
    *xo = x;
    return DF_OK;
}

int admm_global_solve(df_admm *s, df_error *err)
{
    const double *x;
    int rc = admm_solve_rhs(s, 1, &x, err);
    if (rc) return rc;
    int32_t nf = s->nfree;
    for (int32_t f = 0; f < nf; f++) {
        double *v = s->V + 3 * (size_t)s->fvert[f];
        v[0] = x[f]; v[1] = x[f + nf]; v[2] = x[f + 2 * (size_t)nf];
    }
    for (int32_t h = 0; h < s->nh; h++) memcpy(s->V + 3 * (size_t)s->hidx[h], s->target + 3 * (size_t)h, 3 * sizeof(double));
    return DF_OK;
}

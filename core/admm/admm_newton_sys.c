/* admm_newton_sys.c — the polish's sparse Newton system (admm_newton.h): the cache kept in the
 * solver (own cholmod_common, support, Hessian pattern, symbolic factor, affine projectors), the
 * assembly of the exact or projected Hessian on the support, factorization and solve. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_newton.h"

#define PN_CHUNK 2048 /* elements whose 12 x 12 Hessians are computed in parallel per batch */

static void free_pattern(admm_polish_cache *c)
{
    if (c->H) cholmod_free_sparse(&c->H, &c->cc);
    if (c->L) cholmod_free_factor(&c->L, &c->cc);
    free(c->sup);
    c->sup = NULL;
    c->n = 0;
}

void admm_polish_free(df_admm *s)
{
    if (!s || !s->polish) return;
    admm_polish_cache *c = s->polish;
    free_pattern(c);
    if (c->started) cholmod_finish(&c->cc);
    free(c->sidx); free(c->pidx); free(c->Pv); free(c->Pres);
    free(c);
    s->polish = NULL;
}

/* per-vertex projectors onto the null space of the vertex's affine rows (all sets it is in) */
static int build_projectors(df_admm *s, admm_polish_cache *c)
{
    c->pidx = malloc((size_t)s->nv * sizeof(int32_t));
    if (!c->pidx) return -1;
    for (int32_t i = 0; i < s->nv; i++) c->pidx[i] = -1;
    int32_t n = 0;
    for (int k = 0; k < s->naff; k++)
        for (int32_t t = 0; t < s->aff[k].n; t++)
            if (c->pidx[s->aff[k].verts[t]] < 0) c->pidx[s->aff[k].verts[t]] = n++;
    c->npv = n;
    if (n == 0) return 0;
    c->Pv = malloc((size_t)n * 9 * sizeof(double));
    c->Pres = calloc((size_t)n, sizeof(double));
    if (!c->Pv || !c->Pres) return -1;
    for (int32_t j = 0; j < n; j++)
        for (int q = 0; q < 9; q++) c->Pv[9 * (size_t)j + q] = (q % 4) == 0;
    for (int k = 0; k < s->naff; k++) {
        const df_admm_affine *a = s->aff + k;
        for (int32_t t = 0; t < a->n; t++) {
            int32_t v = a->verts[t], j = c->pidx[v];
            double *P = c->Pv + 9 * (size_t)j;
            const double *x = s->Vrest + 3 * (size_t)v;
            for (int r = 0; r < a->m; r++) {
                const double *row = a->A + 3 * r;
                double nr = sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2]);
                double viol = fabs(row[0] * x[0] + row[1] * x[1] + row[2] * x[2] - a->b[r]) / nr;
                if (viol > c->Pres[j]) c->Pres[j] = viol;
                double q[3];
                for (int u = 0; u < 3; u++) q[u] = P[3 * u] * row[0] + P[3 * u + 1] * row[1] + P[3 * u + 2] * row[2];
                double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
                if (!(nq > 1e-10 * nr)) continue; /* dependent on the rows already taken */
                for (int u = 0; u < 3; u++) q[u] /= nq;
                for (int u = 0; u < 3; u++)
                    for (int w = 0; w < 3; w++) P[3 * u + w] -= q[u] * q[w];
            }
        }
    }
    return 0;
}

int admm_pn_cache(df_admm *s, df_error *err)
{
    if (s->polish) return DF_OK;
    admm_polish_cache *c = calloc(1, sizeof(*c));
    if (!c) return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory");
    c->sidx = malloc((size_t)s->nv * sizeof(int32_t));
    if (!c->sidx || build_projectors(s, c)) {
        free(c->sidx); free(c->pidx); free(c->Pv); free(c->Pres); free(c);
        return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory");
    }
    cholmod_start(&c->cc);
    c->cc.print = 0;
    c->cc.error_handler = NULL;
    c->cc.supernodal = CHOLMOD_SUPERNODAL; /* LL^T: reports a non-positive-definite matrix (simplicial LDL^T may not) */
    c->started = 1;
    s->polish = c;
    return DF_OK;
}

void admm_pn_project(const df_admm *s, int32_t i, double v[3])
{
    const admm_polish_cache *c = s->polish;
    int32_t j = c->pidx[i];
    if (j < 0) return;
    const double *P = c->Pv + 9 * (size_t)j;
    double o[3];
    for (int u = 0; u < 3; u++) o[u] = P[3 * u] * v[0] + P[3 * u + 1] * v[1] + P[3 * u + 2] * v[2];
    memcpy(v, o, sizeof(o));
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* support neighbours of support vertex j with index <= j (sorted, unique) into nb; returns count */
static int32_t neighbours(const df_admm *s, const admm_polish_cache *c, int32_t j, int32_t *nb)
{
    int32_t v = c->sup[j], k = 0;
    for (int32_t p = s->ve_ptr[v]; p < s->ve_ptr[v + 1]; p++) {
        const int32_t *el = s->E + (size_t)(s->ve_ent[p] / 4) * 4;
        for (int a = 0; a < 4; a++) {
            int32_t t = c->sidx[el[a]];
            if (t >= 0 && t <= j) nb[k++] = t;
        }
    }
    nb[k++] = j;
    qsort(nb, (size_t)k, sizeof(int32_t), cmp_i32);
    int32_t u = 0;
    for (int32_t q = 0; q < k; q++)
        if (u == 0 || nb[q] != nb[u - 1]) nb[u++] = nb[q];
    return u;
}

int admm_pn_prepare(df_admm *s, const int32_t *sup, int32_t n, long *analyses, df_error *err)
{
    admm_polish_cache *c = s->polish;
    if (c->H && c->n == n && memcmp(c->sup, sup, (size_t)n * sizeof(int32_t)) == 0) return DF_OK;
    free_pattern(c);
    c->sup = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t));
    int32_t maxdeg = 1;
    for (int32_t i = 0; i < s->nv; i++) {
        int32_t d = 4 * (s->ve_ptr[i + 1] - s->ve_ptr[i]) + 1;
        if (d > maxdeg) maxdeg = d;
    }
    int32_t *nb = malloc((size_t)maxdeg * sizeof(int32_t));
    if (!c->sup || !nb) { free(nb); free_pattern(c); return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory"); }
    memcpy(c->sup, sup, (size_t)n * sizeof(int32_t));
    c->n = n;
    for (int32_t i = 0; i < s->nv; i++) c->sidx[i] = -1;
    for (int32_t j = 0; j < n; j++) c->sidx[sup[j]] = j;
    int64_t nnz = 0;
    for (int32_t j = 0; j < n; j++) {
        int32_t k = neighbours(s, c, j, nb);
        nnz += 3 * (int64_t)(3 * (k - 1)) + 6; /* off-diagonal blocks full, diagonal upper */
    }
    size_t N = 3 * (size_t)n;
    c->H = cholmod_allocate_sparse(N, N, (size_t)nnz, 1, 1, 1, CHOLMOD_REAL, &c->cc);
    if (!c->H) { free(nb); free_pattern(c); return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory (Hessian)"); }
    int *Hp = c->H->p, *Hi = c->H->i;
    int64_t pos = 0;
    for (int32_t j = 0; j < n; j++) {
        int32_t k = neighbours(s, c, j, nb);
        for (int col = 0; col < 3; col++) {
            Hp[3 * j + col] = (int)pos;
            for (int32_t q = 0; q < k; q++) {
                int lmax = nb[q] == j ? col : 2;
                for (int l = 0; l <= lmax; l++) Hi[pos++] = 3 * nb[q] + l;
            }
        }
    }
    Hp[N] = (int)pos;
    free(nb);
    memset(c->H->x, 0, (size_t)pos * sizeof(double));
    for (size_t d = 0; d < N; d++) ((double *)c->H->x)[Hp[d + 1] - 1] = 1.0; /* identity to analyze */
    c->L = cholmod_analyze(c->H, &c->cc);
    if (!c->L) { free_pattern(c); return df_error_set(err, DF_EINTERNAL, "admm_polish: cholmod_analyze failed (status %d)", c->cc.status); }
    (*analyses)++;
    return DF_OK;
}

static void add_entry(admm_polish_cache *c, int row, int col, double v)
{
    const int *Hp = c->H->p, *Hi = c->H->i;
    int lo = Hp[col], hi = Hp[col + 1] - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (Hi[mid] < row) lo = mid + 1; else hi = mid;
    }
    ((double *)c->H->x)[lo] += v;
}

/* 12 x 12 element Hessian vol G^T H_F G at V, rows/columns (corner a, coordinate r) = 3 a + r */
static void element_hessian(const df_admm *s, const double *V, int32_t e, int project, double *K)
{
    double F[9], P[9], HF[81];
    admm_newton_element_F(s, V, e, F);
    if (admm_newton_density(s->p.energy, s->mu, s->lambda, F, P, HF, project) < 0) {
        memset(K, 0, 144 * sizeof(double)); /* inverted: never reached (starts are uninverted) */
        return;
    }
    const double *g = s->grad + (size_t)e * 12;
    double T[9 * 12]; /* T[(r,c), (b,r')] = sum_c' HF[(r,c),(r',c')] g_b,c' */
    for (int rc = 0; rc < 9; rc++)
        for (int b = 0; b < 4; b++)
            for (int r2 = 0; r2 < 3; r2++) {
                const double *h = HF + 9 * rc + 3 * r2;
                T[12 * rc + 3 * b + r2] = h[0] * g[3 * b] + h[1] * g[3 * b + 1] + h[2] * g[3 * b + 2];
            }
    double vol = s->vol[e];
    for (int a = 0; a < 4; a++)
        for (int r = 0; r < 3; r++)
            for (int col = 0; col < 12; col++) {
                const double *t = T + 12 * (3 * r) + col;
                K[12 * (3 * a + r) + col] = vol * (g[3 * a] * t[0] + g[3 * a + 1] * t[12] + g[3 * a + 2] * t[24]);
            }
}

/* P_a K_ab P_b for the corners with an affine projector */
static void project_blocks(const df_admm *s, const int32_t *el, double *K)
{
    const admm_polish_cache *c = s->polish;
    for (int a = 0; a < 4; a++) {
        int32_t j = c->pidx[el[a]];
        if (j < 0) continue;
        const double *P = c->Pv + 9 * (size_t)j;
        for (int col = 0; col < 12; col++) { /* rows of corner a: P * */
            double v[3];
            for (int u = 0; u < 3; u++) v[u] = P[3 * u] * K[12 * (3 * a) + col] + P[3 * u + 1] * K[12 * (3 * a + 1) + col] + P[3 * u + 2] * K[12 * (3 * a + 2) + col];
            for (int u = 0; u < 3; u++) K[12 * (3 * a + u) + col] = v[u];
        }
        for (int row = 0; row < 12; row++) { /* columns of corner a: * P (P symmetric) */
            double *k = K + 12 * row + 3 * a, v[3];
            for (int u = 0; u < 3; u++) v[u] = P[3 * u] * k[0] + P[3 * u + 1] * k[1] + P[3 * u + 2] * k[2];
            memcpy(k, v, sizeof(v));
        }
    }
}

int admm_pn_assemble(df_admm *s, const double *V, int project, double shift)
{
    admm_polish_cache *c = s->polish;
    memset(c->H->x, 0, (size_t)((int *)c->H->p)[c->H->ncol] * sizeof(double));
    double *K = malloc((size_t)PN_CHUNK * 144 * sizeof(double));
    int32_t *list = malloc((size_t)PN_CHUNK * sizeof(int32_t));
    if (!K || !list) { free(K); free(list); return -1; }
    for (int32_t e0 = 0; e0 < s->ne;) {
        int32_t m = 0; /* next batch of elements with a support corner */
        for (; e0 < s->ne && m < PN_CHUNK; e0++) {
            const int32_t *el = s->E + (size_t)e0 * 4;
            if (c->sidx[el[0]] >= 0 || c->sidx[el[1]] >= 0 || c->sidx[el[2]] >= 0 || c->sidx[el[3]] >= 0) list[m++] = e0;
        }
        #pragma omp parallel for schedule(static) num_threads(s->nthreads)
        for (int32_t k = 0; k < m; k++) {
            element_hessian(s, V, list[k], project, K + 144 * (size_t)k);
            if (c->npv) project_blocks(s, s->E + (size_t)list[k] * 4, K + 144 * (size_t)k);
        }
        for (int32_t k = 0; k < m; k++) {
            const int32_t *el = s->E + (size_t)list[k] * 4;
            const double *Ke = K + 144 * (size_t)k;
            for (int a = 0; a < 4; a++) {
                int32_t sa = c->sidx[el[a]];
                if (sa < 0) continue;
                for (int b = 0; b < 4; b++) {
                    int32_t sb = c->sidx[el[b]];
                    if (sb < sa) continue;
                    for (int kk = 0; kk < 3; kk++)
                        for (int l = 0; l < 3 && (sa < sb || l <= kk); l++)
                            add_entry(c, 3 * sa + l, 3 * sb + kk, Ke[12 * (3 * a + l) + 3 * b + kk]);
                }
            }
        }
    }
    free(K);
    free(list);
    /* SC-L1 blocks, affine complements, shift */
    double sc = s->p.s;
    for (int32_t j = 0; j < c->n; j++) {
        int32_t i = c->sup[j];
        double B[9] = {0};
        double wa = s->p.w * s->a[i], d[3], r2 = 0;
        for (int k = 0; k < 3; k++) { d[k] = V[3 * (size_t)i + k] - s->Vrest[3 * (size_t)i + k]; r2 += d[k] * d[k]; }
        double r = sqrt(r2);
        if (wa > 0 && r > 0 && r < sc) {
            double tan = wa * (1.0 - r / sc) / r, rad = project ? 0.0 : -wa / sc;
            for (int u = 0; u < 3; u++)
                for (int w = 0; w < 3; w++) {
                    double nn = d[u] * d[w] / r2;
                    B[3 * u + w] = tan * ((u == w) - nn) + rad * nn;
                }
        }
        int32_t pj = c->pidx[i];
        if (pj >= 0) {
            const double *P = c->Pv + 9 * (size_t)pj;
            double T[9], PBP[9];
            for (int u = 0; u < 3; u++)
                for (int w = 0; w < 3; w++) T[3 * u + w] = P[3 * u] * B[w] + P[3 * u + 1] * B[3 + w] + P[3 * u + 2] * B[6 + w];
            for (int u = 0; u < 3; u++)
                for (int w = 0; w < 3; w++) PBP[3 * u + w] = T[3 * u] * P[w] + T[3 * u + 1] * P[3 + w] + T[3 * u + 2] * P[6 + w];
            /* constrained directions decouple: identity there (their step is 0) */
            for (int q = 0; q < 9; q++) B[q] = PBP[q] + ((q % 4) == 0) - P[q];
        }
        for (int kk = 0; kk < 3; kk++)
            for (int l = 0; l <= kk; l++) add_entry(c, 3 * j + l, 3 * j + kk, B[3 * l + kk] + (l == kk ? shift : 0.0));
    }
    return 0;
}

int admm_pn_factor(df_admm *s, int *pd, df_error *err)
{
    admm_polish_cache *c = s->polish;
    int ok = cholmod_factorize(c->H, c->L, &c->cc);
    if (!ok && c->cc.status != CHOLMOD_NOT_POSDEF)
        return df_error_set(err, DF_EINTERNAL, "admm_polish: cholmod_factorize failed (status %d)", c->cc.status);
    *pd = c->cc.status != CHOLMOD_NOT_POSDEF && c->L->minor >= c->L->n;
    return DF_OK;
}

int admm_pn_solve(df_admm *s, const double *b, double *x, df_error *err)
{
    admm_polish_cache *c = s->polish;
    size_t N = 3 * (size_t)c->n;
    cholmod_dense *B = cholmod_allocate_dense(N, 1, N, CHOLMOD_REAL, &c->cc);
    if (!B) return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory (solve)");
    memcpy(B->x, b, N * sizeof(double));
    cholmod_dense *X = cholmod_solve(CHOLMOD_A, c->L, B, &c->cc);
    cholmod_free_dense(&B, &c->cc);
    if (!X) return df_error_set(err, DF_EINTERNAL, "admm_polish: cholmod_solve failed (status %d)", c->cc.status);
    memcpy(x, X->x, N * sizeof(double));
    cholmod_free_dense(&X, &c->cc);
    return DF_OK;
}

/* admm_setup.c — per-element and per-vertex operators of the ADMM solver for its rest shape:
 * deformation-gradient vectors g_{e,a} (tets, cloth triangles), spokes-and-rims cells with
 * cotangent (triangles) or uniform (polylines) weights, locality weights a_i, the cloth bending
 * rows and the vertex incidence lists used to gather the global right-hand side. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"
#include "core/admm/nh_prox.h"

/* kept elements are checked again (defensive; admm_degen.c excluded the degenerate ones) */
#define ADMM_DEGENERATE_REL DF_ADMM_DEGENERATE_SHAPE_REL

static double dist2(const double *x, const double *y)
{
    double d0 = x[0] - y[0], d1 = x[1] - y[1], d2 = x[2] - y[2];
    return d0 * d0 + d1 * d1 + d2 * d2;
}

void admm_free_operators(df_admm *s)
{
    free(s->grad); free(s->vol); free(s->gam); free(s->ve_ptr); free(s->ve_ent);
    free(s->sr_ptr); free(s->sr_own); free(s->sr_a); free(s->sr_b); free(s->sr_w); free(s->sr_d);
    free(s->in_ptr); free(s->in_ent); free(s->bl_ptr); free(s->bl_idx); free(s->bl_val);
    free(s->a);
    s->grad = s->vol = s->gam = s->sr_w = s->sr_d = s->bl_val = s->a = NULL;
    s->sr_own = NULL;
    s->ve_ptr = s->ve_ent = s->sr_ptr = s->sr_a = s->sr_b = s->in_ptr = s->in_ent = NULL;
    s->bl_ptr = s->bl_idx = NULL;
}

/* tets (q = 3) and cloth triangles (q = 2): g vectors, volumes, penalty weights */
static int build_elements(df_admm *s, df_error *err)
{
    const int esz = s->esz;
    s->grad = calloc((size_t)s->ne * esz * 3, sizeof(double));
    s->vol = malloc((size_t)s->ne * sizeof(double));
    s->gam = malloc((size_t)s->ne * sizeof(double));
    if (!s->grad || !s->vol || !s->gam) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    double gfac = 1.0;
    if (s->p.energy == DF_ADMM_NEOHOOKEAN) gfac = 2.0066 * s->mu + 1.0122 * s->lambda;
    for (int32_t e = 0; e < s->ne; e++) {
        const int32_t *el = s->E + (size_t)e * esz;
        const double *x0 = s->Vrest + 3 * (size_t)el[0];
        double longest = 0;
        for (int i = 0; i < esz; i++)
            for (int j = i + 1; j < esz; j++) {
                double l = dist2(s->Vrest + 3 * (size_t)el[i], s->Vrest + 3 * (size_t)el[j]);
                if (l > longest) longest = l;
            }
        longest = sqrt(longest);
        double *g = s->grad + (size_t)e * esz * 3;
        if (s->q == 3) {
            double D[9]; /* columns x_a - x_0 */
            for (int a = 1; a <= 3; a++)
                for (int k = 0; k < 3; k++) D[3 * k + a - 1] = s->Vrest[3 * (size_t)el[a] + k] - x0[k];
            double c0 = D[4] * D[8] - D[5] * D[7], c1 = D[5] * D[6] - D[3] * D[8],
                   c2 = D[3] * D[7] - D[4] * D[6];
            double det = D[0] * c0 + D[1] * c1 + D[2] * c2;
            double v = det / 6.0;
            if (!(fabs(v) > ADMM_DEGENERATE_REL * longest * longest * longest))
                return df_error_set(err, DF_EINVAL, "admm: tet %d is degenerate (volume %g)", (int)s->e_map[e], v);
            if (v < 0)
                return df_error_set(err, DF_EINVAL, "admm: tet %d is inverted (volume %g)", (int)s->e_map[e], v);
            double inv[9] = {c0 / det, (D[2] * D[7] - D[1] * D[8]) / det, (D[1] * D[5] - D[2] * D[4]) / det,
                             c1 / det, (D[0] * D[8] - D[2] * D[6]) / det, (D[2] * D[3] - D[0] * D[5]) / det,
                             c2 / det, (D[1] * D[6] - D[0] * D[7]) / det, (D[0] * D[4] - D[1] * D[3]) / det};
            for (int a = 1; a <= 3; a++)
                for (int k = 0; k < 3; k++) {
                    g[3 * a + k] = inv[3 * (a - 1) + k];
                    g[k] -= inv[3 * (a - 1) + k];
                }
            s->vol[e] = v;
        } else {
            double e1[3], e2[3];
            for (int k = 0; k < 3; k++) {
                e1[k] = s->Vrest[3 * (size_t)el[1] + k] - x0[k];
                e2[k] = s->Vrest[3 * (size_t)el[2] + k] - x0[k];
            }
            double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
            double area = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            if (!(area > ADMM_DEGENERATE_REL * longest * longest))
                return df_error_set(err, DF_EINVAL, "admm: triangle %d is degenerate (area %g)", (int)s->e_map[e], area);
            if (s->planar && cr[2] < 0)
                return df_error_set(err, DF_EINVAL, "admm: triangle %d is inverted (clockwise)", (int)s->e_map[e]);
            double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
            double t1[3] = {e1[0] / l1, e1[1] / l1, e1[2] / l1};
            double p = e2[0] * t1[0] + e2[1] * t1[1] + e2[2] * t1[2];
            double h = 2.0 * area / l1; /* e2 . t2 */
            /* Dm = [[l1, p], [0, h]], inverse [[1/l1, -p/(l1 h)], [0, 1/h]] */
            double r0[2] = {1.0 / l1, -p / (l1 * h)}, r1[2] = {0.0, 1.0 / h};
            for (int k = 0; k < 2; k++) {
                g[3 + k] = r0[k];
                g[6 + k] = r1[k];
                g[k] = -(r0[k] + r1[k]);
            }
            s->vol[e] = area;
        }
        s->gam[e] = gfac * s->vol[e];
    }
    /* vertex -> (element, corner) incidence */
    s->ve_ptr = calloc((size_t)s->nv + 1, sizeof(int32_t));
    s->ve_ent = malloc((size_t)s->ne * esz * sizeof(int32_t));
    if (!s->ve_ptr || !s->ve_ent) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    for (int64_t t = 0; t < (int64_t)s->ne * esz; t++) s->ve_ptr[s->E[t] + 1]++;
    for (int32_t i = 0; i < s->nv; i++) s->ve_ptr[i + 1] += s->ve_ptr[i];
    int32_t *fill = malloc((size_t)s->nv * sizeof(int32_t));
    if (!fill) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    memcpy(fill, s->ve_ptr, (size_t)s->nv * sizeof(int32_t));
    for (int64_t t = 0; t < (int64_t)s->ne * esz; t++) s->ve_ent[fill[s->E[t]]++] = (int32_t)t;
    free(fill);
    return DF_OK;
}

/* cot of the angle at corner c of triangle el, halved */
static double half_cot(const double *Vr, const int32_t *el, int c)
{
    const double *p = Vr + 3 * (size_t)el[c], *q = Vr + 3 * (size_t)el[(c + 1) % 3],
                 *r = Vr + 3 * (size_t)el[(c + 2) % 3];
    double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double n = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    return 0.5 * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / n;
}

static int check_simplices(const df_admm *s, df_error *err)
{
    for (int32_t e = 0; e < s->ne; e++) {
        const int32_t *el = s->E + (size_t)e * s->esz;
        if (s->esz == 2) {
            double l = dist2(s->Vrest + 3 * (size_t)el[0], s->Vrest + 3 * (size_t)el[1]);
            if (!(l > 0)) return df_error_set(err, DF_EINVAL, "admm: segment %d has zero length", (int)s->e_map[e]);
        } else {
            const double *x0 = s->Vrest + 3 * (size_t)el[0];
            const double *x1 = s->Vrest + 3 * (size_t)el[1], *x2 = s->Vrest + 3 * (size_t)el[2];
            double u[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
            double v[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
            double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
            double a2 = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            double lm = fmax(fmax(dist2(x0, x1), dist2(x0, x2)), dist2(x1, x2));
            if (!(a2 > 2 * ADMM_DEGENERATE_REL * lm))
                return df_error_set(err, DF_EINVAL, "admm: triangle %d is degenerate", (int)s->e_map[e]);
            if (s->planar && cr[2] < 0)
                return df_error_set(err, DF_EINVAL, "admm: triangle %d is inverted (clockwise)", (int)s->e_map[e]);
        }
    }
    return DF_OK;
}

/* spokes-and-rims cells: triangles give every edge of every incident triangle with half-cot
 * weights; polylines give the incident segments with weight 1 */
static int build_cells(df_admm *s, df_error *err)
{
    int rc = check_simplices(s, err);
    if (rc) return rc;
    int per = s->esz == 3 ? 3 : 1; /* entries per (element, corner) */
    int64_t nent = (int64_t)s->ne * s->esz * per;
    s->sr_ptr = calloc((size_t)s->nv + 1, sizeof(int32_t));
    s->sr_a = malloc((size_t)nent * sizeof(int32_t));
    s->sr_b = malloc((size_t)nent * sizeof(int32_t));
    s->sr_w = malloc((size_t)nent * sizeof(double));
    s->sr_own = malloc((size_t)nent * sizeof(int32_t));
    s->sr_d = malloc((size_t)nent * 3 * sizeof(double));
    s->Rv = s->Rv ? s->Rv : malloc((size_t)s->nv * 9 * sizeof(double));
    if (!s->sr_ptr || !s->sr_own || !s->sr_a || !s->sr_b || !s->sr_w || !s->sr_d || !s->Rv)
        return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    for (int64_t t = 0; t < (int64_t)s->ne * s->esz; t++) s->sr_ptr[s->E[t] + 1] += per;
    for (int32_t i = 0; i < s->nv; i++) s->sr_ptr[i + 1] += s->sr_ptr[i];
    int32_t *fill = malloc((size_t)s->nv * sizeof(int32_t));
    if (!fill) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    memcpy(fill, s->sr_ptr, (size_t)s->nv * sizeof(int32_t));
    for (int32_t e = 0; e < s->ne; e++) {
        const int32_t *el = s->E + (size_t)e * s->esz;
        double w[3] = {1, 1, 1};
        if (s->esz == 3)
            for (int c = 0; c < 3; c++) w[c] = half_cot(s->Vrest, el, c);
        for (int c = 0; c < s->esz; c++) {
            int32_t owner = el[c];
            for (int k = 0; k < per; k++) {
                int32_t t = fill[owner]++;
                int32_t a, b;
                if (s->esz == 3) { a = el[(k + 1) % 3]; b = el[(k + 2) % 3]; s->sr_w[t] = w[k]; }
                else { a = el[0]; b = el[1]; s->sr_w[t] = 1.0; }
                s->sr_a[t] = a;
                s->sr_own[t] = owner;
                s->sr_b[t] = b;
                for (int d = 0; d < 3; d++)
                    s->sr_d[3 * (size_t)t + d] = s->Vrest[3 * (size_t)b + d] - s->Vrest[3 * (size_t)a + d];
            }
        }
    }
    /* incidence: vertex v appears as b (+) or a (-) of entries */
    memset(fill, 0, (size_t)s->nv * sizeof(int32_t));
    s->in_ptr = calloc((size_t)s->nv + 1, sizeof(int32_t));
    s->in_ent = malloc((size_t)nent * 2 * sizeof(int32_t));
    if (!s->in_ptr || !s->in_ent) { free(fill); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    for (int64_t t = 0; t < nent; t++) { s->in_ptr[s->sr_a[t] + 1]++; s->in_ptr[s->sr_b[t] + 1]++; }
    for (int32_t i = 0; i < s->nv; i++) s->in_ptr[i + 1] += s->in_ptr[i];
    memcpy(fill, s->in_ptr, (size_t)s->nv * sizeof(int32_t));
    for (int64_t t = 0; t < nent; t++) {
        s->in_ent[fill[s->sr_b[t]]++] = (int32_t)(t + 1);
        s->in_ent[fill[s->sr_a[t]]++] = (int32_t)-(t + 1);
    }
    free(fill);
    return DF_OK;
}

static int cmp_i64(const void *x, const void *y)
{
    int64_t a = *(const int64_t *)x, b = *(const int64_t *)y;
    return a < b ? -1 : a > b;
}

/* cloth bending rows: for interior vertex k, c_kj = L_kj / sqrt(M_k) (L cotangent Laplacian with
 * half-cot weights, M barycentric area); E_b = bending / 2 sum_k |sum_j c_kj V_j|^2 */
static int build_bending(df_admm *s, df_error *err)
{
    int32_t nv = s->nv, ne = s->ne;
    int64_t ned = 3 * (int64_t)ne;
    int64_t *keys = malloc((size_t)ned * sizeof(int64_t));
    char *bnd = calloc((size_t)nv, 1);
    double *M = calloc((size_t)nv, sizeof(double));
    int32_t *cnt = calloc((size_t)nv + 1, sizeof(int32_t));
    if (!keys || !bnd || !M || !cnt) { free(keys); free(bnd); free(M); free(cnt); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    for (int32_t e = 0; e < ne; e++) {
        const int32_t *el = s->E + 3 * (size_t)e;
        for (int c = 0; c < 3; c++) {
            int64_t i = el[(c + 1) % 3], j = el[(c + 2) % 3];
            keys[3 * (int64_t)e + c] = i < j ? i * nv + j : j * nv + i;
            M[el[c]] += s->vol[e] / 3.0;
        }
    }
    qsort(keys, (size_t)ned, sizeof(int64_t), cmp_i64);
    for (int64_t t = 0; t < ned;) {
        int64_t u = t;
        while (u < ned && keys[u] == keys[t]) u++;
        if (u - t == 1) { bnd[keys[t] / nv] = 1; bnd[keys[t] % nv] = 1; }
        t = u;
    }
    free(keys);
    /* rows: per vertex, (neighbour, weight) pairs merged */
    for (int32_t e = 0; e < ne; e++)
        for (int c = 0; c < 3; c++) cnt[s->E[3 * (size_t)e + c] + 1] += 5; /* 2 edges x 2 + self */
    for (int32_t i = 0; i < nv; i++) cnt[i + 1] += cnt[i];
    int32_t *idx = malloc((size_t)cnt[nv] * sizeof(int32_t));
    double *val = malloc((size_t)cnt[nv] * sizeof(double));
    int32_t *fill = malloc((size_t)nv * sizeof(int32_t));
    if (!idx || !val || !fill) { free(idx); free(val); free(fill); free(bnd); free(M); free(cnt); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    memcpy(fill, cnt, (size_t)nv * sizeof(int32_t));
    for (int32_t e = 0; e < ne; e++) {
        const int32_t *el = s->E + 3 * (size_t)e;
        for (int c = 0; c < 3; c++) {
            double w = half_cot(s->Vrest, el, c);
            int32_t i = el[(c + 1) % 3], j = el[(c + 2) % 3];
            idx[fill[i]] = j; val[fill[i]++] = w;
            idx[fill[i]] = i; val[fill[i]++] = -w;
            idx[fill[j]] = i; val[fill[j]++] = w;
            idx[fill[j]] = j; val[fill[j]++] = -w;
        }
    }
    /* compact: keep interior rows, merge duplicate columns */
    s->bl_ptr = calloc((size_t)nv + 1, sizeof(int32_t));
    if (!s->bl_ptr) { free(idx); free(val); free(fill); free(bnd); free(M); free(cnt); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    int32_t out = 0;
    for (int32_t k = 0; k < nv; k++) {
        int32_t b = cnt[k], e = fill[k];
        int32_t start = out;
        if (!bnd[k] && M[k] > 0) {
            double sc = 1.0 / sqrt(M[k]);
            for (int32_t t = b; t < e; t++) {
                int32_t u;
                for (u = start; u < out; u++)
                    if (idx[u] == idx[t]) break;
                if (u == out) { idx[out] = idx[t]; val[out] = 0; out++; }
                val[u] += val[t] * sc;
            }
        }
        s->bl_ptr[k + 1] = out;
    }
    free(fill); free(bnd); free(M); free(cnt);
    s->bl_idx = idx;
    s->bl_val = val;
    return DF_OK;
}

int admm_build_operators(df_admm *s, df_error *err)
{
    admm_free_operators(s);
    int rc;
    if (s->family == ADMM_FAM_ELEMENT) rc = build_elements(s, err);
    else rc = build_cells(s, err);
    if (rc) return rc;
    if (s->p.energy == DF_ADMM_CLOTH && s->p.bending > 0) {
        rc = build_bending(s, err);
        if (rc) return rc;
    }
    s->a = malloc((size_t)s->nv * sizeof(double));
    if (!s->a) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    if (!s->p.area_weighting) {
        for (int32_t i = 0; i < s->nv; i++) s->a[i] = 1.0;
    } else {
        memset(s->a, 0, (size_t)s->nv * sizeof(double));
        for (int32_t e = 0; e < s->ne; e++) {
            const int32_t *el = s->E + (size_t)e * s->esz;
            double m;
            if (s->esz == 2) m = sqrt(dist2(s->Vrest + 3 * (size_t)el[0], s->Vrest + 3 * (size_t)el[1]));
            else if (s->vol) m = fabs(s->vol[e]);
            else {
                const double *x0 = s->Vrest + 3 * (size_t)el[0], *x1 = s->Vrest + 3 * (size_t)el[1], *x2 = s->Vrest + 3 * (size_t)el[2];
                double u[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]}, v[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
                double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
                m = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            }
            for (int c = 0; c < s->esz; c++) s->a[el[c]] += m / s->esz;
        }
    }
    if (s->fo_flag) /* vertices of degenerate elements only: no locality term (admm.h) */
        for (int32_t i = 0; i < s->nv; i++)
            if (s->fo_flag[i]) s->a[i] = 0.0;
    s->max_a = 0;
    for (int32_t i = 0; i < s->nv; i++) if (s->a[i] > s->max_a) s->max_a = s->a[i];
    return DF_OK;
}

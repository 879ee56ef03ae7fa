/* admm_degen.c — degenerate elements of the ADMM solver's mesh: classification (zero or near-zero
 * measure, repeated vertex), their exclusion from the energies, and the "followers": vertices
 * every element of which is degenerate, placed after each iteration at their rest offset from the
 * mean displacement of their neighbours through those elements (admm.h, df_admm_find_degenerate). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"

static double dist2(const double *x, const double *y)
{
    double d0 = x[0] - y[0], d1 = x[1] - y[1], d2 = x[2] - y[2];
    return d0 * d0 + d1 * d1 + d2 * d2;
}

/* |measure| of element el (esz corners) and its longest edge */
static double measure(const double *V, const int32_t *el, int esz, double *longest)
{
    double l = 0;
    for (int i = 0; i < esz; i++)
        for (int j = i + 1; j < esz; j++) {
            double d = dist2(V + 3 * (size_t)el[i], V + 3 * (size_t)el[j]);
            if (d > l) l = d;
        }
    *longest = sqrt(l);
    if (esz == 2) return *longest;
    const double *x0 = V + 3 * (size_t)el[0];
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = V[3 * (size_t)el[1] + k] - x0[k];
        v[k] = V[3 * (size_t)el[2] + k] - x0[k];
    }
    double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (esz == 3) return 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    double w[3];
    for (int k = 0; k < 3; k++) w[k] = V[3 * (size_t)el[3] + k] - x0[k];
    return fabs(cr[0] * w[0] + cr[1] * w[1] + cr[2] * w[2]) / 6.0;
}

static int cmp_d(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

/* flag[e] = 1 for the degenerate elements of the ne; *n_deg their count */
static int classify(const double *V, int32_t nv, const int32_t *E, int32_t ne, int esz,
                    uint8_t *flag, int32_t *n_deg, df_error *err)
{
    double *m = malloc((size_t)ne * sizeof(double)), *srt = malloc((size_t)ne * sizeof(double));
    if (!m || !srt) { free(m); free(srt); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    int d = esz - 1, n = 0;
    for (int32_t e = 0; e < ne; e++) {
        const int32_t *el = E + (size_t)e * esz;
        for (int a = 0; a < esz; a++)
            if (el[a] < 0 || el[a] >= nv) {
                free(m); free(srt);
                return df_error_set(err, DF_EINVAL, "admm: element %d references vertex %d (nv %d)",
                                    (int)e, (int)el[a], (int)nv);
            }
        double longest;
        m[e] = measure(V, el, esz, &longest);
        int rep = 0;
        for (int a = 0; a < esz; a++)
            for (int b = a + 1; b < esz; b++) rep |= el[a] == el[b];
        flag[e] = rep || !(m[e] > DF_ADMM_DEGENERATE_SHAPE_REL * pow(longest, d));
        if (!flag[e]) srt[n++] = m[e];
    }
    if (n > 0) { /* near-zero against the typical (median) element of the others */
        qsort(srt, (size_t)n, sizeof(double), cmp_d);
        double thr = DF_ADMM_DEGENERATE_SIZE_REL * srt[n / 2];
        for (int32_t e = 0; e < ne; e++)
            if (!flag[e] && !(m[e] > thr)) flag[e] = 1;
    }
    int32_t c = 0;
    for (int32_t e = 0; e < ne; e++) c += flag[e];
    *n_deg = c;
    free(m); free(srt);
    return DF_OK;
}

/* Followers of the flagged elements in placement order: fo_v[f] follows the mean displacement of
 * fo_src[fo_ptr[f] .. fo_ptr[f+1]), its neighbours in those elements placed before it (anchor[v]
 * = 1: fixed by the solve), or only those of them at its very rest position (V, nv x 3) if any.
 * Followers no anchor reaches are not listed (*at_rest counts them). Arrays may come back NULL
 * when there are no followers. */
static int plan(const double *V, int32_t nv, const int32_t *E, int32_t ne, int esz, const uint8_t *flag,
                const uint8_t *anchor, int32_t *n_fol, int32_t *at_rest, int32_t **fo_v,
                int32_t **fo_ptr, int32_t **fo_src, df_error *err)
{
    *fo_v = *fo_ptr = *fo_src = NULL;
    int32_t *lvl = malloc((size_t)nv * sizeof(int32_t));
    int32_t *dp = calloc((size_t)nv + 1, sizeof(int32_t));
    if (!lvl || !dp) { free(lvl); free(dp); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    int32_t nf = 0;
    int64_t npairs = 0;
    for (int32_t v = 0; v < nv; v++) lvl[v] = anchor[v] ? 0 : INT32_MAX;
    for (int32_t e = 0; e < ne; e++)
        if (flag[e])
            for (int a = 0; a < esz; a++) dp[E[(size_t)e * esz + a] + 1]++;
    for (int32_t v = 0; v < nv; v++) {
        if (dp[v + 1] && !anchor[v]) { nf++; npairs += (int64_t)dp[v + 1] * (esz - 1); }
        dp[v + 1] += dp[v];
    }
    *n_fol = nf;
    *at_rest = 0;
    if (nf == 0) { free(lvl); free(dp); return DF_OK; }
    int32_t *de = malloc((size_t)dp[nv] * sizeof(int32_t)), *fill = malloc((size_t)nv * sizeof(int32_t));
    int32_t *v_out = malloc((size_t)nf * sizeof(int32_t)), *ptr = calloc((size_t)nf + 1, sizeof(int32_t));
    int32_t *src = malloc((size_t)npairs * sizeof(int32_t));
    if (!de || !fill || !v_out || !ptr || !src) {
        free(lvl); free(dp); free(de); free(fill); free(v_out); free(ptr); free(src);
        return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    }
    memcpy(fill, dp, (size_t)nv * sizeof(int32_t));
    for (int32_t e = 0; e < ne; e++)
        if (flag[e])
            for (int a = 0; a < esz; a++) de[fill[E[(size_t)e * esz + a]]++] = e;
    int32_t placed = 0, ns = 0;
    for (int32_t pass = 1; placed < nf; pass++) {
        int32_t before = placed;
        for (int32_t v = 0; v < nv; v++) {
            if (lvl[v] != INT32_MAX || dp[v] == dp[v + 1]) continue;
            int32_t s0 = ns;
            for (int32_t t = dp[v]; t < dp[v + 1]; t++)
                for (int a = 0; a < esz; a++) {
                    int32_t j = E[(size_t)de[t] * esz + a];
                    if (j != v && lvl[j] < pass) src[ns++] = j;
                }
            int32_t nc = s0; /* sources at the very same rest position (a duplicated vertex):
                                follow those alone, so that the follower stays on its twin */
            for (int32_t t = s0; t < ns; t++)
                if (dist2(V + 3 * (size_t)src[t], V + 3 * (size_t)v) == 0.0) src[nc++] = src[t];
            if (nc > s0) ns = nc;
            if (ns > s0) { v_out[placed++] = v; ptr[placed] = ns; }
        }
        for (int32_t f = before; f < placed; f++) lvl[v_out[f]] = pass;
        if (placed == before) break;
    }
    *at_rest = nf - placed;
    *n_fol = placed;
    free(lvl); free(dp); free(de); free(fill);
    if (placed == 0) { free(v_out); free(ptr); free(src); return DF_OK; }
    *fo_v = v_out;
    *fo_ptr = ptr;
    *fo_src = src;
    return DF_OK;
}

int df_admm_find_degenerate(const df_mesh *m, uint8_t *flags, df_admm_degenerate *rep, df_error *err)
{
    if (!m || !rep) return df_error_set(err, DF_EINVAL, "admm_find_degenerate: NULL argument");
    int esz = df_mesh_elem_size(m->kind);
    if (esz == 0) return df_error_set(err, DF_EINVAL, "admm: unknown mesh kind %d", (int)m->kind);
    if (m->nv <= 0 || m->ne <= 0 || !m->V || !m->E) return df_error_set(err, DF_EINVAL, "admm: empty mesh");
    uint8_t *f = flags ? flags : malloc((size_t)m->ne);
    uint8_t *anchor = calloc((size_t)m->nv, 1);
    if (!f || !anchor) { if (!flags) free(f); free(anchor); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    df_admm_degenerate r = {0, 0, 0};
    int rc = classify(m->V, m->nv, m->E, m->ne, esz, f, &r.elements, err);
    int32_t *fv = NULL, *fp = NULL, *fs = NULL;
    if (!rc) {
        for (int32_t e = 0; e < m->ne; e++)
            if (!f[e])
                for (int a = 0; a < esz; a++) anchor[m->E[(size_t)e * esz + a]] = 1;
        rc = plan(m->V, m->nv, m->E, m->ne, esz, f, anchor, &r.followers, &r.at_rest, &fv, &fp, &fs, err);
    }
    free(fv); free(fp); free(fs); free(anchor);
    if (!flags) free(f);
    if (rc) return rc;
    *rep = r;
    return DF_OK;
}

void admm_free_degenerate(df_admm *s)
{
    free(s->E_in); free(s->e_map); free(s->fo_v); free(s->fo_ptr); free(s->fo_src); free(s->fo_flag);
    s->E_in = s->e_map = s->fo_v = s->fo_ptr = s->fo_src = NULL;
    s->fo_flag = NULL;
}

int admm_filter_degenerate(df_admm *s, const df_mesh *m, const int32_t *handles, int32_t nh,
                           const df_admm_affine *aff, int naff, df_error *err)
{
    int esz = s->esz;
    uint8_t *flag = malloc((size_t)m->ne), *anchor = calloc((size_t)m->nv, 1);
    s->E_in = malloc((size_t)m->ne * esz * sizeof(int32_t));
    if (!flag || !anchor || !s->E_in) { free(flag); free(anchor); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    s->ne_in = m->ne;
    memcpy(s->E_in, m->E, (size_t)m->ne * esz * sizeof(int32_t));
    int32_t nd = 0;
    int rc = classify(m->V, m->nv, m->E, m->ne, esz, flag, &nd, err);
    if (!rc && nd == m->ne)
        rc = df_error_set(err, DF_EINVAL, "admm: all %d elements are degenerate (zero or near-zero "
                          "measure, or a repeated vertex): nothing to deform", (int)m->ne);
    if (rc) { free(flag); free(anchor); return rc; }
    s->ne = m->ne - nd;
    s->deg.elements = nd;
    s->E = malloc((size_t)s->ne * esz * sizeof(int32_t));
    s->e_map = malloc((size_t)s->ne * sizeof(int32_t));
    if (!s->E || !s->e_map) { free(flag); free(anchor); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
    int32_t k = 0;
    for (int32_t e = 0; e < m->ne; e++) {
        if (flag[e]) continue;
        memcpy(s->E + (size_t)k * esz, m->E + (size_t)e * esz, (size_t)esz * sizeof(int32_t));
        for (int a = 0; a < esz; a++) anchor[m->E[(size_t)e * esz + a]] = 1;
        s->e_map[k++] = e;
    }
    /* handles and affine vertices are placed by the solve itself */
    for (int32_t h = 0; h < nh; h++) anchor[handles[h]] = 1;
    for (int t = 0; t < naff; t++)
        for (int32_t i = 0; i < aff[t].n; i++) anchor[aff[t].verts[i]] = 1;
    if (nd > 0)
        rc = plan(m->V, m->nv, m->E, m->ne, esz, flag, anchor, &s->deg.followers, &s->deg.at_rest,
                  &s->fo_v, &s->fo_ptr, &s->fo_src, err);
    free(flag);
    if (!rc && nd > 0) { /* followers and unreached ones: no locality term of their own */
        s->fo_flag = calloc((size_t)m->nv, 1);
        if (!s->fo_flag) rc = df_error_set(err, DF_ENOMEM, "admm: out of memory");
        else /* a vertex no anchor covers is one of degenerate elements only */
            for (int64_t t = 0; t < (int64_t)m->ne * esz; t++)
                if (!anchor[m->E[t]]) s->fo_flag[m->E[t]] = 1;
    }
    free(anchor);
    return rc;
}

void admm_place_followers(const df_admm *s, double *V)
{
    for (int32_t f = 0; f < s->deg.followers; f++) {
        int32_t v = s->fo_v[f], b = s->fo_ptr[f], e = s->fo_ptr[f + 1];
        double d[3] = {0, 0, 0};
        for (int32_t t = b; t < e; t++)
            for (int k = 0; k < 3; k++) d[k] += V[3 * (size_t)s->fo_src[t] + k] - s->Vrest[3 * (size_t)s->fo_src[t] + k];
        for (int k = 0; k < 3; k++) V[3 * (size_t)v + k] = s->Vrest[3 * (size_t)v + k] + d[k] / (double)(e - b);
    }
}

void df_admm_get_degenerate(const df_admm *s, df_admm_degenerate *out)
{
    if (!out) return;
    if (!s) { memset(out, 0, sizeof(*out)); return; }
    *out = s->deg;
}

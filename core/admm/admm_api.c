/* admm_api.c — solver lifetime and state access: create (validation, operators, factorization),
 * set_targets, set_positions, positions, evaluate, reset_rest (sculpting), stats, free. */
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"
#include "core/admm/nh_prox.h"

/* Energy and mesh kind by their wire / deformctl names ("--energy polyline"). */
static const char *energy_name(df_admm_energy e)
{
    switch (e) {
    case DF_ADMM_ARAP: return "arap";
    case DF_ADMM_ACAP: return "acap";
    case DF_ADMM_NEOHOOKEAN: return "neohookean";
    case DF_ADMM_CLOTH: return "cloth";
    case DF_ADMM_POLYLINE: return "polyline";
    }
    return "unknown";
}

static const char *kind_name(df_mesh_kind k)
{
    return k == DF_MESH_POLYLINE ? "a polyline" : k == DF_MESH_TRIANGLE ? "a triangle mesh"
           : k == DF_MESH_TET ? "a tet mesh" : "of unknown kind";
}

/* The energy that fits a mesh kind, to suggest in the error. */
static const char *energy_for(df_mesh_kind k)
{
    return k == DF_MESH_POLYLINE ? "polyline" : k == DF_MESH_TRIANGLE ? "arap, acap or cloth"
           : "arap, acap or neohookean";
}

static int check_kind(const df_admm_params *p, const df_mesh *m, df_error *err)
{
    df_mesh_kind k = m->kind;
    const char *needs = NULL;
    switch (p->energy) {
    case DF_ADMM_ARAP:
    case DF_ADMM_ACAP:
        if (k == DF_MESH_TRIANGLE || k == DF_MESH_TET) return DF_OK;
        needs = "triangles or tets";
        break;
    case DF_ADMM_NEOHOOKEAN:
        if (k == DF_MESH_TET) return DF_OK;
        needs = "tets";
        break;
    case DF_ADMM_CLOTH:
        if (k == DF_MESH_TRIANGLE) return DF_OK;
        needs = "triangles";
        break;
    case DF_ADMM_POLYLINE:
        if (k == DF_MESH_POLYLINE) return DF_OK;
        needs = "a polyline (segments)";
        break;
    default:
        return df_error_set(err, DF_EINVAL, "admm: unknown energy %d", (int)p->energy);
    }
    return df_error_set(err, DF_EINVAL, "admm: energy %s needs %s; this mesh is %s: use energy "
                        "%s (deformctl --energy %s)", energy_name(p->energy), needs, kind_name(k),
                        energy_for(k), k == DF_MESH_POLYLINE ? "polyline" : "arap");
}

static int check_inputs(const df_mesh *m, const df_admm_params *p, const int32_t *handles, int32_t nh,
                        const df_admm_affine *aff, int naff, df_error *err)
{
    int rc = admm_validate_params(p, err);
    if (rc) return rc;
    int esz = df_mesh_elem_size(m->kind);
    if (esz == 0) return df_error_set(err, DF_EINVAL, "admm: unknown mesh kind %d", (int)m->kind);
    if (m->nv <= 0 || m->ne <= 0 || !m->V || !m->E) return df_error_set(err, DF_EINVAL, "admm: empty mesh");
    if (m->nv > DF_ADMM_MAX_VERTICES)
        return df_error_set(err, DF_ELIMIT, "admm: %d vertices exceed the limit %d", (int)m->nv, DF_ADMM_MAX_VERTICES);
    rc = check_kind(p, m, err);
    if (rc) return rc;
    for (int64_t i = 0; i < 3 * (int64_t)m->nv; i++)
        if (!isfinite(m->V[i])) return df_error_set(err, DF_EINVAL, "admm: vertex %d has a non-finite coordinate", (int)(i / 3));
    for (int64_t t = 0; t < (int64_t)m->ne * esz; t++)
        if (m->E[t] < 0 || m->E[t] >= m->nv)
            return df_error_set(err, DF_EINVAL, "admm: element %d references vertex %d (nv %d)", (int)(t / esz), (int)m->E[t], (int)m->nv);
    if (!handles || nh <= 0) return df_error_set(err, DF_EINVAL, "admm: empty handle set");
    if (nh >= m->nv) return df_error_set(err, DF_EINVAL, "admm: %d handles leave no free vertex", (int)nh);
    char *seen = calloc((size_t)m->nv, 1);
    if (!seen) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    for (int32_t h = 0; h < nh; h++) {
        int32_t v = handles[h];
        if (v < 0 || v >= m->nv) { free(seen); return df_error_set(err, DF_EINVAL, "admm: handle %d = vertex %d out of range [0, %d)", (int)h, (int)v, (int)m->nv); }
        if (seen[v]) { free(seen); return df_error_set(err, DF_EINVAL, "admm: vertex %d is a handle twice", (int)v); }
        seen[v] = 1;
    }
    if (naff < 0 || (naff > 0 && !aff)) { free(seen); return df_error_set(err, DF_EINVAL, "admm: bad affine set list"); }
    int64_t rows = 0;
    for (int k = 0; k < naff; k++) {
        const df_admm_affine *a = aff + k;
        if (a->n <= 0 || !a->verts || a->m < 1 || a->m > 3) { free(seen); return df_error_set(err, DF_EINVAL, "admm: affine set %d is empty or has m = %d", k, a->m); }
        for (int i = 0; i < 3 * a->m; i++)
            if (!isfinite(a->A[i])) { free(seen); return df_error_set(err, DF_EINVAL, "admm: affine set %d has a non-finite A", k); }
        for (int i = 0; i < a->m; i++)
            if (!isfinite(a->b[i])) { free(seen); return df_error_set(err, DF_EINVAL, "admm: affine set %d has a non-finite b", k); }
        for (int32_t t = 0; t < a->n; t++) {
            int32_t v = a->verts[t];
            if (v < 0 || v >= m->nv) { free(seen); return df_error_set(err, DF_EINVAL, "admm: affine set %d vertex %d out of range", k, (int)v); }
            if (seen[v] == 1) { free(seen); return df_error_set(err, DF_EINVAL, "admm: affine set %d vertex %d is also a handle", k, (int)v); }
        }
        rows += (int64_t)a->n * a->m;
    }
    free(seen);
    if (rows > DF_ADMM_MAX_AFFINE_ROWS)
        return df_error_set(err, DF_ELIMIT, "admm: %lld affine rows exceed the limit %d", (long long)rows, DF_ADMM_MAX_AFFINE_ROWS);
    return DF_OK;
}

int df_admm_create(const df_mesh *mesh, const df_admm_params *params, const int32_t *handles,
                   int32_t nh, const df_admm_affine *affine, int n_affine, df_admm **out, df_error *err)
{
    if (!mesh || !params || !out) return df_error_set(err, DF_EINVAL, "admm_create: NULL argument");
    int rc = check_inputs(mesh, params, handles, nh, affine, n_affine, err);
    if (rc) return rc;
    df_admm *s = calloc(1, sizeof(*s));
    if (!s) return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    s->p = *params;
    s->kind = mesh->kind;
    s->nv = mesh->nv;
    s->esz = df_mesh_elem_size(mesh->kind);
    rc = admm_filter_degenerate(s, mesh, handles, nh, affine, n_affine, err); /* sets E, ne */
    if (rc) { df_admm_free(s); return rc; }
    /* 2D only when the mesh is declared 2D: a flat 3D mesh (every z = 0) deforms in 3D */
    s->planar = mesh->planar != 0;
#ifdef _OPENMP
    s->nthreads = params->threads > 0 ? params->threads : omp_get_max_threads();
#else
    s->nthreads = 1; /* built without OpenMP (make tsan): every kernel is serial */
#endif
    s->family = (mesh->kind == DF_MESH_TET || params->energy == DF_ADMM_CLOTH) ? ADMM_FAM_ELEMENT : ADMM_FAM_VERTEX;
    s->q = mesh->kind == DF_MESH_TET ? 3 : 2;
    df_admm_lame(params->youngs, params->poisson, &s->mu, &s->lambda);
    s->E_last = NAN;
    s->el_last = s->lo_last = NAN;
    size_t nv3 = (size_t)s->nv * 3;
    s->n_state = 6 * (int64_t)s->nv + (s->family == ADMM_FAM_ELEMENT ? 9 * (int64_t)s->ne : 0);
    s->Vrest = malloc(nv3 * sizeof(double));
    s->state = calloc((size_t)s->n_state, sizeof(double));
    s->Vout = malloc(nv3 * sizeof(double));
    s->Z = calloc(nv3, sizeof(double));
    s->hidx = malloc((size_t)nh * sizeof(int32_t));
    s->target = malloc((size_t)nh * 3 * sizeof(double));
    s->target_req = malloc((size_t)nh * 3 * sizeof(double));
    s->damp = params->energy == DF_ADMM_NEOHOOKEAN;
    if (s->damp) {
        s->damp_va = malloc(nv3 * sizeof(double));
        s->damp_dp = malloc((size_t)nh * 3 * sizeof(double));
    }
    if (s->family == ADMM_FAM_ELEMENT) {
        s->RX = calloc((size_t)s->ne * 9, sizeof(double));
        s->Ce = calloc((size_t)s->ne * s->esz * 3, sizeof(double));
    }
    if (params->energy == DF_ADMM_NEOHOOKEAN) {
        s->nhQ = malloc((size_t)s->ne * 9 * sizeof(double));
        s->nhx = calloc((size_t)s->ne * 3, sizeof(double)); /* zeros: no warm start yet */
        if (!s->nhQ || !s->nhx) {
            df_admm_free(s);
            return df_error_set(err, DF_ENOMEM, "admm: out of memory");
        }
        for (int32_t e = 0; e < s->ne; e++) {
            double *Q = s->nhQ + 9 * (size_t)e;
            memset(Q, 0, 9 * sizeof(double));
            Q[0] = Q[4] = Q[8] = 1.0;
        }
    }
    if (!s->E || !s->Vrest || !s->state || !s->Vout || !s->Z || !s->hidx || !s->target || !s->target_req ||
        (s->damp && (!s->damp_va || !s->damp_dp)) ||
        (s->family == ADMM_FAM_ELEMENT && (!s->RX || !s->Ce))) {
        df_admm_free(s);
        return df_error_set(err, DF_ENOMEM, "admm: out of memory");
    }
    memcpy(s->Vrest, mesh->V, nv3 * sizeof(double));
    s->V = s->state;
    s->U = s->state + nv3;
    s->W = s->family == ADMM_FAM_ELEMENT ? s->state + 2 * nv3 : NULL;
    memcpy(s->V, mesh->V, nv3 * sizeof(double));
    memcpy(s->Vout, mesh->V, nv3 * sizeof(double));
    s->nh = nh;
    memcpy(s->hidx, handles, (size_t)nh * sizeof(int32_t));
    for (int32_t h = 0; h < nh; h++) memcpy(s->target + 3 * (size_t)h, mesh->V + 3 * (size_t)handles[h], 3 * sizeof(double));
    memcpy(s->target_req, s->target, (size_t)nh * 3 * sizeof(double));
    if (n_affine > 0) {
        s->aff = calloc((size_t)n_affine, sizeof(df_admm_affine));
        if (!s->aff) { df_admm_free(s); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
        s->naff = n_affine;
        for (int k = 0; k < n_affine; k++) {
            s->aff[k] = affine[k];
            int32_t *v = malloc((size_t)affine[k].n * sizeof(int32_t));
            if (!v) { s->aff[k].verts = NULL; s->aff[k].n = 0; df_admm_free(s); return df_error_set(err, DF_ENOMEM, "admm: out of memory"); }
            memcpy(v, affine[k].verts, (size_t)affine[k].n * sizeof(int32_t));
            s->aff[k].verts = v;
        }
    }
    rc = admm_build_operators(s, err);
    if (!rc) admm_rho_init(s); /* params.rho <= 0: the adaptive penalty's initial rho */
    if (!rc && !(s->p.rho * s->p.s > s->p.w * s->max_a))
        rc = df_error_set(err, DF_EINVAL,
                          "admm: rho = %g must exceed w max(a_i) / s = %g (SC-L1 prox would be nonconvex)",
                          s->p.rho, s->p.w * s->max_a / s->p.s);
    /* active-set mode: the whole-mesh factorization waits until a full run needs it */
    if (!rc)
        rc = admm_active_defers(s) ? admm_active_prepare(s, err)
                                   : admm_build_system_affine(s, s->aff, s->naff, err);
    if (!rc) admm_rho_set_gap(s);
    if (!rc && s->p.accelerate && admm_aa_init(&s->aa, s->p.anderson_m, s->n_state))
        rc = df_error_set(err, DF_ENOMEM, "admm: out of memory (Anderson history)");
    s->aa.nthreads = s->nthreads;
    if (rc) { df_admm_free(s); return rc; }
    *out = s;
    return DF_OK;
}

int df_admm_set_targets(df_admm *s, const double *targets, df_error *err)
{
    if (!s || !targets) return df_error_set(err, DF_EINVAL, "admm_set_targets: NULL argument");
    for (int64_t i = 0; i < 3 * (int64_t)s->nh; i++)
        if (!isfinite(targets[i])) return df_error_set(err, DF_EINVAL, "admm_set_targets: target of handle %d is not finite", (int)(i / 3));
    if (s->planar) /* a 2D solve would drop z: a handle would silently miss its target */
        for (int32_t k = 0; k < s->nh; k++)
            if (targets[3 * (size_t)k + 2] != 0.0)
                return df_error_set(err, DF_EINVAL, "admm_set_targets: the mesh is 2D, but the "
                                    "target of handle %d has z = %g (load the mesh as 3D to move "
                                    "it out of the z = 0 plane)", (int)k, targets[3 * (size_t)k + 2]);
    memcpy(s->target_req, targets, (size_t)s->nh * 3 * sizeof(double));
    if (s->damp) {
        /* applied by the next global steps, damped (admm_damp.c) */
        s->tgt_pending = memcmp(s->target_req, s->target, (size_t)s->nh * 3 * sizeof(double)) != 0;
        s->damp_stall = 0;
    } else {
        memcpy(s->target, targets, (size_t)s->nh * 3 * sizeof(double));
        admm_update_kfhp(s);
    }
    if (s->p.accelerate) admm_aa_reset(&s->aa);
    /* the objective does not depend on the targets: E_last (of the current positions) stays valid */
    return DF_OK;
}

int df_admm_set_positions(df_admm *s, const double *V, int32_t *n_changed, df_error *err)
{
    if (!s || !V) return df_error_set(err, DF_EINVAL, "admm_set_positions: NULL argument");
    size_t nv3 = (size_t)s->nv * 3;
    for (size_t i = 0; i < nv3; i++)
        if (!isfinite(V[i])) return df_error_set(err, DF_EINVAL, "admm_set_positions: vertex %d is not finite", (int)(i / 3));
    int32_t changed = 0;
    for (int32_t i = 0; i < s->nv; i++) {
        size_t o = 3 * (size_t)i;
        if (memcmp(V + o, s->Vout + o, 3 * sizeof(double)) == 0) continue;
        changed++;
        for (int k = 0; k < 3; k++) {
            s->V[o + k] = V[o + k];
            s->Z[o + k] = V[o + k] - s->Vrest[o + k];
            s->U[o + k] = 0.0;
        }
    }
    if (n_changed) *n_changed = changed;
    if (changed == 0) return DF_OK;
    admm_active_stale(s); /* changed vertices may lie outside the active region */
    if (s->W) /* element duals of elements touching a changed vertex */
        for (int32_t e = 0; e < s->ne; e++) {
            const int32_t *el = s->E + (size_t)e * s->esz;
            for (int a = 0; a < s->esz; a++)
                if (memcmp(V + 3 * (size_t)el[a], s->Vout + 3 * (size_t)el[a], 3 * sizeof(double))) {
                    memset(s->W + 9 * (size_t)e, 0, 9 * sizeof(double));
                    break;
                }
        }
    memcpy(s->Vout, V, nv3 * sizeof(double));
    if (s->damp) { /* damped handle steps restart from where the handles are now */
        for (int32_t h = 0; h < s->nh; h++) memcpy(s->target + 3 * (size_t)h, V + 3 * (size_t)s->hidx[h], 3 * sizeof(double));
        s->tgt_pending = memcmp(s->target_req, s->target, (size_t)s->nh * 3 * sizeof(double)) != 0;
        s->damp_stall = 0;
        admm_update_kfhp(s);
    }
    if (s->p.accelerate) admm_aa_reset(&s->aa);
    s->E_last = NAN;
    s->el_last = s->lo_last = NAN;
    return DF_OK;
}

int32_t df_admm_num_vertices(const df_admm *s) { return s ? s->nv : 0; }

const double *df_admm_positions(const df_admm *s) { return s ? s->Vout : NULL; }

int df_admm_get_positions(const df_admm *s, double *V_out, df_error *err)
{
    if (!s || !V_out) return df_error_set(err, DF_EINVAL, "admm_get_positions: NULL argument");
    memcpy(V_out, s->Vout, (size_t)s->nv * 3 * sizeof(double));
    return DF_OK;
}

int df_admm_evaluate(const df_admm *s, const double *V, double *elastic, double *locality, df_error *err)
{
    if (!s || !V) return df_error_set(err, DF_EINVAL, "admm_evaluate: NULL argument");
    for (int64_t i = 0; i < 3 * (int64_t)s->nv; i++)
        if (!isfinite(V[i])) return df_error_set(err, DF_EINVAL, "admm_evaluate: vertex %d is not finite", (int)(i / 3));
    double el = admm_elastic(s, V);
    if (!isfinite(el)) return df_error_set(err, DF_EINVAL, "admm_evaluate: infinite elastic energy (inverted element)");
    if (elastic) *elastic = el;
    if (locality) *locality = admm_locality(s, V);
    return DF_OK;
}

int df_admm_reset_rest(df_admm *s, df_error *err)
{
    if (!s) return df_error_set(err, DF_EINVAL, "admm_reset_rest: NULL solver");
    df_mesh m;
    memset(&m, 0, sizeof(m));
    m.kind = s->kind;
    m.nv = s->nv;
    m.V = s->Vout;
    m.ne = s->ne_in; /* as given: classified again on the new rest shape */
    m.E = s->E_in;
    df_admm *n = NULL;
    df_admm_params p = s->p;
    p.rho = s->rho_req; /* adaptive stays adaptive (from its initial rho on the new rest shape) */
    int rc = df_admm_create(&m, &p, s->hidx, s->nh, s->aff, s->naff, &n, err);
    if (rc) return rc;
    n->st.analyses += s->st.analyses;
    n->st.factorizations += s->st.factorizations;
    n->st.solves += s->st.solves;
    n->st.iterations = s->st.iterations;
    n->st.refactorizations += s->st.refactorizations;
    n->st.rho_changes += s->st.rho_changes;
    df_admm tmp = *s;
    *s = *n;
    *n = tmp;
    df_admm_free(n);
    return DF_OK;
}

double df_admm_rho(const df_admm *s) { return s ? s->p.rho : 0.0; }

void df_admm_get_stats(const df_admm *s, df_admm_stats *out)
{
    if (!out) return;
    if (!s) { memset(out, 0, sizeof(*out)); return; }
    *out = s->st;
}

void df_admm_free(df_admm *s)
{
    if (!s) return;
    admm_polish_free(s);
    admm_free_system(s);
    admm_active_free(s);
    if (s->cc_started) cholmod_finish(&s->cc);
    admm_free_operators(s);
    admm_free_degenerate(s);
    admm_aa_free(&s->aa);
    for (int k = 0; k < s->naff; k++) free((void *)s->aff[k].verts);
    free(s->aff);
    free(s->E); free(s->Vrest); free(s->state); free(s->Vout); free(s->Z); free(s->hidx); free(s->target);
    free(s->target_req); free(s->damp_va); free(s->damp_dp);
    free(s->RX); free(s->Ce); free(s->Rv); free(s->nhQ); free(s->nhx);
    free(s);
}

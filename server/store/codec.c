/* codec.c — the store's blob layouts (see codec.h). */
#include "server/store/codec.h"
#include "server/session/blob_io.h"

#include <stdlib.h>
#include <string.h>

/* ---- brush ---- */
void df_codec_brush_pack(const df_brush_state *b, uint8_t out[DF_CODEC_BRUSH_BYTES])
{
    df_wbuf w = {out, 0};
    df_wput(&w, &b->type, 1);
    df_wput(&w, &b->falloff, 1);
    df_wput(&w, &b->integrator, 1);
    df_wput(&w, &b->has_mirror, 1);
    df_wput(&w, &b->steps, 2);
    df_wput_f64(&w, b->radius);
    df_wput_f64(&w, b->nu);
    df_wput_f64(&w, b->strength);
    df_wput_f64(&w, b->ratio);
    for (int k = 0; k < 3; k++) df_wput_f64(&w, b->mirror_point[k]);
    for (int k = 0; k < 3; k++) df_wput_f64(&w, b->mirror_normal[k]);
}

int df_codec_brush_unpack(const uint8_t *p, size_t len, df_brush_state *out, df_error *err)
{
    if (len != DF_CODEC_BRUSH_BYTES)
        return df_error_set(err, DF_EFORMAT, "store: brush blob of %zu bytes, %d expected", len,
                            DF_CODEC_BRUSH_BYTES);
    df_rbuf r = {p, len, 0, 0};
    memset(out, 0, sizeof *out);
    df_rget(&r, &out->type, 1);
    df_rget(&r, &out->falloff, 1);
    df_rget(&r, &out->integrator, 1);
    df_rget(&r, &out->has_mirror, 1);
    df_rget(&r, &out->steps, 2);
    out->radius = df_rget_f64(&r);
    out->nu = df_rget_f64(&r);
    out->strength = df_rget_f64(&r);
    out->ratio = df_rget_f64(&r);
    for (int k = 0; k < 3; k++) out->mirror_point[k] = df_rget_f64(&r);
    for (int k = 0; k < 3; k++) out->mirror_normal[k] = df_rget_f64(&r);
    return DF_OK;
}

/* ---- handle set ---- */
#define PARAMS_BYTES (4 + 4 * 8 + 4 + 2 * 8 + 3 * 4 + 3 * 8 + 4)

int df_codec_handles_encode(const df_handleset *hs, uint8_t **out, size_t *len, df_error *err)
{
    size_t n = PARAMS_BYTES + 12 + 4 * (size_t)hs->nh;
    for (int a = 0; a < hs->n_affine; a++) n += 8 + 12 * 8 + 4 * (size_t)hs->affine[a].n;
    df_wbuf w = {malloc(n), 0};
    if (!w.p) return df_error_set(err, DF_ENOMEM, "store: out of memory encoding handles");
    const df_admm_params *p = &hs->params;
    df_wput_i32(&w, (int32_t)p->energy);
    df_wput_f64(&w, p->w);
    df_wput_f64(&w, p->s);
    df_wput_f64(&w, p->rho);
    df_wput_f64(&w, p->tol);
    df_wput_i32(&w, p->max_iters);
    df_wput_f64(&w, p->youngs);
    df_wput_f64(&w, p->poisson);
    df_wput_i32(&w, p->area_weighting);
    df_wput_i32(&w, p->accelerate);
    df_wput_i32(&w, p->anderson_m);
    df_wput_f64(&w, p->strain_min);
    df_wput_f64(&w, p->strain_max);
    df_wput_f64(&w, p->bending);
    df_wput_i32(&w, p->threads);
    df_wput_i32(&w, hs->nh);
    df_wput_i32(&w, hs->n_affine);
    df_wput_i32(&w, hs->max_iters);
    df_wput(&w, hs->handles, 4 * (size_t)hs->nh);
    for (int a = 0; a < hs->n_affine; a++) {
        const df_admm_affine *f = &hs->affine[a];
        df_wput_i32(&w, f->n);
        df_wput_i32(&w, f->m);
        for (int k = 0; k < 9; k++) df_wput_f64(&w, f->A[k]);
        for (int k = 0; k < 3; k++) df_wput_f64(&w, f->b[k]);
        df_wput(&w, f->verts, 4 * (size_t)f->n);
    }
    *out = w.p;
    *len = w.n;
    return DF_OK;
}

static int bad_index(const int32_t *v, int32_t n, int32_t nv)
{
    for (int32_t i = 0; i < n; i++)
        if (v[i] < 0 || v[i] >= nv) return 1;
    return 0;
}

int df_codec_handles_decode(const uint8_t *b, size_t len, int32_t nv, df_handleset **out,
                            df_error *err)
{
    *out = NULL;
    df_rbuf r = {b, len, 0, 0};
    df_handleset *hs = calloc(1, sizeof *hs);
    if (!hs) return df_error_set(err, DF_ENOMEM, "store: out of memory reading handles");
    df_admm_params *p = &hs->params;
    p->energy = (df_admm_energy)df_rget_i32(&r);
    p->w = df_rget_f64(&r);
    p->s = df_rget_f64(&r);
    p->rho = df_rget_f64(&r);
    p->tol = df_rget_f64(&r);
    p->max_iters = df_rget_i32(&r);
    p->youngs = df_rget_f64(&r);
    p->poisson = df_rget_f64(&r);
    p->area_weighting = df_rget_i32(&r);
    p->accelerate = df_rget_i32(&r);
    p->anderson_m = df_rget_i32(&r);
    p->strain_min = df_rget_f64(&r);
    p->strain_max = df_rget_f64(&r);
    p->bending = df_rget_f64(&r);
    p->threads = df_rget_i32(&r);
    hs->nh = df_rget_i32(&r);
    int na = df_rget_i32(&r);
    hs->max_iters = df_rget_i32(&r);
    int rc = DF_OK;
    if (r.bad || hs->nh < 1 || hs->nh > nv || na < 0 || na > DF_ADMM_MAX_AFFINE_ROWS ||
        (size_t)hs->nh * 4 > len - r.at) {
        rc = DF_EFORMAT;
    } else if (!(hs->handles = malloc(4 * (size_t)hs->nh)) ||
               (na && !(hs->affine = calloc((size_t)na, sizeof *hs->affine)))) {
        rc = DF_ENOMEM;
    } else {
        df_rget(&r, hs->handles, 4 * (size_t)hs->nh);
        if (bad_index(hs->handles, hs->nh, nv)) rc = DF_EFORMAT;
        for (int a = 0; a < na && rc == DF_OK; a++) {
            df_admm_affine *f = &hs->affine[a];
            f->n = df_rget_i32(&r);
            f->m = df_rget_i32(&r);
            for (int k = 0; k < 9; k++) f->A[k] = df_rget_f64(&r);
            for (int k = 0; k < 3; k++) f->b[k] = df_rget_f64(&r);
            if (r.bad || f->n < 0 || f->n > nv || f->m < 1 || f->m > 3 ||
                (size_t)f->n * 4 > len - r.at) {
                rc = DF_EFORMAT;
                break;
            }
            int32_t *v = malloc(4 * (size_t)(f->n ? f->n : 1));
            if (!v) {
                rc = DF_ENOMEM;
                break;
            }
            df_rget(&r, v, 4 * (size_t)f->n);
            f->verts = v;
            hs->n_affine = a + 1;
            if (bad_index(v, f->n, nv)) rc = DF_EFORMAT;
        }
        if (rc == DF_OK && (r.bad || r.at != len)) rc = DF_EFORMAT;
    }
    if (rc != DF_OK) {
        df_handleset_free(NULL, hs);
        return df_error_set(err, rc, rc == DF_ENOMEM ? "store: out of memory reading handles"
                                                     : "store: malformed handle-set blob (%zu "
                                                       "bytes)", len);
    }
    *out = hs;
    return DF_OK;
}

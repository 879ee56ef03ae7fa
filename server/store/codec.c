/* codec.c — the store's blob layouts (see codec.h). */
#include "server/store/codec.h"

#include <stdlib.h>
#include <string.h>

/* ---- a bounded writer / reader ---- */
typedef struct wbuf {
    uint8_t *p;
    size_t n;
} wbuf;
static void put(wbuf *w, const void *v, size_t n)
{
    memcpy(w->p + w->n, v, n);
    w->n += n;
}
static void put_i32(wbuf *w, int32_t v) { put(w, &v, 4); }
static void put_f64(wbuf *w, double v) { put(w, &v, 8); }

typedef struct rbuf {
    const uint8_t *p;
    size_t n, at;
    int bad;
} rbuf;
static void get(rbuf *r, void *v, size_t n)
{
    if (r->bad || n > r->n - r->at) {
        r->bad = 1;
        memset(v, 0, n);
        return;
    }
    memcpy(v, r->p + r->at, n);
    r->at += n;
}
static int32_t get_i32(rbuf *r)
{
    int32_t v;
    get(r, &v, 4);
    return v;
}
static double get_f64(rbuf *r)
{
    double v;
    get(r, &v, 8);
    return v;
}


/* ---- brush ---- */
void df_codec_brush_pack(const df_brush_state *b, uint8_t out[DF_CODEC_BRUSH_BYTES])
{
    wbuf w = {out, 0};
    put(&w, &b->type, 1);
    put(&w, &b->falloff, 1);
    put(&w, &b->integrator, 1);
    put(&w, &b->has_mirror, 1);
    put(&w, &b->steps, 2);
    put_f64(&w, b->radius);
    put_f64(&w, b->nu);
    put_f64(&w, b->strength);
    put_f64(&w, b->ratio);
    for (int k = 0; k < 3; k++) put_f64(&w, b->mirror_point[k]);
    for (int k = 0; k < 3; k++) put_f64(&w, b->mirror_normal[k]);
}

int df_codec_brush_unpack(const uint8_t *p, size_t len, df_brush_state *out, df_error *err)
{
    if (len != DF_CODEC_BRUSH_BYTES)
        return df_error_set(err, DF_EFORMAT, "store: brush blob of %zu bytes, %d expected", len,
                            DF_CODEC_BRUSH_BYTES);
    rbuf r = {p, len, 0, 0};
    memset(out, 0, sizeof *out);
    get(&r, &out->type, 1);
    get(&r, &out->falloff, 1);
    get(&r, &out->integrator, 1);
    get(&r, &out->has_mirror, 1);
    get(&r, &out->steps, 2);
    out->radius = get_f64(&r);
    out->nu = get_f64(&r);
    out->strength = get_f64(&r);
    out->ratio = get_f64(&r);
    for (int k = 0; k < 3; k++) out->mirror_point[k] = get_f64(&r);
    for (int k = 0; k < 3; k++) out->mirror_normal[k] = get_f64(&r);
    return DF_OK;
}

/* ---- handle set ---- */
#define PARAMS_BYTES (4 + 4 * 8 + 4 + 2 * 8 + 3 * 4 + 3 * 8 + 4)

int df_codec_handles_encode(const df_handleset *hs, uint8_t **out, size_t *len, df_error *err)
{
    size_t n = PARAMS_BYTES + 12 + 4 * (size_t)hs->nh;
    for (int a = 0; a < hs->n_affine; a++) n += 8 + 12 * 8 + 4 * (size_t)hs->affine[a].n;
    wbuf w = {malloc(n), 0};
    if (!w.p) return df_error_set(err, DF_ENOMEM, "store: out of memory encoding handles");
    const df_admm_params *p = &hs->params;
    put_i32(&w, (int32_t)p->energy);
    put_f64(&w, p->w);
    put_f64(&w, p->s);
    put_f64(&w, p->rho);
    put_f64(&w, p->tol);
    put_i32(&w, p->max_iters);
    put_f64(&w, p->youngs);
    put_f64(&w, p->poisson);
    put_i32(&w, p->area_weighting);
    put_i32(&w, p->accelerate);
    put_i32(&w, p->anderson_m);
    put_f64(&w, p->strain_min);
    put_f64(&w, p->strain_max);
    put_f64(&w, p->bending);
    put_i32(&w, p->threads);
    put_i32(&w, hs->nh);
    put_i32(&w, hs->n_affine);
    put_i32(&w, hs->max_iters);
    put(&w, hs->handles, 4 * (size_t)hs->nh);
    for (int a = 0; a < hs->n_affine; a++) {
        const df_admm_affine *f = &hs->affine[a];
        put_i32(&w, f->n);
        put_i32(&w, f->m);
        for (int k = 0; k < 9; k++) put_f64(&w, f->A[k]);
        for (int k = 0; k < 3; k++) put_f64(&w, f->b[k]);
        put(&w, f->verts, 4 * (size_t)f->n);
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
    rbuf r = {b, len, 0, 0};
    df_handleset *hs = calloc(1, sizeof *hs);
    if (!hs) return df_error_set(err, DF_ENOMEM, "store: out of memory reading handles");
    df_admm_params *p = &hs->params;
    p->energy = (df_admm_energy)get_i32(&r);
    p->w = get_f64(&r);
    p->s = get_f64(&r);
    p->rho = get_f64(&r);
    p->tol = get_f64(&r);
    p->max_iters = get_i32(&r);
    p->youngs = get_f64(&r);
    p->poisson = get_f64(&r);
    p->area_weighting = get_i32(&r);
    p->accelerate = get_i32(&r);
    p->anderson_m = get_i32(&r);
    p->strain_min = get_f64(&r);
    p->strain_max = get_f64(&r);
    p->bending = get_f64(&r);
    p->threads = get_i32(&r);
    hs->nh = get_i32(&r);
    int na = get_i32(&r);
    hs->max_iters = get_i32(&r);
    int rc = DF_OK;
    if (r.bad || hs->nh < 1 || hs->nh > nv || na < 0 || na > DF_ADMM_MAX_AFFINE_ROWS ||
        (size_t)hs->nh * 4 > len - r.at) {
        rc = DF_EFORMAT;
    } else if (!(hs->handles = malloc(4 * (size_t)hs->nh)) ||
               (na && !(hs->affine = calloc((size_t)na, sizeof *hs->affine)))) {
        rc = DF_ENOMEM;
    } else {
        get(&r, hs->handles, 4 * (size_t)hs->nh);
        if (bad_index(hs->handles, hs->nh, nv)) rc = DF_EFORMAT;
        for (int a = 0; a < na && rc == DF_OK; a++) {
            df_admm_affine *f = &hs->affine[a];
            f->n = get_i32(&r);
            f->m = get_i32(&r);
            for (int k = 0; k < 9; k++) f->A[k] = get_f64(&r);
            for (int k = 0; k < 3; k++) f->b[k] = get_f64(&r);
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
            get(&r, v, 4 * (size_t)f->n);
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

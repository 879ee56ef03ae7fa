/* stroke_recipe.c — a stroke kept as its request, recomputed on demand (see stroke_recipe.h). */
#include "server/session/stroke_recipe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_surface.h"
#include "core/mesh/geodesic.h"

#define RECIPE_MAGIC_V1 0x31525344u /* "DSR1" */
#define RECIPE_MAGIC_V2 0x32525344u /* "DSR2": + i32 surface */
#define RECIPE_MAGIC 0x33525344u    /* "DSR3": + i32 arith */

void df_stroke_loaded_brush(const df_kelvinlet_brush *b, double strength,
                            const double load[DF_STROKE_LOAD_N], df_kelvinlet_brush *out)
{
    df_kelvinlet_brush t = *b;
    for (int i = 0; i < 3; i++) {
        t.tip[i] = strength * load[i];
        t.omega[i] = strength * load[3 + i];
    }
    t.s = strength * load[6];
    for (int i = 0; i < 9; i++) t.grad[i] = strength * load[7 + i];
    *out = t;
}

void df_stroke_motion(const float *x0, float *d, const double *base, double *pos, size_t n)
{
#pragma omp simd /* one fused pass; distinct arrays (gcc -O2 would not vectorize it) */
    for (size_t i = 0; i < n; i++) {
        float m = (x0[i] + d[i]) - x0[i];
        d[i] = m;
        pos[i] = base[i] + (double)m;
    }
}

/* x0 (n floats) widened to a new double array, or NULL (out of memory). */
static double *widen(const float *x0, size_t n)
{
    double *x = malloc(n * sizeof *x);
    if (x)
        for (size_t i = 0; i < n; i++) x[i] = (double)x0[i];
    return x;
}

int32_t df_stroke_surface_src(const float *x0, int32_t nv, const double *c)
{
    if (!x0 || !c || nv <= 0) return -1;
    int32_t best = 0;
    double bd = INFINITY;
    for (int32_t i = 0; i < nv; i++) { /* df_mesh_nearest_vertex over (double)x0 */
        const float *p = x0 + 3 * (size_t)i;
        double dx = (double)p[0] - c[0], dy = (double)p[1] - c[1], dz = (double)p[2] - c[2];
        double d = dx * dx + dy * dy + dz * dz;
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

int df_stroke_surface_dist(const df_mesh_sparse *adj, const double *rest, const float *x0,
                           int32_t nv, const double *c, int32_t *src, double *dist,
                           df_error *err)
{
    if (!adj || !rest || !x0 || !c || !src || !dist || nv <= 0 || adj->n_rows != nv)
        return df_error_set(err, DF_EINVAL, "surface brush: bad arguments (adjacency of %d "
                            "rows for %d vertices, rest %s)", adj ? adj->n_rows : -1, nv,
                            rest ? "given" : "missing");
    *src = df_stroke_surface_src(x0, nv, c);
    return df_mesh_geodesic_from(adj, rest, *src, dist, err);
}

int df_stroke_surface_mask(const df_kelvinlet_brush *b, const float *x0, int32_t nv,
                           const double *dist, int32_t src, float *d, df_error *err)
{
    if (!b || !x0 || !dist || !d || nv <= 0)
        return df_error_set(err, DF_EINVAL, "surface brush: bad arguments");
    double *x = widen(x0, 3 * (size_t)nv);
    float *w = malloc((size_t)nv * sizeof *w);
    int rc = x && w ? DF_OK : df_error_set(err, DF_ENOMEM, "surface brush: out of memory");
    if (rc == DF_OK)
        rc = df_kelvinlet_surface_weights(x, nv, dist, src, b->centre, b->radius, b->order, w,
                                          err);
    if (rc == DF_OK) df_kelvinlet_surface_mask(d, w, (size_t)nv);
    free(x);
    free(w);
    return rc;
}

/* The field of the loaded recipe at x0 into d (n = 3 nv floats), masked for surface-aware
 * recipes (adj: the mesh adjacency). */
static int field(const df_stroke_recipe *r, const float *x0, int32_t nv,
                 const df_mesh_sparse *adj, const double *rest, int planar, int threads,
                 float *d, df_error *err)
{
    if (r->brush.surface && (!adj || !rest))
        return df_error_set(err, DF_EINVAL, "stroke replay: a surface-aware stroke needs the "
                            "mesh adjacency (df_stroke_recipe_replay_mesh)");
    df_kelvinlet_brush b;
    df_stroke_loaded_brush(&r->brush, r->strength, r->load, &b);
    df_kelvinlet_prepared prep;
    df_kelvinlet_constraints *kc = NULL;
    int rc;
    if (r->n_pins) {
        df_kelvinlet_pins pins = {.n = r->n_pins, .points = r->pins, .flags = r->pin_flags,
                                  .radius = b.radius, .ratio = b.ratio, .nu = b.nu,
                                  .order = b.order, .threads = threads};
        rc = df_kelvinlet_constraints_create(&pins, &kc, err);
        if (rc == DF_OK) rc = df_kelvinlet_constraints_solve(kc, &b, &prep, err);
    } else {
        rc = df_kelvinlet_prepare(&b, &prep, err);
    }
    if (rc == DF_OK) {
        prep.threads = threads;
        rc = df_kelvinlet_displacements(&prep, x0, (size_t)nv, d, err);
        df_kelvinlet_prepared_free(&prep);
    }
    df_kelvinlet_constraints_free(kc);
    if (rc == DF_OK && r->brush.surface) {
        double *dist = malloc((size_t)nv * sizeof *dist);
        int32_t src = 0;
        rc = dist ? df_stroke_surface_dist(adj, rest, x0, nv, r->brush.centre, &src, dist, err)
                  : df_error_set(err, DF_ENOMEM, "stroke replay: out of memory");
        if (rc == DF_OK) rc = df_stroke_surface_mask(&b, x0, nv, dist, src, d, err);
        free(dist);
    }
    if (rc == DF_OK && planar)
        for (int32_t i = 0; i < nv; i++)
            if (d[3 * (size_t)i + 2] != 0.0f)
                return df_error_set(err, DF_EINVAL, "stroke replay: the field moves vertex %d "
                                    "off the plane of a 2D session", i);
    return rc;
}

int df_stroke_recipe_replay(const df_stroke_recipe *r, const double *from, int32_t nv,
                            int planar, int threads, double *to, df_error *err)
{
    return df_stroke_recipe_replay_mesh(r, from, nv, NULL, NULL, planar, threads, to, err);
}

int df_stroke_recipe_replay_mesh(const df_stroke_recipe *r, const double *from, int32_t nv,
                                 const df_mesh_sparse *adj, const double *rest, int planar,
                                 int threads, double *to, df_error *err)
{
    if (!r || !from || !to || nv <= 0 || (adj && adj->n_rows != nv))
        return df_error_set(err, DF_EINVAL, "stroke replay: bad arguments");
    float *scratch = malloc(6 * (size_t)nv * sizeof *scratch);
    if (!scratch)
        return df_error_set(err, DF_ENOMEM, "stroke replay: out of memory (%d vertices)", nv);
    int rc = df_stroke_recipe_replay_with(r, from, nv, adj, rest, planar, threads, scratch, to,
                                          err);
    free(scratch);
    return rc;
}

int df_stroke_recipe_replay_with(const df_stroke_recipe *r, const double *from, int32_t nv,
                                 const df_mesh_sparse *adj, const double *rest, int planar,
                                 int threads, float *scratch, double *to, df_error *err)
{
    if (!r || !from || !to || !scratch || nv <= 0 || (adj && adj->n_rows != nv))
        return df_error_set(err, DF_EINVAL, "stroke replay: bad arguments");
    size_t n = 3 * (size_t)nv;
    float *x0 = scratch, *d = scratch + n;
    for (size_t i = 0; i < n; i++) x0[i] = (float)from[i];
    int rc = field(r, x0, nv, adj, rest, planar, threads, d, err);
    if (rc == DF_OK) df_stroke_motion(x0, d, from, to, n);
    return rc;
}

/* A little writer / reader over a byte buffer (memcpy: no alignment assumed). */
typedef struct cursor {
    uint8_t *w;
    const uint8_t *r;
    size_t left;
} cursor;

static void put(cursor *c, const void *v, size_t k)
{
    memcpy(c->w, v, k);
    c->w += k;
}

static void put_i32(cursor *c, int32_t v) { put(c, &v, 4); }

static int get(cursor *c, void *v, size_t k)
{
    if (c->left < k) return 0;
    memcpy(v, c->r, k);
    c->r += k;
    c->left -= k;
    return 1;
}

static int get_i32(cursor *c, int *v)
{
    int32_t t;
    if (!get(c, &t, 4)) return 0;
    *v = t;
    return 1;
}

int df_stroke_recipe_encode(const df_stroke_recipe *r, uint8_t **out, size_t *len,
                            df_error *err)
{
    if (!r || !out || !len || r->n_pins > DF_KELVINLET_MAX_PINS || (r->n_pins && !r->pins))
        return df_error_set(err, DF_EINVAL, "stroke recipe: bad pins (%u)", r ? r->n_pins : 0);
    if (r->brush.arith < 0 || r->brush.arith > DF_KELVINLET_ARITH_CURRENT)
        return df_error_set(err, DF_EINVAL, "stroke recipe: Kelvinlet arithmetic version %d "
                            "unknown (0..%d)", r->brush.arith, DF_KELVINLET_ARITH_CURRENT);
    size_t n = DF_STROKE_RECIPE_FIXED + 24 * (size_t)r->n_pins;
    uint8_t *b = malloc(n);
    if (!b) return df_error_set(err, DF_ENOMEM, "stroke recipe: out of memory");
    const df_kelvinlet_brush *k = &r->brush;
    cursor c = {.w = b};
    uint32_t magic = RECIPE_MAGIC;
    put(&c, &magic, 4);
    put_i32(&c, (int32_t)k->type);
    put_i32(&c, k->dim);
    put_i32(&c, k->order);
    put_i32(&c, (int32_t)k->integrator);
    put_i32(&c, k->steps);
    put_i32(&c, k->mirror);
    put_i32(&c, k->moving);
    put_i32(&c, k->surface);
    put_i32(&c, k->arith ? k->arith : DF_KELVINLET_ARITH_CURRENT);
    put(&c, &k->ratio, 8);
    put(&c, &k->radius, 8);
    put(&c, &k->nu, 8);
    put(&c, k->centre, 24);
    put(&c, k->mirror_point, 24);
    put(&c, k->mirror_normal, 24);
    put(&c, &r->strength, 8);
    put(&c, r->load, 8 * DF_STROKE_LOAD_N);
    put(&c, &r->n_pins, 4);
    put_i32(&c, r->pin_flags);
    if (r->n_pins) put(&c, r->pins, 24 * (size_t)r->n_pins);
    *out = b;
    *len = n;
    return DF_OK;
}

/* 0 when any of the k doubles at p is NaN (infinities are legal: nu = +-INFINITY). */
static int no_nan(const double *p, size_t k)
{
    for (size_t i = 0; i < k; i++)
        if (isnan(p[i])) return 0;
    return 1;
}

int df_stroke_recipe_decode(const uint8_t *b, size_t len, df_stroke_recipe *r, df_error *err)
{
    memset(r, 0, sizeof *r);
    cursor c = {.r = b, .left = b ? len : 0};
    uint32_t magic = 0;
    int type = 0, integrator = 0;
    df_kelvinlet_brush *k = &r->brush;
    int ok = get(&c, &magic, 4) &&
             (magic == RECIPE_MAGIC || magic == RECIPE_MAGIC_V2 || magic == RECIPE_MAGIC_V1) &&
             get_i32(&c, &type) &&
             get_i32(&c, &k->dim) && get_i32(&c, &k->order) && get_i32(&c, &integrator) &&
             get_i32(&c, &k->steps) && get_i32(&c, &k->mirror) && get_i32(&c, &k->moving) &&
             (magic == RECIPE_MAGIC_V1 || get_i32(&c, &k->surface)) &&
             (magic != RECIPE_MAGIC || get_i32(&c, &k->arith)) &&
             get(&c, &k->ratio, 8) && get(&c, &k->radius, 8) && get(&c, &k->nu, 8) &&
             get(&c, k->centre, 24) && get(&c, k->mirror_point, 24) &&
             get(&c, k->mirror_normal, 24) && get(&c, &r->strength, 8) &&
             get(&c, r->load, 8 * DF_STROKE_LOAD_N) && get(&c, &r->n_pins, 4) &&
             get_i32(&c, &r->pin_flags);
    if (!ok || r->n_pins > DF_KELVINLET_MAX_PINS || c.left != 24 * (size_t)r->n_pins ||
        (k->surface != 0 && k->surface != 1)) {
        memset(r, 0, sizeof *r);
        return df_error_set(err, DF_EFORMAT, "stroke recipe: malformed (%zu bytes)", len);
    }
    if (magic == RECIPE_MAGIC &&
        (k->arith < DF_KELVINLET_ARITH_1 || k->arith > DF_KELVINLET_ARITH_CURRENT)) {
        int v = k->arith;
        memset(r, 0, sizeof *r);
        return df_error_set(err, DF_EFORMAT, "stroke recipe: Kelvinlet arithmetic version %d "
                            "unknown to this build (1..%d)", v, DF_KELVINLET_ARITH_CURRENT);
    }
    if (magic != RECIPE_MAGIC)
        k->arith = DF_KELVINLET_ARITH_1; /* written by a build before arithmetic versions */
    k->type = (df_kelvinlet_type)type;
    k->integrator = (df_kelvinlet_integrator)integrator;
    if (r->n_pins) {
        r->pins = malloc(24 * (size_t)r->n_pins);
        if (!r->pins) {
            memset(r, 0, sizeof *r);
            return df_error_set(err, DF_ENOMEM, "stroke recipe: out of memory");
        }
        get(&c, r->pins, 24 * (size_t)r->n_pins);
    }
    if (!no_nan(&k->ratio, 1) || !no_nan(&k->radius, 1) || !no_nan(&k->nu, 1) ||
        !no_nan(k->centre, 3) || !no_nan(k->mirror_point, 3) || !no_nan(k->mirror_normal, 3) ||
        !no_nan(&r->strength, 1) || !no_nan(r->load, DF_STROKE_LOAD_N) ||
        (r->n_pins && !no_nan(r->pins, 3 * (size_t)r->n_pins))) {
        df_stroke_recipe_free(r);
        return df_error_set(err, DF_EFORMAT, "stroke recipe: a number is NaN");
    }
    return DF_OK;
}

void df_stroke_recipe_free(df_stroke_recipe *r)
{
    if (!r) return;
    free(r->pins);
    memset(r, 0, sizeof *r);
}

uint64_t df_positions_checksum(const double *p, size_t n)
{
    /* four interleaved multiply-rotate lanes (fast on 24 MB), folded at the end */
    const uint64_t K = 0x9E3779B97F4A7C15ULL;
    uint64_t h[4] = {K, K ^ 1, K ^ 2, K ^ 3};
    size_t i = 0;
    for (; i + 4 <= n; i += 4)
        for (int l = 0; l < 4; l++) {
            uint64_t v;
            memcpy(&v, p + i + l, 8);
            h[l] = ((h[l] ^ v) * K);
            h[l] ^= h[l] >> 29;
        }
    uint64_t x = (uint64_t)n * K;
    for (int l = 0; l < 4; l++) x = (x ^ h[l]) * K, x ^= x >> 31;
    for (; i < n; i++) {
        uint64_t v;
        memcpy(&v, p + i, 8);
        x = (x ^ v) * K;
        x ^= x >> 29;
    }
    return x ^ (x >> 32);
}

/* raycast.c — nearest ray / triangle-mesh hit through Embree 3 (see raycast.h). */
#include "core/geom/raycast.h"

#include <embree3/rtcore.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One slot of TBB's arena (the calling thread), no worker threads started, no affinity changes:
 * builds and refits run on the caller (raycast.h, "Threads"). */
#define DF_EMBREE_CONFIG "threads=1,user_threads=1,start_threads=0,set_affinity=0,verbose=0"

/* The process's one Embree device, made on first use and never released (raycast.h, "Device"):
 * releasing the last Embree device makes TBB start a thread. */
static pthread_once_t g_dev_once = PTHREAD_ONCE_INIT;
static RTCDevice g_dev;
static enum RTCError g_dev_error;   /* why rtcNewDevice failed (g_dev NULL) */

/* Embree errors of the calling thread's current create/refit (the callback runs on the thread
 * whose call failed, so concurrent calls never share these). */
static _Thread_local enum RTCError tl_code;
static _Thread_local char tl_msg[160];

struct df_raycast {
    RTCScene scene;
    RTCGeometry geom;       /* owned by the scene after attach; kept to update its buffers */
    int32_t nv, nf;
    double *V;              /* nv x 3: the positions of the last create/refit (double) */
    const uint32_t *F;      /* nf x 3: Embree's index buffer (owned by geom) */
    int broken;             /* the last refit failed inside Embree: every hit misses */
};

static const char *rtc_error_name(enum RTCError e)
{
    switch (e) {
    case RTC_ERROR_NONE: return "none";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
    }
}

/* Embree's error callback: keeps the calling thread's first error and its text. */
static void on_rtc_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    if (tl_code != RTC_ERROR_NONE)
        return;
    tl_code = code;
    snprintf(tl_msg, sizeof tl_msg, "%s", str ? str : "");
}

static void dev_init(void)
{
    g_dev = rtcNewDevice(DF_EMBREE_CONFIG);
    if (!g_dev)
        g_dev_error = rtcGetDeviceError(NULL);
    else
        rtcSetDeviceErrorFunction(g_dev, on_rtc_error, NULL);
}

/* DF_OK with the shared device (made once) in *dev, or DF_ENOMEM / DF_EINTERNAL when Embree
 * could not make it. Clears the calling thread's Embree error state. */
static int device(RTCDevice *dev, df_error *err)
{
    pthread_once(&g_dev_once, dev_init);
    if (!g_dev)
        return df_error_set(err, g_dev_error == RTC_ERROR_OUT_OF_MEMORY ? DF_ENOMEM
                                                                        : DF_EINTERNAL,
                            "raycast: Embree device creation failed: %s",
                            rtc_error_name(g_dev_error));
    tl_code = RTC_ERROR_NONE;
    tl_msg[0] = 0;
    (void)rtcGetDeviceError(g_dev);   /* drop a stale per-thread error code */
    *dev = g_dev;
    return DF_OK;
}

/* DF_OK, or the DF_E* for the calling thread's first Embree error since device() (the device's
 * per-thread error code as a fallback when the callback gave nothing), naming `what`. */
static int rtc_check(const char *what, df_error *err)
{
    enum RTCError e = rtcGetDeviceError(g_dev);
    if (tl_code != RTC_ERROR_NONE)
        e = tl_code;
    if (e == RTC_ERROR_NONE)
        return DF_OK;
    return df_error_set(err, e == RTC_ERROR_OUT_OF_MEMORY ? DF_ENOMEM : DF_EINTERNAL,
                        "raycast: Embree %s failed: %s%s%s", what, rtc_error_name(e),
                        tl_msg[0] ? ": " : "", tl_msg);
}

/* DF_OK when every coordinate of V (nv x 3) is finite and within float range. */
static int check_positions(const double *V, int32_t nv, df_error *err)
{
    for (int64_t i = 0; i < 3 * (int64_t)nv; i++)
        if (!(fabs(V[i]) <= FLT_MAX))
            return df_error_set(err, DF_EINVAL,
                                "raycast: vertex %lld coordinate %d is %g (must be finite and "
                                "within float range)", (long long)(i / 3), (int)(i % 3), V[i]);
    return DF_OK;
}

/* Writes V into the geometry's float vertex buffer and the double copy. */
static void load_positions(df_raycast *rc, const double *V)
{
    float *vb = rtcGetGeometryBufferData(rc->geom, RTC_BUFFER_TYPE_VERTEX, 0);
    double *vd = rc->V;
    for (int64_t i = 0; i < 3 * (int64_t)rc->nv; i++) {
        vb[i] = (float)V[i];
        vd[i] = V[i];
    }
}

int df_raycast_create(const double *V, int32_t nv, const int32_t *F, int32_t nf,
                      df_raycast **out, df_error *err)
{
    if (!V || !F || !out)
        return df_error_set(err, DF_EINVAL, "raycast: NULL %s", !V ? "positions" : !F ? "faces"
                                                                                     : "output");
    if (nv < 1 || nf < 1)
        return df_error_set(err, DF_EINVAL, "raycast: need at least one vertex and one face "
                            "(%d vertices, %d faces)", (int)nv, (int)nf);
    for (int64_t i = 0; i < 3 * (int64_t)nf; i++)
        if (F[i] < 0 || F[i] >= nv)
            return df_error_set(err, DF_EINVAL, "raycast: face %lld index %d out of range "
                                "(%d vertices)", (long long)(i / 3), (int)F[i], (int)nv);
    int rcode = check_positions(V, nv, err);
    if (rcode != DF_OK)
        return rcode;

    df_raycast *rc = calloc(1, sizeof *rc);
    double *Vc = malloc(3 * (size_t)nv * sizeof *Vc);
    if (!rc || !Vc) {
        free(rc);
        free(Vc);
        return df_error_set(err, DF_ENOMEM, "raycast: out of memory for %d vertices", (int)nv);
    }
    rc->V = Vc;
    rc->nv = nv;
    rc->nf = nf;
    RTCDevice dev = NULL;
    int rv = device(&dev, err);
    if (rv != DF_OK)
        goto fail;
    rc->scene = rtcNewScene(dev);
    rc->geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if ((rv = rtc_check("scene setup", err)) != DF_OK)
        goto fail;
    if (!rc->scene || !rc->geom) {
        rv = df_error_set(err, DF_EINTERNAL, "raycast: Embree returned no scene/geometry");
        goto fail;
    }
    /* Dynamic scene, low-quality top level, refittable geometry: a commit after a vertex-buffer
     * update refits the mesh's BVH instead of rebuilding it (bench_raycast: ~3% of a build).
     * Compact: leaves hold vertex indices, not vertex copies, so a refit only recomputes bounds
     * (3.1 ms instead of 4.7 ms on 278k faces; casts 0.55 us instead of 0.45 us). Robust: no
     * precision shortcuts, so rays do not slip between adjacent faces. */
    rtcSetSceneFlags(rc->scene,
                     RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_COMPACT | RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(rc->scene, RTC_BUILD_QUALITY_LOW);
    rtcSetGeometryBuildQuality(rc->geom, RTC_BUILD_QUALITY_REFIT);
    float *vb = rtcSetNewGeometryBuffer(rc->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), (size_t)nv);
    uint32_t *ib = rtcSetNewGeometryBuffer(rc->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(uint32_t), (size_t)nf);
    if ((rv = rtc_check("buffer allocation", err)) != DF_OK)
        goto fail;
    if (!vb || !ib) {
        rv = df_error_set(err, DF_ENOMEM, "raycast: Embree buffers for %d vertices, %d faces",
                          (int)nv, (int)nf);
        goto fail;
    }
    for (int64_t i = 0; i < 3 * (int64_t)nf; i++)
        ib[i] = (uint32_t)F[i];
    rc->F = ib;
    load_positions(rc, V);
    rtcCommitGeometry(rc->geom);
    rtcAttachGeometry(rc->scene, rc->geom);
    rtcCommitScene(rc->scene);
    if ((rv = rtc_check("build", err)) != DF_OK)
        goto fail;
    *out = rc;
    return DF_OK;
fail:
    df_raycast_free(rc);
    return rv;
}

int df_raycast_refit(df_raycast *rc, const double *V, df_error *err)
{
    if (!rc || !V)
        return df_error_set(err, DF_EINVAL, "raycast: NULL %s", !rc ? "object" : "positions");
    int rv = check_positions(V, rc->nv, err);
    if (rv != DF_OK)
        return rv;
    RTCDevice dev = NULL;
    if ((rv = device(&dev, err)) != DF_OK)
        return rv;
    load_positions(rc, V);
    rtcUpdateGeometryBuffer(rc->geom, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(rc->geom);
    rtcCommitScene(rc->scene);
    rv = rtc_check("refit", err);
    rc->broken = rv != DF_OK;
    return rv;
}

static void sub3(const double *a, const double *b, double *o)
{
    o[0] = a[0] - b[0], o[1] = a[1] - b[1], o[2] = a[2] - b[2];
}
static void cross3(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Refines Embree's float hit on face f in double: the ray / face-plane intersection (Möller-
 * Trumbore without the inside test), u and v clamped into the triangle. Keeps Embree's values
 * when the ray is (numerically) parallel to the plane. */
static void refine(const df_raycast *rc, const double org[3], const double dir[3], int32_t f,
                   double *t, double *u, double *v)
{
    const double *a = rc->V + 3 * (size_t)rc->F[3 * (size_t)f],
                 *b = rc->V + 3 * (size_t)rc->F[3 * (size_t)f + 1],
                 *c = rc->V + 3 * (size_t)rc->F[3 * (size_t)f + 2];
    double e1[3], e2[3], p[3], s[3], q[3];
    sub3(b, a, e1);
    sub3(c, a, e2);
    cross3(dir, e2, p);
    double det = dot3(e1, p);
    double scale = sqrt(dot3(e1, e1) * dot3(e2, e2) * dot3(dir, dir));
    if (!(fabs(det) > 1e-12 * scale))
        return;
    sub3(org, a, s);
    cross3(s, e1, q);
    double uu = dot3(s, p) / det, vv = dot3(dir, q) / det, tt = dot3(e2, q) / det;
    if (!isfinite(uu) || !isfinite(vv) || !isfinite(tt) || tt < 0)
        return;
    if (uu < 0) uu = 0;
    if (vv < 0) vv = 0;
    if (uu + vv > 1) {
        double k = uu + vv;
        uu /= k;
        vv /= k;
    }
    *t = tt, *u = uu, *v = vv;
}

int df_raycast_hit(const df_raycast *rc, const double org[3], const double dir[3],
                   df_ray_hit *hit)
{
    if (!rc || !org || !dir || !hit || rc->broken)
        return 0;
    for (int k = 0; k < 3; k++)
        if (!(fabs(org[k]) <= FLT_MAX) || !(fabs(dir[k]) <= FLT_MAX))
            return 0;
    if (dir[0] == 0 && dir[1] == 0 && dir[2] == 0)
        return 0;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = (float)org[0], rh.ray.org_y = (float)org[1], rh.ray.org_z = (float)org[2];
    rh.ray.dir_x = (float)dir[0], rh.ray.dir_y = (float)dir[1], rh.ray.dir_z = (float)dir[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rc->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.primID >= (unsigned)rc->nf)
        return 0;
    int32_t f = (int32_t)rh.hit.primID;
    double t = rh.ray.tfar, u = rh.hit.u, v = rh.hit.v;
    refine(rc, org, dir, f, &t, &u, &v);
    const double *a = rc->V + 3 * (size_t)rc->F[3 * (size_t)f],
                 *b = rc->V + 3 * (size_t)rc->F[3 * (size_t)f + 1],
                 *c = rc->V + 3 * (size_t)rc->F[3 * (size_t)f + 2];
    hit->t = t;
    hit->face = f;
    hit->u = u;
    hit->v = v;
    for (int k = 0; k < 3; k++)
        hit->point[k] = (1 - u - v) * a[k] + u * b[k] + v * c[k];
    return 1;
}

int32_t df_raycast_nv(const df_raycast *rc)
{
    return rc ? rc->nv : 0;
}

int32_t df_raycast_nf(const df_raycast *rc)
{
    return rc ? rc->nf : 0;
}

void df_raycast_free(df_raycast *rc)
{
    if (!rc)
        return;
    if (rc->geom)
        rtcReleaseGeometry(rc->geom);
    if (rc->scene)
        rtcReleaseScene(rc->scene);
    free(rc->V);
    free(rc);
}

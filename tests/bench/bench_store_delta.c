/* bench_store_delta — bytes per change of the store's change log (`make bench`).
 *
 * Workload (issue 12's target): an n x n vertex grid over [0,1]^2 (n = 1000: 1,000,000
 * vertices; DF_BENCH_DELTA_N overrides), 200 local grab strokes at pseudo-random centres
 * (fixed seed), radius 0.02, tip 0.01 along z, nu 0.5, each one brush version computed as the
 * server does (server/handlers/h_brush.c: float32 displacements of the float32 start, motion
 * m = fl32(x0 + disp) - x0 added to the double positions). Every stroke's delta is encoded
 * with df_codec_delta_encode (the packed layout when smaller) and compared with the raw layout
 * (codec.h) it replaces; every delta is applied to a replay copy, which must stay bit-identical.
 * Two falloffs: order 1 (the wire default: 1/r far field) and order 3 (tri-scale: far-field
 * terms cancelled).
 * Target: 200 strokes hold <= 2 x the mesh's position bytes (24 bytes per vertex) of log.
 * Reported: vertices moved by more than 1e-3 x |tip| ("noticeably") and moved at all per
 * stroke, raw and packed bytes per change, their ratio, encode / apply time per change. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/kelvinlet/kelvinlet.h"
#include "server/store/codec.h"

#define STROKES 200
#define TARGET_X_POS 2.0

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double rnd(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

static int run(int n, int order)
{
    size_t nv = (size_t)n * n, nd = 3 * nv;
    double *cur = malloc(nd * sizeof(double)), *pos = malloc(nd * sizeof(double));
    double *replay = malloc(nd * sizeof(double));
    float *x0 = malloc(nd * sizeof(float)), *disp = malloc(nd * sizeof(float));
    if (!cur || !pos || !replay || !x0 || !disp) return fprintf(stderr, "out of memory\n"), 1;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            size_t v = 3 * ((size_t)j * n + i);
            float x = (float)i / (float)(n - 1), y = (float)j / (float)(n - 1);
            float p[3] = {x, y, 0.05f * (x - x * x) * (y - y * y) * 16.0f};
            for (int k = 0; k < 3; k++) cur[v + k] = p[k];
        }
    memcpy(replay, cur, nd * sizeof(double));
    uint64_t seed = 12;
    double raw_total = 0, packed_total = 0, t_enc = 0, t_apply = 0, moved = 0, noticed = 0;
    for (int s = 0; s < STROKES; s++) {
        df_kelvinlet_brush b;
        df_kelvinlet_brush_defaults(&b);
        b.order = order;
        b.radius = 0.02;
        b.nu = 0.5;
        b.centre[0] = 0.1 + 0.8 * rnd(&seed);
        b.centre[1] = 0.1 + 0.8 * rnd(&seed);
        b.centre[2] = 0.0;
        b.tip[2] = 0.01;
        df_kelvinlet_prepared prep;
        df_error e;
        for (size_t i = 0; i < nd; i++) x0[i] = (float)cur[i];
        if (df_kelvinlet_prepare(&b, &prep, &e) != DF_OK ||
            df_kelvinlet_displacements(&prep, x0, nv, disp, &e) != DF_OK)
            return fprintf(stderr, "kelvinlet: %s\n", e.msg), 1;
        for (size_t v = 0; v < nv; v++) {
            double d2 = 0;
            int any = 0;
            for (int k = 0; k < 3; k++) {
                size_t i = 3 * v + (size_t)k;
                float m = (x0[i] + disp[i]) - x0[i];
                pos[i] = cur[i] + (double)m;
                d2 += (double)m * m;
                any |= m != 0.0f;
            }
            moved += any;
            noticed += sqrt(d2) > 1e-3 * 0.01;
        }
        uint32_t count = 0;
        for (size_t v = 0; v < nv; v++)
            count += memcmp(cur + 3 * v, pos + 3 * v, 24) != 0;
        double raw = 8.0 + (count == nv ? 0 : 4.0 * count) + 24.0 * count;
        uint8_t *blob;
        size_t len;
        double t0 = now();
        if (df_codec_delta_encode(cur, pos, (int32_t)nv, &blob, &len, &e) != DF_OK)
            return fprintf(stderr, "encode: %s\n", e.msg), 1;
        double t1 = now();
        if (df_codec_delta_apply(blob, len, replay, (int32_t)nv, NULL, &e) != DF_OK)
            return fprintf(stderr, "apply: %s\n", e.msg), 1;
        t_apply += now() - t1;
        t_enc += t1 - t0;
        free(blob);
        if (memcmp(replay, pos, nd * sizeof(double)) != 0)
            return fprintf(stderr, "stroke %d: the replay differs\n", s), 1;
        raw_total += raw;
        packed_total += (double)len;
        memcpy(cur, pos, nd * sizeof(double));
    }
    double pos_bytes = 24.0 * (double)nv;
    printf("  order %d: %zu vertices, %d strokes: moved %.1f%% / noticeably %.2f%% of vertices "
           "per stroke\n", order, nv, STROKES, 100 * moved / STROKES / (double)nv,
           100 * noticed / STROKES / (double)nv);
    printf("    raw    %10.0f bytes/change (%.2f B/vertex), %d strokes = %.2f x position bytes\n",
           raw_total / STROKES, raw_total / STROKES / (double)nv, STROKES, raw_total / pos_bytes);
    printf("    packed %10.0f bytes/change (%.3f B/vertex), %d strokes = %.2f x position bytes "
           "(target <= %.1f x: %s); %.1fx smaller than raw\n", packed_total / STROKES,
           packed_total / STROKES / (double)nv, STROKES, packed_total / pos_bytes, TARGET_X_POS,
           packed_total <= TARGET_X_POS * pos_bytes ? "met" : "MISSED",
           raw_total / packed_total);
    printf("    encode %.1f ms/change, apply %.1f ms/change; replay bit-identical\n",
           1e3 * t_enc / STROKES, 1e3 * t_apply / STROKES);
    free(cur);
    free(pos);
    free(replay);
    free(x0);
    free(disp);
    return 0;
}

int main(void)
{
    const char *env = getenv("DF_BENCH_DELTA_N");
    int n = env ? atoi(env) : 1000;
    if (n < 8 || n > 4000) return fprintf(stderr, "DF_BENCH_DELTA_N %d out of [8, 4000]\n", n), 1;
    printf("store change-log bytes per change, local grab strokes on a %d x %d grid\n", n, n);
    if (run(n, 1) || run(n, 3)) return 1;
    return 0;
}

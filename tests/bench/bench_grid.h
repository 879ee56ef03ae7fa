/* bench_grid.h — a synthetic test mesh shared by the network benchmarks (header-only). */
#ifndef DF_BENCH_GRID_H
#define DF_BENCH_GRID_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Binary little-endian PLY of an n x n vertex grid over [0,1]^2 with a gentle z bump, 2(n-1)^2
 * triangles. Returns a malloc'd buffer and its size. */
static inline uint8_t *grid_ply(int n, size_t *len)
{
    size_t nv = (size_t)n * n, nf = 2 * (size_t)(n - 1) * (n - 1);
    char head[256];
    int hl = snprintf(head, sizeof head,
                      "ply\nformat binary_little_endian 1.0\nelement vertex %zu\nproperty float x\n"
                      "property float y\nproperty float z\nelement face %zu\n"
                      "property list uchar int vertex_indices\nend_header\n", nv, nf);
    *len = (size_t)hl + nv * 12 + nf * 13;
    uint8_t *b = malloc(*len), *p = b;
    if (!b)
        return NULL;
    memcpy(p, head, (size_t)hl);
    p += hl;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float x = (float)i / (float)(n - 1), y = (float)j / (float)(n - 1);
            float v[3] = {x, y, 0.05f * (x - x * x) * (y - y * y) * 16.0f};
            memcpy(p, v, 12);
            p += 12;
        }
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            int32_t a = j * n + i, t[2][3] = {{a, a + 1, a + n + 1}, {a, a + n + 1, a + n}};
            for (int k = 0; k < 2; k++) {
                *p++ = 3;
                memcpy(p, t[k], 12);
                p += 12;
            }
        }
    return b;
}

#endif

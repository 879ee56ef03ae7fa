/* bench_table.h — the "table" case of issue 14 item 5 (bench_kguess; header-only): the shared
 * meshes have no table, so this builds one. A tet mesh of a table on a lattice of cubes of side
 * TABLE_H (6 Kuhn tets each, so neighbouring cubes share faces): a top of TABLE_NX x TABLE_NY x
 * TABLE_NZ cubes on four square legs of TABLE_LEG x TABLE_LEG cubes and TABLE_LEG_NZ cubes high
 * at the corners (top 2 x 1.2 x 0.1, legs 0.1 x 0.1 x 1: 3,795 vertices, 13,440 tets). Handles: the
 * bottom vertices of the four feet; three feet stay, the fourth (at x = 0, y = 0) is dragged
 * outwards by TABLE_DRAG in x and y (the leg splays). Fills bench_paper.h's `loaded`. */
#ifndef DF_BENCH_TABLE_H
#define DF_BENCH_TABLE_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bench_paper.h"

#define TABLE_H 0.05
#define TABLE_NX 40
#define TABLE_NY 24
#define TABLE_NZ 2
#define TABLE_LEG 2
#define TABLE_LEG_NZ 20
#define TABLE_DRAG 0.25

/* 1 when lattice cube (i, j, k) belongs to the table */
static inline int table_cell(int i, int j, int k)
{
    if (i < 0 || j < 0 || k < 0 || i >= TABLE_NX || j >= TABLE_NY || k >= TABLE_LEG_NZ + TABLE_NZ)
        return 0;
    if (k >= TABLE_LEG_NZ)
        return 1;
    int leg_i = i < TABLE_LEG || i >= TABLE_NX - TABLE_LEG, leg_j = j < TABLE_LEG || j >= TABLE_NY - TABLE_LEG;
    return leg_i && leg_j;
}

/* Builds the table into *L (free with unload). Returns 0, or -1 when out of memory (printed). */
static inline int table_load(loaded *L)
{
    const int ni = TABLE_NX + 1, nj = TABLE_NY + 1, nk = TABLE_LEG_NZ + TABLE_NZ + 1;
    int32_t *id = malloc((size_t)ni * nj * nk * sizeof *id);
    int ncell = 0;
    df_mesh_init(&L->m);
    if (!id) { printf("  table: out of memory\n"); return -1; }
    for (int n = 0; n < ni * nj * nk; n++) id[n] = -1;
    for (int k = 0; k + 1 < nk; k++)
        for (int j = 0; j + 1 < nj; j++)
            for (int i = 0; i + 1 < ni; i++)
                if (table_cell(i, j, k)) {
                    ncell++;
                    for (int c = 0; c < 8; c++)
                        id[((k + (c >> 2 & 1)) * nj + j + (c >> 1 & 1)) * ni + i + (c & 1)] = 0;
                }
    int32_t nv = 0;
    for (int n = 0; n < ni * nj * nk; n++)
        if (id[n] == 0) id[n] = nv++;
    L->m.kind = DF_MESH_TET;
    L->m.nv = nv;
    L->m.ne = 6 * ncell;
    L->m.V = malloc(3 * (size_t)nv * sizeof(double));
    L->m.E = malloc(4 * (size_t)L->m.ne * sizeof(int32_t));
    L->h = malloc((size_t)nv * sizeof(int32_t));
    L->tg = malloc(3 * (size_t)nv * sizeof(double));
    if (!L->m.V || !L->m.E || !L->h || !L->tg) { printf("  table: out of memory\n"); free(id); return -1; }
    L->nh = 0;
    for (int k = 0; k < nk; k++)
        for (int j = 0; j < nj; j++)
            for (int i = 0; i < ni; i++) {
                int32_t v = id[(k * nj + j) * ni + i];
                if (v < 0) continue;
                double *x = L->m.V + 3 * (size_t)v;
                x[0] = i * TABLE_H; x[1] = j * TABLE_H; x[2] = k * TABLE_H;
                if (k == 0) { /* a foot's bottom: a handle; the foot at the origin is dragged */
                    int drag = i <= TABLE_LEG && j <= TABLE_LEG;
                    L->h[L->nh] = v;
                    double *t = L->tg + 3 * (size_t)L->nh++;
                    t[0] = x[0] - (drag ? TABLE_DRAG : 0.0);
                    t[1] = x[1] - (drag ? TABLE_DRAG : 0.0);
                    t[2] = x[2];
                }
            }
    /* Kuhn subdivision: the 6 paths 0 -> 7 through the cube's corners (bit 0: x, 1: y, 2: z) */
    static const int perm[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
    int32_t *E = L->m.E;
    for (int k = 0; k + 1 < nk; k++)
        for (int j = 0; j + 1 < nj; j++)
            for (int i = 0; i + 1 < ni; i++) {
                if (!table_cell(i, j, k)) continue;
                int32_t c[8];
                for (int b = 0; b < 8; b++)
                    c[b] = id[((k + (b >> 2 & 1)) * nj + j + (b >> 1 & 1)) * ni + i + (b & 1)];
                for (int p = 0; p < 6; p++) {
                    int32_t t[4] = {c[0], c[perm[p][0]], c[perm[p][0] | perm[p][1]], c[7]};
                    const double *a = L->m.V + 3 * (size_t)t[0], *b1 = L->m.V + 3 * (size_t)t[1],
                                 *b2 = L->m.V + 3 * (size_t)t[2], *b3 = L->m.V + 3 * (size_t)t[3];
                    double u[3], v[3], w[3];
                    for (int d = 0; d < 3; d++) { u[d] = b1[d] - a[d]; v[d] = b2[d] - a[d]; w[d] = b3[d] - a[d]; }
                    double vol = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                                 u[2] * (v[0] * w[1] - v[1] * w[0]);
                    if (vol < 0) { int32_t s = t[1]; t[1] = t[2]; t[2] = s; }
                    memcpy(E, t, sizeof t);
                    E += 4;
                }
            }
    free(id);
    return 0;
}

#endif

/* mesh_topo.c — sorted edge keys and tet faces (see mesh_topo.h). */
#include "core/mesh/mesh_topo.h"

#include <stdlib.h>
#include <string.h>

/* Arrays up to this length are insertion-sorted. */
#define DF_TOPO_SMALL_SORT 64

const int df_topo_tet_face_corners[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

int df_topo_sort_u64(uint64_t *keys, int64_t n, df_error *err)
{
    if (n < 2)
        return DF_OK;
    if (n <= DF_TOPO_SMALL_SORT) { /* insertion sort: no 512 KB histogram for tiny inputs */
        for (int64_t i = 1; i < n; i++) {
            uint64_t k = keys[i];
            int64_t j = i;
            while (j > 0 && keys[j - 1] > k) {
                keys[j] = keys[j - 1];
                j--;
            }
            keys[j] = k;
        }
        return DF_OK;
    }
    uint64_t *tmp = malloc((size_t)n * sizeof *tmp);
    size_t *count = malloc(65537 * sizeof *count);
    if (!tmp || !count) {
        free(tmp);
        free(count);
        return df_error_set(err, DF_ENOMEM, "out of memory sorting %lld keys", (long long)n);
    }
    uint64_t all_or = 0;
    for (int64_t i = 0; i < n; i++)
        all_or |= keys[i];
    uint64_t *src = keys, *dst = tmp;
    for (int shift = 0; shift < 64; shift += 16) {
        if (((all_or >> shift) & 0xFFFFu) == 0)
            continue;
        memset(count, 0, 65537 * sizeof *count);
        for (int64_t i = 0; i < n; i++)
            count[((src[i] >> shift) & 0xFFFFu) + 1]++;
        for (int b = 0; b < 65536; b++)
            count[b + 1] += count[b];
        for (int64_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 0xFFFFu]++] = src[i];
        uint64_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != keys)
        memcpy(keys, src, (size_t)n * sizeof *keys);
    free(tmp);
    free(count);
    return DF_OK;
}

static int face_cmp(const void *pa, const void *pb)
{
    const df_topo_face *a = pa, *b = pb;
    for (int i = 0; i < 3; i++)
        if (a->k[i] != b->k[i])
            return a->k[i] < b->k[i] ? -1 : 1;
    if (a->tet != b->tet)
        return a->tet < b->tet ? -1 : 1;
    return a->local - b->local;
}

static void sort3(int32_t *k)
{
    int32_t t;
    if (k[0] > k[1]) { t = k[0]; k[0] = k[1]; k[1] = t; }
    if (k[1] > k[2]) { t = k[1]; k[1] = k[2]; k[2] = t; }
    if (k[0] > k[1]) { t = k[0]; k[0] = k[1]; k[1] = t; }
}

int df_topo_tet_faces(const df_mesh *m, df_topo_face **faces, df_error *err)
{
    size_t n = (size_t)m->ne * 4;
    df_topo_face *f = malloc((n ? n : 1) * sizeof *f);
    if (!f)
        return df_error_set(err, DF_ENOMEM, "out of memory listing %zu tet faces", n);
    for (int32_t t = 0; t < m->ne; t++) {
        const int32_t *c = m->E + 4 * (size_t)t;
        for (int l = 0; l < 4; l++) {
            df_topo_face *r = f + 4 * (size_t)t + l;
            for (int i = 0; i < 3; i++)
                r->k[i] = c[df_topo_tet_face_corners[l][i]];
            sort3(r->k);
            r->tet = t;
            r->local = l;
        }
    }
    qsort(f, n, sizeof *f, face_cmp);
    *faces = f;
    return DF_OK;
}

int df_topo_edge_keys(const int32_t *E, int64_t ne, int k, uint64_t **keys, int64_t *n,
                      df_error *err)
{
    int per = k * (k - 1) / 2;
    int64_t total = ne * per;
    uint64_t *a = malloc((size_t)(total ? total : 1) * sizeof *a);
    if (!a)
        return df_error_set(err, DF_ENOMEM, "out of memory listing %lld edges", (long long)total);
    int64_t w = 0;
    for (int64_t e = 0; e < ne; e++) {
        const int32_t *c = E + (size_t)k * (size_t)e;
        for (int i = 0; i < k; i++)
            for (int j = i + 1; j < k; j++)
                a[w++] = df_topo_edge_key(c[i], c[j]);
    }
    int rc = df_topo_sort_u64(a, total, err);
    if (rc) {
        free(a);
        return rc;
    }
    *keys = a;
    *n = total;
    return DF_OK;
}

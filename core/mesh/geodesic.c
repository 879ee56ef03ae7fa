/* geodesic.c — Dijkstra on the vertex adjacency graph (see geodesic.h). */
#include "core/mesh/geodesic.h"

#include <math.h>
#include <stdlib.h>

/* A binary min-heap of (distance, vertex) with lazy deletion: a vertex may sit in the heap
 * several times; stale entries (distance above the settled one) are skipped when popped. */
typedef struct hent {
    double d;
    int32_t v;
} hent;

static int less(const hent *a, const hent *b)
{
    return a->d < b->d || (a->d == b->d && a->v < b->v);
}

static void push(hent *h, size_t *n, hent e)
{
    size_t i = (*n)++;
    while (i > 0) {
        size_t p = (i - 1) / 2;
        if (!less(&e, &h[p]))
            break;
        h[i] = h[p];
        i = p;
    }
    h[i] = e;
}

static hent pop(hent *h, size_t *n)
{
    hent top = h[0], last = h[--*n];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= *n)
            break;
        if (c + 1 < *n && less(&h[c + 1], &h[c]))
            c++;
        if (!less(&h[c], &last))
            break;
        h[i] = h[c];
        i = c;
    }
    if (*n > 0)
        h[i] = last;
    return top;
}

int df_mesh_geodesic_from(const df_mesh_sparse *adj, const double *xyz, int32_t src,
                          double *dist, df_error *err)
{
    if (!adj || !adj->ptr || !xyz || !dist)
        return df_error_set(err, DF_EINVAL, "geodesic: NULL argument");
    int32_t nv = adj->n_rows;
    if (src < 0 || src >= nv)
        return df_error_set(err, DF_EINVAL, "geodesic: source vertex %d not in [0, %d)", src,
                            nv);
    for (size_t i = 0; i < 3 * (size_t)nv; i++)
        if (!isfinite(xyz[i]))
            return df_error_set(err, DF_EINVAL, "geodesic: vertex %zu is not finite", i / 3);
    /* lazy deletion: at most one push per directed edge plus the source */
    size_t cap = (size_t)adj->ptr[nv] + 1, n = 0;
    hent *h = malloc(cap * sizeof *h);
    if (!h)
        return df_error_set(err, DF_ENOMEM, "geodesic: out of memory (%zu heap entries)", cap);
    for (int32_t i = 0; i < nv; i++)
        dist[i] = INFINITY;
    dist[src] = 0.0;
    push(h, &n, (hent){0.0, src});
    while (n > 0) {
        hent e = pop(h, &n);
        if (e.d > dist[e.v])
            continue;
        const double *a = xyz + 3 * (size_t)e.v;
        for (int32_t k = adj->ptr[e.v]; k < adj->ptr[e.v + 1]; k++) {
            int32_t w = adj->idx[k];
            const double *b = xyz + 3 * (size_t)w;
            double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
            double nd = e.d + sqrt(dx * dx + dy * dy + dz * dz);
            if (nd < dist[w]) {
                dist[w] = nd;
                push(h, &n, (hent){nd, w});
            }
        }
    }
    free(h);
    return DF_OK;
}

int32_t df_mesh_nearest_vertex(const double *xyz, int32_t nv, const double *c)
{
    if (!xyz || !c || nv <= 0)
        return -1;
    int32_t best = 0;
    double bd = INFINITY;
    for (int32_t i = 0; i < nv; i++) {
        const double *p = xyz + 3 * (size_t)i;
        double d = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1])
                   + (p[2] - c[2]) * (p[2] - c[2]);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

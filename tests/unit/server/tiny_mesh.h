/* tiny_mesh.h — the one-triangle mesh the server unit tests build sessions from (header-only). */
#ifndef DF_TEST_SERVER_TINY_MESH_H
#define DF_TEST_SERVER_TINY_MESH_H

#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh.h"

/* A triangle (0,0,0), (1,0,0), (0,1,0) with malloc'd V (3 x 3) and E (3); NULL arrays when out of
 * memory (the caller asserts). Ownership passes to the caller (df_session_create takes it). */
static inline df_mesh tiny_mesh(void)
{
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = 3;
    m.ne = 1;
    m.V = calloc(9, sizeof(double));
    m.E = malloc(3 * sizeof(int32_t));
    if (m.V) m.V[3] = m.V[7] = 1;
    if (m.E) m.E[0] = 0, m.E[1] = 1, m.E[2] = 2;
    return m;
}

#endif

/* Unit tests for the declared dimension of a mesh (issue 9 item 16): a mesh is 2D (`planar`)
 * only when its file says so (OBJ `v x y`, MEDIT Dimension 2, TetGen .node dimension 2, PLY
 * without z) or the reader is asked for 2D (want_2d); a flat 3D mesh (every z = 0, a subdivided
 * plane) stays 3D. Writers keep a 2D mesh 2D where the format can say so. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"

static int rd(const char *text, const df_mesh_read_opts *o, df_mesh *m, df_error *e)
{
    df_mesh_init(m);
    return df_mesh_read_memory(text, strlen(text), DF_FMT_AUTO, "t", o, m, NULL, e);
}

static int planar_of(const char *text)
{
    df_mesh m;
    df_error e;
    int rc = rd(text, NULL, &m, &e);
    if (rc)
        fail_msg("read failed: %s", e.msg);
    int p = m.planar;
    df_mesh_free(&m);
    return p;
}

static void test_flat_3d_files_stay_3d(void **state)
{
    (void)state;
    assert_int_equal(planar_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), 0);
    assert_int_equal(planar_of("v 0 0 0.000000\nv 1 0 -0\nv 0 1 0\nf 1 2 3\n"), 0);
    assert_int_equal(planar_of("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), 0);
    assert_int_equal(planar_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n"
                               "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), 0);
    assert_int_equal(planar_of("MeshVersionFormatted 2\nDimension 3\nVertices\n3\n0 0 0 0\n"
                               "1 0 0 0\n0 1 0 0\nTriangles\n1\n1 2 3 0\nEnd\n"), 0);
    /* some vertices with z, some without: 3D */
    assert_int_equal(planar_of("v 0 0\nv 1 0 0\nv 0 1\nf 1 2 3\n"), 0);
}

static void test_declared_2d_files_are_2d(void **state)
{
    (void)state;
    assert_int_equal(planar_of("v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n"), 1);
    assert_int_equal(planar_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n"
                               "0 0\n1 0\n0 1\n3 0 1 2\n"), 1);
    assert_int_equal(planar_of("MeshVersionFormatted 2\nDimension 2\nVertices\n3\n0 0 0\n"
                               "1 0 0\n0 1 0\nTriangles\n1\n1 2 3 0\nEnd\n"), 1);
    const char *node2 = "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n";
    const char *node3 = "3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n";
    const char *ele = "1 3 0\n1 1 2 3\n";
    df_mesh m;
    df_error e;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node2, strlen(node2), ele, strlen(ele), "t",
                                                NULL, &m, NULL, &e), DF_OK);
    assert_int_equal(m.planar, 1);
    df_mesh_free(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node3, strlen(node3), ele, strlen(ele), "t",
                                                NULL, &m, NULL, &e), DF_OK);
    assert_int_equal(m.planar, 0);
    df_mesh_free(&m);
}

static void test_want_2d(void **state)
{
    (void)state;
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.want_2d = 1;
    df_mesh m;
    df_error e;
    assert_int_equal(rd("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &o, &m, &e), DF_OK);
    assert_int_equal(m.planar, 1);
    df_mesh_free(&m);
    assert_int_equal(rd("v 0 0 0\nv 1 0 0.5\nv 0 1 0\nf 1 2 3\n", &o, &m, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "vertex 1"));
    assert_non_null(strstr(e.msg, "2D"));
    assert_int_equal(rd("MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n"
                        "0 1 0 0\n0 0 0 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n", &o, &m, &e),
                     DF_EFORMAT);
    assert_non_null(strstr(e.msg, "tetrahedra"));
}

static void test_writers_keep_2d(void **state)
{
    (void)state;
    const df_mesh_format fmts[] = {DF_FMT_OBJ, DF_FMT_PLY, DF_FMT_PLY_BINARY, DF_FMT_MEDIT,
                                   DF_FMT_OFF};
    for (int planar = 0; planar < 2; planar++) {
        df_mesh m;
        df_error e;
        assert_int_equal(rd(planar ? "v 0 0\nv 1 0\nv 0 1\nf 1 2 3\n"
                                   : "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", NULL, &m, &e), DF_OK);
        for (size_t k = 0; k < sizeof fmts / sizeof fmts[0]; k++) {
            char *buf;
            size_t len;
            assert_int_equal(df_mesh_write_memory(&m, fmts[k], &buf, &len, &e), DF_OK);
            df_mesh back;
            df_mesh_init(&back);
            assert_int_equal(df_mesh_read_memory(buf, len, DF_FMT_AUTO, "w", NULL, &back, NULL,
                                                 &e), DF_OK);
            /* OFF has no 2D form: a 2D mesh written as OFF reads back as flat 3D */
            assert_int_equal(back.planar, fmts[k] == DF_FMT_OFF ? 0 : planar);
            df_mesh_free(&back);
            free(buf);
        }
        df_mesh_free(&m);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_3d_files_stay_3d),
        cmocka_unit_test(test_declared_2d_files_are_2d),
        cmocka_unit_test(test_want_2d),
        cmocka_unit_test(test_writers_keep_2d),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

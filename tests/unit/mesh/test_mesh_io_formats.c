/* Unit tests for core/mesh/mesh_io.h on small hand-written inputs: every OBJ/OFF/PLY/MEDIT/TetGen
 * feature the readers claim (v/vt/vn forms, negative indices, n-gons, polylines, 2D, ASCII and
 * binary PLY, MEDIT sections, 0/1-based TetGen), content sniffing, bit-exact write -> read round
 * trips for every format and kind, copy/free. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"

static int read_str(const char *text, df_mesh_format fmt, df_mesh *m, df_mesh_report *rep,
                    df_error *err)
{
    df_mesh_init(m);
    return df_mesh_read_memory(text, strlen(text), fmt, "t", NULL, m, rep, err);
}

static void expect_E(const df_mesh *m, const int32_t *E, int n)
{
    assert_int_equal(m->ne * df_mesh_elem_size(m->kind), n);
    for (int i = 0; i < n; i++)
        assert_int_equal(m->E[i], E[i]);
}

static void test_obj_forms(void **state)
{
    (void)state;
    const char *obj = "# comment\nmtllib x.mtl\no thing\n"
                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0.25 1.0\n"
                      "vt 0 0\nvt 1 0\nvn 0 0 1\ng grp\ns off\nusemtl m\n"
                      "f 1/1/1 2/2/1 3/1/1\n"      /* v/vt/vn */
                      "f 1//1 3//1 4//1\r\n"       /* v//vn, CRLF */
                      "f -5/1 -4/2 -1/1\n"         /* negative + v/vt */
                      "f 1 2 3 5 4   # pentagon\n"; /* n-gon -> 3 triangles */
    df_mesh m;
    df_mesh_report r;
    df_error err;
    assert_int_equal(read_str(obj, DF_FMT_OBJ, &m, &r, &err), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    assert_int_equal(m.nv, 5);
    assert_int_equal(m.planar, 0);
    const int32_t E[] = {0, 1, 2, 0, 2, 3, 0, 1, 4, 0, 1, 2, 0, 2, 4, 0, 4, 3};
    expect_E(&m, E, 18);
    assert_true(m.V[3 * 4 + 2] == 0.25);
    assert_int_equal(r.input_polygons, 4);
    assert_int_equal(r.polygons_triangulated, 1);
    assert_int_equal(r.format, DF_FMT_OBJ);
    df_mesh_free(&m);
    /* 2D vertices (two coordinates) -> planar. */
    assert_int_equal(read_str("v 0 0\nv 2 0\nv 0 2\nf 1 2 3\n", DF_FMT_AUTO, &m, &r, &err), DF_OK);
    assert_int_equal(m.planar, 1);
    assert_true(fabs(r.min_signed_volume - 2.0) < 1e-15);
    df_mesh_free(&m);
}

static void test_obj_polylines(void **state)
{
    (void)state;
    df_mesh m;
    df_mesh_report r;
    df_error err;
    assert_int_equal(read_str("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 3 1 1\nl 1 2 3 4\nl -1 -4\n",
                              DF_FMT_OBJ, &m, &r, &err), DF_OK);
    assert_int_equal(m.kind, DF_MESH_POLYLINE);
    const int32_t E[] = {0, 1, 1, 2, 2, 3, 3, 0};
    expect_E(&m, E, 8);
    df_mesh_free(&m);
    /* faces win over lines; the lines are counted as ignored */
    assert_int_equal(read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nl 1 2\n", DF_FMT_OBJ, &m,
                              &r, &err), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    assert_int_equal(r.ignored_elements, 1);
    df_mesh_free(&m);
}

static void test_off_variants(void **state)
{
    (void)state;
    const char *off = "COFF\n# colours follow each vertex\n5 2 0\n"
                      "0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n"
                      "0.5 0.5 1 9 9 9 9\n"
                      "4 0 1 2 3 200 10 10\n3 0 1 4\n";
    df_mesh m;
    df_mesh_report r;
    df_error err;
    assert_int_equal(read_str(off, DF_FMT_AUTO, &m, &r, &err), DF_OK);
    assert_int_equal(r.format, DF_FMT_OFF);
    assert_int_equal(m.nv, 5);
    const int32_t E[] = {0, 1, 2, 0, 2, 3, 0, 1, 4};
    expect_E(&m, E, 9);
    assert_int_equal(r.polygons_triangulated, 1);
    df_mesh_free(&m);
    /* counts on the header line */
    assert_int_equal(read_str("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", DF_FMT_OFF, &m, &r, &err),
                     DF_OK);
    assert_int_equal(m.ne, 1);
    assert_int_equal(m.planar, 0);   /* OFF is 3D: a flat OFF mesh is a flat 3D mesh */
    df_mesh_free(&m);
}

static void test_ply_ascii(void **state)
{
    (void)state;
    const char *ply = "ply\nformat ascii 1.0\ncomment made by hand\nobj_info x\n"
                      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                      "property uchar red\nproperty float nx\n"
                      "element face 2\nproperty list uchar int vertex_indices\nproperty int flags\n"
                      "element material 1\nproperty list int float values\n"
                      "end_header\n"
                      "0 0 0 255 0.5\n1 0 0 1 1\n1 1 0 2 2\n0 1 0.5 3 3\n"
                      "4 0 1 2 3 7\n3 0 2 3 8\n"
                      "2 1.5 2.5\n";
    df_mesh m;
    df_mesh_report r;
    df_error err;
    assert_int_equal(read_str(ply, DF_FMT_AUTO, &m, &r, &err), DF_OK);
    assert_int_equal(r.format, DF_FMT_PLY);
    assert_int_equal(m.nv, 4);
    assert_true(m.V[11] == 0.5);
    const int32_t E[] = {0, 1, 2, 0, 2, 3, 0, 2, 3};
    expect_E(&m, E, 9);
    assert_int_equal(r.ignored_elements, 1);
    df_mesh_free(&m);
    /* edge elements -> polyline; vertex_index spelling */
    const char *edges = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                        "property double y\nelement edge 2\nproperty int vertex1\n"
                        "property int vertex2\nend_header\n0 0\n1 0\n2 1\n0 1\n1 2\n";
    assert_int_equal(read_str(edges, DF_FMT_PLY, &m, &r, &err), DF_OK);
    assert_int_equal(m.kind, DF_MESH_POLYLINE);
    assert_int_equal(m.planar, 1);
    const int32_t P[] = {0, 1, 1, 2};
    expect_E(&m, P, 4);
    df_mesh_free(&m);
}

static size_t put(unsigned char *p, const void *v, size_t n)
{
    memcpy(p, v, n);
    return n;
}

static void test_ply_binary_handmade(void **state)
{
    (void)state;
    const char *hdr = "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 3\r\n"
                      "property float x\r\nproperty float y\r\nproperty float z\r\n"
                      "property ushort flags\r\nelement face 1\r\n"
                      "property list uchar uint vertex_indices\r\nend_header\r\n";
    unsigned char buf[512];
    size_t n = put(buf, hdr, strlen(hdr));
    const float xyz[9] = {0, 0, 0, 2, 0, 0.5f, 0, 3, 0.25f};
    for (int i = 0; i < 3; i++) {
        n += put(buf + n, xyz + 3 * i, 12);
        uint16_t fl = 7;
        n += put(buf + n, &fl, 2);
    }
    uint8_t cnt = 3;
    uint32_t idx[3] = {0, 1, 2};
    n += put(buf + n, &cnt, 1);
    n += put(buf + n, idx, 12);
    df_mesh m;
    df_mesh_report r;
    df_error err;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_memory(buf, n, DF_FMT_AUTO, "b.ply", NULL, &m, &r, &err), DF_OK);
    assert_int_equal(m.nv, 3);
    assert_true(m.V[3] == 2.0 && m.V[5] == 0.5 && m.V[7] == 3.0 && m.V[8] == 0.25);
    const int32_t E[] = {0, 1, 2};
    expect_E(&m, E, 3);
    df_mesh_free(&m);
    /* one byte short: an error naming the byte offset */
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_memory(buf, n - 1, DF_FMT_PLY, "b.ply", NULL, &m, &r, &err),
                     DF_EFORMAT);
    assert_non_null(strstr(err.msg, "b.ply: byte offset"));
    assert_non_null(strstr(err.msg, "truncated"));
    assert_null(m.V);
}

static void test_medit_sections(void **state)
{
    (void)state;
    const char *m2 = "MeshVersionFormatted 2\n# 2D mesh\nDimension\n2\nVertices\n4\n"
                     "0 0 1\n1 0 1\n1 1 1\n0 1 2\nCorners\n2\n1 3\nEdges\n1\n1 2 0\n"
                     "Quadrilaterals\n1\n1 2 3 4 5\nNormals\n1\n0 0 1\nEnd\n";
    df_mesh m;
    df_mesh_report r;
    df_error err;
    assert_int_equal(read_str(m2, DF_FMT_AUTO, &m, &r, &err), DF_OK);
    assert_int_equal(r.format, DF_FMT_MEDIT);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    assert_int_equal(m.planar, 1);
    const int32_t E[] = {0, 1, 2, 0, 2, 3};
    expect_E(&m, E, 6);
    assert_int_equal(r.ignored_elements, 1); /* the edge */
    df_mesh_free(&m);
    const char *tet = "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n"
                      "0 1 0 0\n0 0 1 0\nTriangles\n1\n1 3 2 7\nTetrahedra\n1\n1 2 3 4 0\nEnd\n";
    assert_int_equal(read_str(tet, DF_FMT_MEDIT, &m, &r, &err), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TET);
    assert_int_equal(m.nf, 1);
    assert_int_equal(m.F[1], 2);
    assert_true(fabs(r.min_signed_volume - 1.0 / 6.0) < 1e-15);
    df_mesh_free(&m);
}

static void test_tetgen_bases_and_kinds(void **state)
{
    (void)state;
    const char *node0 = "# zero-based\n5 3 1 1\n0 0 0 0 9.5 1\n1 1 0 0 9.5 1\n2 0 1 0 9.5 1\n"
                        "3 0 0 1 9.5 1\n4 1 1 1 9.5 0\n";
    const char *ele0 = "2 4 1\n0 0 1 2 3 1\n1 1 3 2 4 1 # attr\n";
    df_mesh m;
    df_mesh_report r;
    df_error err;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node0, strlen(node0), ele0, strlen(ele0), "z", NULL,
                                                &m, &r, &err), DF_OK);
    assert_int_equal(r.index_base, 0);
    const int32_t E[] = {0, 1, 2, 3, 1, 3, 2, 4};
    expect_E(&m, E, 8);
    assert_int_equal(r.inverted_elements, 1); /* (1,3,2,4) is negatively oriented */
    df_mesh_free(&m);
    /* 1-based, 2D triangles (3 nodes per element) */
    const char *node1 = "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n", *ele1 = "1 3 0\n1 1 2 3\n";
    assert_int_equal(df_mesh_read_tetgen_memory(node1, strlen(node1), ele1, strlen(ele1), "o", NULL,
                                                &m, &r, &err), DF_OK);
    assert_int_equal(r.index_base, 1);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    assert_int_equal(m.planar, 1);
    df_mesh_free(&m);
    /* 10-node tets keep their 4 corners */
    const char *ele10 = "1 10 0\n0 0 1 2 3 4 4 4 4 4 4\n";
    assert_int_equal(df_mesh_read_tetgen_memory(node0, strlen(node0), ele10, strlen(ele10), "q",
                                                NULL, &m, &r, &err), DF_OK);
    const int32_t Q[] = {0, 1, 2, 3};
    expect_E(&m, Q, 4);
    df_mesh_free(&m);
    /* a single buffer cannot hold a TetGen pair */
    assert_int_equal(read_str(node0, DF_FMT_TETGEN, &m, &r, &err), DF_EUNSUPPORTED);
    assert_non_null(strstr(err.msg, "df_mesh_read_tetgen_memory"));
    /* positions only */
    double *V = NULL;
    int32_t nv = 0;
    assert_int_equal(df_mesh_read_tetgen_nodes_memory(node0, strlen(node0), "n", &V, &nv, &err),
                     DF_OK);
    assert_int_equal(nv, 5);
    assert_true(V[12] == 1.0 && V[13] == 1.0 && V[14] == 1.0);
    free(V);
}

/* Awkward doubles that "%.17g" must carry exactly. */
static void fill_tricky(df_mesh *m)
{
    for (int32_t i = 0; i < m->nv; i++)
        for (int k = 0; k < 3; k++) {
            double base = (k == 0 ? 0.1 : k == 1 ? 1.0 / 3.0 : 2.0 / 7.0) * (i + 1);
            m->V[3 * i + k] = m->planar && k == 2 ? 0.0 : base * (i % 3 == 1 ? 1e-7 : 1.0) +
                              (i == 2 ? 5e-324 : 0.0) - (i == 3 ? 2.5e17 : 0.0);
        }
}

static void assert_same(const df_mesh *a, const df_mesh *b, int with_F)
{
    assert_int_equal(a->kind, b->kind);
    assert_int_equal(a->planar, b->planar);
    assert_int_equal(a->nv, b->nv);
    assert_int_equal(a->ne, b->ne);
    assert_memory_equal(a->V, b->V, (size_t)a->nv * 3 * sizeof(double));
    assert_memory_equal(a->E, b->E, (size_t)a->ne * df_mesh_elem_size(a->kind) * sizeof(int32_t));
    if (with_F) {
        assert_int_equal(a->nf, b->nf);
        if (a->nf)
            assert_memory_equal(a->F, b->F, (size_t)a->nf * 3 * sizeof(int32_t));
    }
}

static void roundtrip(const df_mesh *m, df_mesh_format fmt, int expect_rc)
{
    char *buf = NULL;
    size_t len = 0;
    df_error err;
    int rc = df_mesh_write_memory(m, fmt, &buf, &len, &err);
    assert_int_equal(rc, expect_rc);
    if (rc) {
        assert_null(buf);
        return;
    }
    df_mesh back;
    df_mesh_init(&back);
    rc = df_mesh_read_memory(buf, len, DF_FMT_AUTO, "rt", NULL, &back, NULL, &err);
    if (rc)
        fprintf(stderr, "%s round trip: %s\n", df_mesh_format_name(fmt), err.msg);
    assert_int_equal(rc, DF_OK);
    if (fmt == DF_FMT_OFF && m->planar) { /* OFF has no 2D form: a 2D mesh reads back flat 3D */
        assert_int_equal(back.planar, 0);
        back.planar = 1;
    }
    assert_same(m, &back, fmt == DF_FMT_MEDIT);
    df_mesh_free(&back);
    free(buf);
}

static void test_roundtrips_all_formats_all_kinds(void **state)
{
    (void)state;
    double V[15];
    int32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 4};
    int32_t tri[] = {0, 1, 2, 0, 2, 3, 0, 3, 4};
    int32_t tet[] = {0, 1, 2, 3, 1, 2, 3, 4};
    int32_t F[] = {0, 2, 1};
    for (int planar = 0; planar < 2; planar++) {
        df_mesh m;
        df_mesh_init(&m);
        m.V = V;
        m.nv = 5;
        m.planar = planar;
        fill_tricky(&m);
        m.kind = DF_MESH_POLYLINE; m.E = seg; m.ne = 4;
        roundtrip(&m, DF_FMT_OBJ, DF_OK);
        roundtrip(&m, DF_FMT_PLY, DF_OK);
        roundtrip(&m, DF_FMT_PLY_BINARY, DF_OK);
        roundtrip(&m, DF_FMT_MEDIT, DF_OK);
        roundtrip(&m, DF_FMT_OFF, DF_EUNSUPPORTED);
        m.kind = DF_MESH_TRIANGLE; m.E = tri; m.ne = 3;
        roundtrip(&m, DF_FMT_OBJ, DF_OK);
        roundtrip(&m, DF_FMT_OFF, DF_OK);
        roundtrip(&m, DF_FMT_PLY, DF_OK);
        roundtrip(&m, DF_FMT_PLY_BINARY, DF_OK);
        roundtrip(&m, DF_FMT_MEDIT, DF_OK);
        if (planar)
            continue;
        m.kind = DF_MESH_TET; m.E = tet; m.ne = 2; m.F = F; m.nf = 1;
        roundtrip(&m, DF_FMT_MEDIT, DF_OK);
        roundtrip(&m, DF_FMT_OBJ, DF_EUNSUPPORTED);
        roundtrip(&m, DF_FMT_PLY, DF_EUNSUPPORTED);
        /* TetGen pair */
        char *nb, *eb;
        size_t nl, el;
        df_error err;
        assert_int_equal(df_mesh_write_tetgen_memory(&m, &nb, &nl, &eb, &el, &err), DF_OK);
        df_mesh back;
        df_mesh_init(&back);
        assert_int_equal(df_mesh_read_tetgen_memory(nb, nl, eb, el, "rt", NULL, &back, NULL, &err),
                         DF_OK);
        assert_same(&m, &back, 0);
        df_mesh_free(&back);
        free(nb);
        free(eb);
    }
}

static void test_files_and_tetgen_pair(void **state)
{
    (void)state;
    char dir[] = "/tmp/df_mesh_io_XXXXXX";
    assert_non_null(mkdtemp(dir));
    double V[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    int32_t E[] = {0, 1, 2, 3};
    df_mesh m, back;
    df_mesh_init(&m);
    m.kind = DF_MESH_TET; m.V = V; m.nv = 4; m.E = E; m.ne = 1;
    char path[256], other[256];
    df_error err;
    df_mesh_report rep;
    snprintf(path, sizeof path, "%s/cube.node", dir);
    assert_int_equal(df_mesh_write_file(path, &m, &err), DF_OK);
    df_mesh_init(&back);
    snprintf(other, sizeof other, "%s/cube.ele", dir); /* either name of the pair works */
    assert_int_equal(df_mesh_read_file(other, NULL, &back, &rep, &err), DF_OK);
    assert_same(&m, &back, 0);
    assert_int_equal(rep.format, DF_FMT_TETGEN);
    df_mesh_free(&back);
    double *P = NULL;
    int32_t np = 0;
    assert_int_equal(df_mesh_read_tetgen_nodes(path, &P, &np, &err), DF_OK);
    assert_int_equal(np, 4);
    assert_memory_equal(P, V, sizeof V);
    free(P);
    unlink(other);
    assert_int_equal(df_mesh_read_file(path, NULL, &back, &rep, &err), DF_EIO);
    assert_non_null(strstr(err.msg, "cube.ele"));
    unlink(path);
    /* extension-driven formats, and refusals */
    snprintf(path, sizeof path, "%s/t.MESH", dir);
    assert_int_equal(df_mesh_write_file(path, &m, &err), DF_OK);
    assert_int_equal(df_mesh_read_file(path, NULL, &back, &rep, &err), DF_OK);
    assert_int_equal(rep.format, DF_FMT_MEDIT);
    df_mesh_free(&back);
    unlink(path);
    snprintf(path, sizeof path, "%s/t.obj", dir);
    assert_int_equal(df_mesh_write_file(path, &m, &err), DF_EUNSUPPORTED);
    snprintf(path, sizeof path, "%s/t.xyz", dir);
    assert_int_equal(df_mesh_write_file(path, &m, &err), DF_EINVAL);
    snprintf(path, sizeof path, "%s/missing.off", dir);
    assert_int_equal(df_mesh_read_file(path, NULL, &back, &rep, &err), DF_EIO);
    assert_non_null(strstr(err.msg, "missing.off"));
    assert_int_equal(df_mesh_read_file(dir, NULL, &back, &rep, &err), DF_EIO);
    assert_non_null(strstr(err.msg, "is a directory"));
    assert_null(back.V);
    rmdir(dir);
}

static void test_copy_free_names(void **state)
{
    (void)state;
    df_mesh m, c;
    df_error err;
    assert_int_equal(read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", DF_FMT_OBJ, &m, NULL, &err),
                     DF_OK);
    df_mesh_init(&c);
    assert_int_equal(df_mesh_copy(&m, &c, &err), DF_OK);
    assert_ptr_not_equal(c.V, m.V);
    assert_same(&m, &c, 1);
    df_mesh_free(&m);
    df_mesh_free(&m); /* idempotent */
    df_mesh_free(NULL);
    assert_null(m.V);
    assert_true(c.V[3] == 1.0);
    df_mesh_free(&c);
    assert_int_equal(df_mesh_copy(NULL, &c, &err), DF_EINVAL);
    assert_int_equal(df_mesh_format_from_path("a/b.Ply"), DF_FMT_PLY);
    assert_int_equal(df_mesh_format_from_path("x.ele"), DF_FMT_TETGEN);
    assert_int_equal(df_mesh_format_from_path("dir.d/noext"), DF_FMT_AUTO);
    assert_string_equal(df_mesh_format_name(DF_FMT_MEDIT), "mesh");
    df_mesh_read_opts o = df_mesh_read_opts_default();
    assert_int_equal(o.max_vertices, DF_MESH_DEFAULT_MAX_VERTICES);
    assert_int_equal(o.allow_inverted, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_obj_forms),
        cmocka_unit_test(test_obj_polylines),
        cmocka_unit_test(test_off_variants),
        cmocka_unit_test(test_ply_ascii),
        cmocka_unit_test(test_ply_binary_handmade),
        cmocka_unit_test(test_medit_sections),
        cmocka_unit_test(test_tetgen_bases_and_kinds),
        cmocka_unit_test(test_roundtrips_all_formats_all_kinds),
        cmocka_unit_test(test_files_and_tetgen_pair),
        cmocka_unit_test(test_copy_free_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

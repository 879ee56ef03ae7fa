/* Unit tests for the reader behaviour a server relies on when it loads files for clients (issue
 * 9): coordinates beyond float32 are refused in every format, with the file, line and vertex;
 * redact_content keeps input bytes out of error messages; duplicate and dropped elements are
 * counted in the report; TetGen siblings keep the case of the extension (T1.NODE + T1.ELE);
 * df_mesh_read_file reads regular files only (a FIFO fails at once instead of blocking). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"

static int read_str(const char *text, df_mesh_format fmt, const char *name,
                    const df_mesh_read_opts *o, df_mesh *m, df_mesh_report *rep, df_error *e)
{
    df_mesh_init(m);
    return df_mesh_read_memory(text, strlen(text), fmt, name, o, m, rep, e);
}

static void test_float32_overflow_is_refused_in_every_format(void **state)
{
    (void)state;
    static const struct {
        df_mesh_format fmt;
        const char *name, *text, *where;
    } cases[] = {
        {DF_FMT_OBJ, "a.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", "a.obj:2: vertex 1"},
        {DF_FMT_OBJ, "b.obj", "v 0 0 0\nv 1 0 0\nv 0 -3.5e38 0\nf 1 2 3\n", "b.obj:3: vertex 2"},
        {DF_FMT_OFF, "c.off", "OFF\n3 1 0\n0 0 0\n1 0 3.5e38\n0 1 0\n3 0 1 2\n", "c.off:4"},
        {DF_FMT_PLY, "d.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
         "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1e39 0\n3 0 1 2\n", "vertex 2"},
        {DF_FMT_MEDIT, "e.mesh",
         "MeshVersionFormatted 1\nDimension 3\nVertices\n3\n0 0 0 0\n1e39 0 0 0\n0 1 0 0\n"
         "Triangles\n1\n1 2 3 0\nEnd\n", "e.mesh:6: vertex 1"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        df_mesh m;
        df_error e = {0, ""};
        int rc = read_str(cases[i].text, cases[i].fmt, cases[i].name, NULL, &m, NULL, &e);
        if (rc != DF_EFORMAT || !strstr(e.msg, "float32") || !strstr(e.msg, cases[i].where))
            fail_msg("%s: rc %d '%s'", cases[i].name, rc, e.msg);
        assert_null(m.V);
    }
    /* the largest float32 itself is fine */
    df_mesh m;
    df_error e;
    assert_int_equal(read_str("v 0 0 0\nv 3.4028234e38 0 0\nv 0 1 0\nf 1 2 3\n", DF_FMT_OBJ,
                              "ok.obj", NULL, &m, NULL, &e), DF_OK);
    df_mesh_free(&m);
    /* binary little-endian PLY with double coordinates */
    const char *hdr = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
                      "property double y\nproperty double z\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n";
    unsigned char bin[512];
    size_t hl = strlen(hdr), n = hl;
    memcpy(bin, hdr, hl);
    const double xyz[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1e300};
    memcpy(bin + n, xyz, sizeof xyz);
    n += sizeof xyz;
    bin[n++] = 3;
    const int32_t tri[3] = {0, 1, 2};
    memcpy(bin + n, tri, sizeof tri);
    n += sizeof tri;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_memory(bin, n, DF_FMT_PLY, "bin.ply", NULL, &m, NULL, &e),
                     DF_EFORMAT);
    assert_non_null(strstr(e.msg, "bin.ply: byte offset"));
    assert_non_null(strstr(e.msg, "vertex 2 coordinate z is outside the float32 range"));
    /* TetGen .node */
    const char *node = "3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1e39 0\n", *ele = "1 3 0\n1 1 2 3\n";
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), ele, strlen(ele), "t", NULL,
                                                &m, NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "t.node:4: vertex 2 coordinate y"));
}

static void test_redact_content_never_quotes_input(void **state)
{
    (void)state;
    const char *secret = "root:*:19000:0:99999:7:::";
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.redact_content = 1;
    char buf[256];
    const df_mesh_format fmts[] = {DF_FMT_OBJ, DF_FMT_OFF, DF_FMT_PLY, DF_FMT_MEDIT};
    const char *prefix[] = {"v ", "OFF\n", "ply\nformat ", "MeshVersionFormatted 1\n"};
    for (size_t i = 0; i < 4; i++) {
        snprintf(buf, sizeof buf, "%s%s\n", prefix[i], secret);
        df_mesh m;
        df_error e = {0, ""};
        assert_int_not_equal(read_str(buf, fmts[i], "x", &o, &m, NULL, &e), DF_OK);
        if (strstr(e.msg, "root") || strstr(e.msg, "99999"))
            fail_msg("format %d quoted the input: %s", (int)fmts[i], e.msg);
        /* without redaction the token is quoted (what a local tool wants) */
        assert_int_not_equal(read_str(buf, fmts[i], "x", NULL, &m, NULL, &e), DF_OK);
    }
    const char *node = "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n";
    df_mesh m;
    df_error e = {0, ""};
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), secret, strlen(secret), "X",
                                                &o, &m, NULL, &e), DF_EFORMAT);
    assert_null(strstr(e.msg, "root"));
    assert_non_null(strstr(e.msg, "X.ele:1: element count"));
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), secret, strlen(secret), "X",
                                                NULL, &m, NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "root")); /* the unredacted message, for contrast */
}

static void test_report_counts_dropped_and_duplicate_elements(void **state)
{
    (void)state;
    df_mesh m;
    df_mesh_report r;
    df_error e;
    assert_int_equal(read_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 3 1 2\nl 1 4\n",
                              DF_FMT_OBJ, "mixed.obj", NULL, &m, &r, &e), DF_OK);
    assert_int_equal(m.kind, DF_MESH_TRIANGLE);
    assert_int_equal(r.ignored_elements, 1);
    assert_int_equal(r.duplicate_elements, 1);
    assert_int_equal(r.unreferenced_vertices, 1);
    df_mesh_free(&m);
    assert_int_equal(read_str("MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n"
                              "0 1 0 0\n0 0 1 0\nEdges\n2\n1 2 0\n2 3 0\nTetrahedra\n1\n"
                              "1 2 3 4 0\nEnd\n", DF_FMT_MEDIT, "t.mesh", NULL, &m, &r, &e),
                     DF_OK);
    assert_int_equal(m.kind, DF_MESH_TET);
    assert_int_equal(r.ignored_elements, 2);
    assert_int_equal(r.duplicate_elements, 0);
    df_mesh_free(&m);
}

static void test_tetgen_sibling_keeps_case(void **state)
{
    (void)state;
    char out[64];
    assert_int_equal(df_mesh_tetgen_sibling("d/T1.NODE", out, sizeof out), 0);
    assert_string_equal(out, "d/T1.ELE");
    assert_int_equal(df_mesh_tetgen_sibling("T1.ELE", out, sizeof out), 0);
    assert_string_equal(out, "T1.NODE");
    assert_int_equal(df_mesh_tetgen_sibling("pig.node", out, sizeof out), 0);
    assert_string_equal(out, "pig.ele");
    assert_int_equal(df_mesh_tetgen_sibling("pig.Node", out, sizeof out), 0);
    assert_string_equal(out, "pig.ele");
    assert_int_equal(df_mesh_tetgen_sibling("pig.obj", out, sizeof out), -1);
    assert_int_equal(df_mesh_tetgen_sibling("a.node/x", out, sizeof out), -1);
    assert_int_equal(df_mesh_tetgen_sibling("long-name.node", out, 8), -1);
    /* the pair is read from upper-case files, and messages keep the case */
    char dir[] = "/tmp/df_case_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char np[128], ep[128];
    snprintf(np, sizeof np, "%s/T1.NODE", dir);
    snprintf(ep, sizeof ep, "%s/T1.ELE", dir);
    FILE *f = fopen(np, "w");
    fputs("4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", f);
    fclose(f);
    f = fopen(ep, "w");
    fputs("1 4 0\n1 1 2 3 4\n", f);
    fclose(f);
    df_mesh m;
    df_error e;
    df_mesh_init(&m);
    int rc = df_mesh_read_file(np, NULL, &m, NULL, &e);
    if (rc)
        fail_msg("%s", e.msg);
    assert_int_equal(m.ne, 1);
    df_mesh_free(&m);
    f = fopen(ep, "w");
    fputs("1 4 0\n1 1 2 3 9\n", f);
    fclose(f);
    assert_int_equal(df_mesh_read_file(np, NULL, &m, NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "T1.ELE:2:"));
    unlink(np);
    unlink(ep);
    rmdir(dir);
}

static void test_read_file_refuses_fifos_at_once(void **state)
{
    (void)state;
    char dir[] = "/tmp/df_fifo_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char p[128];
    snprintf(p, sizeof p, "%s/f.obj", dir);
    assert_int_equal(mkfifo(p, 0600), 0);
    df_mesh m;
    df_error e;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_file(p, NULL, &m, NULL, &e), DF_EIO); /* blocked forever before */
    assert_non_null(strstr(e.msg, "not a regular file"));
    assert_int_equal(df_mesh_read_file("/dev/zero", NULL, &m, NULL, &e), DF_EIO);
    assert_null(m.V);
    unlink(p);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_float32_overflow_is_refused_in_every_format),
        cmocka_unit_test(test_redact_content_never_quotes_input),
        cmocka_unit_test(test_report_counts_dropped_and_duplicate_elements),
        cmocka_unit_test(test_tetgen_sibling_keeps_case),
        cmocka_unit_test(test_read_file_refuses_fifos_at_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

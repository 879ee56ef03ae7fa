/* Unit tests for the mesh readers' failure modes: every error names the file and the line or byte
 * offset; truncation, wrong counts, out-of-range indices, NaN/Inf, degenerate and inverted tets
 * (reported; refused by df_mesh_check_for_solver or by allow_inverted = 0), non-manifold edges
 * (allowed, reported), vertex limits. Buffers are placed right before a PROT_NONE guard page and are
 * not NUL-terminated, so any read past the end crashes the test; every prefix and thousands of
 * byte mutations of valid inputs must give DF_OK or a clean error. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>
#include <cmocka.h>

#include "core/mesh/mesh_io.h"

/* A buffer of `len` bytes ending exactly at a PROT_NONE page. */
typedef struct {
    unsigned char *map;
    size_t map_len;
    unsigned char *data;
} guarded;

static guarded guard_copy(const void *src, size_t len)
{
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t body = (len + page - 1) / page * page;
    guarded g;
    g.map_len = body + page;
    g.map = mmap(NULL, g.map_len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    assert_true(g.map != MAP_FAILED);
    assert_int_equal(mprotect(g.map + body, page, PROT_NONE), 0);
    g.data = g.map + body - len;
    memcpy(g.data, src, len);
    return g;
}

static void guard_free(guarded *g)
{
    munmap(g->map, g->map_len);
}

/* Reads text (without its NUL) through a guard page; returns rc, leaves message in err. */
static int read_guarded(const void *text, size_t len, df_mesh_format fmt, const char *name,
                        const df_mesh_read_opts *o, df_mesh_report *rep, df_error *err)
{
    guarded g = guard_copy(text, len);
    df_mesh m;
    df_mesh_init(&m);
    df_error_clear(err);
    int rc = df_mesh_read_memory(g.data, len, fmt, name, o, &m, rep, err);
    if (rc == DF_OK) {
        assert_int_equal(df_mesh_validate(&m, NULL), DF_OK);
        df_mesh_free(&m);
    } else {
        assert_null(m.V); /* untouched */
        assert_true(strlen(err->msg) > 0);
    }
    guard_free(&g);
    return rc;
}

static int rd(const char *text, df_mesh_format fmt, const char *name, df_error *err)
{
    return read_guarded(text, strlen(text), fmt, name, NULL, NULL, err);
}

#define EXPECT(text, fmt, name, code, needle1, needle2)                                          \
    do {                                                                                          \
        df_error e_;                                                                              \
        assert_int_equal(rd(text, fmt, name, &e_), code);                                         \
        if (!strstr(e_.msg, needle1) || !strstr(e_.msg, needle2))                                 \
            fail_msg("message '%s' lacks '%s' / '%s'", e_.msg, needle1, needle2);                 \
    } while (0)

static const char *OFF_OK = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n";

static void test_truncation_and_counts(void **state)
{
    (void)state;
    EXPECT("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2", DF_FMT_OFF, "bad.off",
           DF_EFORMAT, "bad.off:8:", "truncated");
    EXPECT("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n", DF_FMT_OFF, "c.off",
           DF_EFORMAT, "c.off:8:", "wrong counts");
    EXPECT("OFF\n400 2 0\n0 0 0\n1 0 0\n", DF_FMT_OFF, "big.off", DF_EFORMAT, "big.off:3:",
           "truncated: 400 vertices declared");
    EXPECT("OFF\n4 2\n0 0 0\n1 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n", DF_FMT_OFF, "r.off",
           DF_EFORMAT, "r.off:4:", "expected vertex z");
    EXPECT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "element face 1\nproperty list uchar int vertex_indices\n", DF_FMT_PLY, "h.ply",
           DF_EFORMAT, "h.ply:8:", "no end_header");
    EXPECT("MeshVersionFormatted 1\nDimension 3\nVertices\n2\n0.5 0.25 0.125 1\n1.5 1", DF_FMT_MEDIT,
           "t.mesh", DF_EFORMAT, "t.mesh:6:", "truncated");
    EXPECT("3 3 0 0\n1 0 0 0\n2 1 0 0\n", DF_FMT_AUTO, "n.obj", DF_EFORMAT, "n.obj", "no elements");
    df_error e;
    const char *node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    df_mesh m;
    df_mesh_init(&m);
    const char *ele = "2 4 0\n1 1 2 3 4\n2 1 2 3 # lost\n";
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), ele, strlen(ele), "p", NULL, &m,
                                                NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "p.ele:3: truncated: expected element vertex index"));
    const char *skip = "1 4 0\n2 1 2 3 4\n";
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), skip, strlen(skip), "p", NULL,
                                                &m, NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "first element id 2"));
    const char *seq = "4 3 0 0\n1 0 0 0\n2 1 0 0\n4 0 1 0\n5 0 0 1\n";
    assert_int_equal(df_mesh_read_tetgen_memory(seq, strlen(seq), ele, strlen(ele), "p", NULL, &m,
                                                NULL, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "p.node:4: node id 4 out of sequence (expected 3)"));
    assert_null(m.V);
}

static void test_indices_and_numbers(void **state)
{
    (void)state;
    EXPECT("OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 7 3\n", DF_FMT_OFF, "i.off",
           DF_EFORMAT, "i.off:8:", "vertex index 7 out of range (4 vertices, 0-based)");
    EXPECT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", DF_FMT_OBJ, "i.obj", DF_EFORMAT, "i.obj:4:",
           "vertex index 4 out of range");
    EXPECT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", DF_FMT_OBJ, "n.obj", DF_EFORMAT, "n.obj:4:",
           "vertex index -4 out of range (3 vertices so far)");
    EXPECT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", DF_FMT_OBJ, "z.obj", DF_EFORMAT, "z.obj:4:",
           "bad vertex reference '0'");
    EXPECT("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n", DF_FMT_OBJ, "s.obj", DF_EFORMAT, "s.obj:4:",
           "bad vertex reference '3/x'");
    EXPECT("v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", DF_FMT_OBJ, "nan.obj", DF_EFORMAT, "nan.obj:1:",
           "not finite");
    EXPECT("OFF\n3 1 0\n0 0 0\n1 0 1e999\n0 1 0\n3 0 1 2\n", DF_FMT_OFF, "inf.off", DF_EFORMAT,
           "inf.off:4:", "not finite");
    EXPECT("OFF\n3 1 0\n0 0 0\n1 0 0x\n0 1 0\n3 0 1 2\n", DF_FMT_OFF, "x.off", DF_EFORMAT,
           "x.off:4:", "not a number");
    EXPECT("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999\n", DF_FMT_OFF, "o.off", DF_EFORMAT,
           "o.off:6:", "out of 32-bit range");
    EXPECT("ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n", DF_FMT_PLY,
           "be.ply", DF_EFORMAT, "be.ply:2:", "unsupported PLY format");
    EXPECT("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n"
           "3 0 1 1.5\n", DF_FMT_PLY, "f.ply", DF_EFORMAT, "f.ply:12:", "not an integer");
    EXPECT("MeshVersionFormatted 1\nDimension 3\nVertices\n1\n0 0 0 0\nBogus\n1\nEnd\n",
           DF_FMT_MEDIT, "k.mesh", DF_EFORMAT, "k.mesh:6:", "unknown MEDIT keyword 'Bogus'");
    EXPECT("MeshVersionFormatted 1\nDimension 3\nVertices\n3\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"
           "Triangles\n1\n1 2 4 0\nEnd\n", DF_FMT_MEDIT, "r.mesh", DF_EFORMAT, "r.mesh:10:",
           "vertex index 4 out of range (3 vertices, 1-based)");
}

static void test_limits(void **state)
{
    (void)state;
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.max_vertices = 3;
    df_error e;
    assert_int_equal(read_guarded(OFF_OK, strlen(OFF_OK), DF_FMT_OFF, "l.off", &o, NULL, &e),
                     DF_ELIMIT);
    assert_non_null(strstr(e.msg, "l.off:3: 4 vertices exceed the configured limit 3"));
    const char *obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nf 1 2 3\n";
    assert_int_equal(read_guarded(obj, strlen(obj), DF_FMT_OBJ, "l.obj", &o, NULL, &e), DF_ELIMIT);
    assert_non_null(strstr(e.msg, "l.obj:4: more than 3 vertices"));
    /* A header claiming 2e9 vertices is refused before any allocation. */
    const char *huge = "OFF\n2000000000 1 0\n0 0 0\n";
    assert_int_equal(read_guarded(huge, strlen(huge), DF_FMT_OFF, "h.off", NULL, NULL, &e), DF_ELIMIT);
    o.max_vertices = 0; /* <= 0: default */
    o.max_elements = 1;
    assert_int_equal(read_guarded(OFF_OK, strlen(OFF_OK), DF_FMT_OFF, "m.off", &o, NULL, &e),
                     DF_ELIMIT);
    assert_non_null(strstr(e.msg, "2 faces exceed the configured limit 1"));
}

static void test_degenerate_inverted_nonmanifold(void **state)
{
    (void)state;
    /* tet 1 fine, tet 2 inverted, tet 3 flat (degenerate), tet 4 repeats a vertex */
    const char *node = "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 0\n";
    const char *ele = "4 4 0\n1 1 2 3 4\n2 1 3 2 4\n3 1 2 5 3\n4 1 1 2 3\n";
    df_mesh m;
    df_mesh_report r;
    df_error e;
    df_mesh_init(&m);
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), ele, strlen(ele), "d", NULL, &m,
                                                &r, &e), DF_OK);
    assert_int_equal(r.inverted_elements, 1);
    assert_int_equal(r.first_inverted, 1);
    assert_int_equal(r.degenerate_elements, 2);
    assert_int_equal(r.first_degenerate, 2);
    assert_true(r.min_signed_volume < -0.16 && r.min_signed_volume > -0.17);
    df_mesh_report r2;
    assert_int_equal(df_mesh_check_for_solver(&m, &r2, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "2 degenerate element(s) (first: element 2)"));
    df_mesh_free(&m);
    /* only the inverted one: the solver check names it; allow_inverted = 0 refuses the read */
    const char *ele2 = "2 4 0\n1 1 2 3 4\n2 1 3 2 4\n";
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), ele2, strlen(ele2), "d", NULL,
                                                &m, &r, &e), DF_OK);
    assert_int_equal(df_mesh_check_for_solver(&m, NULL, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "1 inverted element(s) (first: element 1"));
    df_mesh_free(&m);
    df_mesh_read_opts o = df_mesh_read_opts_default();
    o.allow_inverted = 0;
    assert_int_equal(df_mesh_read_tetgen_memory(node, strlen(node), ele2, strlen(ele2), "d", &o,
                                                &m, &r, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "d.ele: 1 inverted element(s)"));
    assert_null(m.V);
    /* three triangles on one edge: allowed, reported */
    const char *fan = "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 1 4\n";
    assert_int_equal(read_guarded(fan, strlen(fan), DF_FMT_OFF, "nm.off", NULL, &r, &e), DF_OK);
    assert_int_equal(r.nonmanifold_edges, 1);
    assert_int_equal(r.boundary_edges, 6);
    /* a face shared by three tets: non-manifold face, reported */
    const char *n3 = "6 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0 0 -1\n6 0 0 2\n";
    const char *e3 = "3 4 0\n1 1 2 3 4\n2 1 3 2 5\n3 1 2 3 6\n";
    assert_int_equal(df_mesh_read_tetgen_memory(n3, strlen(n3), e3, strlen(e3), "nf", NULL, &m, &r,
                                                &e), DF_OK);
    assert_int_equal(r.nonmanifold_faces, 1);
    df_mesh_free(&m);
}

/* Every prefix of each valid input reads cleanly (OK or error), through a guard page. */
static const char *VALID[][2] = {
    {"OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n4 0 2 3 1\n", "off"},
    {"# c\nv 0 0 0\nv 1 0 0\nv 0 1 0.5\nv 1 1 1\nvt 0 0\nf 1/1 2/1 3/1\nf -1//1 -2//1 -3//1\n"
     "l 1 2 3\n", "obj"},
    {"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
     "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "ply"},
    {"MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
     "Triangles\n1\n1 2 3 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n", "mesh"},
};

static void test_every_prefix_is_safe(void **state)
{
    (void)state;
    for (size_t f = 0; f < sizeof VALID / sizeof VALID[0]; f++) {
        size_t len = strlen(VALID[f][0]);
        int ok = 0;
        for (size_t n = 0; n <= len; n++) {
            df_error e;
            int rc = read_guarded(VALID[f][0], n, DF_FMT_AUTO, VALID[f][1], NULL, NULL, &e);
            if (rc == DF_OK)
                ok++;
            else if (!strstr(e.msg, VALID[f][1]))
                fail_msg("prefix %zu of %s: message '%s' does not name the file", n, VALID[f][1],
                         e.msg);
        }
        assert_true(ok >= 1); /* at least the full file */
    }
}

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

/* Deterministic byte mutations (flips, digit swaps, cuts) never crash or over-read. */
static void test_mutations_are_safe(void **state)
{
    (void)state;
    static const char alphabet[] = "0123456789 \n-+.eE/#naif";
    uint32_t seed = 12345;
    unsigned char buf[512];
    int errors = 0, oks = 0;
    for (int it = 0; it < 4000; it++) {
        size_t f = it % (sizeof VALID / sizeof VALID[0]);
        size_t len = strlen(VALID[f][0]);
        memcpy(buf, VALID[f][0], len);
        int edits = 1 + (int)(lcg(&seed) % 4);
        for (int k = 0; k < edits; k++) {
            size_t at = lcg(&seed) % len;
            uint32_t r = lcg(&seed);
            if (r % 3 == 0)
                buf[at] = (unsigned char)(r >> 8);
            else if (r % 3 == 1)
                buf[at] = (unsigned char)alphabet[(r >> 8) % (sizeof alphabet - 1)];
            else
                len = at + 1;
        }
        df_error e;
        df_mesh_format fmt = (df_mesh_format)(it / 4 % 5);
        if (read_guarded(buf, len, fmt, "mut", NULL, NULL, &e) == DF_OK)
            oks++;
        else
            errors++;
    }
    assert_int_equal(oks + errors, 4000);
    assert_true(errors > 1000); /* most mutations must be detected */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truncation_and_counts),
        cmocka_unit_test(test_indices_and_numbers),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_degenerate_inverted_nonmanifold),
        cmocka_unit_test(test_every_prefix_is_safe),
        cmocka_unit_test(test_mutations_are_safe),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

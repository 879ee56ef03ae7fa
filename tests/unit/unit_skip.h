/* The one skip helper of the cmocka unit tests (issue 10): a test that cannot run here (the shared
 * meshes folder is missing, deformd is not built) calls unit_skip() with the reason. Outside CI the
 * test is skipped with that reason printed; under CI (environment CI=true) it fails instead, so a
 * missing prerequisite fails the run rather than silently thinning it out. Include after
 * <cmocka.h>; linked into every unit binary (tests/unit/unit_skip.c). */
#ifndef DF_TESTS_UNIT_SKIP_H
#define DF_TESTS_UNIT_SKIP_H

/* 1 when the environment variable CI is exactly "true", else 0. */
int unit_ci(void);

/* Prints "skipping: <reason>" and skips the running cmocka test, or under CI prints the reason and
 * fails it. Does not return (cmocka leaves the test through its jump buffer). `fmt` is printf-style. */
void unit_skip_at(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4), noreturn));
#define unit_skip(...) unit_skip_at(__FILE__, __LINE__, __VA_ARGS__)

/* The shared meshes folder: $MESHES when set and non-empty, else "../shared/meshes". */
const char *unit_meshes_dir(void);

/* Fills `out` with unit_meshes_dir()/file and returns it when that file can be opened for reading;
 * otherwise calls unit_skip() naming the path (and does not return). */
const char *unit_mesh_or_skip(const char *file, char *out, unsigned long cap);

/* The shared HID folder: $MESHES/../hid when MESHES is set and non-empty, else "../shared/hid".
 * Fills `out` and returns it when that folder can be opened; otherwise calls unit_skip() naming the
 * path (and does not return). */
const char *unit_hid_dir_or_skip(char *out, unsigned long cap);

#endif

/* The unit tests' skip helper: see unit_skip.h. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <dirent.h>

#include "tests/unit/unit_skip.h"

int unit_ci(void)
{
    const char *ci = getenv("CI");
    return ci && strcmp(ci, "true") == 0;
}

void unit_skip_at(const char *file, int line, const char *fmt, ...)
{
    char why[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    fflush(stdout);
    if (unit_ci()) {
        printf("FAIL (CI=true, a skip is a failure): %s\n", why);
        fflush(stdout);
        _fail(file, line);
    } else {
        printf("skipping: %s\n", why);
        fflush(stdout);
        _skip(file, line);
    }
    abort(); /* not reached: cmocka jumps out of the test */
}

const char *unit_meshes_dir(void)
{
    const char *d = getenv("MESHES");
    return d && *d ? d : "../shared/meshes";
}

const char *unit_mesh_or_skip(const char *file, char *out, unsigned long cap)
{
    snprintf(out, (size_t)cap, "%s/%s", unit_meshes_dir(), file);
    FILE *f = fopen(out, "r");
    if (!f) unit_skip("mesh file %s not found (set MESHES to the shared meshes folder)", out);
    fclose(f);
    return out;
}

const char *unit_hid_dir_or_skip(char *out, unsigned long cap)
{
    const char *m = getenv("MESHES");
    if (m && *m) snprintf(out, (size_t)cap, "%s/../hid", m);
    else snprintf(out, (size_t)cap, "../shared/hid");
    DIR *d = opendir(out);
    if (!d) unit_skip("HID folder %s not found (set MESHES to the shared meshes folder)", out);
    closedir(d);
    return out;
}

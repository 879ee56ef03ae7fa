/* Shared by the hid unit tests: reads a whole file of the shared HID folder into memory. */
#ifndef DF_TESTS_UNIT_HID_FILES_H
#define DF_TESTS_UNIT_HID_FILES_H

#include <stdio.h>
#include <stdlib.h>

/* The bytes of dir/name (malloc'ed, *n set), or NULL when it cannot be read. */
static inline char *hid_read_file(const char *dir, const char *name, size_t *n)
{
    char path[2304];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t cap = 0, len = 0;
    for (;;) {
        if (cap - len < 4096) {
            char *nb = realloc(buf, cap = cap ? cap * 2 : 65536);
            if (!nb) { free(buf); fclose(f); return NULL; }
            buf = nb;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) break;
    }
    fclose(f);
    *n = len;
    return buf;
}

#endif

/* mesh_scan.h — internal: a bounds-checked text scanner over a (pointer, length) buffer that need
 * not be NUL-terminated, used by the mesh readers. Numbers are split into tokens by hand; only the
 * token (copied to a small stack buffer) goes to strtod, so parsing never reads past the buffer. */
#ifndef DF_MESH_SCAN_H
#define DF_MESH_SCAN_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"

/* Longest numeric token accepted (characters). */
#define DF_SCAN_MAX_NUMBER 127

typedef struct df_scan {
    const char *p;     /* buffer */
    size_t len;        /* its length in bytes */
    size_t pos;        /* current offset */
    int32_t line;      /* 1-based line of `pos` */
    const char *name;  /* file name for messages */
    char comment;      /* comment character ('#') or 0 */
    int redact;        /* 1: messages never quote input bytes (df_scan_quote) */
    /* Optional progress callback: called with (user, pos, len) every DF_SCAN_PROGRESS_LINES
     * lines (NULL: none); set by df_scan_set_progress. */
    void (*progress)(void *user, size_t done, size_t total);
    void *progress_user;
} df_scan;

/* Lines between two calls of a scanner's progress callback. */
#define DF_SCAN_PROGRESS_LINES 16384

/* Starts scanning `len` bytes at `buf`; line 1, comment char '#'. */
void df_scan_init(df_scan *s, const void *buf, size_t len, const char *name);

/* Sets the progress callback of `s` (fn NULL: none); see df_scan.progress. */
void df_scan_set_progress(df_scan *s, void (*fn)(void *user, size_t done, size_t total),
                          void *user);

/* Formats the n-byte token t for an error message into buf (size bn >= 20): "'tok'" (cut at 32
 * bytes), or "(value not shown)" when s->redact is set (files a server reads for a client must
 * never have their content echoed). Returns buf. */
const char *df_scan_quote(const df_scan *s, const char *t, size_t n, char *buf, size_t bn);

/* Skips spaces, tabs, CR, VT, FF on the current line (not newlines, not comments). */
void df_scan_skip_blank(df_scan *s);

/* Skips all whitespace, newlines and comments (a comment runs to the end of its line). */
void df_scan_skip_ws(df_scan *s);

/* Moves to the start of the next line (or the end of the buffer). */
void df_scan_next_line(df_scan *s);

/* 1 when only blanks and maybe a comment remain on the current line (or at end of buffer). */
int df_scan_at_eol(df_scan *s);

/* 1 at the end of the buffer. */
int df_scan_eof(const df_scan *s);

/* Next whitespace-delimited token: on the current line only (cross_lines = 0) or after skipping
 * newlines and comments (cross_lines = 1). Returns its length (0 when none) and sets *tok to its
 * first byte; the scanner moves past it. */
size_t df_scan_token(df_scan *s, int cross_lines, const char **tok);

/* Parses exactly the n bytes at t as a decimal integer (optional sign). 0 on success, -1 when not
 * an integer, -2 when outside int32 range. */
int df_scan_parse_int(const char *t, size_t n, int64_t *v);

/* Parses exactly the n bytes at t as a double (strtod syntax). 0 on success (finite or not),
 * -1 when not a number or longer than DF_SCAN_MAX_NUMBER. */
int df_scan_parse_double(const char *t, size_t n, double *v);

/* Reads the next token as a finite double / an int32, with an error naming the file, line and
 * `what` when the token is missing, malformed, non-finite or out of range. */
int df_scan_double(df_scan *s, int cross_lines, const char *what, double *v, df_error *err);
int df_scan_int(df_scan *s, int cross_lines, const char *what, int32_t *v, df_error *err);

/* Case-sensitive comparison of a token with a NUL-terminated word. */
int df_scan_tok_eq(const char *t, size_t n, const char *word);

#endif

/* mesh_scan.c — bounds-checked text scanning for the mesh readers (see mesh_scan.h). */
#include "core/mesh/mesh_scan.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

void df_scan_init(df_scan *s, const void *buf, size_t len, const char *name)
{
    s->p = (const char *)buf;
    s->len = buf ? len : 0;
    s->pos = 0;
    s->line = 1;
    s->name = name ? name : "<memory>";
    s->comment = '#';
    s->redact = 0;
    s->progress = NULL;
    s->progress_user = NULL;
}

void df_scan_set_progress(df_scan *s, void (*fn)(void *user, size_t done, size_t total),
                          void *user)
{
    s->progress = fn;
    s->progress_user = user;
}

/* One more line scanned: counts it and calls the progress callback every
 * DF_SCAN_PROGRESS_LINES lines. */
static void new_line(df_scan *s)
{
    s->line++;
    if (s->progress && s->line % DF_SCAN_PROGRESS_LINES == 0)
        s->progress(s->progress_user, s->pos, s->len);
}

void df_scan_skip_blank(df_scan *s)
{
    while (s->pos < s->len && is_blank(s->p[s->pos]))
        s->pos++;
}

void df_scan_next_line(df_scan *s)
{
    const char *nl = s->pos < s->len ? memchr(s->p + s->pos, '\n', s->len - s->pos) : NULL;
    if (nl) {
        s->pos = (size_t)(nl - s->p) + 1;
        new_line(s);
    } else {
        s->pos = s->len;
    }
}

void df_scan_skip_ws(df_scan *s)
{
    while (s->pos < s->len) {
        char c = s->p[s->pos];
        if (is_blank(c)) {
            s->pos++;
        } else if (c == '\n') {
            s->pos++;
            new_line(s);
        } else if (s->comment && c == s->comment) {
            df_scan_next_line(s);
        } else {
            break;
        }
    }
}

int df_scan_at_eol(df_scan *s)
{
    df_scan_skip_blank(s);
    if (s->pos >= s->len)
        return 1;
    char c = s->p[s->pos];
    return c == '\n' || (s->comment && c == s->comment);
}

int df_scan_eof(const df_scan *s)
{
    return s->pos >= s->len;
}

size_t df_scan_token(df_scan *s, int cross_lines, const char **tok)
{
    if (cross_lines)
        df_scan_skip_ws(s);
    else if (df_scan_at_eol(s))
        return 0;
    size_t start = s->pos;
    while (s->pos < s->len) {
        char c = s->p[s->pos];
        if (is_blank(c) || c == '\n')
            break;
        s->pos++;
    }
    *tok = s->p + start;
    return s->pos - start;
}

int df_scan_parse_int(const char *t, size_t n, int64_t *v)
{
    size_t i = 0;
    int neg = 0;
    if (n > 0 && (t[0] == '-' || t[0] == '+')) {
        neg = t[0] == '-';
        i = 1;
    }
    if (i == n)
        return -1;
    int64_t acc = 0;
    for (; i < n; i++) {
        unsigned d = (unsigned)(unsigned char)t[i] - '0';
        if (d > 9)
            return -1;
        if (acc > INT32_MAX)
            continue; /* keep validating digits; range error reported below */
        acc = acc * 10 + d;
    }
    if (acc > (int64_t)INT32_MAX + (neg ? 1 : 0))
        return -2;
    *v = neg ? -acc : acc;
    return 0;
}

int df_scan_parse_double(const char *t, size_t n, double *v)
{
    char buf[DF_SCAN_MAX_NUMBER + 1];
    if (n == 0 || n > DF_SCAN_MAX_NUMBER)
        return -1;
    memcpy(buf, t, n);
    buf[n] = '\0';
    char *end = NULL;
    double x = strtod(buf, &end);
    if (end != buf + n)
        return -1;
    *v = x;
    return 0;
}

const char *df_scan_quote(const df_scan *s, const char *t, size_t n, char *buf, size_t bn)
{
    if (s->redact)
        snprintf(buf, bn, "(value not shown)");
    else
        snprintf(buf, bn, "'%.*s'", (int)(n > 32 ? 32 : n), t);
    return buf;
}

int df_scan_double(df_scan *s, int cross_lines, const char *what, double *v, df_error *err)
{
    const char *t;
    size_t n = df_scan_token(s, cross_lines, &t);
    if (n == 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: truncated: expected %s, found %s", s->name,
                            (int)s->line, what, df_scan_eof(s) ? "end of file" : "end of line");
    double x;
    char q[48];
    if (df_scan_parse_double(t, n, &x) != 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: %s %s is not a number", s->name,
                            (int)s->line, what, df_scan_quote(s, t, n, q, sizeof q));
    if (!isfinite(x))
        return df_error_set(err, DF_EFORMAT, "%s:%d: %s %s is not finite (NaN/Inf)", s->name,
                            (int)s->line, what, df_scan_quote(s, t, n, q, sizeof q));
    *v = x;
    return DF_OK;
}

int df_scan_int(df_scan *s, int cross_lines, const char *what, int32_t *v, df_error *err)
{
    const char *t;
    size_t n = df_scan_token(s, cross_lines, &t);
    if (n == 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: truncated: expected %s, found %s", s->name,
                            (int)s->line, what, df_scan_eof(s) ? "end of file" : "end of line");
    int64_t x;
    int rc = df_scan_parse_int(t, n, &x);
    char q[48];
    if (rc == -2)
        return df_error_set(err, DF_EFORMAT, "%s:%d: %s %s out of 32-bit range", s->name,
                            (int)s->line, what, df_scan_quote(s, t, n, q, sizeof q));
    if (rc != 0)
        return df_error_set(err, DF_EFORMAT, "%s:%d: %s %s is not an integer", s->name,
                            (int)s->line, what, df_scan_quote(s, t, n, q, sizeof q));
    *v = (int32_t)x;
    return DF_OK;
}

int df_scan_tok_eq(const char *t, size_t n, const char *word)
{
    size_t w = strlen(word);
    return n == w && memcmp(t, word, n) == 0;
}

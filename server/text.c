/* text.c — UTF-8 validation and log escaping (see text.h). */
#include "server/text.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* Length of the well-formed UTF-8 sequence at s (n bytes available), or 0 when the bytes there
 * do not start one. *cp receives the code point. */
static size_t utf8_seq(const unsigned char *s, size_t n, uint32_t *cp)
{
    unsigned char b = s[0];
    if (b < 0x80) return *cp = b, 1;
    size_t len;
    uint32_t v, min;
    if (b >= 0xC2 && b <= 0xDF) len = 2, v = b & 0x1F, min = 0x80;
    else if (b >= 0xE0 && b <= 0xEF) len = 3, v = b & 0x0F, min = 0x800;
    else if (b >= 0xF0 && b <= 0xF4) len = 4, v = b & 0x07, min = 0x10000;
    else return 0;
    if (n < len) return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xC0) != 0x80) return 0;
        v = (v << 6) | (s[i] & 0x3F);
    }
    if (v < min || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return 0;
    *cp = v;
    return len;
}

static int is_control(uint32_t cp) { return cp < 0x20 || (cp >= 0x7F && cp <= 0x9F); }

int df_text_utf8_valid(const char *s, size_t n)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t i = 0;
    uint32_t cp;
    while (i < n) {
        size_t l = utf8_seq(p + i, n - i, &cp);
        if (!l) return 0;
        i += l;
    }
    return 1;
}

int df_text_check_name(const char *what, const char *name, df_error *err)
{
    const unsigned char *p = (const unsigned char *)name;
    size_t n = strlen(name), i = 0;
    uint32_t cp;
    while (i < n) {
        size_t l = utf8_seq(p + i, n - i, &cp);
        if (!l)
            return df_error_set(err, DF_EINVAL, "%s is not valid UTF-8 (byte %zu: 0x%02x)", what,
                                i, p[i]);
        if (is_control(cp))
            return df_error_set(err, DF_EINVAL,
                                "%s contains the control character U+%04X at byte %zu", what,
                                (unsigned)cp, i);
        i += l;
    }
    return DF_OK;
}

size_t df_text_escape(char *out, size_t cap, const char *in)
{
    const unsigned char *p = (const unsigned char *)in;
    size_t n = strlen(in), i = 0, o = 0;
    uint32_t cp;
    if (cap == 0) return 0;
    while (i < n) {
        size_t l = utf8_seq(p + i, n - i, &cp);
        if (l && !is_control(cp)) {
            if (o + l >= cap) break;
            memcpy(out + o, p + i, l);
            o += l;
            i += l;
            continue;
        }
        /* a control character or a stray byte: escape every byte of it */
        size_t k = l ? l : 1;
        if (o + 4 * k >= cap) break;
        for (size_t j = 0; j < k; j++) {
            snprintf(out + o, 5, "\\x%02x", p[i + j]);
            o += 4;
        }
        i += k;
    }
    out[o] = '\0';
    return o;
}

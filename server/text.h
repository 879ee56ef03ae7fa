/* text.h — untrusted text from clients: UTF-8 validation of names and escaping for log lines.
 *
 * Names (session names in LOAD_MESH, client names in HELLO) must be UTF-8 (PROTOCOL.md 2) without
 * control characters. Every log line passes through df_text_escape (server/log.c), so whatever a
 * client manages to get into a message cannot start a new line or send terminal escapes. */
#ifndef DF_SERVER_TEXT_H
#define DF_SERVER_TEXT_H

#include <stddef.h>

#include "core/common/df_error.h"

/* 1 when the n bytes at s are well-formed UTF-8 (no overlong forms, no surrogates, <= U+10FFFF),
 * else 0. */
int df_text_utf8_valid(const char *s, size_t n);

/* Checks a client-chosen name (NUL-terminated): DF_OK, or DF_EINVAL naming `what` ("load_mesh:
 * name") and the byte offset when it is not valid UTF-8 or holds a control character (U+0000..
 * U+001F, U+007F, U+0080..U+009F). */
int df_text_check_name(const char *what, const char *name, df_error *err);

/* Copies the NUL-terminated `in` into `out` (cap >= 1 bytes, always NUL-terminated, truncated at a
 * character boundary when short), writing each control character (C0, DEL, C1) and each byte that
 * is not part of well-formed UTF-8 as the four characters \xNN. Returns the length written. */
size_t df_text_escape(char *out, size_t cap, const char *in);

#endif

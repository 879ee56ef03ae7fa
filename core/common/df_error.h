/* df_error.h — the one error convention of deformd's C code.
 *
 * Every fallible function returns an int: DF_OK (0) on success or a negative DF_E* code, and,
 * when given a non-NULL `df_error *err`, fills it with the code and a human-readable message
 * ("bunny.off:12: face index 9000 out of range (3485 vertices)"). On error, outputs are left
 * untouched unless a function's comment says otherwise. The codes are stable: the wire protocol
 * reports them to clients. */
#ifndef DF_ERROR_H
#define DF_ERROR_H

#include <stdarg.h>

enum {
    DF_OK = 0,
    DF_EINVAL = -1,     /* an argument is out of range, NaN/Inf, or inconsistent */
    DF_ENOMEM = -2,     /* allocation failed */
    DF_ESINGULAR = -3,  /* a linear system is singular (e.g. coincident pinned points) */
    DF_EIO = -4,        /* a file could not be opened, read or written */
    DF_EFORMAT = -5,    /* a file or buffer is malformed (truncated, bad counts, bad indices) */
    DF_ELIMIT = -6,     /* a configured size limit is exceeded */
    DF_ENOTFOUND = -7,  /* a named object (session, handle set, ...) does not exist */
    DF_ESTATE = -8,     /* the request is valid but not in the current state (e.g. no stroke open) */
    DF_EUNSUPPORTED = -9, /* a valid request this build or mesh kind does not support */
    DF_EINTERNAL = -10, /* a library call failed unexpectedly (CHOLMOD, LAPACK) */
    DF_EEXIST = -11,    /* the name is already in use (e.g. a session name) */
    DF_EPERM = -12,     /* the peer lacks a right on the session (access control) */
    DF_EMOVED = -13     /* the session is owned by another daemon of the cluster: the message
                         * is "MOVED <id> <host:port>" (server/cluster/cluster.h) */
};

#define DF_ERROR_MSG_MAX 256

typedef struct df_error {
    int code;                     /* one of the DF_E* codes, DF_OK when no error */
    char msg[DF_ERROR_MSG_MAX];   /* NUL-terminated message, "" when no error */
} df_error;

/* Records `code` and a printf-style message in `err` (which may be NULL) and returns `code`, so
 * that callers can write `return df_error_set(err, DF_EINVAL, "radius %g <= 0", r);`. */
int df_error_set(df_error *err, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Clears `err` (may be NULL) to DF_OK and an empty message. */
void df_error_clear(df_error *err);

/* Returns a short stable name for a DF_E* code ("EINVAL"), "EUNKNOWN" for anything else. */
const char *df_error_name(int code);

#endif

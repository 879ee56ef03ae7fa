/* log.c — leveled logging to stderr (see log.h). */
#include "server/log.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <strings.h>

#include "core/common/df_error.h"
#include "server/text.h"

static atomic_int g_level = DF_LOG_INFO;
static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
static const char *const k_names[] = {"error", "warn", "info", "debug"};

void df_log_set_level(int level)
{
    if (level < DF_LOG_ERROR) level = DF_LOG_ERROR;
    if (level > DF_LOG_DEBUG) level = DF_LOG_DEBUG;
    atomic_store(&g_level, level);
}

int df_log_get_level(void) { return atomic_load(&g_level); }

int df_log_parse_level(const char *s, int *level)
{
    if (!s || !level) return DF_EINVAL;
    for (int i = 0; i < 4; i++) {
        if (strcasecmp(s, k_names[i]) == 0 || (s[0] == '0' + i && s[1] == '\0')) {
            *level = i;
            return DF_OK;
        }
    }
    if (strcasecmp(s, "warning") == 0) {
        *level = DF_LOG_WARN;
        return DF_OK;
    }
    return DF_EINVAL;
}

void df_log(int level, const char *fmt, ...)
{
    if (level > atomic_load(&g_level) || level < DF_LOG_ERROR) return;
    char line[1024], safe[4 * sizeof line];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    /* Client-chosen text (names, paths) may be part of the message: one log line stays one line,
     * without terminal escapes (text.h). */
    df_text_escape(safe, sizeof safe, line);
    pthread_mutex_lock(&g_lock);
    fprintf(stderr, "deformd[%s]: %s\n", k_names[level], safe);
    fflush(stderr);
    pthread_mutex_unlock(&g_lock);
}

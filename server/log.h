/* log.h — leveled logging of deformd to stderr (journald picks it up under systemd).
 *
 * Lines look like "deformd[info]: client 3 connected". Thread-safe: worker threads may log. */
#ifndef DF_SERVER_LOG_H
#define DF_SERVER_LOG_H

typedef enum df_log_level {
    DF_LOG_ERROR = 0,
    DF_LOG_WARN = 1,
    DF_LOG_INFO = 2,
    DF_LOG_DEBUG = 3
} df_log_level;

/* Sets the most verbose level that is printed (default DF_LOG_INFO). Out-of-range values clamp. */
void df_log_set_level(int level);

/* Current level (DF_LOG_*). */
int df_log_get_level(void);

/* Parses "error", "warn", "info" or "debug" (case-insensitive) or a digit 0..3 into *level.
 * Returns DF_OK, or DF_EINVAL (and *level untouched) for anything else. */
int df_log_parse_level(const char *s, int *level);

/* Prints one line at `level` when it is enabled: "deformd[<level>]: <message>\n". Control
 * characters and bytes that are not UTF-8 in the message are written as \xNN (df_text_escape),
 * so a logged client-chosen string can never forge a line or reach the terminal raw. */
void df_log(int level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif

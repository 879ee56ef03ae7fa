/* progress_out.h — deformctl's display of WORK_PROGRESS events (PROTOCOL.md 4.37) for load,
 * handles and move: a progress bar redrawn in place on a terminal, or plain lines.
 *
 * Modes (--progress MODE): auto (the default: a bar when stderr is a terminal, else lines, and
 * only once the request has run CTL_PROGRESS_AUTO_DELAY_MS, so quick work prints nothing), bar,
 * lines (every event, at once), none (nothing is asked of the daemon). All output is on stderr:
 *   bar:   "\r<prog> <cmd>: <stage>  [######..............]  31%  6.5/21.0 MB" redrawn in place
 *          (at most every event; the line ends when the stage's final event arrives);
 *   lines: one line per event, "<prog> <cmd>: <stage> <done>/<total> <unit> (<pct>%)" with
 *          " done" appended on the stage's final event; without a total "<stage> <done> <unit>".
 * Stages: upload, parse (bytes), factorize (steps), solve (iterations); a stage newer than
 * this build is "stage N" (units). */
#ifndef DF_DEFORMCTL_PROGRESS_OUT_H
#define DF_DEFORMCTL_PROGRESS_OUT_H

#include <stdint.h>
#include <stdio.h>

#include "client/deformclient.h"

enum { CTL_PROGRESS_AUTO = 0, CTL_PROGRESS_BAR, CTL_PROGRESS_LINES, CTL_PROGRESS_NONE };

/* In auto mode events are shown only from this long after ctl_progress_init on. */
#define CTL_PROGRESS_AUTO_DELAY_MS 1000

/* Mode names for --progress, index = mode, NULL-terminated. */
extern const char *const ctl_progress_modes[];

/* Help line of the --progress option (for the option tables). */
#define CTL_PROGRESS_HELP                                                                    \
    "--progress MODE    progress of long work on stderr: auto (default: after 1 s, a bar on\n" \
    "                     a terminal, plain lines otherwise), bar, lines or none"

typedef struct ctl_progress {
    const char *prog, *cmd; /* "deformctl", the command name */
    int mode;               /* CTL_PROGRESS_BAR, _LINES or _NONE (auto resolved) */
    FILE *out;              /* stderr */
    int bar_open;           /* a bar line is drawn and not yet ended */
    double t0_ms;           /* monotonic clock at init */
    double delay_ms;        /* events before t0_ms + delay_ms are not shown (auto: 1 s) */
    uint64_t events;        /* WORK_PROGRESS events shown */
} ctl_progress;

/* Sets up `p` for command `cmd` of `prog` with `mode` (CTL_PROGRESS_*; AUTO becomes BAR when
 * `out` is a terminal, else LINES, delayed by CTL_PROGRESS_AUTO_DELAY_MS). Call it right before
 * the request. */
void ctl_progress_init(ctl_progress *p, const char *prog, const char *cmd, int mode, FILE *out);

/* 1 when progress is shown (the request should ask the daemon for it). */
int ctl_progress_wanted(const ctl_progress *p);

/* Event callback for df_client_set_event_callback (user = the ctl_progress): shows
 * WORK_PROGRESS events; every other event is ignored. A malformed event is ignored. */
void ctl_progress_event(void *user, const df_frame_header *h, const uint8_t *payload);

/* Shows one event (also for tests; the auto delay applies). */
void ctl_progress_show(ctl_progress *p, const df_msg_work_progress *w);

/* Ends an open bar line (after the request, also when it failed). */
void ctl_progress_finish(ctl_progress *p);

#endif

/* progress_out.c — progress bar / lines of deformctl (see progress_out.h). */
#include <inttypes.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client/deformctl/progress_out.h"

#define BAR_CELLS 20

const char *const ctl_progress_modes[] = {"auto", "bar", "lines", "none", NULL};

static const char *const STAGES[] = {NULL, "upload", "parse", "factorize", "solve"};
static const char *const UNITS[] = {NULL, "bytes", "bytes", "steps", "iterations"};
_Static_assert(sizeof STAGES / sizeof STAGES[0] == DF_STAGE_MAX + 1, "a name per stage");

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

void ctl_progress_init(ctl_progress *p, const char *prog, const char *cmd, int mode, FILE *out)
{
    memset(p, 0, sizeof *p);
    p->prog = prog;
    p->cmd = cmd;
    p->out = out;
    p->t0_ms = now_ms();
    if (mode == CTL_PROGRESS_AUTO) {
        mode = isatty(fileno(out)) ? CTL_PROGRESS_BAR : CTL_PROGRESS_LINES;
        p->delay_ms = CTL_PROGRESS_AUTO_DELAY_MS;
    }
    p->mode = mode;
}

int ctl_progress_wanted(const ctl_progress *p)
{
    return p->mode != CTL_PROGRESS_NONE;
}

static void stage_name(uint8_t stage, char *buf, size_t n)
{
    if (stage <= DF_STAGE_MAX && STAGES[stage])
        snprintf(buf, n, "%s", STAGES[stage]);
    else
        snprintf(buf, n, "stage %u", stage);
}

/* "6.5/21.0 MB" for byte stages, "37/500" otherwise. */
static void amount(const df_msg_work_progress *w, char *buf, size_t n)
{
    int bytes = w->stage == DF_STAGE_UPLOAD || w->stage == DF_STAGE_PARSE;
    if (bytes && w->total)
        snprintf(buf, n, "%.1f/%.1f MB", (double)w->done / 1e6, (double)w->total / 1e6);
    else if (bytes)
        snprintf(buf, n, "%.1f MB", (double)w->done / 1e6);
    else if (w->total)
        snprintf(buf, n, "%" PRIu64 "/%" PRIu64, w->done, w->total);
    else
        snprintf(buf, n, "%" PRIu64, w->done);
}

void ctl_progress_show(ctl_progress *p, const df_msg_work_progress *w)
{
    if (p->mode == CTL_PROGRESS_NONE) return;
    if (p->delay_ms > 0 && now_ms() - p->t0_ms < p->delay_ms) return; /* quick work: quiet */
    char st[32];
    stage_name(w->stage, st, sizeof st);
    int pct = w->total ? (int)(100.0 * (double)w->done / (double)w->total) : -1;
    p->events++;
    if (p->mode == CTL_PROGRESS_LINES) {
        const char *unit = w->stage <= DF_STAGE_MAX && UNITS[w->stage] ? UNITS[w->stage] : "units";
        if (w->total)
            fprintf(p->out, "%s %s: %s %" PRIu64 "/%" PRIu64 " %s (%d%%)%s\n", p->prog, p->cmd,
                    st, w->done, w->total, unit, pct, w->final ? " done" : "");
        else
            fprintf(p->out, "%s %s: %s %" PRIu64 " %s%s\n", p->prog, p->cmd, st, w->done, unit,
                    w->final ? " done" : "");
        fflush(p->out);
        return;
    }
    char bar[BAR_CELLS + 1], am[64];
    int fill = pct < 0 ? (w->final ? BAR_CELLS : 0) : pct * BAR_CELLS / 100;
    for (int i = 0; i < BAR_CELLS; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[BAR_CELLS] = '\0';
    amount(w, am, sizeof am);
    char pcts[16] = "";
    if (pct >= 0) snprintf(pcts, sizeof pcts, "%3d%%", pct);
    fprintf(p->out, "\r%s %s: %-9s [%s] %s  %-24s", p->prog, p->cmd, st, bar, pcts, am);
    p->bar_open = 1;
    if (w->final) {
        fputc('\n', p->out);
        p->bar_open = 0;
    }
    fflush(p->out);
}

void ctl_progress_event(void *user, const df_frame_header *h, const uint8_t *payload)
{
    ctl_progress *p = user;
    if (h->type != DF_MSG_WORK_PROGRESS) return;
    df_msg_work_progress w;
    if (df_msg_work_progress_decode(payload, h->payload_len, &w, NULL) != DF_OK) return;
    ctl_progress_show(p, &w);
}

void ctl_progress_finish(ctl_progress *p)
{
    if (p->bar_open) {
        fputc('\n', p->out);
        fflush(p->out);
        p->bar_open = 0;
    }
}

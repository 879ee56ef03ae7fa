/* Unit tests for deformctl's progress display (client/deformctl/progress_out): the plain lines
 * and the bar as PROTOCOL.md 4.37 events arrive, written to a temporary file and read back. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "client/deformctl/progress_out.h"

static char *slurp(FILE *f)
{
    static char buf[4096];
    fflush(f);
    rewind(f);
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    return buf;
}

static df_msg_work_progress ev(uint8_t stage, uint64_t done, uint64_t total, int final)
{
    df_msg_work_progress w = {0, stage, (uint8_t)final, done, total, 1.5};
    return w;
}

static void test_lines(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    ctl_progress p;
    ctl_progress_init(&p, "deformctl", "load", CTL_PROGRESS_LINES, f);
    assert_true(ctl_progress_wanted(&p));
    df_msg_work_progress a = ev(DF_STAGE_UPLOAD, 300, 1000, 0), b = ev(DF_STAGE_UPLOAD, 1000, 1000, 1),
                         c = ev(DF_STAGE_SOLVE, 7, 0, 0), d = ev(9, 2, 4, 1);
    ctl_progress_show(&p, &a);
    ctl_progress_show(&p, &b);
    ctl_progress_show(&p, &c);
    ctl_progress_show(&p, &d);
    ctl_progress_finish(&p); /* no bar open: nothing more */
    assert_string_equal(slurp(f), "deformctl load: upload 300/1000 bytes (30%)\n"
                                  "deformctl load: upload 1000/1000 bytes (100%) done\n"
                                  "deformctl load: solve 7 iterations\n"
                                  "deformctl load: stage 9 2/4 units (50%) done\n");
    assert_int_equal(p.events, 4);
    fclose(f);
}

static void test_bar_and_event_callback(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    ctl_progress p;
    ctl_progress_init(&p, "deformctl", "move", CTL_PROGRESS_BAR, f);
    /* through the event callback, as the client library delivers it */
    df_msg_work_progress w = ev(DF_STAGE_SOLVE, 50, 200, 0);
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_work_progress_encode(&w, &b, &e), DF_OK);
    df_frame_header h;
    memset(&h, 0, sizeof h);
    h.type = DF_MSG_WORK_PROGRESS;
    h.flags = DF_FLAG_EVENT;
    h.payload_len = (uint32_t)b.len;
    ctl_progress_event(&p, &h, b.data);
    h.type = DF_MSG_DISPLACEMENT; /* other events are not progress */
    ctl_progress_event(&p, &h, b.data);
    h.type = DF_MSG_WORK_PROGRESS;
    h.payload_len = 3; /* malformed: ignored */
    ctl_progress_event(&p, &h, b.data);
    df_buf_free(&b);
    assert_true(p.bar_open);
    ctl_progress_finish(&p);
    assert_false(p.bar_open);
    const char *out = slurp(f);
    assert_non_null(strstr(out, "\rdeformctl move: solve     [#####...............]  25%  50/200"));
    assert_int_equal(out[strlen(out) - 1], '\n');
    assert_int_equal(p.events, 1);
    fclose(f);
}

static void test_none_and_auto_delay(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    ctl_progress p;
    ctl_progress_init(&p, "deformctl", "load", CTL_PROGRESS_NONE, f);
    assert_false(ctl_progress_wanted(&p));
    df_msg_work_progress w = ev(DF_STAGE_PARSE, 1, 2, 1);
    ctl_progress_show(&p, &w);
    /* auto on a file (not a terminal): lines, held back while the request is young */
    ctl_progress_init(&p, "deformctl", "load", CTL_PROGRESS_AUTO, f);
    assert_int_equal(p.mode, CTL_PROGRESS_LINES);
    assert_true(p.delay_ms > 0 && ctl_progress_wanted(&p));
    p.delay_ms = 1e12; /* far in the future: deterministic */
    ctl_progress_show(&p, &w);
    assert_string_equal(slurp(f), "");
    p.delay_ms = 0;
    ctl_progress_show(&p, &w);
    assert_string_equal(slurp(f), "deformctl load: parse 1/2 bytes (50%) done\n");
    fclose(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lines),
        cmocka_unit_test(test_bar_and_event_callback),
        cmocka_unit_test(test_none_and_auto_delay),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

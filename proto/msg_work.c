/* msg_work.c — work_progress body (WORK_PROGRESS event, PROTOCOL.md 4.37; messages.h).
 * u64 session_id, u8 stage, u8 final, u16 reserved, u64 done, u64 total, f64 elapsed_ms
 * (36 bytes). Any stage >= 1 decodes (servers may add stages at the end); done <= total when
 * total != 0. */
#include <math.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

static int work_check(const df_msg_work_progress *m, df_error *err)
{
    const char *M = "work_progress";
    if (m->stage < 1)
        return df_error_set(err, DF_EINVAL, "%s: stage 0 is not a stage", M);
    if (m->final > 1)
        return df_error_set(err, DF_EINVAL, "%s: final %u is not 0 or 1", M, m->final);
    if (m->total && m->done > m->total)
        return df_error_set(err, DF_EINVAL, "%s: done %llu exceeds total %llu", M,
                            (unsigned long long)m->done, (unsigned long long)m->total);
    if (!isfinite(m->elapsed_ms) || m->elapsed_ms < 0)
        return df_error_set(err, DF_EINVAL, "%s: elapsed_ms %g must be finite and >= 0", M,
                            m->elapsed_ms);
    return DF_OK;
}

int df_msg_work_progress_encode(const df_msg_work_progress *m, df_buf *out, df_error *err)
{
    int rc = work_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 36, "work_progress", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->stage);
    df_buf_put_u8(out, m->final);
    df_buf_put_u16(out, 0);
    df_buf_put_u64(out, m->done);
    df_buf_put_u64(out, m->total);
    df_buf_put_f64(out, m->elapsed_ms);
    return DF_OK;
}

int df_msg_work_progress_decode(const uint8_t *p, size_t n, df_msg_work_progress *m,
                                df_error *err)
{
    df_rd r;
    df_msg_work_progress t;
    df_rd_init(&r, p, n, "work_progress", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.stage = df_rd_u8(&r, "stage");
    t.final = df_rd_u8(&r, "final");
    df_rd_reserved16(&r, "reserved");
    t.done = df_rd_u64(&r, "done");
    t.total = df_rd_u64(&r, "total");
    t.elapsed_ms = df_rd_f64(&r, "elapsed_ms");
    int rc = df_rd_end(&r);
    if (rc || (rc = work_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

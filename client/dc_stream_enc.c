/* dc_stream_enc.c — the negotiated stream encodings on the client side (PROTOCOL.md 6.3):
 * unwrapping zstd ZFRAME events and applying quantized QDISP versions to a replica. */
#include "client/dc_client.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#define K_LIMIT 4503599627370495.0 /* 2^52 - 1, as the daemon clamps (server/session/stream_enc.c) */

int df_client_zframe_unwrap(const df_frame_header *h, const uint8_t *payload,
                            df_frame_header *inner, uint8_t **raw, df_error *err)
{
    if (!h || !inner || !raw || (!payload && h->payload_len))
        return df_error_set(err, DF_EINVAL, "zframe unwrap: NULL argument");
    df_msg_zframe z;
    int rc = df_msg_zframe_decode(payload, h->payload_len, &z, err);
    if (rc)
        return rc;
    uint8_t *out = malloc(z.raw_len ? z.raw_len : 1);
    if (!out)
        return df_error_set(err, DF_ENOMEM, "zframe: out of memory for %u bytes", z.raw_len);
    size_t n = ZSTD_decompress(out, z.raw_len, z.z, z.zlen);
    if (ZSTD_isError(n) || n != z.raw_len) {
        free(out);
        return df_error_set(err, DF_EFORMAT, "zframe: zstd data %s (raw_len %u)",
                            ZSTD_isError(n) ? ZSTD_getErrorName(n) : "of another length",
                            z.raw_len);
    }
    *inner = *h;
    inner->type = z.inner_type;
    inner->payload_len = z.raw_len;
    *raw = out;
    return DF_OK;
}

/* K of one component from an exact displacement: floor(u / q + 0.5), clamped (PROTOCOL.md 6.3) */
static int64_t quantize(float u, double q)
{
    double k = floor((double)u / q + 0.5);
    return (int64_t)(k > K_LIMIT ? K_LIMIT : k < -K_LIMIT ? -K_LIMIT : k);
}

int dc_replica_feed_qdisp(df_client_replica *r, const df_msg_qdisp *q, int last, df_error *err)
{
    if (q->session_id != r->session_id)
        return 0;
    if (q->nv != r->nv) {
        r->stale = 1;
        return df_error_set(err, DF_EINVAL, "qdisp: frame has %u vertices, replica %u", q->nv,
                            r->nv);
    }
    if (r->building == 0) {
        if (q->version <= r->version)
            return 0; /* already covered (e.g. by a snapshot) */
        if (r->stale || q->base_version != r->version) {
            int was = r->stale;
            r->stale = 1;
            return df_error_set(err, DF_ESTATE, "stream: version %llu applies to %llu, replica "
                                "is at %llu%s", (unsigned long long)q->version,
                                (unsigned long long)q->base_version,
                                (unsigned long long)r->version, was ? " (stale)" : "");
        }
        r->building = q->version;
    } else if (q->version != r->building) {
        r->stale = 1;
        r->building = 0;
        return df_error_set(err, DF_EFORMAT, "stream: qdisp chunk of version %llu while "
                            "building version %llu", (unsigned long long)q->version,
                            (unsigned long long)r->building);
    }
    size_t m = 3 * (size_t)r->nv;
    if (!r->K || r->step != q->step) { /* K of the exact displacements held (a snapshot) */
        int64_t *K = r->K ? r->K : malloc(m * sizeof *K);
        if (!K) {
            r->stale = 1;
            r->building = 0;
            return df_error_set(err, DF_ENOMEM, "qdisp: out of memory for %u vertices", r->nv);
        }
        for (size_t i = 0; i < m; i++) K[i] = quantize(r->u[i], q->step);
        r->K = K;
        r->step = q->step;
        r->k_exact = 1;
    }
    for (uint32_t j = 0; j < q->count; j++) {
        size_t i = 3 * (size_t)q->idx[j];
        for (int k = 0; k < 3; k++) {
            r->K[i + k] += q->dq[3 * (size_t)j + k];
            if (!r->k_exact)
                r->u[i + k] = (float)(q->step * (double)r->K[i + k]);
        }
    }
    if (!last)
        return 0;
    r->building = 0;
    if (r->k_exact) { /* the first quantized version after exact values: every component */
        for (size_t i = 0; i < m; i++) r->u[i] = (float)(q->step * (double)r->K[i]);
        r->k_exact = 0;
    }
    r->version = q->version;
    r->versions_applied++;
    return 1;
}

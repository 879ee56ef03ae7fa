/* dc_stream.c — applying the displacement stream: the pure chunk/positions helpers and the
 * version-tracking replica (see deformclient.h). */
#include "client/dc_client.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int df_client_disp_apply(const df_msg_disp *d, float *u, uint32_t nv, df_error *err)
{
    if (!d || !u)
        return df_error_set(err, DF_EINVAL, "disp apply: NULL argument");
    if (d->nv != nv)
        return df_error_set(err, DF_EINVAL, "disp apply: frame has %u vertices, replica %u", d->nv,
                            nv);
    if ((uint64_t)d->offset + d->count > d->total || d->total > nv)
        return df_error_set(err, DF_EINVAL, "disp apply: rows [%u, +%u) outside %u of %u", d->offset,
                            d->count, d->total, nv);
    if (d->count && !d->xyz)
        return df_error_set(err, DF_EINVAL, "disp apply: no values");
    if (d->encoding == DF_DISP_SPARSE) {
        if (d->count && !d->idx)
            return df_error_set(err, DF_EINVAL, "disp apply: sparse frame without indices");
        for (uint32_t i = 0; i < d->count; i++)
            if (d->idx[i] < 0 || (uint32_t)d->idx[i] >= nv)
                return df_error_set(err, DF_EINVAL, "disp apply: row %u index %d outside 0..%u",
                                    d->offset + i, d->idx[i], nv - 1);
    } else if (d->encoding != DF_DISP_DENSE) {
        return df_error_set(err, DF_EINVAL, "disp apply: unknown encoding %u", d->encoding);
    }
    for (size_t i = 0; i < (size_t)d->count * 3; i++)
        if (!isfinite(d->xyz[i]))
            return df_error_set(err, DF_EINVAL, "disp apply: row %u has a non-finite value",
                                d->offset + (uint32_t)(i / 3));
    if (d->encoding == DF_DISP_DENSE) {
        memcpy(u + (size_t)d->offset * 3, d->xyz, (size_t)d->count * 3 * sizeof(float));
    } else {
        for (uint32_t i = 0; i < d->count; i++)
            memcpy(u + (size_t)d->idx[i] * 3, d->xyz + (size_t)i * 3, 3 * sizeof(float));
    }
    return DF_OK;
}

void df_client_positions(const float *base, const float *u, uint32_t nv, float *out)
{
    for (size_t i = 0; i < (size_t)nv * 3; i++)
        out[i] = base[i] + u[i];
}

int df_client_replica_init(df_client_replica *r, uint64_t session_id, uint32_t nv,
                           const float *base, const float *u0, uint64_t version, df_error *err)
{
    if (!r || !base || nv == 0)
        return df_error_set(err, DF_EINVAL, "replica init: NULL or empty arguments");
    size_t bytes = (size_t)nv * 3 * sizeof(float);
    float *b = malloc(bytes), *u = malloc(bytes);
    if (!b || !u) {
        free(b);
        free(u);
        return df_error_set(err, DF_ENOMEM, "replica init: out of memory for %u vertices", nv);
    }
    memcpy(b, base, bytes);
    if (u0)
        memcpy(u, u0, bytes);
    else
        memset(u, 0, bytes);
    memset(r, 0, sizeof *r);
    r->session_id = session_id;
    r->nv = nv;
    r->version = version;
    r->base = b;
    r->u = u;
    return DF_OK;
}

void df_client_replica_free(df_client_replica *r)
{
    if (!r)
        return;
    free(r->base);
    free(r->u);
    free(r->K);
    memset(r, 0, sizeof *r);
}

/* Applies one decoded chunk `d`; `last` is 1 when no more chunks of its message follow. */
static int feed_disp(df_client_replica *r, const df_msg_disp *d, int last, df_error *err)
{
    if (d->session_id != r->session_id)
        return 0;
    int snapshot = d->kind == DF_CHANGE_SNAPSHOT;
    if (r->building == 0) {
        if (d->offset != 0) {
            r->stale = 1;
            return df_error_set(err, DF_EFORMAT, "stream: version %llu starts at row %u",
                                (unsigned long long)d->version, d->offset);
        }
        if (!snapshot) {
            if (d->version <= r->version)
                return 0; /* already covered (e.g. by a snapshot) */
            if (r->stale || d->base_version != r->version) {
                int was = r->stale;
                r->stale = 1;
                return df_error_set(err, DF_ESTATE,
                                    "stream: version %llu applies to %llu, replica is at %llu%s",
                                    (unsigned long long)d->version,
                                    (unsigned long long)d->base_version,
                                    (unsigned long long)r->version, was ? " (stale)" : "");
            }
        }
        r->building = d->version;
        r->rows_seen = 0;
    } else if (d->version != r->building || d->offset != r->rows_seen) {
        r->stale = 1;
        r->building = 0;
        return df_error_set(err, DF_EFORMAT, "stream: chunk of version %llu rows [%u, +%u) while "
                            "building version %llu at row %u", (unsigned long long)d->version,
                            d->offset, d->count, (unsigned long long)r->building, r->rows_seen);
    }
    int rc = df_client_disp_apply(d, r->u, r->nv, err);
    if (rc) {
        r->stale = 1;
        r->building = 0;
        return rc;
    }
    r->rows_seen += d->count;
    if (!last)
        return 0;
    r->building = 0;
    if (r->rows_seen != d->total) {
        r->stale = 1;
        return df_error_set(err, DF_EFORMAT, "stream: version %llu ended after %u of %u rows",
                            (unsigned long long)d->version, r->rows_seen, d->total);
    }
    r->version = d->version;
    r->versions_applied++;
    if (snapshot)
        r->stale = 0;
    r->step = 0; /* exact values: a later QDISP derives K from them */
    return 1;
}

int df_client_replica_feed(df_client_replica *r, const df_frame_header *h, const uint8_t *payload,
                           df_error *err)
{
    if (!r || !h || (!payload && h->payload_len))
        return df_error_set(err, DF_EINVAL, "replica feed: NULL argument");
    if (h->flags & DF_FLAG_ERROR)
        return 0;
    int last = !(h->flags & DF_FLAG_MORE);
    int rc;
    if (h->type == DF_MSG_ZFRAME) {
        df_frame_header in;
        uint8_t *raw = NULL;
        rc = df_client_zframe_unwrap(h, payload, &in, &raw, err);
        if (rc) {
            r->stale = 1;
            return rc;
        }
        rc = df_client_replica_feed(r, &in, raw, err);
        free(raw);
        return rc;
    }
    if (h->type == DF_MSG_QDISP) {
        df_msg_qdisp q;
        rc = df_msg_qdisp_decode(payload, h->payload_len, &q, err);
        if (rc) {
            r->stale = 1;
            return rc;
        }
        rc = dc_replica_feed_qdisp(r, &q, last, err);
        df_msg_qdisp_free(&q);
        return rc;
    }
    if (h->type == DF_MSG_DISPLACEMENT || h->type == DF_MSG_SNAPSHOT) {
        df_msg_disp d;
        rc = df_msg_disp_decode(payload, h->payload_len, &d, err);
        if (rc) {
            r->stale = 1;
            return rc;
        }
        rc = feed_disp(r, &d, last, err);
        df_msg_disp_free(&d);
        return rc;
    }
    if (h->type == DF_MSG_PROGRESS) {
        df_msg_progress p;
        rc = df_msg_progress_decode(payload, h->payload_len, &p, err);
        if (rc) {
            r->stale = 1;
            return rc;
        }
        rc = feed_disp(r, &p.disp, last, err);
        df_msg_progress_free(&p);
        return rc;
    }
    df_msg_shm_ref lost;
    if (h->type == DF_MSG_SHM_REF &&
        df_msg_shm_ref_decode(payload, h->payload_len, &lost, NULL) == DF_OK &&
        lost.session_id == r->session_id) {
        r->stale = 1;
        return df_error_set(err, DF_ESTATE, "replica: a frame was lost to the shared-memory "
                            "ring (overwritten before it was read); resync");
    }
    return 0;
}

int df_client_replica_resync(df_client *c, df_client_replica *r, df_error *err)
{
    uint64_t v = 0;
    int rc = df_client_snapshot(c, r->session_id, 0, r->nv, r->u, &v, err);
    if (rc)
        return rc;
    r->version = v;
    r->building = 0;
    r->rows_seen = 0;
    r->stale = 0;
    r->step = 0; /* exact: a later QDISP derives K from these values */
    return DF_OK;
}

void df_client_replica_positions(const df_client_replica *r, float *out)
{
    df_client_positions(r->base, r->u, r->nv, out);
}

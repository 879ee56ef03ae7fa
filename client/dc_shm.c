/* dc_shm.c — the client half of the shared-memory stream (deformclient.h df_client_stream_shm,
 * PROTOCOL.md 6.1): map a session's ring, resolve SHM_REF events into the frames they stand for. */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "client/dc_client.h"
#include "proto/shm_ring.h"

static int reply_shm_info(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_shm_info_decode(p, h->payload_len, user, err);
}

static dc_shm *find(df_client *c, uint64_t session_id)
{
    for (int i = 0; i < c->nshm; i++)
        if (c->shm[i].session_id == session_id) return &c->shm[i];
    return NULL;
}

/* Maps the ring named by `info` read-only and checks its header against it. */
static int map_ring(const df_msg_shm_info *info, dc_shm *out, df_error *err)
{
    int fd = open(info->path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) return df_error_set(err, DF_EIO, "shm: open %s: %s", info->path, strerror(errno));
    struct stat st;
    size_t bytes = DF_SHM_HEADER_BYTES + (size_t)info->capacity;
    void *m = MAP_FAILED;
    if (fstat(fd, &st) == 0 && (uint64_t)st.st_size >= bytes)
        m = mmap(NULL, bytes, PROT_READ, MAP_SHARED | MAP_POPULATE, fd, 0);
    int saved = m == MAP_FAILED && errno ? errno : EINVAL;
    close(fd);
    if (m == MAP_FAILED)
        return df_error_set(err, DF_EIO, "shm: map %s: %s", info->path, strerror(saved));
    int rc = df_shm_ring_check(m, bytes, info->capacity, info->session_id, err);
    if (rc) {
        munmap(m, bytes);
        return rc;
    }
    *out = (dc_shm){.session_id = info->session_id, .base = m, .map_bytes = bytes};
    return DF_OK;
}

int df_client_stream_shm(df_client *c, uint64_t session_id, df_msg_shm_info *info,
                         df_error *err)
{
    df_msg_session_ref ref = {session_id};
    df_msg_shm_info got;
    int rc = dc_request(c, DF_MSG_STREAM_SHM, dc_enc_session_ref, &ref, reply_shm_info, &got, err);
    if (rc) return rc;
    if (!find(c, session_id)) {
        dc_shm ring;
        if ((rc = map_ring(&got, &ring, err)) != DF_OK) return rc;
        dc_shm *n = realloc(c->shm, (size_t)(c->nshm + 1) * sizeof *n);
        if (!n) {
            munmap((void *)ring.base, ring.map_bytes);
            return df_error_set(err, DF_ENOMEM, "shm: out of memory");
        }
        c->shm = n;
        c->shm[c->nshm++] = ring;
    }
    if (info) *info = got;
    return DF_OK;
}

void dc_shm_drop(df_client *c, uint64_t session_id)
{
    for (int i = 0; i < c->nshm;) {
        if (session_id && c->shm[i].session_id != session_id) {
            i++;
            continue;
        }
        munmap((void *)c->shm[i].base, c->shm[i].map_bytes);
        c->shm[i] = c->shm[--c->nshm];
    }
}

/* Copies the frame `r` names into c->shm_frame and decodes its header; DF_OK when it is a
 * complete event frame. */
static int resolve(df_client *c, const df_msg_shm_ref *r, df_frame_header *fh, df_error *err)
{
    dc_shm *ring = find(c, r->session_id);
    if (!ring) return df_error_set(err, DF_ENOTFOUND, "shm: no ring for session %llu",
                                   (unsigned long long)r->session_id);
    if (c->shm_cap < r->length) {
        uint8_t *n = realloc(c->shm_frame, r->length);
        if (!n) return df_error_set(err, DF_ENOMEM, "shm: out of memory");
        c->shm_frame = n;
        c->shm_cap = r->length;
    }
    int rc = df_shm_ring_read(ring->base, ring->map_bytes - DF_SHM_HEADER_BYTES, r->position,
                              r->length, c->shm_frame, err);
    if (rc) return rc;
    rc = df_frame_header_decode(c->shm_frame, r->length, fh, err);
    if (rc == DF_OK &&
        ((size_t)fh->payload_len + DF_FRAME_HEADER_SIZE != r->length || !(fh->flags & DF_FLAG_EVENT)))
        rc = df_error_set(err, DF_EFORMAT, "shm: ring frame is not one whole event frame");
    return rc;
}

void dc_shm_dispatch(df_client *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_shm_ref r;
    df_frame_header fh;
    df_error err;
    int ok = df_msg_shm_ref_decode(p, h->payload_len, &r, &err) == DF_OK &&
             resolve(c, &r, &fh, &err) == DF_OK;
    if (!c->on_event) return;
    if (ok)
        c->on_event(c->event_user, &fh, c->shm_frame + DF_FRAME_HEADER_SIZE);
    else
        c->on_event(c->event_user, h, p); /* lost: the application resyncs */
}

/* shm.h — a session's shared-memory stream ring file (PROTOCOL.md 6.1; layout in
 * proto/shm_ring.h). The daemon creates it in DF_SHM_DIR (tmpfs: a ring on a disk file system
 * would be written back to disk) on the first STREAM_SHM of a session, appends broadcast event
 * frames to it (loop thread only), and removes it when the session is destroyed. Subscribers that
 * attached get a 24-byte SHM_REF instead of each frame. */
#ifndef DF_SERVER_SHM_H
#define DF_SERVER_SHM_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/messages.h"
#include "proto/shm_ring.h"

/* Frames shorter than this stay on the socket: an SHM_REF (48 bytes with its header) would not
 * save a copy worth the reader's extra work. */
#define DF_SHM_MIN_FRAME 1024u
#define DF_SHM_DIR "/dev/shm"            /* where ring files live */
#define DF_SHM_PREFIX "deformd-"         /* ring file names: deformd-<pid>-<session>-<random> */

/* Ring sizing (df_shm_ring_size): room for this many dense versions of the session (a reader may
 * fall this far behind before it loses frames), rounded up to DF_SHM_RING_ROUND bytes, at least
 * DF_SHM_RING_MIN, at most shm_ring_bytes. A dense version of nv vertices is 12 nv bytes of rows
 * plus at most DF_SHM_VERSION_OVERHEAD bytes of headers. */
#define DF_SHM_RING_VERSIONS 128u
#define DF_SHM_RING_ROUND (64u << 10)
#define DF_SHM_RING_MIN (64u << 10)
#define DF_SHM_VERSION_OVERHEAD 128u

typedef struct df_shm_ring {
    char path[DF_MAX_PATH_LEN + 1]; /* absolute */
    df_shm_writer w;                /* w.base: mapping of the whole file, read-write */
    size_t map_bytes;               /* DF_SHM_HEADER_BYTES + capacity */
    uint64_t capacity;
    uint32_t min_frame, max_frame;  /* frames in [min, max] bytes go through the ring */
} df_shm_ring;

/* Creates the ring file of session `session_id` (mode 0600: only the daemon's user can map it)
 * of `capacity` data bytes (DF_SHM_MIN_CAPACITY..DF_SHM_MAX_CAPACITY; allocated at once), maps it
 * and writes its header. Errors: DF_EINVAL (bad capacity), DF_EIO (create, size or map failed;
 * the message has the OS reason, e.g. /dev/shm full), DF_ENOMEM. */
int df_shm_create(uint64_t session_id, uint64_t capacity, df_shm_ring **out, df_error *err);

/* Data bytes of the ring of a session of `nv` vertices under the cap `cap` (shm_ring_bytes,
 * >= DF_SHM_RING_MIN when nonzero): see DF_SHM_RING_VERSIONS. 0 when cap is 0. */
uint64_t df_shm_ring_size(int32_t nv, uint64_t cap);

/* Removes ring files of this user left by daemons that no longer run (a crash skips
 * df_shm_destroy). Returns how many were removed. Called once at start. */
int df_shm_sweep_stale(void);

/* 1 when a frame of `len` bytes goes through the ring. */
int df_shm_takes(const df_shm_ring *r, size_t len);

/* Appends one whole frame; returns its stream position (df_shm_writer_append). */
uint64_t df_shm_put(df_shm_ring *r, const uint8_t *frame, uint32_t len);

/* Unmaps and removes the file (clients keep their own mappings). NULL-safe. */
void df_shm_destroy(df_shm_ring *r);

#endif

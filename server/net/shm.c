/* shm.c — a session's shared-memory stream ring file (see shm.h). */
#include "server/net/shm.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "proto/shm_ring.h"

/* "<DF_SHM_DIR>/deformd-<pid>-<session>-<random>": unique per daemon and session, unguessable
 * (another user cannot create it first; O_EXCL would refuse it anyway). */
static int ring_path(uint64_t session_id, char *out, size_t cap, df_error *err)
{
    uint32_t rnd = 0;
    if (getrandom(&rnd, sizeof rnd, 0) != (ssize_t)sizeof rnd) rnd = (uint32_t)clock();
    int n = snprintf(out, cap, "%s/%s%d-%llu-%08x", DF_SHM_DIR, DF_SHM_PREFIX, (int)getpid(),
                     (unsigned long long)session_id, rnd);
    if (n < 0 || (size_t)n >= cap) return df_error_set(err, DF_EINVAL, "shm: path too long");
    return DF_OK;
}

int df_shm_create(uint64_t session_id, uint64_t capacity, df_shm_ring **out, df_error *err)
{
    if (capacity < DF_SHM_MIN_CAPACITY || capacity > DF_SHM_MAX_CAPACITY)
        return df_error_set(err, DF_EINVAL, "shm: capacity %llu out of range",
                            (unsigned long long)capacity);
    df_shm_ring *r = calloc(1, sizeof *r);
    if (!r) return df_error_set(err, DF_ENOMEM, "shm: out of memory");
    int rc = ring_path(session_id, r->path, sizeof r->path, err);
    if (rc) {
        free(r);
        return rc;
    }
    int fd = open(r->path, O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
    if (fd < 0) {
        rc = df_error_set(err, DF_EIO, "shm: create %s: %s", r->path, strerror(errno));
        free(r);
        return rc;
    }
    r->capacity = capacity;
    r->map_bytes = DF_SHM_HEADER_BYTES + (size_t)capacity;
    void *m = MAP_FAILED;
    /* Allocated and mapped up front: no page faults on the loop thread while streaming, and a
     * /dev/shm too small for the ring is an error here, not a SIGBUS at a later write (a sparse
     * tmpfs file reserves nothing). posix_fallocate returns its error instead of setting errno. */
    int saved = posix_fallocate(fd, 0, (off_t)r->map_bytes);
    if (saved == 0) {
        m = mmap(NULL, r->map_bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd, 0);
        saved = errno;
    }
    close(fd);
    if (m == MAP_FAILED) {
        unlink(r->path);
        rc = df_error_set(err, DF_EIO, "shm: size/map %s: %s", r->path, strerror(saved));
        free(r);
        return rc;
    }
    r->min_frame = DF_SHM_MIN_FRAME;
    r->max_frame = capacity / 2 < UINT32_MAX ? (uint32_t)(capacity / 2) : UINT32_MAX;
    if (r->max_frame < r->min_frame) r->max_frame = r->min_frame;
    df_shm_writer_init(&r->w, m, capacity, session_id);
    *out = r;
    return DF_OK;
}

uint64_t df_shm_ring_size(int32_t nv, uint64_t cap)
{
    uint64_t version = 12 * (uint64_t)(nv > 0 ? nv : 0) + DF_SHM_VERSION_OVERHEAD;
    uint64_t want = version * DF_SHM_RING_VERSIONS;
    want = (want + DF_SHM_RING_ROUND - 1) / DF_SHM_RING_ROUND * DF_SHM_RING_ROUND;
    if (want < DF_SHM_RING_MIN) want = DF_SHM_RING_MIN;
    return want < cap ? want : cap;
}

int df_shm_sweep_stale(void)
{
    DIR *d = opendir(DF_SHM_DIR);
    if (!d) return 0;
    int removed = 0;
    size_t plen = strlen(DF_SHM_PREFIX);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (strncmp(e->d_name, DF_SHM_PREFIX, plen) != 0) continue;
        int pid = atoi(e->d_name + plen);
        if (pid <= 0 || kill(pid, 0) == 0 || errno != ESRCH) continue; /* alive, or not ours */
        struct stat st;
        if (fstatat(dirfd(d), e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 ||
            st.st_uid != geteuid() || !S_ISREG(st.st_mode))
            continue;
        removed += unlinkat(dirfd(d), e->d_name, 0) == 0;
    }
    closedir(d);
    return removed;
}

int df_shm_takes(const df_shm_ring *r, size_t len)
{
    return r && len >= r->min_frame && len <= r->max_frame;
}

uint64_t df_shm_put(df_shm_ring *r, const uint8_t *frame, uint32_t len)
{
    return df_shm_writer_append(&r->w, frame, len);
}

void df_shm_destroy(df_shm_ring *r)
{
    if (!r) return;
    munmap(r->w.base, r->map_bytes);
    unlink(r->path);
    free(r);
}

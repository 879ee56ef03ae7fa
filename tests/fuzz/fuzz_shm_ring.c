/* fuzz_shm_ring.c — libFuzzer target for the shared-memory stream ring (proto/shm_ring.h). The
 * input is a program of operations on one ring: append a frame, read a recorded frame back, read
 * an arbitrary (position, length), or scribble on the shared header (what another process of the
 * same user could do). Oracles: no read or append ever touches memory outside the ring (ASan);
 * a read that succeeds returns exactly the bytes appended at that position; while the header is
 * untouched, a frame reads back unless a later append overwrote part of its span.
 * Seeds: tests/fuzz/corpus/shm_ring. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "proto/shm_ring.h"

#define CAP 8192u
#define MAX_FRAMES 512

typedef struct reader {
    const uint8_t *p;
    size_t n;
} reader;

static unsigned next(reader *r, unsigned bytes)
{
    unsigned v = 0;
    for (unsigned i = 0; i < bytes && r->n; i++, r->p++, r->n--) v |= (unsigned)*r->p << (8 * i);
    return v;
}

static void pattern(uint8_t *f, uint32_t len, uint8_t seed)
{
    for (uint32_t i = 0; i < len; i++) f[i] = (uint8_t)(seed + 13 * i);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t *ring = aligned_alloc(4096, DF_SHM_HEADER_BYTES + CAP);
    static uint8_t frame[CAP], out[CAP], want[CAP];
    static uint64_t pos[MAX_FRAMES];
    static uint32_t len[MAX_FRAMES];
    static uint8_t seed[MAX_FRAMES];
    int n = 0, scribbled = 0;
    memset(ring, 0, DF_SHM_HEADER_BYTES + CAP);
    df_shm_writer w;
    df_shm_writer_init(&w, ring, CAP, 1);
    reader r = {data, size};
    df_error e;
    while (r.n) {
        unsigned op = next(&r, 1) % 4;
        if (op == 0 && n < MAX_FRAMES) { /* append */
            len[n] = 1 + next(&r, 2) % (CAP / 2);
            seed[n] = (uint8_t)next(&r, 1);
            pattern(frame, len[n], seed[n]);
            pos[n] = df_shm_writer_append(&w, frame, len[n]);
            if (pos[n] % CAP + len[n] > CAP || (n && pos[n] < pos[n - 1] + len[n - 1])) abort();
            n++;
        } else if (op == 1 && n) { /* read a recorded frame back */
            int k = (int)(next(&r, 2) % (unsigned)n);
            int rc = df_shm_ring_read(ring, CAP, pos[k], len[k], out, &e);
            uint64_t end = pos[n - 1] + len[n - 1];
            int overwritten = end > CAP && pos[k] < end - CAP;
            if (rc == DF_OK) {
                pattern(want, len[k], seed[k]);
                /* (a scribbled valid_from may let an overwritten frame through: the reader has to
                 * trust the header; memory safety is all that holds then) */
                if (!scribbled && (overwritten || memcmp(out, want, len[k]) != 0)) abort();
            } else if ((rc != DF_ENOTFOUND && rc != DF_EFORMAT) || (!overwritten && !scribbled)) {
                abort(); /* an intact frame of an untouched ring must read back */
            }
        } else if (op == 2) { /* read whatever the input names */
            uint64_t p = next(&r, 4) | (uint64_t)next(&r, 4) << 32;
            uint32_t l = next(&r, 4);
            int rc = df_shm_ring_read(ring, CAP, p, l > CAP ? CAP : l, out, &e);
            if (rc != DF_OK && (rc >= 0 || e.msg[0] == '\0')) abort();
        } else if (op == 3) { /* scribble on the shared header */
            unsigned off = 16 + next(&r, 1) % 32;
            ring[off] = (uint8_t)next(&r, 1);
            scribbled = 1;
        }
    }
    free(ring);
    return 0;
}

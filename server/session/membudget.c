/* membudget.c — memory accounting by kind against the configured caps (see membudget.h). */
#include "server/session/membudget.h"

#include <string.h>
#include <unistd.h>

#define MIB(x) ((unsigned long long)((x) >> 20))

static const char *const k_kind_name[DF_MEM_KINDS] = {"uploads in flight", "sessions",
                                                      "shared-memory rings", "undo history",
                                                      "resync rings", "stream encodings"};
/* Config key of each kind's own cap ("" when it has none) and how it is written. */
static const char *const k_kind_key[DF_MEM_KINDS] = {"uploads_max_mb", "", "shm_total_bytes", "",
                                                     "", ""};

void df_mem_set_limits(df_membudget *b, uint64_t max, uint64_t uploads_max, uint64_t shm_max)
{
    b->max = max;
    for (int k = 0; k < DF_MEM_KINDS; k++) b->kind_max[k] = UINT64_MAX;
    b->kind_max[DF_MEM_UPLOADS] = uploads_max;
    b->kind_max[DF_MEM_SHM] = shm_max;
}

void df_mem_init(df_membudget *b, uint64_t max, uint64_t uploads_max, uint64_t shm_max)
{
    memset(b, 0, sizeof *b);
    df_mem_set_limits(b, max, uploads_max, shm_max);
}

uint64_t df_mem_used(const df_membudget *b)
{
    uint64_t t = 0;
    for (int k = 0; k < DF_MEM_KINDS; k++) t += b->used[k];
    return t;
}

uint64_t df_mem_room(const df_membudget *b, df_mem_kind kind)
{
    if ((unsigned)kind >= DF_MEM_KINDS) return 0;
    uint64_t used = df_mem_used(b);
    uint64_t room = used < b->max ? b->max - used : 0;
    uint64_t kmax = b->kind_max[kind], kused = b->used[kind];
    uint64_t kroom = kused < kmax ? kmax - kused : 0;
    return kroom < room ? kroom : room;
}

int df_mem_charge(df_membudget *b, df_mem_kind kind, uint64_t bytes, const char *what,
                  df_error *err)
{
    if (!b || (unsigned)kind >= DF_MEM_KINDS)
        return df_error_set(err, DF_EINVAL, "memory budget: bad kind");
    if (!what) what = "request";
    uint64_t kmax = b->kind_max[kind], kused = b->used[kind];
    if (kused > kmax || bytes > kmax - kused) {
        b->refused++;
        return df_error_set(err, DF_ELIMIT,
                            "%s: %llu more bytes would exceed the %s limit %s (%llu MiB; %llu "
                            "bytes in use)",
                            what, (unsigned long long)bytes, k_kind_name[kind], k_kind_key[kind],
                            MIB(kmax), (unsigned long long)kused);
    }
    uint64_t used = df_mem_used(b);
    if (used > b->max || bytes > b->max - used) {
        b->refused++;
        return df_error_set(err, DF_ELIMIT,
                            "%s: %llu more bytes for %s would exceed the daemon's memory budget "
                            "memory_max_mb (%llu MiB; %llu bytes in use)",
                            what, (unsigned long long)bytes, k_kind_name[kind], MIB(b->max),
                            (unsigned long long)used);
    }
    b->used[kind] += bytes;
    return DF_OK;
}

void df_mem_release(df_membudget *b, df_mem_kind kind, uint64_t bytes)
{
    if (!b || (unsigned)kind >= DF_MEM_KINDS) return;
    b->used[kind] -= bytes < b->used[kind] ? bytes : b->used[kind];
}

void df_mem_adjust(df_membudget *b, df_mem_kind kind, uint64_t old_bytes, uint64_t new_bytes)
{
    if (!b || (unsigned)kind >= DF_MEM_KINDS) return;
    df_mem_release(b, kind, old_bytes);
    b->used[kind] += new_bytes;
}

uint64_t df_mem_physical_bytes(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || page <= 0) return 0;
    return (uint64_t)pages * (uint64_t)page;
}

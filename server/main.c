/* main.c — deformd entry point.
 *
 * README-internals: threading model
 * ---------------------------------
 * One libuv loop thread owns every connection, session, subscriber list, job FIFO, the undo
 * history bookkeeping and all stats; all socket I/O happens there (non-blocking, partial reads
 * reassembled into frames, writes queued per client with a byte bound). Compute (mesh parsing,
 * Kelvinlet fields, ADMM factorizations and iterations, stream encoding) runs off the loop on
 * the server's compute pool (pool.h: `threads` workers, eventfd completions, LIFO wake-ups,
 * optional bounded spin `spin_us`; mesh loads in its long lane like handle moves). The one
 * exception: a brush update whose stroke's previous update measured <= `inline_us` (default
 * 50 us, cheaper than the two hand-offs; job.h) runs on the loop thread. Replies go out
 * with one uv_try_write when the socket takes them (uv_write for the rest), TCP with NODELAY.
 * Each session has a FIFO of jobs and only its head job runs; its work reads the session
 * (which the FIFO guarantees no other job changes meanwhile) and fills a change record, and
 * df_session_commit applies that record on the loop thread in one fixed order (commit.h:
 * state, history, caches, hook, broadcast, answer). Different sessions run in parallel.
 * Progress iterates of a running handle move are change records too, posted through the pool's
 * one completion channel (df_pool_post) and committed as they arrive, always before the move's
 * own completion, so versions stay in order. A newer move
 * supersedes a running one through an atomic flag read in the ADMM progress callback. Encoded
 * frames are built once and shared by reference count across subscribers' queues.
 * Shutdown (SIGINT/SIGTERM): stop listening and reading, cancel running moves, wait for running
 * jobs, answer queued ones, close connections, free sessions, unlink the socket.
 */
#include <malloc.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <uv.h>

#include "server/config.h"
#include "server/hid/hid_manager.h"
#include "server/log.h"
#include "server/net/sd.h"
#include "server/server.h"

#define DF_MAIN_MMAP_THRESHOLD (32 << 20) /* glibc's maximum */
#define DF_MAIN_TRIM_THRESHOLD (256 << 20)

/* Forks into the background; the parent exits 0 once the child reports readiness on a pipe
 * (or 1 when it fails). Returns the write end of the pipe in the child. */
static int daemonize(void)
{
    int fds[2];
    if (pipe(fds) != 0) return -1;
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid > 0) {
        close(fds[1]);
        char c = 0;
        ssize_t n = read(fds[0], &c, 1);
        _exit(n == 1 && c == 'R' ? 0 : 1);
    }
    close(fds[0]);
    setsid();
    if (chdir("/") != 0) { /* keep going: paths are absolute or already resolved */
    }
    return fds[1];
}

int main(int argc, char **argv)
{
    df_server_config cfg;
    df_cli_action action;
    df_error err;
    if (df_config_from_args(&cfg, argc, argv, getenv("XDG_RUNTIME_DIR"), &action, &err) != DF_OK) {
        fprintf(stderr, "deformd: %s\n", err.msg);
        return 2;
    }
    if (action == DF_CLI_HELP) {
        fputs(df_config_usage(), stdout);
        return 0;
    }
    df_log_set_level(cfg.log_level);
    signal(SIGPIPE, SIG_IGN); /* a peer that hung up is an EPIPE write error, not a crash */
    /* Frames and per-session buffers are large (12 MB for a dense 1M-vertex version) and
     * short-lived: keep them in the heap instead of mmap/munmap (and page faults) per frame. */
    mallopt(M_MMAP_THRESHOLD, DF_MAIN_MMAP_THRESHOLD);
    mallopt(M_TRIM_THRESHOLD, DF_MAIN_TRIM_THRESHOLD);
    char threads[16];
    snprintf(threads, sizeof threads, "%d", cfg.threads);
    setenv("UV_THREADPOOL_SIZE", threads, 0);
    int ready_fd = -1;
    if (!cfg.foreground && getenv("NOTIFY_SOCKET") == NULL) {
        ready_fd = daemonize();
        if (ready_fd < 0) {
            fprintf(stderr, "deformd: cannot daemonize\n");
            return 1;
        }
    }
    uv_loop_t *loop = uv_default_loop();
    static df_server srv;
    if (df_server_start(&srv, loop, &cfg, &err) != DF_OK) {
        fprintf(stderr, "deformd: %s\n", err.msg);
        uv_run(loop, UV_RUN_NOWAIT);
        uv_loop_close(loop);
        return 1;
    }
    if (df_hid_manager_start(&srv, &err) != DF_OK) { /* HID devices (hid_manager.h) */
        fprintf(stderr, "deformd: %s\n", err.msg);
        df_server_stop(&srv);
        uv_run(loop, UV_RUN_DEFAULT);
        df_server_free(&srv);
        uv_loop_close(loop);
        return 1;
    }
    char where[512];
    df_server_describe(&srv, where, sizeof where);
    fprintf(stderr, "deformd: listening on %s\n", where);
    fflush(stderr);
    df_sd_notify("READY=1");
    if (ready_fd >= 0) {
        if (write(ready_fd, "R", 1) != 1) { /* the parent exits either way */
        }
        close(ready_fd);
    }
    uv_run(loop, UV_RUN_DEFAULT);
    df_server_free(&srv);
    int rc = uv_loop_close(loop);
    if (rc != 0) df_log(DF_LOG_WARN, "loop closed with handles still open: %s", uv_strerror(rc));
    df_log(DF_LOG_INFO, "stopped");
    return 0;
}

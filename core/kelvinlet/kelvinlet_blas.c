/* kelvinlet_blas.c — OpenBLAS on one thread around the pin system's dense factorization
 * (kelvinlet_lu.c shares the work over the kernel's own OpenMP team instead).
 *
 * The K_pp assembly runs on an OpenMP team; OpenBLAS (the pthreads build Debian ships) keeps
 * its own worker threads. Right after a parallel region the OpenMP workers still spin (libgomp's
 * default wait policy) while OpenBLAS's threads start dgetrf, and on a 2-core machine the two
 * pools fought: pin set-up on 2 threads took 3x its 1-thread time (OMP_WAIT_POLICY=passive hid
 * it).
 * The OpenBLAS thread count is process-wide: a depth counter under a mutex lowers it once for
 * overlapping callers and restores the saved value when the last one leaves (other BLAS users
 * of the process run single-threaded for that window, never with a wrong result). */
#include <cblas.h>
#include <pthread.h>

#include "core/kelvinlet/kelvinlet_internal.h"

static pthread_mutex_t blas_mu = PTHREAD_MUTEX_INITIALIZER;
static int blas_depth, blas_saved;

void dfk_blas_serial_begin(void)
{
    pthread_mutex_lock(&blas_mu);
    if (blas_depth++ == 0) {
        blas_saved = openblas_get_num_threads();
        if (blas_saved > 1)
            openblas_set_num_threads(1);
    }
    pthread_mutex_unlock(&blas_mu);
}

void dfk_blas_serial_end(void)
{
    pthread_mutex_lock(&blas_mu);
    if (blas_depth > 0 && --blas_depth == 0 && blas_saved > 1)
        openblas_set_num_threads(blas_saved);
    pthread_mutex_unlock(&blas_mu);
}

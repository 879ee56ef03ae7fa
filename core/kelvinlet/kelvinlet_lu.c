/* kelvinlet_lu.c — the pin system's LU (K_pp = P L U, LAPACK dgetrf's result and layout) on
 * the kernel's own OpenMP team.
 *
 * Right-looking blocked LU with partial pivoting: per block column, the panel is factorized by
 * dgetrf, then every column to its right is swapped (dlaswp), solved (dtrsm) and updated
 * (dgemm) in chunks of DFK_LU_CHUNK columns that the team shares. OpenBLAS itself runs on one
 * thread meanwhile (kelvinlet_blas.c): before, its own pool started right after the assembly's
 * OpenMP team and the two fought for the cores (pin set-up on 2 threads took ~3x its 1-thread
 * time). The chunks are fixed, whatever the thread count, and each chunk's BLAS calls are the
 * same, so the factors are the same bits on any number of threads. */
#include <cblas.h>
#include <lapacke.h>

#include "core/kelvinlet/kelvinlet_internal.h"

_Static_assert(sizeof(lapack_int) == sizeof(int), "LAPACK with 32-bit integers (not ILP64)");

#define DFK_LU_BLOCK 64    /* panel width */
#define DFK_LU_CHUNK 128   /* columns per task of the trailing update */
#define DFK_LU_PAR_MIN 1024 /* below this order the LU (< 0.7 GFlop, a few ms) stays on the
                             * calling thread: one team wake-up per block column costs more */

int dfk_lu_factor(int m, double *a, int *ipiv, int nthreads)
{
    int info = 0;
    dfk_blas_serial_begin();
    for (int k = 0; k < m; k += DFK_LU_BLOCK) {
        int nb = m - k < DFK_LU_BLOCK ? m - k : DFK_LU_BLOCK;
        double *akk = a + (size_t)k * m + k;
        lapack_int pinfo = LAPACKE_dgetrf(LAPACK_COL_MAJOR, m - k, nb, akk, m, ipiv + k);
        if (pinfo > 0 && info == 0)
            info = (int)pinfo + k;
        for (int i = k; i < k + nb; i++)
            ipiv[i] += k;                               /* panel rows -> global rows */
        if (k > 0)                                      /* the columns to the left */
            LAPACKE_dlaswp(LAPACK_COL_MAJOR, k, a, m, k + 1, k + nb, ipiv, 1);
        int rest = m - k - nb;
        if (rest <= 0)
            continue;
        int nchunks = (rest + DFK_LU_CHUNK - 1) / DFK_LU_CHUNK;
        (void)nthreads; /* only the pragma reads it: unused without OpenMP */
#pragma omp parallel for schedule(dynamic, 1) \
    if (nthreads > 1 && m >= DFK_LU_PAR_MIN && nchunks > 1) num_threads(nthreads)
        for (int c = 0; c < nchunks; c++) {
            int c0 = k + nb + c * DFK_LU_CHUNK;
            int nc = m - c0 < DFK_LU_CHUNK ? m - c0 : DFK_LU_CHUNK;
            double *col = a + (size_t)c0 * m;
            LAPACKE_dlaswp(LAPACK_COL_MAJOR, nc, col, m, k + 1, k + nb, ipiv, 1);
            cblas_dtrsm(CblasColMajor, CblasLeft, CblasLower, CblasNoTrans, CblasUnit, nb, nc,
                        1.0, akk, m, col + k, m);
            cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, rest, nc, nb, -1.0,
                        akk + nb, m, col + k, m, 1.0, col + k + nb, m);
        }
    }
    dfk_blas_serial_end();
    return info;
}

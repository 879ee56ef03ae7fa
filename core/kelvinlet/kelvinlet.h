/* kelvinlet.h — regularized Kelvinlet sculpting brushes (de Goes & James 2017).
 *
 * Units: lengths are in the mesh's units; displacements in the same units; gradients are
 * dimensionless. The shear modulus drops out of every brush (forces are normalized by the
 * requested tip displacement or centre gradient), so it is not exposed: internally a = 1,
 * b = a / (4 (1 - nu)) (b = 0 for nu = +-INFINITY, the classic radial-falloff brush).
 *
 * Gradients are 3x3 row-major: grad[3*i + j] = d u_i / d x_j.
 * Positions handed to the float path are interleaved xyz float32 (n*3 floats).
 *
 * Workflow: fill a df_kelvinlet_brush (start from df_kelvinlet_brush_defaults), call
 * df_kelvinlet_prepare once per brush event (validates, inverts the tip/gradient normalization,
 * mirrors), then df_kelvinlet_apply (in place) or df_kelvinlet_displacements on the points.
 * For pinned points, create a df_kelvinlet_constraints solver once (it caches the LU of K_pp)
 * and call df_kelvinlet_constraints_solve per brush event instead of df_kelvinlet_prepare. */
#ifndef DF_KELVINLET_H
#define DF_KELVINLET_H

#include <stddef.h>

#include "core/common/df_error.h"

#define DF_KELVINLET_MAX_ORDER 8          /* highest n-scale falloff order */
#define DF_KELVINLET_DEFAULT_RATIO 1.1    /* eps_{i+1} = ratio * eps_i (paper default) */
#define DF_KELVINLET_MAX_STEPS 1024       /* integrator substeps per apply call */
#define DF_KELVINLET_MAX_PINS 2048        /* pinned points of one constraint solver */
#define DF_KELVINLET_NU_MIN (-1.0)        /* finite nu must lie in [NU_MIN, NU_MAX] ...   */
#define DF_KELVINLET_NU_MAX 0.5           /* ... or be +-INFINITY                          */
#define DF_KELVINLET_MIN_RADIUS 1e-6      /* every radius eps_i must lie in [MIN, MAX] so    */
#define DF_KELVINLET_MAX_RADIUS 1e6       /* that the float32 kernels cannot over/underflow */
#define DF_KELVINLET_MAX_VALUE 1e9        /* |coordinate|, |tip|, |omega|, |s|, |grad| bound */

/* Arithmetic versions of the float32 path (df_kelvinlet_brush.arith). A version fixes the bits
 * every brush produces; a new one is added (never an old one changed) when a faster or more
 * accurate evaluation changes bits, and the old ones stay evaluable so that journaled strokes
 * recorded by older builds replay bit for bit (server/session/stroke_recipe.h). */
#define DF_KELVINLET_ARITH_1 1            /* 2D grab of orders 1-3 summed in double          */
#define DF_KELVINLET_ARITH_2 2            /* 2D grab of orders 1-3 in float32 (kelvinlet_simd2d.h);
                                             every other load as in version 1              */
#define DF_KELVINLET_ARITH_CURRENT DF_KELVINLET_ARITH_2

typedef enum df_kelvinlet_type {
    DF_KELVINLET_GRAB = 0,   /* translation: `tip` is the wanted displacement of the centre */
    DF_KELVINLET_TWIST = 1,  /* rotation: grad u(centre) = [omega]x (2D: uses omega[2])      */
    DF_KELVINLET_SCALE = 2,  /* grad u(centre) = s I (singular at nu = 0.5 -> DF_ESINGULAR)  */
    DF_KELVINLET_PINCH = 3,  /* grad u(centre) = `grad`, symmetric and traceless             */
    DF_KELVINLET_AFFINE = 4  /* grad u(centre) = `grad`, any matrix (2D: upper-left 2x2)     */
} df_kelvinlet_type;

typedef enum df_kelvinlet_integrator {
    DF_KELVINLET_EULER = 0,  /* x += h u(x) per substep, u evaluated at the current position */
    DF_KELVINLET_RK4 = 1     /* classic Runge-Kutta 4 along the field's streamlines          */
} df_kelvinlet_integrator;

/* A brush event as the user describes it. All doubles must be finite except nu. */
typedef struct df_kelvinlet_brush {
    df_kelvinlet_type type;
    int dim;                 /* 3, or 2 for meshes in the z = const plane (z is left untouched) */
    int order;               /* falloff order n in [1, DF_KELVINLET_MAX_ORDER]: 1 single-scale,
                                2 bi-scale, 3 tri-scale (paper weights), n: far-field terms
                                1..n-1 cancelled (Vandermonde weights in eps_i^2)              */
    double ratio;            /* eps_{i+1} / eps_i, > 1 (default 1.1)                          */
    double radius;           /* eps_1 > 0, length units                                       */
    double nu;               /* Poisson ratio: [-1, 0.5] or +-INFINITY                        */
    double centre[3];        /* brush centre x0 (2D: z ignored)                               */
    double tip[3];           /* GRAB: wanted displacement of the centre (2D: tip[2] ignored)  */
    double omega[3];         /* TWIST: rotation vector                                        */
    double s;                /* SCALE: wanted divergence / dim, grad u(x0) = s I              */
    double grad[9];          /* PINCH / AFFINE: wanted grad u(x0), row-major                  */
    int mirror;              /* 1: symmetrize across the plane (mirror_point, mirror_normal) */
    double mirror_point[3];  /* a point of the mirror plane                                   */
    double mirror_normal[3]; /* its normal (any non-zero length; normalized internally)       */
    df_kelvinlet_integrator integrator;
    int steps;               /* substeps N in [1, DF_KELVINLET_MAX_STEPS] over unit time      */
    int moving;              /* 1: moving brush (section 9): substep k uses the centre advected
                                by k/N of the stroke and the force of the last shift (tip/N or
                                gradient/N), i.e. N small clicks; 0: stationary brush          */
    int surface;             /* 1: surface-aware, the field is attenuated by the distance along
                                the mesh from the centre (kelvinlet_surface.h). The field
                                functions of this header ignore it: the caller holding the
                                mesh applies the weights; 0: plain field                      */
    int arith;               /* float32 arithmetic version: 0 (the defaults) = the current one,
                                DF_KELVINLET_ARITH_1..CURRENT = that version (a replay of a
                                stroke recorded by an older build); the double reference
                                functions ignore it                                           */
} df_kelvinlet_brush;

/* The multi-scale kernel of one brush: radii eps[i] = radius * ratio^i and weights w[i]
 * (w[0] = 1, sum_i w_i eps_i^(2k) = 0 for k < order-1). a = 1, b = 1/(4(1-nu)) or 0. */
typedef struct df_kelvinlet_kernel {
    int dim, order;
    double radius, ratio, nu, a, b;
    double eps[DF_KELVINLET_MAX_ORDER];
    double w[DF_KELVINLET_MAX_ORDER];
} df_kelvinlet_kernel;

/* One load of a field: a force vector f (grab) or a force matrix F (affine, row-major). */
typedef struct df_kelvinlet_source {
    double centre[3];
    int affine;              /* 0: u = sum_i w_i K_eps_i(x - c) f; 1: u = sum_i w_i A_eps_i(x - c) F */
    int kernel;              /* index into df_kelvinlet_prepared.kernel[] */
    double f[3];
    double F[9];
} df_kelvinlet_source;

/* A prepared (validated, normalized) field ready to evaluate. Plain data: may be copied while
 * `ext` is NULL (always so for df_kelvinlet_prepare results); constrained fields own `ext`
 * and must be released with df_kelvinlet_prepared_free. */
typedef struct df_kelvinlet_prepared {
    df_kelvinlet_brush brush;        /* the validated description (moving brushes re-prepare it
                                        per substep)                                             */
    df_kelvinlet_kernel kernel[2];   /* [0] live brush, [1] pinned loads of a constrained field */
    size_t nsrc;                     /* number of loads                                          */
    df_kelvinlet_source src[2];      /* loads when ext == NULL (brush and its mirror image)      */
    df_kelvinlet_source *ext;        /* heap loads of a constrained field (nsrc of them) or NULL */
    int threads;                     /* OpenMP threads of apply/displacements: 0 (what prepare
                                        and constraints_solve set) = OpenMP's default
                                        (omp_get_max_threads), n > 0 = at most n, 1 = serial on
                                        the caller's thread. The caller sets it after preparing;
                                        the library never calls omp_set_num_threads. Results are
                                        bit-identical for every value.                           */
} df_kelvinlet_prepared;

/* Fills `b` with defaults: GRAB, dim 3, order 1, ratio 1.1, radius 1, nu 0.5, everything else 0,
 * no mirror, Euler with 1 step, stationary, not surface-aware, arith 0 (the current version). */
void df_kelvinlet_brush_defaults(df_kelvinlet_brush *b);

/* Multi-scale radii and weights. In: order in [1, MAX_ORDER], ratio > 1, radius > 0.
 * Out: eps[order], w[order] (w[0] = 1; orders 2 and 3 equal the paper's closed forms; general
 * n solves the Vandermonde system sum_i w_i eps_i^(2k) = 0, k = 0..n-2).
 * Errors: DF_EINVAL (order, ratio, radius out of range or not finite); outputs untouched. */
int df_kelvinlet_weights(int order, double ratio, double radius, double *eps, double *w,
                         df_error *err);

/* Validates `b` and produces the normalized field: grab f = c (sum_i w_i / eps_i)^-1 tip (3D),
 * affine F = L^-1(grad) / (sum_i w_i / eps_i^3); a mirror adds the image load (f1 = M f0,
 * F1 = M F0 M) and the normalization then includes the image's contribution at the centre so
 * that the tip displacement / centre gradient stays exact.
 * For affine brushes the image load is a plain copy (the paper's F1 = M F0 M with F0 from the
 * unmirrored normalization), so the centre gradient then also holds the image's (decayed)
 * contribution; a mirrored grab solves the 3x3 (2D: 2x2) tip constraint including the image.
 * Errors: DF_EINVAL (NaN/Inf, radius <= 0, ratio <= 1, order outside [1, 8], nu outside the
 * allowed set, dim not 2/3, zero mirror normal, steps outside [1, MAX_STEPS], bad type, pinch
 * gradient not symmetric traceless, radii or values outside the MIN/MAX bounds, arith outside
 * [0, DF_KELVINLET_ARITH_CURRENT]);
 * DF_ESINGULAR when the normalization map is singular (scale at nu = 0.5, affine gradient
 * with a trace at nu = 0.5, 2D single-scale radius where the tip map vanishes, mirrored grab
 * centred on the plane with a tip across it); `out` untouched. */
int df_kelvinlet_prepare(const df_kelvinlet_brush *b, df_kelvinlet_prepared *out, df_error *err);

/* Releases the heap loads of a constrained field (no-op for plain brushes; NULL is fine). */
void df_kelvinlet_prepared_free(df_kelvinlet_prepared *p);

/* Moving-brush stroke helper: advances the brush centre by its tip (GRAB) so that the next
 * event's `tip` can be the latest mouse shift. No-op for affine brushes. */
void df_kelvinlet_brush_advance(df_kelvinlet_brush *b);

/* Deforms n float32 xyz points in place along the field with the brush's integrator/steps
 * (2D brushes leave z untouched). OpenMP over blocks on p->threads, SIMD kernel dispatched at
 * run time (AVX2/FMA or SSE4.2), in the arithmetic version of p->brush.arith (every version:
 * within 1e-6 of max |u| of the double reference for a plain brush, the centre moved by `tip`
 * to a few float roundings). Errors: DF_EINVAL (NULL with n > 0, non-finite input coordinate or
 * |coordinate| > MAX_VALUE, invalid prepared field), DF_ENOMEM, DF_ESINGULAR (a moving brush
 * whose substep normalization becomes singular); points untouched on error. */
int df_kelvinlet_apply(const df_kelvinlet_prepared *p, float *xyz, size_t n, df_error *err);

/* Same integration, but writes the displacement (final - initial position) of each point to
 * out[n*3] and leaves xyz alone. With EULER and 1 step this is the field u(x). Same errors;
 * `out` untouched on error. */
int df_kelvinlet_displacements(const df_kelvinlet_prepared *p, const float *xyz, size_t n,
                               float *out, df_error *err);

/* Double-precision scalar reference: the field u(x) (no integration) at x[3] -> u[3].
 * Errors: DF_EINVAL (NULL, non-finite x). */
int df_kelvinlet_eval_ref(const df_kelvinlet_prepared *p, const double *x, double *u,
                          df_error *err);

/* Double-precision analytic gradient of the field at x[3] -> g[9] (row-major du_i/dx_j).
 * Errors: DF_EINVAL (NULL, non-finite x). */
int df_kelvinlet_gradient_ref(const df_kelvinlet_prepared *p, const double *x, double *g,
                              df_error *err);

/* Double-precision scalar, single-threaded reference of df_kelvinlet_apply on n xyz doubles
 * (the oracle of the tests and the benchmark's baseline). Same errors. */
int df_kelvinlet_apply_ref(const df_kelvinlet_prepared *p, double *xyz, size_t n, df_error *err);

/* ---- constrained deformations (section 7), 3D only ----------------------------------------
 *
 * Evaluation cost and accuracy: a constrained field is evaluated exactly, every pin load at
 * every point, by the same SIMD kernels as a brush (no far-field approximation), so its float
 * error is the brush path's: max |u - u_double| <= 2e-6 of max |u| at every point, pins
 * included (test_kelvinlet_pinned: random pin sets, pin radii, orders, pin kinds; measured
 * 4e-7 to 1.3e-6), the same bits on any thread count and in any block or SIMD lane.
 * Cost per point and pin on one core (issue 14 table): ~0.75 ns per displacement pin, ~1.3 ns
 * per gradient pin, so 160 displacement pins take ~120 CPU ns per point (~60 ms for 1M points
 * on 2 threads) where the unpinned brush takes ~3 ns.
 * Why no far-field approximation at the bound (1e-6 of max |u|): measured on the
 * bench's eyeball (160 pins on a sphere of radius 0.2, pin radius 0.05), a degree-4 tensor
 * interpolant of the pin field over a box of half-width a reaches 1e-6 only when the nearest
 * pin is >= 8a from the box centre (9e-7 at D/a = 8, 2e-5 to 5e-5 at D/a = 4). Covering the
 * 1M points of the unit cube around the pins then takes ~31,000 boxes (adaptive octree, exact
 * evaluation only within 0.0125 of a pin), whose 125 interpolation nodes each need the 160
 * exact loads: 6e8 load evaluations before the 375 multiply-adds per point, against 1.6e8 for
 * the direct sum. A fast multipole method would cut the node cost but stays within a few
 * times the direct sum for 160 loads; an approximation pays off for far more pins per point
 * or points far from every pin, not for the 5 ms per 1M points that issue 14 asked. */

enum {
    DF_KELVINLET_PIN_DISPLACEMENT = 1,  /* u(x_k) = 0: a grab load at each pin (3 DoF)       */
    DF_KELVINLET_PIN_GRADIENT = 2       /* grad u(x_k) = 0: an affine load at each pin (9 DoF;
                                           8 at nu = 0.5, where the trace load vanishes and the
                                           field is divergence-free anyway)                  */
};

/* The pinned set and the kernel of its loads. */
typedef struct df_kelvinlet_pins {
    size_t n;                /* number of pinned points, 1..DF_KELVINLET_MAX_PINS */
    const double *points;    /* n*3 xyz                                           */
    int flags;               /* DF_KELVINLET_PIN_* bit set, non-zero              */
    double radius, ratio, nu;/* kernel of the pinned loads (same rules as brushes) */
    int order;
    int threads;             /* OpenMP threads of the K_pp assembly and LU (create/update):
                                0 = OpenMP's default, n > 0 = at most n, 1 = serial;
                                fewer on an oversubscribed machine (OpenMP dynamic
                                adjustment; libgomp: CPUs minus the 15-minute load
                                average); not part of the pinned set's identity */
} df_kelvinlet_pins;

/* Opaque solver; not thread-safe (one per session/stroke owner). Every other function of this
 * header is reentrant and may run concurrently on different data. */
typedef struct df_kelvinlet_constraints df_kelvinlet_constraints;

/* Builds K_pp (3n, 9n or 12n square; 8n / 11n at nu = 0.5) and caches its LU (blocked, in
 * dgetrf's layout; condition checked with dgecon), both on pins->threads OpenMP threads: the
 * LU's trailing updates are shared by the same team, OpenBLAS runs on one thread meanwhile
 * (its process-wide thread count is lowered to 1 for the call and restored), so its pool and
 * the OpenMP team no longer compete, and the factors are the same bits on any thread count.
 * The team is trimmed on an oversubscribed machine (the calling thread's OpenMP dynamic
 * adjustment is enabled for the call and restored): a team member waiting for a core made
 * the 2-thread set-up slower than the 1-thread one.
 * Errors: DF_EINVAL (bad numbers, n = 0, flags 0), DF_ELIMIT (n > MAX_PINS), DF_ENOMEM,
 * DF_ESINGULAR (duplicated / coincident pins or numerically singular K_pp); *out untouched. */
int df_kelvinlet_constraints_create(const df_kelvinlet_pins *pins, df_kelvinlet_constraints **out,
                                    df_error *err);

/* Replaces the pinned set / kernel. Refactorizes only when points, flags, radius, ratio, nu or
 * order differ from the cached ones. Errors as create; on error the previous state is kept. */
int df_kelvinlet_constraints_update(df_kelvinlet_constraints *cs, const df_kelvinlet_pins *pins,
                                    df_error *err);

/* Solves for the constrained field of a live 3D brush (not mirrored, not moving): pins keep
 * zero displacement / gradient and the live brush keeps its tip displacement / centre
 * gradient. Uses the cached LU and a Schur complement (3x3 for grab, 9x9 for affine); the
 * coupling K_p,live^-1 solve is cached per live centre/type/kernel, so a new tip costs one
 * small solve. `out` receives heap loads: release with df_kelvinlet_prepared_free.
 * Errors: DF_EINVAL (bad brush), DF_EUNSUPPORTED (2D, mirror or moving), DF_ESINGULAR
 * (live centre on a pin), DF_ENOMEM; *out untouched. */
int df_kelvinlet_constraints_solve(df_kelvinlet_constraints *cs, const df_kelvinlet_brush *live,
                                   df_kelvinlet_prepared *out, df_error *err);

/* Number of LU factorizations of K_pp done so far (for stats and cache tests). */
unsigned long df_kelvinlet_constraints_factorizations(const df_kelvinlet_constraints *cs);

/* Frees the solver (NULL is fine). */
void df_kelvinlet_constraints_free(df_kelvinlet_constraints *cs);

#endif

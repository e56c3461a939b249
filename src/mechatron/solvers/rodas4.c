/* Rodas4: a variable-step, L-stable Rosenbrock method of order 4 with an embedded order-3
 * error estimate (Hairer & Wanner, Solving ODEs II, section IV.7), for x' = f(t, x).
 *
 * This file is appended to the C that CasADi generates for one model, with m the modes,
 * event counters and event times of its relations (constant between events):
 *   mt_f(t, x, m, p)   -> f             the state derivative
 *   mt_jac(t, x, m, p) -> J, f_t        df/dx (dense, column-major) and df/dt
 *   mt_out(t, x, m, p) -> y             every logged variable
 *   mt_zero(t, x, m, p) -> g            event indicators (mode * distance), if MT_NR > 0
 *   mt_trans(k, t, x, m, p) -> X        the state after an event of relation k
 * and to the sizes MT_NX, MT_NR, MT_NY and the chattering mark MT_CHATTER_FLAG (see
 * mechatron.compiler.events).  One call integrates from tout[0] to tout[nout - 1] and
 * writes y at every output time (Rodas4's dense output of x between steps, order 3, exact
 * at the steps), so the whole run is a single native call.
 *
 * One step of size h from (t0, x0), with W = I / (h gamma) - J(t0, x0):
 *   W k_i = f(t0 + alpha_i h, x0 + sum_j a_ij k_j) + sum_j (c_ij / h) k_j + h g_i f_t
 *   x1 = x0 + sum_j m_j k_j,   local error estimate = k_6 (the method is stiffly accurate)
 * The step size follows the usual controller h_new = h * clamp(0.9 err^(-1/4), 0.2, 6)
 * with err the RMS norm of k_6 weighted by atol + rtol max(|x0|, |x1|).
 */

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MT_STAGES 6

static const double mt_gamma = 0.25;
static const double mt_alpha[MT_STAGES] = {0.0, 0.386, 0.21, 0.63, 1.0, 1.0};
static const double mt_g[MT_STAGES] = {0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0};
/* strictly lower triangular A and C, row by row: (2,1), (3,1), (3,2), (4,1), ... */
static const double mt_a[15] = {
    1.544,
    0.9466785280815826, 0.2557011698983284,
    3.314825187068521, 2.896124015972201, 0.9986419139977817,
    1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950,
    1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0};
static const double mt_c[15] = {
    -5.6688,
    -2.430093356833875, -0.2063599157091915,
    -0.1073529058151375, -9.594562251023355, -20.47028614809616,
    7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160,
    8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
    -6.058818238834054};
static const double mt_m[MT_STAGES] = {
    1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 1.0};
/* the dense output's two stage combinations (Hairer & Wanner's RODAS code) */
static const double mt_d2[MT_STAGES - 1] = {
    10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823,
    1.025137723295662};
static const double mt_d3[MT_STAGES - 1] = {
    -0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386,
    -6.594389125716872};

enum {
    MT_OK = 0, MT_MAX_STEPS = -1, MT_STEP_TOO_SMALL = -2, MT_NOT_FINITE = -3,
    MT_SINGULAR = -4, MT_NO_MEMORY = -5, MT_ZENO = -6,
    MT_CHATTERING = -7
};

/* One evaluation context per generated function: its work arrays (argument and result
 * pointer arrays are as long as the function asks: a transition that calls the event
 * iteration needs more than its own five arguments). */
typedef struct {
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
} mt_ctx;

static int mt_ctx_init(mt_ctx *c, int (*work)(casadi_int *, casadi_int *, casadi_int *,
                                             casadi_int *)) {
    casadi_int n_arg, n_res, n_iw, n_w;
    work(&n_arg, &n_res, &n_iw, &n_w);
    if (n_arg < 8) n_arg = 8;
    if (n_res < 8) n_res = 8;
    c->arg = (const casadi_real **)calloc((size_t)n_arg, sizeof(casadi_real *));
    c->res = (casadi_real **)calloc((size_t)n_res, sizeof(casadi_real *));
    c->iw = (casadi_int *)malloc(sizeof(casadi_int) * (size_t)(n_iw > 0 ? n_iw : 1));
    c->w = (casadi_real *)malloc(sizeof(casadi_real) * (size_t)(n_w > 0 ? n_w : 1));
    return (c->arg && c->res && c->iw && c->w) ? MT_OK : MT_NO_MEMORY;
}

static void mt_ctx_free(mt_ctx *c) {
    free((void *)c->arg);
    free(c->res);
    free(c->iw);
    free(c->w);
    c->arg = 0;
    c->res = 0;
    c->iw = 0;
    c->w = 0;
}

static int mt_all_finite(const double *v, int n) {
    int i;
    for (i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* LU factorization with partial pivoting of the n x n column-major matrix a, in place. */
static int mt_lu(double *a, int *piv, int n) {
    int i, j, k, q;
    for (k = 0; k < n; ++k) {
        double big = fabs(a[k + k * n]);
        q = k;
        for (i = k + 1; i < n; ++i)
            if (fabs(a[i + k * n]) > big) {
                big = fabs(a[i + k * n]);
                q = i;
            }
        piv[k] = q;
        if (big == 0.0 || !isfinite(big)) return MT_SINGULAR;
        if (q != k)
            for (j = 0; j < n; ++j) {
                double tmp = a[k + j * n];
                a[k + j * n] = a[q + j * n];
                a[q + j * n] = tmp;
            }
        for (i = k + 1; i < n; ++i) a[i + k * n] /= a[k + k * n];
        for (j = k + 1; j < n; ++j) {
            double akj = a[k + j * n];
            if (akj != 0.0)
                for (i = k + 1; i < n; ++i) a[i + j * n] -= a[i + k * n] * akj;
        }
    }
    return MT_OK;
}

static void mt_lu_solve(const double *a, const int *piv, double *b, int n) {
    int i, j;
    for (i = 0; i < n; ++i) {
        double tmp = b[piv[i]];
        b[piv[i]] = b[i];
        b[i] = tmp;
    }
    for (j = 0; j < n; ++j)
        for (i = j + 1; i < n; ++i) b[i] -= a[i + j * n] * b[j];
    for (j = n - 1; j >= 0; --j) {
        b[j] /= a[j + j * n];
        for (i = 0; i < j; ++i) b[i] -= a[i + j * n] * b[j];
    }
}

/* Weighted RMS norm of v with scale atol + rtol max(|x0|, |x1|). */
static double mt_norm(const double *v, const double *x0, const double *x1, int n,
                      double rtol, double atol) {
    double s = 0.0;
    int i;
    if (n == 0) return 0.0;
    for (i = 0; i < n; ++i) {
        double ref = fabs(x0[i]);
        double sc, r;
        if (x1 && fabs(x1[i]) > ref) ref = fabs(x1[i]);
        sc = atol + rtol * ref;
        r = v[i] / sc;
        s += r * r;
    }
    return sqrt(s / n);
}

/* The integration state besides x: the relations' modes, event counters and event
 * times (MT_NM = 3 MT_NR values), constant between events. */
#define MT_NM (3 * MT_NR)

typedef struct {
    const double *p;
    double *m;                  /* modes, counters, event times */
    mt_ctx cf, cj, co, cz, ct;
    long nfev;
} mt_model;

/* A generated function of (t, x, m, p) -> out (and out2 when it has two results). */
typedef int (*mt_fn)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);

static void mt_call(mt_ctx *c, mt_fn fn, const mt_model *md, double t, const double *x,
                    double *out, double *out2) {
    c->arg[0] = &t;
    c->arg[1] = x;
    c->arg[2] = md->m;
    c->arg[3] = md->p;
    c->res[0] = out;
    c->res[1] = out2;
    fn(c->arg, c->res, c->iw, c->w, 0);
}

static void mt_eval_f(mt_model *md, double t, const double *x, double *out) {
    mt_call(&md->cf, mt_f, md, t, x, out, 0);
    ++md->nfev;
}

static void mt_eval_out(mt_model *md, double t, const double *x, double *out) {
    mt_call(&md->co, mt_out, md, t, x, out, 0);
}

#if MT_NR > 0
static void mt_eval_zero(mt_model *md, double t, const double *x, double *g) {
    mt_call(&md->cz, mt_zero, md, t, x, g, 0);
}

/* The transition of relation k at (t, x): x and the modes/counters/times in place. */
static void mt_eval_transition(mt_model *md, int k, double t, double *x, double *xpost) {
    double index = (double)k;
    int i;
    md->ct.arg[0] = &index;
    md->ct.arg[1] = &t;
    md->ct.arg[2] = x;
    md->ct.arg[3] = md->m;
    md->ct.arg[4] = md->p;
    md->ct.res[0] = xpost;
    mt_trans(md->ct.arg, md->ct.res, md->ct.iw, md->ct.w, 0);
    for (i = 0; i < MT_NX; ++i) x[i] = xpost[i];
    for (i = 0; i < MT_NM; ++i) md->m[i] = xpost[MT_NX + i];
}
#endif

/* The step's dense output at t0 + th h, Rodas4's own (order 3, from its stages):
 *   x(th) = x0 (1 - th) + th (x1 + (1 - th) (d2 + th d3)),  d2, d3 = sums of D2, D3 times k
 * Built from the stages, it stays bounded inside a step over a fast transient, where a
 * cubic Hermite through f at the ends overshoots by h f0 (f of a stiff mode is huge at the
 * step's start): the mmf of an eddy-current path (G dphi/dt) read 600 times its value. Written as
 * x0 + th (...) so that a state that does not move (a discrete one: x1 = x0, its stages
 * zero) is reproduced exactly. */
static void mt_dense(const double *x0, const double *x1, const double *d2, const double *d3,
                     double th, double *out, int n) {
    double s1 = 1.0 - th;
    int i;
    for (i = 0; i < n; ++i) out[i] = x0[i] + th * ((x1[i] - x0[i]) + s1 * (d2[i] + th * d3[i]));
}

/* Integrate; see the top of the file.  x0 holds the whole integration state
 * X = [x; modes; counters; event times] (MT_NX + MT_NM values), and so does xf at the end.
 * Relations: after every accepted step the indicators g = mode * distance are checked; one
 * that went from positive to <= 0 is an event, located on the dense output by a
 * safeguarded secant (Illinois) iteration to event_tol, after which the compiled transition
 * updates X and the integration restarts there.  info (10 entries) receives the accepted
 * steps, rejected steps, f evaluations, Jacobian evaluations, LU factorizations, the time
 * reached, the last step size, the output points written, the events and the
 * indicator evaluations.  With fixed_h > 0 every step has that size and is accepted (for
 * convergence-order tests).  Returns MT_OK or a negative code. */
int mt_rodas4(const double *tout, long nout, const double *x0, const double *p,
              double rtol, double atol, double hmax, double event_tol, long max_steps,
              double fixed_h, double *y, double *xf, double *info) {
    const int n = MT_NX;
    const double eps = 2.220446049250313e-16;
    double t, h, tend, fac, err, h_last = 0.0;
    long k_out = 0, steps = 0, rejected = 0, njev = 0, nlu = 0, events = 0, nzero = 0;
    long same_time = 0, it;
    int i, j, s, status = MT_OK, reject_run = 0;
    double *mem, *x, *x1, *f0, *f1, *fs, *ys, *jac, *ft, *w, *ks, *d2, *d3, *g0, *g1, *ga, *gb,
        *gc;
    double *xpost;
    int *piv;
    mt_model md;
    size_t nn = (size_t)(n > 0 ? n : 1), nr = (size_t)(MT_NR > 0 ? MT_NR : 1);

    memset(&md, 0, sizeof md);
    md.p = p;
#if MT_NR == 0
    (void)event_tol;          /* no relations: nothing to locate */
    (void)same_time;
#endif
    if (nout < 1) return MT_OK;
    if (mt_ctx_init(&md.cf, mt_f_work) || mt_ctx_init(&md.cj, mt_jac_work) ||
        mt_ctx_init(&md.co, mt_out_work)
#if MT_NR > 0
        || mt_ctx_init(&md.cz, mt_zero_work) || mt_ctx_init(&md.ct, mt_trans_work)
#endif
    ) {
        status = MT_NO_MEMORY;
        goto release;
    }
    mem = (double *)malloc(sizeof(double) * (8 * nn + 2 * nn * nn + (MT_STAGES + 2) * nn +
                                             11 * nr + nn + 1));
    piv = (int *)malloc(sizeof(int) * nn);
    if (!mem || !piv) {
        free(mem);
        free(piv);
        status = MT_NO_MEMORY;
        goto release;
    }
    x = mem;
    x1 = x + nn;
    f0 = x1 + nn;
    f1 = f0 + nn;
    fs = f1 + nn;
    ys = fs + nn;
    ft = ys + nn;
    jac = ft + 2 * nn;
    w = jac + nn * nn;
    ks = w + nn * nn;
    d2 = ks + MT_STAGES * nn;
    d3 = d2 + nn;
    g0 = d3 + nn;
    g1 = g0 + nr;
    ga = g1 + nr;
    gb = ga + nr;
    gc = gb + nr;
    md.m = gc + nr;                     /* 3 nr (+1) values */
    xpost = md.m + 3 * nr + 1;          /* nn + 3 nr values */
    (void)xpost;

    t = tout[0];
    tend = tout[nout - 1];
    for (i = 0; i < n; ++i) x[i] = x0[i];
    for (i = 0; i < MT_NM; ++i) md.m[i] = x0[n + i];

    mt_eval_out(&md, t, x, y);
    k_out = 1;
    mt_eval_f(&md, t, x, f0);
    if (!mt_all_finite(f0, n)) {
        status = MT_NOT_FINITE;
        goto done;
    }
#if MT_NR > 0
    mt_eval_zero(&md, t, x, g0);
    ++nzero;
#endif

    /* initial step: Hairer & Wanner's estimate from |x| and |f| and one Euler step */
    if (fixed_h > 0.0) {
        h = fixed_h;
    } else {
        double d0 = mt_norm(x, x, 0, n, rtol, atol), d1 = mt_norm(f0, x, 0, n, rtol, atol);
        double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1, d2, h1;
        if (h0 > tend - t) h0 = tend - t;
        for (i = 0; i < n; ++i) x1[i] = x[i] + h0 * f0[i];
        mt_eval_f(&md, t + h0, x1, f1);
        for (i = 0; i < n; ++i) fs[i] = (f1[i] - f0[i]) / h0;
        d2 = mt_norm(fs, x, 0, n, rtol, atol);
        d2 = d1 > d2 ? d1 : d2;
        h1 = d2 <= 1e-15 ? (h0 * 1e-3 > 1e-6 ? h0 * 1e-3 : 1e-6) : pow(0.01 / d2, 0.2);
        h = 100.0 * h0 < h1 ? 100.0 * h0 : h1;
    }

    while (t < tend) {
        int last = 0;
        double hg, t1;
        if (steps + rejected >= max_steps) {
            status = MT_MAX_STEPS;
            goto done;
        }
        if (hmax > 0.0 && h > hmax) h = hmax;
        if (t + 1.0001 * h >= tend) {   /* no sliver of a step left at the end */
            h = tend - t;
            last = 1;
        }
        if (h <= 16.0 * eps * fabs(t) || h <= 0.0) {
            status = MT_STEP_TOO_SMALL;
            goto done;
        }
        mt_call(&md.cj, mt_jac, &md, t, x, jac, ft);
        ++njev;
        hg = 1.0 / (h * mt_gamma);
        for (j = 0; j < n * n; ++j) w[j] = -jac[j];
        for (i = 0; i < n; ++i) w[i + i * n] += hg;
        ++nlu;
        if (mt_lu(w, piv, n) != MT_OK) {
            h *= 0.25;
            ++rejected;
            if (++reject_run > 20) {
                status = MT_SINGULAR;
                goto done;
            }
            continue;
        }
        for (s = 0; s < MT_STAGES; ++s) {
            double *ki = ks + (size_t)s * nn;
            const double *fi = f0;
            if (s > 0) {
                const double *as = mt_a + s * (s - 1) / 2;
                for (i = 0; i < n; ++i) ys[i] = x[i];
                for (j = 0; j < s; ++j)
                    if (as[j] != 0.0)
                        for (i = 0; i < n; ++i) ys[i] += as[j] * ks[(size_t)j * nn + i];
                mt_eval_f(&md, t + mt_alpha[s] * h, ys, fs);
                fi = fs;
            }
            for (i = 0; i < n; ++i) ki[i] = fi[i] + h * mt_g[s] * ft[i];
            if (s > 0) {
                const double *cs = mt_c + s * (s - 1) / 2;
                for (j = 0; j < s; ++j) {
                    double c_h = cs[j] / h;
                    for (i = 0; i < n; ++i) ki[i] += c_h * ks[(size_t)j * nn + i];
                }
            }
            mt_lu_solve(w, piv, ki, n);
        }
        for (i = 0; i < n; ++i) {
            double v = x[i];
            for (s = 0; s < MT_STAGES; ++s) v += mt_m[s] * ks[(size_t)s * nn + i];
            x1[i] = v;
        }
        err = mt_norm(ks + (size_t)(MT_STAGES - 1) * nn, x, x1, n, rtol, atol);
        if (!isfinite(err) || !mt_all_finite(x1, n)) {
            if (fixed_h > 0.0) {
                status = MT_NOT_FINITE;
                goto done;
            }
            h *= 0.25;
            ++rejected;
            if (++reject_run > 50) {
                status = MT_NOT_FINITE;
                goto done;
            }
            continue;
        }
        fac = err > 0.0 ? 0.9 * pow(err, -0.25) : 6.0;
        if (fac > 6.0) fac = 6.0;
        if (fac < 0.2) fac = 0.2;
        if (!(err <= 1.0 || fixed_h > 0.0)) {
            ++rejected;
            ++reject_run;
            h *= fac;
            continue;
        }
        for (i = 0; i < n; ++i) {
            double a = 0.0, b = 0.0;
            for (s = 0; s < MT_STAGES - 1; ++s) {
                a += mt_d2[s] * ks[(size_t)s * nn + i];
                b += mt_d3[s] * ks[(size_t)s * nn + i];
            }
            d2[i] = a;
            d3[i] = b;
        }
        t1 = last ? tend : t + h;
        mt_eval_f(&md, t1, x1, f1);
        if (!mt_all_finite(f1, n)) {
            status = MT_NOT_FINITE;
            t = t1;
            goto done;
        }
#if MT_NR > 0
        {
            /* an indicator that went from > 0 to <= 0 is an event; find the first */
            double ta = t, tb = t1, te;
            int crossed = 0, side = 0, k_ev = -1, round;
            mt_eval_zero(&md, t1, x1, g1);
            ++nzero;
            for (i = 0; i < MT_NR; ++i)
                if (g0[i] > 0.0 && g1[i] <= 0.0) crossed = 1;
            if (crossed) {
                for (i = 0; i < MT_NR; ++i) {
                    ga[i] = g0[i];
                    gb[i] = g1[i];
                }
                for (round = 0; round < 200 && tb - ta > event_tol; ++round) {
                    /* secant estimate of the earliest crossing; Illinois halving of the
                     * retained end's values keeps it from stalling on one side */
                    double tc = tb;
                    int any = 0;
                    for (i = 0; i < MT_NR; ++i)
                        if (g0[i] > 0.0 && gb[i] <= 0.0 && ga[i] > 0.0) {
                            double est = ta + (tb - ta) * ga[i] / (ga[i] - gb[i]);
                            if (est < tc) tc = est;
                        }
                    /* an estimate on an end of the bracket is moved half a tolerance
                     * inside: a root hit exactly (a clock tick) then closes the bracket
                     * at once instead of by bisection */
                    if (tc < ta + 0.5 * event_tol) tc = ta + 0.5 * event_tol;
                    if (tc > tb - 0.5 * event_tol) tc = tb - 0.5 * event_tol;
                    if (!(tc > ta && tc < tb)) tc = 0.5 * (ta + tb);
                    mt_dense(x, x1, d2, d3, (tc - t) / (t1 - t), ys, n);
                    mt_eval_zero(&md, tc, ys, gc);
                    ++nzero;
                    for (i = 0; i < MT_NR; ++i)
                        if (g0[i] > 0.0 && gc[i] <= 0.0) any = 1;
                    if (any) {
                        tb = tc;
                        for (i = 0; i < MT_NR; ++i) gb[i] = gc[i];
                        if (side == -1)
                            for (i = 0; i < MT_NR; ++i) ga[i] *= 0.5;
                        side = -1;
                    } else {
                        ta = tc;
                        for (i = 0; i < MT_NR; ++i) ga[i] = gc[i];
                        if (side == 1)
                            for (i = 0; i < MT_NR; ++i) gb[i] *= 0.5;
                        side = 1;
                    }
                }
                te = tb;
                /* outputs before the event's bracket use the step's interpolant; one
                 * inside it (within event_tol of the event, e.g. at a clock tick) shows
                 * the state after the event, as the CasADi integrators do */
                while (k_out < nout && tout[k_out] < ta) {
                    mt_dense(x, x1, d2, d3, (tout[k_out] - t) / (t1 - t), ys, n);
                    mt_eval_out(&md, tout[k_out], ys, y + (size_t)k_out * MT_NY);
                    ++k_out;
                }
                mt_dense(x, x1, d2, d3, (te - t) / (t1 - t), ys, n);
                mt_eval_zero(&md, te, ys, gc);
                ++nzero;
                for (i = 0; i < MT_NR; ++i)
                    if (g0[i] > 0.0 && gc[i] <= 0.0) {
                        k_ev = i;
                        break;
                    }
                if (k_ev < 0) k_ev = 0;   /* not reached: tb always has a crossing */
                for (i = 0; i < n; ++i) x[i] = ys[i];
                mt_eval_transition(&md, k_ev, te, x, xpost);
                ++events;
                for (i = 0; i < MT_NR; ++i)
                    if (md.m[MT_NR + i] >= 0.5 * MT_CHATTER_FLAG) {
                        /* the transition marked a sliding mode: the caller reports it */
                        status = MT_CHATTERING;
                        t = te;
                        goto done;
                    }
                same_time = (te - t <= event_tol) ? same_time + 1 : 0;
                if (same_time > 1000) {
                    status = MT_ZENO;
                    t = te;
                    goto done;
                }
                h_last = te - t;
                t = te;
                ++steps;
                mt_eval_f(&md, t, x, f0);
                if (!mt_all_finite(f0, n)) {
                    status = MT_NOT_FINITE;
                    goto done;
                }
                mt_eval_zero(&md, t, x, g0);
                ++nzero;
                if (fixed_h > 0.0) h = fixed_h;
                reject_run = 0;
                continue;
            }
            for (i = 0; i < MT_NR; ++i) g0[i] = g1[i];
        }
#endif
        /* outputs inside (t, t1]: the step's dense output */
        while (k_out < nout && tout[k_out] <= t1) {
            mt_dense(x, x1, d2, d3, (tout[k_out] - t) / (t1 - t), ys, n);
            mt_eval_out(&md, tout[k_out], ys, y + (size_t)k_out * MT_NY);
            ++k_out;
        }
        h_last = t1 - t;
        t = t1;
        for (i = 0; i < n; ++i) {
            x[i] = x1[i];
            f0[i] = f1[i];
        }
        ++steps;
        if (fixed_h > 0.0) {
            h = fixed_h;
        } else {
            if (reject_run && fac > 1.0) fac = 1.0;
            h *= fac;
        }
        reject_run = 0;
    }
    for (it = k_out; it < nout; ++it) mt_eval_out(&md, tout[it], x, y + (size_t)it * MT_NY);
    k_out = nout;

done:
    for (i = 0; i < n; ++i) xf[i] = x[i];
    for (i = 0; i < MT_NM; ++i) xf[n + i] = md.m[i];
    info[0] = (double)steps;
    info[1] = (double)rejected;
    info[2] = (double)md.nfev;
    info[3] = (double)njev;
    info[4] = (double)nlu;
    info[5] = t;
    info[6] = h_last;
    info[7] = (double)k_out;
    info[8] = (double)events;
    info[9] = (double)nzero;
    free(mem);
    free(piv);
release:
    mt_ctx_free(&md.cf);
    mt_ctx_free(&md.cj);
    mt_ctx_free(&md.co);
    mt_ctx_free(&md.cz);
    mt_ctx_free(&md.ct);
    return status;
}

/* Hand-written C of the DC motor's RK4 step: the peer of the generated C in
 * bench_codegen.py. Written from the equations, not from the generated code:
 *
 *     L di/dt = V - R i - k w,    J dw/dt = k i - D w
 *
 * One step does what the generated step does: RK4 from (i, w) over DT with runtime
 * parameters (tunable, not compile-time constants), then every logged variable of the
 * model at the new state (43, in the order of CompiledModel.names), then a finiteness
 * check of the states.
 *
 *   ./dc_motor_rk4 V R L k J D N      times N steps; prints JSON like the generated
 *                                     harness's --bench, and the state after N steps
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define DT 1e-4
#define NY 43

typedef struct {
    double x[2];      /* i, w */
    double p[6];      /* V, R, L, k, J, D */
    double y[NY];
    double t;
    unsigned long k;
} motor;

static void deriv(const double *p, double i, double w, double *di, double *dw)
{
    *di = (p[0] - p[1] * i - p[3] * w) / p[2];
    *dw = (p[3] * i - p[5] * w) / p[4];
}

static int motor_step(motor *m)
{
    const double *p = m->p;
    double i = m->x[0], w = m->x[1];
    double k1i, k1w, k2i, k2w, k3i, k3w, k4i, k4w;
    double V = p[0], R = p[1], k = p[3], D = p[5];
    double vR, vL, tau, tauD;
    double *y = m->y;
    deriv(p, i, w, &k1i, &k1w);
    deriv(p, i + 0.5 * DT * k1i, w + 0.5 * DT * k1w, &k2i, &k2w);
    deriv(p, i + 0.5 * DT * k2i, w + 0.5 * DT * k2w, &k3i, &k3w);
    deriv(p, i + DT * k3i, w + DT * k3w, &k4i, &k4w);
    i += DT / 6.0 * (k1i + 2.0 * k2i + 2.0 * k3i + k4i);
    w += DT / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
    m->x[0] = i;
    m->x[1] = w;
    m->k += 1;
    m->t = DT * (double)m->k;
    /* logged variables at the new state */
    vR = R * i;
    vL = V - vR - k * w;
    tau = k * i;            /* torque of the EMF on the shaft */
    tauD = D * w;           /* damper torque */
    y[0] = V;   y[1] = -i;  y[2] = V;   y[3] = -i;  y[4] = 0.0;       /* source */
    y[5] = vR;  y[6] = vR;  y[7] = i;   y[8] = V;   y[9] = i;         /* resistor */
    y[10] = V - vR; y[11] = -i;
    y[12] = vL; y[13] = i;  y[14] = V - vR; y[15] = i;                /* inductor */
    y[16] = k * w; y[17] = -i;
    y[18] = w;  y[19] = -tau; y[20] = k * w; y[21] = i;               /* emf */
    y[22] = w;  y[23] = -tau; y[24] = 0.0; y[25] = tau;
    y[26] = k * w; y[27] = i; y[28] = 0.0; y[29] = -i;
    y[30] = w;  y[31] = w;  y[32] = tau - tauD;                       /* inertia */
    y[33] = w;  y[34] = tauD; y[35] = w; y[36] = tauD;                /* damper */
    y[37] = 0.0; y[38] = -tauD;
    y[39] = 0.0; y[40] = 0.0; y[41] = 0.0; y[42] = tauD - tau;        /* ground, fixed */
    return !(isfinite(i) && isfinite(w));
}

/* The timing loop calls the step through a volatile pointer, as a real-time loop calls
 * it from its timer. Inlined into the loop, the step would be compiled into less than one
 * step's work: the state kept in registers, the logged variables stored once after the
 * loop instead of every step. The generated harness calls its step in another file. */
static int (*volatile step)(motor *) = motor_step;

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    static motor model;
    motor *m = &model;
    long n, s, c, chunk, done = 0;
    int j, status = 0;
    double start, dt, elapsed = 0.0, best = HUGE_VAL, check = 0.0;
    if (argc < 8) {
        fprintf(stderr, "usage: dc_motor_rk4 V R L k J D N\n");
        return 2;
    }
    for (j = 0; j < 6; ++j) {
        m->p[j] = strtod(argv[1 + j], 0);
    }
    n = strtol(argv[7], 0, 10);
    chunk = n >= 10 ? n / 10 : n;   /* timed in 10 chunks, as the generated harness */
    while (done < n) {
        c = n - done < chunk ? n - done : chunk;
        start = seconds_now();
        for (s = 0; s < c; ++s) {
            status |= step(m);
        }
        dt = seconds_now() - start;
        elapsed += dt;
        best = dt / (double)c < best ? dt / (double)c : best;
        done += c;
    }
    for (j = 0; j < NY; ++j) {
        check += m->y[j];
    }
    printf("{\"steps\": %ld, \"seconds\": %.9g, \"ns_per_step\": %.6g, "
           "\"best_chunk_ns_per_step\": %.6g, \"status\": %d, \"checksum\": %.17g, "
           "\"x\": [%.17g, %.17g]}\n", n, elapsed, 1e9 * elapsed / (double)n, 1e9 * best,
           status, isfinite(check) ? check : 0.0, m->x[0], m->x[1]);
    return 0;
}

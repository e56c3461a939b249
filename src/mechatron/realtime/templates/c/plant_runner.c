/* mt_plant: the real-time runner of a generated plant (docs/hil.md).
 *
 * Runs plant_out/plant_step (generated from the Mechatron model) at a fixed rate with
 * absolute deadlines (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)), in SCHED_FIFO
 * when asked and permitted. Each step k:
 *   1. sleep until t_k = start + k / rate; the wake-up lateness is the step's jitter;
 *   2. measure (plant_out), send SAMPLE(seq k, encoder count) to the controller;
 *   3. wait for COMMAND(seq k) until t_k + wait * period (lockstep mode: until a timeout,
 *      once replies have come LOSS_RTT_FACTOR x their mean round trip, at least
 *      LOSS_FLOOR_S and at most the --lockstep timeout, so that a lost packet costs a
 *      bounded wait, not the start-up timeout), else keep the previous duty (a missed
 *      step); older replies are counted late;
 *   4. advance the plant (plant_step) with the duty over [t_k, t_k+1];
 *   5. log the step; an overrun is a step that ends after t_k+1.
 * With --transport none it runs open loop at a fixed --duty (a pure timing test).
 * SIGINT/SIGTERM or the step limit end the run; the log and the statistics are written
 * in every case, and the controller receives STOP.
 *
 * Usage: mt_plant --rate HZ --steps N [--transport udp|pty|none] [--wait FRAC]
 *        [--lockstep TIMEOUT_S] [--loss P] [--seed N] [--rt] [--duty D]
 *        [--log FILE] [--stats FILE] [--hello-timeout S]
 * It prints "READY udp PORT" or "READY pty PATH" on stdout, then waits for HELLO.
 */
#include <errno.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

#include "mt_fpmode.h"
#include "mt_plant_io.h"
#include "mt_transport.h"

#define NCOL MT_LOG_NCOL
/* lockstep: a reply not in after LOSS_RTT_FACTOR mean round trips (>= LOSS_FLOOR_S) is lost */
#define LOSS_RTT_FACTOR 20.0
#define LOSS_FLOOR_S 0.05

typedef struct {
    double rate;
    long steps;
    const char *transport;
    double wait;
    double lockstep;           /* > 0: wait this long for each reply, not real time */
    double loss;
    unsigned long seed;
    int rt;
    double duty;
    const char *log;
    const char *stats;
    double hello_timeout;
} options;

static int parse(int argc, char **argv, options *o)
{
    int i;
    o->rate = 10000.0; o->steps = 0; o->transport = "udp"; o->wait = 0.8;
    o->lockstep = 0.0; o->loss = 0.0; o->seed = 1; o->rt = 0; o->duty = 0.5;
    o->log = NULL; o->stats = NULL; o->hello_timeout = 10.0;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (!strcmp(a, "--rt")) { o->rt = 1; continue; }
        if (!v) { fprintf(stderr, "mt_plant: %s needs a value\n", a); return -1; }
        if (!strcmp(a, "--rate")) o->rate = atof(v);
        else if (!strcmp(a, "--steps")) o->steps = atol(v);
        else if (!strcmp(a, "--transport")) o->transport = v;
        else if (!strcmp(a, "--wait")) o->wait = atof(v);
        else if (!strcmp(a, "--lockstep")) o->lockstep = atof(v);
        else if (!strcmp(a, "--loss")) o->loss = atof(v);
        else if (!strcmp(a, "--seed")) o->seed = strtoul(v, NULL, 10);
        else if (!strcmp(a, "--duty")) o->duty = atof(v);
        else if (!strcmp(a, "--log")) o->log = v;
        else if (!strcmp(a, "--stats")) o->stats = v;
        else if (!strcmp(a, "--hello-timeout")) o->hello_timeout = atof(v);
        else { fprintf(stderr, "mt_plant: unknown option %s\n", a); return -1; }
        ++i;
    }
    if (!(o->rate > 0) || o->steps < 1 || o->wait <= 0 || o->wait > 1 || o->loss < 0
        || o->loss >= 1) {
        fprintf(stderr, "mt_plant: need --rate > 0, --steps >= 1, 0 < --wait <= 1, "
                        "0 <= --loss < 1\n");
        return -1;
    }
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    options o;
    mt_link link;
    int have_link = 0, rt_ok = 0;
    double x[MT_MAX_STATES], meas[MT_MAX_MEAS], duty, ref = 0.0;
    double *log;
    long k, done = 0, overruns = 0, missed = 0, late = 0, stale = 0;
    double max_exec = 0, max_late = 0, sum_exec = 0;
    double sum_rtt = 0, max_tmo = 0;      /* lockstep: replies' round trips, longest wait */
    long n_rtt = 0;
    struct timespec start, deadline;
    int64_t period_ns;
    int nx, i;
    double t_wall0, t_wall;

    mt_flush_subnormals();      /* as the desktop solvers run (mt_fpmode.h) */
    if (parse(argc, argv, &o) != 0) return 2;
    nx = mt_plant_size("mt_plant");
    if (nx < 0) return 2;
    log = calloc((size_t)o.steps * NCOL, sizeof(double));
    if (!log) { fprintf(stderr, "mt_plant: cannot allocate the log\n"); return 2; }
    mt_catch_stop();
    signal(SIGPIPE, SIG_IGN);

    if (!strcmp(o.transport, "udp")) {
        if (mt_link_udp(&link, 0, 0) != 0) { perror("mt_plant: udp"); return 1; }
        printf("READY udp %d\n", mt_link_udp_port(&link));
        have_link = 1;
    } else if (!strcmp(o.transport, "pty")) {
        char name[256];
        if (mt_link_pty(&link, name, sizeof name) != 0) { perror("mt_plant: pty"); return 1; }
        printf("READY pty %s\n", name);
        have_link = 1;
    } else if (!strcmp(o.transport, "none")) {
        printf("READY none 0\n");
    } else {
        fprintf(stderr, "mt_plant: unknown transport %s (udp, pty, none)\n", o.transport);
        return 2;
    }
    fflush(stdout);
    if (have_link) {
        mt_packet p;
        struct timespec until;
        int r;
        mt_link_set_loss(&link, o.loss, (uint64_t)o.seed);
        clock_gettime(CLOCK_MONOTONIC, &until);
        mt_ts_add(&until, (int64_t)(o.hello_timeout * 1e9));
        do {
            r = mt_link_recv(&link, &p, &until);
        } while (r == 1 && p.type != MT_HELLO);
        if (r != 1) {
            fprintf(stderr, "mt_plant: no HELLO from the controller within %g s\n",
                    o.hello_timeout);
            return 1;
        }
    }
    if (o.rt) {
        struct sched_param sp;
        sp.sched_priority = 80;
        rt_ok = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
        if (rt_ok) mlockall(MCL_CURRENT | MCL_FUTURE);
    }

    mt_plant_start(x);
    duty = o.duty;
    period_ns = (int64_t)(1e9 / o.rate + 0.5);
    clock_gettime(CLOCK_MONOTONIC, &start);
    mt_ts_add(&start, 1000000);          /* first deadline 1 ms from now */
    deadline = start;
    t_wall0 = mt_ts_sec(&start);
    for (k = 0; k < o.steps && !mt_stop; ++k) {
        double t_wake, t0, t1, t_end, e_out, rtt = -1.0;
        int got = 0;
        double *row = log + (size_t)k * NCOL;
        if (o.lockstep <= 0 || k == 0) {
            while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, NULL) == EINTR)
                if (mt_stop) break;
            if (mt_stop) break;
        }
        t_wake = mt_now();
        mt_plant_measure(x, meas);
        e_out = mt_now() - t_wake;
        if (have_link) {
            mt_packet s, r;
            struct timespec until = deadline;
            double t_send;
            s.type = MT_SAMPLE; s.flags = 0; s.seq = (uint32_t)k;
            s.a = meas[0]; s.b = (double)k / o.rate;
            t_send = mt_now();
            mt_link_send(&link, &s, 1);
            if (o.lockstep > 0) {
                double tmo = o.lockstep;
                if (n_rtt > 0) {
                    double adaptive = LOSS_RTT_FACTOR * sum_rtt / (double)n_rtt;
                    if (adaptive < LOSS_FLOOR_S) adaptive = LOSS_FLOOR_S;
                    if (adaptive < tmo) tmo = adaptive;
                    if (tmo > max_tmo) max_tmo = tmo;
                }
                clock_gettime(CLOCK_MONOTONIC, &until);
                mt_ts_add(&until, (int64_t)(tmo * 1e9));
            } else {
                mt_ts_add(&until, (int64_t)(o.wait * (double)period_ns));
            }
            while (!got && mt_link_recv(&link, &r, &until) == 1) {
                if (r.type != MT_COMMAND) continue;
                if (r.seq == (uint32_t)k) {
                    got = 1;
                    duty = r.a;
                    ref = r.b;
                    rtt = mt_now() - t_send;
                    sum_rtt += rtt;
                    n_rtt++;
                } else if (r.seq < (uint32_t)k) {
                    late++;
                } else {
                    stale++;
                }
            }
            if (!got) missed++;
        } else {
            got = 1;
        }
        t0 = mt_now();
        mt_plant_advance(x, nx, duty, k);
        t1 = mt_now();
        mt_log_fill(row, (double)k / o.rate, duty, ref, meas, got);
        row[9] = t_wake - mt_ts_sec(&deadline);
        row[10] = (t1 - t0) + e_out;
        t_end = mt_now();
        row[11] = t_end - t_wake;
        row[12] = rtt;
        if (row[10] > max_exec) max_exec = row[10];
        if (row[9] > max_late) max_late = row[9];
        sum_exec += row[10];
        mt_ts_add(&deadline, period_ns);
        if (t_end > mt_ts_sec(&deadline)) {
            overruns++;
            if (o.lockstep > 0) {           /* not real time: restart the schedule */
                clock_gettime(CLOCK_MONOTONIC, &deadline);
            }
        }
        done++;
    }
    t_wall = mt_now() - t_wall0;
    if (have_link) {
        mt_packet s, r;
        struct timespec until;
        s.type = MT_STOP; s.flags = 0; s.seq = (uint32_t)done; s.a = 0; s.b = 0;
        for (i = 0; i < 3; ++i) mt_link_send(&link, &s, 0);
        /* drain replies still under way: they count as late, not lost */
        clock_gettime(CLOCK_MONOTONIC, &until);
        mt_ts_add(&until, 20000000);
        while (mt_link_recv(&link, &r, &until) == 1)
            if (r.type == MT_COMMAND && r.seq < (uint32_t)done) late++;
    }
    if (o.log && mt_log_write(o.log, log, done, "mt_plant") != 0) return 1;
    {
        double *ex = malloc(sizeof(double) * (size_t)(done ? done : 1));
        double median = 0;
        FILE *f = o.stats ? fopen(o.stats, "w") : stdout;
        for (k = 0; k < done; ++k) ex[k] = log[(size_t)k * NCOL + 10];
        if (done) {
            qsort(ex, (size_t)done, sizeof(double), cmp_double);
            median = ex[done / 2];
        }
        if (!f) { fprintf(stderr, "mt_plant: cannot write %s\n", o.stats); return 1; }
        fprintf(f, "{\"steps\": %ld, \"requested_steps\": %ld, \"rate_hz\": %.17g,\n",
                done, o.steps, o.rate);
        fprintf(f, " \"overruns\": %ld, \"missed_steps\": %ld, \"late_packets\": %ld,\n",
                overruns, missed, late);
        fprintf(f, " \"lost_packets\": %ld, \"stale_packets\": %ld,\n",
                missed - late > 0 ? missed - late : 0, stale);
        fprintf(f, " \"dropped_on_purpose\": %u, \"sent\": %u, \"received\": %u, "
                   "\"bad_frames\": %u,\n",
                have_link ? link.dropped : 0u, have_link ? link.sent : 0u,
                have_link ? link.received : 0u, have_link ? link.bad : 0u);
        fprintf(f, " \"max_step_time_s\": %.9g, \"median_step_time_s\": %.9g, "
                   "\"mean_step_time_s\": %.9g,\n",
                max_exec, median, done ? sum_exec / (double)done : 0.0);
        fprintf(f, " \"max_wake_late_s\": %.9g, \"wall_time_s\": %.9g, "
                   "\"realtime\": %s, \"lockstep\": %s,\n",
                max_late, t_wall, rt_ok ? "true" : "false", o.lockstep > 0 ? "true" : "false");
        /* the longest a step waited for its reply once the link was up */
        fprintf(f, " \"reply_timeout_s\": %.9g,\n", o.lockstep > 0 ? max_tmo : o.wait / o.rate);
        mt_json_columns(f);
        if (o.stats) fclose(f);
        free(ex);
    }
    if (have_link) mt_link_close(&link);
    free(log);
    return 0;
}

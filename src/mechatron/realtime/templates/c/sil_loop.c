/* mt_sil: plant and controller in one real-time loop, one process (docs/hil.md, "The SIL
 * loop").
 *
 * The generated plant (plant_model.c: plant_out, plant_step) and the generated controller
 * (controller/hilctrl.c, driven by ctrl_core.c exactly as over a link) run in one C loop
 * with absolute deadlines (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)); no Python, no
 * socket, no system call per period but the sleep. Each step k:
 *   1. sleep until t_k = start + k / rate; the wake-up lateness is the step's jitter;
 *   2. measure (plant_out) and hand SAMPLE(seq k, count, t_k) to the controller core;
 *      with --loss P the sample, or the controller's reply, is dropped with probability P
 *      (the plant then holds the previous duty: a missed step, a lost sample);
 *   3. a step that starts after the next deadline t_k+1 has passed skips the exchange
 *      (its sample is lost) and only advances the plant, so the schedule is regained;
 *   4. advance the plant (plant_step) with the duty over [t_k, t_k+1];
 *   5. log the step; an overrun is a step that ends after t_k+1.
 *
 * --rt asks for SCHED_FIFO (priority 80) and mlockall; --cpu N pins the loop to CPU N.
 * Each is reported as granted or refused (with errno's text) in the statistics.
 * --max-overruns F is the overrun budget, a fraction of the steps: when exceeded the run
 * still completes and writes its log, prints a warning on stderr and exits with 3.
 *
 * --spin S sleeps until S seconds before each deadline and polls the clock for the rest
 * (the sleep's wake-up latency, tens of us in a virtual machine, is then hidden).
 *
 * --keep-awake (with --cpu) runs a SCHED_IDLE child spinning on the same CPU, so that a
 * virtual CPU never halts between periods: it takes only time nobody else wants.
 *
 * Usage: mt_sil --rate HZ --steps N [--loss P] [--seed N] [--rt] [--cpu N] [--spin S]
 *        [--keep-awake]
 *        [--max-overruns F] [--log FILE] [--stats FILE]
 */
#include <errno.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "ctrl_core.h"
#include "mt_fpmode.h"
#include "mt_plant_io.h"
#include "mt_transport.h"

#define NCOL MT_LOG_NCOL
#define EXIT_BUDGET 3

typedef struct {
    double rate;
    long steps;
    double loss;
    unsigned long seed;
    int rt;
    int cpu;
    double max_overruns;       /* < 0: no budget */
    double spin;               /* s before each deadline spent polling the clock */
    int awake;                 /* keep the loop's CPU from idling (a SCHED_IDLE spinner) */
    const char *log;
    const char *stats;
} options;

/* A child pinned to the loop's CPU in SCHED_IDLE that spins: it runs only when nothing
 * else wants that CPU, and keeps a virtual CPU from halting between periods (waking a
 * halted virtual CPU costs the host's scheduling delay, up to milliseconds). Returns its
 * pid, or -1 (errno set). */
static pid_t start_spinner(int cpu)
{
    pid_t pid = fork();
    if (pid == 0) {
        struct sched_param sp;
        cpu_set_t set;
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        CPU_ZERO(&set);
        CPU_SET(cpu, &set);
        sp.sched_priority = 0;
        if (sched_setaffinity(0, sizeof set, &set) != 0
            || sched_setscheduler(0, SCHED_IDLE, &sp) != 0)
            _exit(1);
        for (;;) {
        }
    }
    return pid;
}

static int parse(int argc, char **argv, options *o)
{
    int i;
    o->rate = 10000.0; o->steps = 0; o->loss = 0.0; o->seed = 1; o->rt = 0; o->cpu = -1;
    o->max_overruns = -1.0; o->spin = 0.0; o->awake = 0; o->log = NULL; o->stats = NULL;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (!strcmp(a, "--rt")) { o->rt = 1; continue; }
        if (!strcmp(a, "--keep-awake")) { o->awake = 1; continue; }
        if (!v) { fprintf(stderr, "mt_sil: %s needs a value\n", a); return -1; }
        if (!strcmp(a, "--rate")) o->rate = atof(v);
        else if (!strcmp(a, "--steps")) o->steps = atol(v);
        else if (!strcmp(a, "--loss")) o->loss = atof(v);
        else if (!strcmp(a, "--seed")) o->seed = strtoul(v, NULL, 10);
        else if (!strcmp(a, "--cpu")) o->cpu = atoi(v);
        else if (!strcmp(a, "--max-overruns")) o->max_overruns = atof(v);
        else if (!strcmp(a, "--spin")) o->spin = atof(v);
        else if (!strcmp(a, "--log")) o->log = v;
        else if (!strcmp(a, "--stats")) o->stats = v;
        else { fprintf(stderr, "mt_sil: unknown option %s\n", a); return -1; }
        ++i;
    }
    if (!(o->rate > 0) || o->steps < 1 || o->loss < 0 || o->loss >= 1) {
        fprintf(stderr, "mt_sil: need --rate > 0, --steps >= 1, 0 <= --loss < 1\n");
        return -1;
    }
    return 0;
}

/* JSON string of a note (the texts are ours: no quote or backslash to escape). */
static void json_note(FILE *f, int *first, const char *what, const char *why)
{
    fprintf(f, "%s\"%s%s%s\"", *first ? "" : ", ", what, why ? ": " : "", why ? why : "");
    *first = 0;
}

int main(int argc, char **argv)
{
    options o;
    mt_ctrl ctrl;
    mt_rng rng_plant, rng_ctrl;
    double x[MT_MAX_STATES], meas[MT_MAX_MEAS], duty, ref;
    double *log;
    long k, done = 0, overruns = 0, missed = 0, skipped = 0, dropped_plant = 0;
    long dropped_ctrl = 0;
    struct timespec start, deadline;
    int64_t period_ns, spin_ns;
    int nx, fifo_ok = 0, lock_ok = 0, cpu_ok = 0, over_budget = 0;
    const char *fifo_err = NULL, *lock_err = NULL, *cpu_err = NULL, *awake_err = NULL;
    pid_t spinner = -1;
    double t_wall0, t_wall, period;

    mt_flush_subnormals();      /* as the desktop solvers run (mt_fpmode.h) */
    if (parse(argc, argv, &o) != 0) return 2;
    nx = mt_plant_size("mt_sil");
    if (nx < 0) return 2;
    log = calloc((size_t)o.steps * NCOL, sizeof(double));
    if (!log) { fprintf(stderr, "mt_sil: cannot allocate the log\n"); return 2; }
    memset(log, 0, (size_t)o.steps * NCOL * sizeof(double));   /* fault every page in */
    mt_catch_stop();

    if (o.awake && o.cpu >= 0) {
        spinner = start_spinner(o.cpu);
        if (spinner < 0) awake_err = strerror(errno);
    }
    if (o.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(o.cpu, &set);
        cpu_ok = sched_setaffinity(0, sizeof set, &set) == 0;
        if (!cpu_ok) cpu_err = strerror(errno);
    }
    if (o.rt) {
        struct sched_param sp;
        sp.sched_priority = 80;
        fifo_ok = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
        if (!fifo_ok) fifo_err = strerror(errno);
        lock_ok = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
        if (!lock_ok) lock_err = strerror(errno);
    }
    mt_rng_seed(&rng_plant, (uint64_t)o.seed);
    mt_rng_seed(&rng_ctrl, (uint64_t)o.seed + 1);
    mt_ctrl_init(&ctrl);
    mt_plant_start(x);
    duty = ctrl.last_duty;
    ref = ctrl.last_ref;
    period = 1.0 / o.rate;
    period_ns = (int64_t)(1e9 / o.rate + 0.5);
    spin_ns = (int64_t)(o.spin * 1e9);
    if (spin_ns > period_ns) spin_ns = period_ns;
    clock_gettime(CLOCK_MONOTONIC, &start);
    mt_ts_add(&start, 1000000);          /* first deadline 1 ms from now */
    deadline = start;
    t_wall0 = mt_ts_sec(&start);
    for (k = 0; k < o.steps && !mt_stop; ++k) {
        double t_wake, t_dead, t0, t1, t2, t_end;
        int got = 0;
        double *row = log + (size_t)k * NCOL;
        t_dead = mt_ts_sec(&deadline);
        {
            struct timespec nap = deadline;
            mt_ts_add(&nap, -spin_ns);
            while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &nap, NULL) == EINTR)
                if (mt_stop) break;
            if (mt_stop) break;
            while (spin_ns > 0 && mt_now() < t_dead) {
            }
        }
        t_wake = mt_now();
        t0 = mt_now();
        mt_plant_measure(x, meas);
        t1 = mt_now();
        row[12] = -1.0;
        if (t1 > t_dead + period) {
            skipped++;                     /* behind by a period: the sample is lost */
        } else if (o.loss > 0 && mt_rng_uniform(&rng_plant) < o.loss) {
            dropped_plant++;
        } else {
            mt_packet s, r;
            s.type = MT_SAMPLE; s.flags = 0; s.seq = (uint32_t)k;
            s.a = meas[0]; s.b = (double)k * period;
            if (mt_ctrl_handle(&ctrl, &s, &r) == 1) {
                if (o.loss > 0 && mt_rng_uniform(&rng_ctrl) < o.loss) {
                    dropped_ctrl++;
                } else {
                    got = 1;
                    duty = r.a;
                    ref = r.b;
                }
            }
            row[12] = mt_now() - t1;
        }
        if (!got) missed++;
        t2 = mt_now();
        mt_plant_advance(x, nx, duty, k);
        t_end = mt_now();
        mt_log_fill(row, (double)k * period, duty, ref, meas, got);
        row[9] = t_wake - t_dead;
        row[10] = (t1 - t0) + (t_end - t2) + (row[12] > 0 ? row[12] : 0.0);
        row[11] = t_end - t_wake;
        mt_ts_add(&deadline, period_ns);
        if (t_end > mt_ts_sec(&deadline)) overruns++;
        done++;
    }
    t_wall = mt_now() - t_wall0;
    if (spinner > 0) {
        kill(spinner, SIGKILL);
        waitpid(spinner, NULL, 0);
    }
    if (o.max_overruns >= 0 && (double)overruns > o.max_overruns * (double)(done ? done : 1))
        over_budget = 1;
    if (o.log && mt_log_write(o.log, log, done, "mt_sil") != 0) return 1;
    {
        FILE *f = o.stats ? fopen(o.stats, "w") : stdout;
        int first = 1;
        if (!f) { fprintf(stderr, "mt_sil: cannot write %s\n", o.stats); return 1; }
        fprintf(f, "{\"steps\": %ld, \"requested_steps\": %ld, \"rate_hz\": %.17g,\n",
                done, o.steps, o.rate);
        fprintf(f, " \"overruns\": %ld, \"missed_steps\": %ld, \"late_packets\": 0,\n",
                overruns, missed);
        fprintf(f, " \"lost_packets\": %ld, \"skipped_samples\": %ld, \"stale_packets\": 0,\n",
                dropped_plant + dropped_ctrl + skipped, skipped);
        fprintf(f, " \"dropped_on_purpose\": %ld, \"bad_frames\": 0,\n", dropped_plant);
        fprintf(f, " \"wall_time_s\": %.9g, \"realtime\": %s, \"mlockall\": %s, "
                   "\"cpu\": %d, \"keep_awake\": %s, \"lockstep\": false,\n",
                t_wall, fifo_ok ? "true" : "false", lock_ok ? "true" : "false",
                cpu_ok ? o.cpu : -1, spinner > 0 ? "true" : "false");
        fprintf(f, " \"overrun_budget\": %.9g, \"over_budget\": %s,\n",
                o.max_overruns, over_budget ? "true" : "false");
        fprintf(f, " \"controller\": {\"samples\": %u, \"lost_samples\": %u, "
                   "\"stale_samples\": %u, \"steps\": %u, \"dropped_on_purpose\": %ld, "
                   "\"bad_inputs\": %u},\n",
                ctrl.samples, ctrl.lost_samples, ctrl.stale_samples, ctrl.steps,
                dropped_ctrl, ctrl.bad_inputs);
        fprintf(f, " \"notes\": [");
        if (o.rt && !fifo_ok) json_note(f, &first, "SCHED_FIFO refused", fifo_err);
        if (o.rt && !lock_ok) json_note(f, &first, "mlockall refused", lock_err);
        if (o.cpu >= 0 && !cpu_ok) json_note(f, &first, "CPU pinning refused", cpu_err);
        if (o.awake && o.cpu < 0)
            json_note(f, &first, "keep-awake needs a pinned CPU (--cpu)", NULL);
        if (o.awake && awake_err) json_note(f, &first, "keep-awake refused", awake_err);
        fprintf(f, "],\n");
        mt_json_columns(f);
        if (o.stats) fclose(f);
    }
    free(log);
    if (over_budget) {
        fprintf(stderr, "mt_sil: warning: %ld overruns in %ld steps (%.3g %%) exceed the "
                        "budget of %.3g %%\n", overruns, done,
                100.0 * (double)overruns / (double)(done ? done : 1), 100.0 * o.max_overruns);
        return EXIT_BUDGET;
    }
    return 0;
}

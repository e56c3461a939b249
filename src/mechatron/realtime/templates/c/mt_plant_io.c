/* See mt_plant_io.h. */
#include "mt_plant_io.h"

#include <string.h>
#include <sys/prctl.h>

#include "mt_casadi.h"
#include "plant_model.h"

const char *const MT_LOG_COLS[MT_LOG_NCOL] = {
    "t", "duty", "ref", "count", "w", "phi", "v_c", "i", "got", "wake_late_s", "exec_s",
    "busy_s", "rtt_s"};

volatile sig_atomic_t mt_stop = 0;

static void on_signal(int sig)
{
    (void)sig;
    mt_stop = 1;
}

void mt_catch_stop(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
}

int mt_plant_size(const char *who)
{
    int nx = MT_DIM_OUT(plant_step, 0);
    if (nx > MT_MAX_STATES || MT_DIM_OUT(plant_out, 0) > MT_MAX_MEAS) {
        fprintf(stderr, "%s: model too large (at most %d states and %d measurements)\n",
                who, MT_MAX_STATES, MT_MAX_MEAS);
        return -1;
    }
    return nx;
}

void mt_plant_start(double *x)
{
    casadi_real *res[1];
    res[0] = x;
    MT_CALL(plant_x0, (const casadi_real **)0, res);
}

void mt_plant_measure(const double *x, double *meas)
{
    const casadi_real *arg[1];
    casadi_real *res[1];
    arg[0] = x;
    res[0] = meas;
    MT_CALL(plant_out, arg, res);
}

void mt_plant_advance(double *x, int nx, double duty, long k)
{
    double xn[MT_MAX_STATES], kk = (double)k;
    const casadi_real *arg[3];
    casadi_real *res[1];
    int i;
    arg[0] = x; arg[1] = &duty; arg[2] = &kk;
    res[0] = xn;
    MT_CALL(plant_step, arg, res);
    for (i = 0; i < nx; ++i) x[i] = xn[i];
}

void mt_log_fill(double *row, double t, double duty, double ref, const double *meas,
                 int got)
{
    int i;
    row[0] = t; row[1] = duty; row[2] = ref;
    for (i = 0; i < 5; ++i) row[3 + i] = meas[i];
    row[8] = got;
}

int mt_log_write(const char *path, const double *log, long done, const char *who)
{
    FILE *f = fopen(path, "wb");
    size_t n = (size_t)done;
    if (!f || fwrite(log, sizeof(double) * MT_LOG_NCOL, n, f) != n) {
        fprintf(stderr, "%s: cannot write %s\n", who, path);
        if (f) fclose(f);
        return -1;
    }
    if (fclose(f) != 0) {
        fprintf(stderr, "%s: cannot write %s\n", who, path);
        return -1;
    }
    return 0;
}

void mt_json_columns(FILE *f)
{
    int i;
    fprintf(f, " \"interrupted\": %s, \"columns\": [", mt_stop ? "true" : "false");
    for (i = 0; i < MT_LOG_NCOL; ++i) fprintf(f, "%s\"%s\"", i ? ", " : "", MT_LOG_COLS[i]);
    fprintf(f, "]}\n");
}

/* The plant side that mt_plant (plant_runner.c) and mt_sil (sil_loop.c) share: the
 * generated plant's calls, the step log's columns and its file, and the stop signals.
 * The log is NCOL doubles per step; both programs fill columns 0-8 the same way
 * (mt_log_fill) and 9-12 with their own timings. */
#ifndef MT_PLANT_IO_H
#define MT_PLANT_IO_H

#include <signal.h>
#include <stdio.h>

#define MT_LOG_NCOL 13
#define MT_MAX_STATES 64
#define MT_MAX_MEAS 8

extern const char *const MT_LOG_COLS[MT_LOG_NCOL];
extern volatile sig_atomic_t mt_stop;     /* set by SIGINT and SIGTERM */

/* Route SIGINT and SIGTERM to mt_stop, and ask for 1 ns timer slack (not 50 us). */
void mt_catch_stop(void);
/* The plant's state count, or -1 (with a message naming `who`) if the generated plant
 * has more states or measurements than the fixed arrays hold. */
int mt_plant_size(const char *who);
void mt_plant_start(double *x);                          /* x <- plant_x0() */
void mt_plant_measure(const double *x, double *meas);    /* meas <- plant_out(x) */
void mt_plant_advance(double *x, int nx, double duty, long k);   /* x <- plant_step */
/* Columns 0-8 of step k's row: t, duty, ref, the five measurements, got. */
void mt_log_fill(double *row, double t, double duty, double ref, const double *meas,
                 int got);
/* Write `done` rows of the log to `path` (0), or say why not as `who` (-1). */
int mt_log_write(const char *path, const double *log, long done, const char *who);
/* The statistics' closing fields: "interrupted" and the log's "columns". */
void mt_json_columns(FILE *f);

#endif

/* mt_controller: the generated controller as a host process (SIL), docs/hil.md.
 *
 * Usage: mt_controller --udp PLANT_PORT | --tty PATH  [--loss P] [--seed N] [--rt]
 *        [--stats FILE] [--idle-timeout S]
 * Sends HELLO, then answers every SAMPLE with a COMMAND (ctrl_core.c) until STOP, a
 * signal, or --idle-timeout seconds without a packet. Replies are dropped on purpose
 * with probability P. Writes its statistics as JSON to --stats (or stdout).
 */
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include "ctrl_core.h"
#include "mt_fpmode.h"
#include "mt_transport.h"

static volatile sig_atomic_t g_stop = 0;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

int main(int argc, char **argv)
{
    int udp_port = 0, rt = 0, rt_ok = 0, i, stopped = 0;
    const char *tty = NULL, *stats = NULL;
    double loss = 0.0, idle = 5.0, max_exec = 0.0;
    unsigned long seed = 2;
    mt_link link;
    mt_ctrl ctrl;
    mt_packet in, out;
    struct sigaction sa;

    mt_flush_subnormals();      /* as the desktop solvers run (mt_fpmode.h) */
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (!strcmp(a, "--rt")) { rt = 1; continue; }
        if (!v) { fprintf(stderr, "mt_controller: %s needs a value\n", a); return 2; }
        if (!strcmp(a, "--udp")) udp_port = atoi(v);
        else if (!strcmp(a, "--tty")) tty = v;
        else if (!strcmp(a, "--loss")) loss = atof(v);
        else if (!strcmp(a, "--seed")) seed = strtoul(v, NULL, 10);
        else if (!strcmp(a, "--stats")) stats = v;
        else if (!strcmp(a, "--idle-timeout")) idle = atof(v);
        else { fprintf(stderr, "mt_controller: unknown option %s\n", a); return 2; }
        ++i;
    }
    if ((udp_port <= 0) == (tty == NULL)) {
        fprintf(stderr, "mt_controller: give one of --udp PORT or --tty PATH\n");
        return 2;
    }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
    if (mt_ctrl_init(&ctrl) != 0) {
        fprintf(stderr, "mt_controller: controller init failed\n");
        return 2;
    }
    if (udp_port > 0 ? mt_link_udp(&link, 0, udp_port) != 0 : mt_link_tty(&link, tty) != 0) {
        perror("mt_controller: open link");
        return 1;
    }
    mt_link_set_loss(&link, loss, (uint64_t)seed);
    if (rt) {
        struct sched_param sp;
        sp.sched_priority = 79;
        rt_ok = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
        if (rt_ok) mlockall(MCL_CURRENT | MCL_FUTURE);
    }
    memset(&out, 0, sizeof out);
    out.type = MT_HELLO;
    mt_link_send(&link, &out, 0);
    while (!g_stop) {
        struct timespec until;
        int r;
        clock_gettime(CLOCK_MONOTONIC, &until);
        mt_ts_add(&until, (int64_t)(idle * 1e9));
        r = mt_link_recv(&link, &in, &until);
        if (r != 1) break;
        {
            double t0 = mt_now();
            r = mt_ctrl_handle(&ctrl, &in, &out);
            t0 = mt_now() - t0;
            if (t0 > max_exec) max_exec = t0;
        }
        if (r == 2) { stopped = 1; break; }
        if (r == 1) mt_link_send(&link, &out, 1);
    }
    {
        FILE *f = stats ? fopen(stats, "w") : stdout;
        if (!f) { fprintf(stderr, "mt_controller: cannot write %s\n", stats); return 1; }
        fprintf(f, "{\"samples\": %u, \"lost_samples\": %u, \"stale_samples\": %u, "
                   "\"steps\": %u, \"dropped_on_purpose\": %u, \"sent\": %u, "
                   "\"bad_frames\": %u, \"bad_inputs\": %u, \"max_ctrl_time_s\": %.9g, "
                   "\"realtime\": %s, \"stopped\": %s}\n",
                ctrl.samples, ctrl.lost_samples, ctrl.stale_samples, ctrl.steps,
                link.dropped, link.sent, link.bad, ctrl.bad_inputs, max_exec,
                rt_ok ? "true" : "false", stopped ? "true" : "false");
        if (stats) fclose(f);
    }
    mt_link_close(&link);
    return 0;
}

/* The reference firmware's board layer for a host (tests, docs/hil.md): the serial line
 * is a tty path (one end of a pseudo-terminal, or a USB-UART), the fixed-rate timer is
 * clock_nanosleep at --rate. Everything else is mt_fw.c, as on the microcontroller.
 *
 * Usage: mt_fw_host --tty PATH [--rate HZ] [--stats FILE] [--idle-timeout S]
 * Sends HELLO; every tick reads the bytes that came, runs mt_fw_tick and writes the
 * COMMAND frame; ends on STOP (or --idle-timeout s without a byte) and writes its
 * counters as JSON.
 */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "mt_fw.h"

static mt_fw fw;

static void put_all(int fd, const uint8_t *b, int n)
{
    while (n > 0) {
        ssize_t w = write(fd, b, (size_t)n);
        if (w < 0) {
            if (errno == EINTR || errno == EAGAIN) continue;
            return;
        }
        b += w;
        n -= (int)w;
    }
}

int main(int argc, char **argv)
{
    const char *path = NULL, *stats = NULL;
    double rate = 20000.0, idle = 5.0, last_rx;
    int fd, i;
    struct termios t;
    struct timespec next, now;
    long period_ns;
    uint8_t frame[MT_FRAME_SIZE], buf[256];

    for (i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--tty")) path = argv[i + 1];
        else if (!strcmp(argv[i], "--rate")) rate = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--stats")) stats = argv[i + 1];
        else if (!strcmp(argv[i], "--idle-timeout")) idle = atof(argv[i + 1]);
        else { fprintf(stderr, "mt_fw_host: unknown option %s\n", argv[i]); return 2; }
    }
    if (!path || !(rate > 0)) {
        fprintf(stderr, "mt_fw_host: give --tty PATH and --rate > 0\n");
        return 2;
    }
    fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0 || tcgetattr(fd, &t) != 0) { perror("mt_fw_host: open"); return 1; }
    cfmakeraw(&t);
    tcsetattr(fd, TCSANOW, &t);
    mt_fw_init(&fw);
    mt_fw_hello(frame);
    put_all(fd, frame, MT_FRAME_SIZE);
    period_ns = (long)(1e9 / rate + 0.5);
    clock_gettime(CLOCK_MONOTONIC, &next);
    last_rx = (double)next.tv_sec + 1e-9 * (double)next.tv_nsec;
    while (!fw.stop) {
        ssize_t n;
        next.tv_nsec += period_ns;
        while (next.tv_nsec >= 1000000000L) { next.tv_nsec -= 1000000000L; next.tv_sec++; }
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) {
        }
        clock_gettime(CLOCK_MONOTONIC, &now);
        while ((n = read(fd, buf, sizeof buf)) > 0) {
            for (i = 0; i < n; ++i) mt_fw_rx(&fw, buf[i]);
            last_rx = (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
        }
        if (mt_fw_tick(&fw, frame)) put_all(fd, frame, MT_FRAME_SIZE);
        if ((double)now.tv_sec + 1e-9 * (double)now.tv_nsec - last_rx > idle) break;
    }
    {
        FILE *f = stats ? fopen(stats, "w") : stdout;
        if (!f) return 1;
        fprintf(f, "{\"samples\": %u, \"lost_samples\": %u, \"stale_samples\": %u, "
                   "\"steps\": %u, \"ticks\": %u, \"idle_ticks\": %u, \"overwritten\": %u, "
                   "\"bad_frames\": %u, \"stopped\": %s}\n",
                fw.ctrl.samples, fw.ctrl.lost_samples, fw.ctrl.stale_samples, fw.ctrl.steps,
                fw.ticks, fw.idle_ticks, fw.overwritten, fw.parser.bad_frames,
                fw.stop ? "true" : "false");
        if (stats) fclose(f);
    }
    close(fd);
    return 0;
}

/* Host transports of the HIL bridge (see mt_transport.h). */
#include "mt_transport.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

double mt_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void mt_ts_add(struct timespec *t, int64_t ns)
{
    int64_t total = (int64_t)t->tv_nsec + ns;
    t->tv_sec += (time_t)(total / 1000000000);
    total %= 1000000000;
    if (total < 0) {
        total += 1000000000;
        t->tv_sec -= 1;
    }
    t->tv_nsec = (long)total;
}

double mt_ts_sec(const struct timespec *t)
{
    return (double)t->tv_sec + 1e-9 * (double)t->tv_nsec;
}

static void link_init(mt_link *l, int kind)
{
    memset(l, 0, sizeof *l);
    l->kind = kind;
    l->fd = -1;
    l->hold_fd = -1;
    mt_frame_parser_init(&l->parser);
    mt_rng_seed(&l->rng, 1);
}

int mt_link_udp(mt_link *l, int local_port, int peer_port)
{
    struct sockaddr_in a;
    link_init(l, MT_LINK_UDP);
    l->fd = socket(AF_INET, SOCK_DGRAM, 0);
    if (l->fd < 0) return -1;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons((uint16_t)local_port);
    if (bind(l->fd, (struct sockaddr *)&a, sizeof a) != 0) return -1;
    if (peer_port > 0) {
        l->peer = a;
        l->peer.sin_port = htons((uint16_t)peer_port);
        l->have_peer = 1;
    }
    return 0;
}

int mt_link_udp_port(const mt_link *l)
{
    struct sockaddr_in a;
    socklen_t n = sizeof a;
    if (getsockname(l->fd, (struct sockaddr *)&a, &n) != 0) return -1;
    return ntohs(a.sin_port);
}

static int make_raw(int fd)
{
    struct termios t;
    if (tcgetattr(fd, &t) != 0) return -1;
    cfmakeraw(&t);
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    return tcsetattr(fd, TCSANOW, &t);
}

int mt_link_pty(mt_link *l, char *name, size_t n)
{
    const char *slave;
    link_init(l, MT_LINK_STREAM);
    l->fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (l->fd < 0 || grantpt(l->fd) != 0 || unlockpt(l->fd) != 0) return -1;
    slave = ptsname(l->fd);
    if (!slave || strlen(slave) + 1 > n) return -1;
    strcpy(name, slave);
    /* keep the slave open: the master then never sees a hang-up between peers */
    l->hold_fd = open(slave, O_RDWR | O_NOCTTY);
    if (l->hold_fd < 0 || make_raw(l->hold_fd) != 0) return -1;
    (void)make_raw(l->fd);      /* the master's settings matter little; best effort */
    return 0;
}

int mt_link_tty(mt_link *l, const char *path)
{
    link_init(l, MT_LINK_STREAM);
    l->fd = open(path, O_RDWR | O_NOCTTY);
    if (l->fd < 0) return -1;
    return make_raw(l->fd);
}

void mt_link_set_loss(mt_link *l, double p, uint64_t seed)
{
    l->loss = p;
    mt_rng_seed(&l->rng, seed);
}

static int write_all(int fd, const uint8_t *b, int n)
{
    while (n > 0) {
        ssize_t w = write(fd, b, (size_t)n);
        if (w < 0) {
            if (errno == EINTR || errno == EAGAIN) continue;
            return -1;
        }
        b += w;
        n -= (int)w;
    }
    return 0;
}

int mt_link_send(mt_link *l, const mt_packet *p, int drop_ok)
{
    if (drop_ok && l->loss > 0 && mt_rng_uniform(&l->rng) < l->loss) {
        l->dropped++;
        return 0;
    }
    if (l->kind == MT_LINK_UDP) {
        uint8_t b[MT_PACKET_SIZE];
        if (!l->have_peer) return -1;
        mt_packet_encode(p, b);
        if (sendto(l->fd, b, sizeof b, 0, (struct sockaddr *)&l->peer, sizeof l->peer)
            != (ssize_t)sizeof b)
            return -1;
    } else {
        uint8_t b[MT_FRAME_SIZE];
        mt_frame_encode(p, b);
        if (write_all(l->fd, b, MT_FRAME_SIZE) != 0) return -1;
    }
    l->sent++;
    return 1;
}

/* Wait until fd is readable or the deadline passes: 1 readable, 0 deadline, -1 error. */
static int wait_readable(int fd, const struct timespec *deadline)
{
    struct pollfd pfd;
    pfd.fd = fd;
    pfd.events = POLLIN;
    for (;;) {
        int r;
        if (deadline) {
            struct timespec now, rel;
            clock_gettime(CLOCK_MONOTONIC, &now);
            rel.tv_sec = deadline->tv_sec - now.tv_sec;
            rel.tv_nsec = deadline->tv_nsec - now.tv_nsec;
            if (rel.tv_nsec < 0) {
                rel.tv_nsec += 1000000000;
                rel.tv_sec -= 1;
            }
            if (rel.tv_sec < 0) {
                rel.tv_sec = 0;
                rel.tv_nsec = 0;
            }
            r = ppoll(&pfd, 1, &rel, NULL);
        } else {
            r = ppoll(&pfd, 1, NULL, NULL);
        }
        if (r > 0) return (pfd.revents & POLLIN) ? 1 : -1;
        if (r == 0) return 0;
        if (errno != EINTR) return -1;
        return 0;                   /* a signal: let the caller look at its stop flag */
    }
}

int mt_link_recv(mt_link *l, mt_packet *p, const struct timespec *deadline)
{
    for (;;) {
        if (l->kind == MT_LINK_STREAM) {
            while (l->rpos < l->rlen) {
                if (mt_frame_feed(&l->parser, l->rbuf[l->rpos++], p)) {
                    l->received++;
                    return 1;
                }
            }
            l->bad = l->parser.bad_frames;
        }
        {
            int r = wait_readable(l->fd, deadline);
            if (r <= 0) return r;
        }
        if (l->kind == MT_LINK_UDP) {
            uint8_t b[64];
            struct sockaddr_in from;
            socklen_t fl = sizeof from;
            ssize_t n = recvfrom(l->fd, b, sizeof b, 0, (struct sockaddr *)&from, &fl);
            if (n < 0) {
                if (errno == EINTR || errno == EAGAIN) continue;
                return -1;
            }
            if (n != MT_PACKET_SIZE || mt_packet_decode(b, p) != 0) {
                l->bad++;
                continue;
            }
            if (!l->have_peer) {
                l->peer = from;
                l->have_peer = 1;
            }
            l->received++;
            return 1;
        } else {
            ssize_t n = read(l->fd, l->rbuf, sizeof l->rbuf);
            if (n < 0) {
                if (errno == EINTR || errno == EAGAIN) continue;
                return -1;
            }
            if (n == 0) return -1;
            l->rpos = 0;
            l->rlen = (int)n;
        }
    }
}

void mt_link_close(mt_link *l)
{
    if (l->fd >= 0) close(l->fd);
    if (l->hold_fd >= 0) close(l->hold_fd);
    l->fd = l->hold_fd = -1;
}

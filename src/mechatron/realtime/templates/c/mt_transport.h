/* Host transports of the HIL bridge: UDP on loopback (one packet per datagram) and
 * pseudo-terminal serial lines (framed byte stream, see mt_packet.h). POSIX/Linux. */
#ifndef MT_TRANSPORT_H
#define MT_TRANSPORT_H

#include <netinet/in.h>
#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include "mt_packet.h"

enum { MT_LINK_UDP = 1, MT_LINK_STREAM = 2 };

typedef struct {
    int kind;
    int fd;
    int hold_fd;                 /* pty slave kept open by the side that created it */
    struct sockaddr_in peer;
    int have_peer;
    mt_frame_parser parser;
    uint8_t rbuf[4096];
    int rpos, rlen;
    mt_rng rng;
    double loss;                 /* probability of dropping a packet on purpose */
    uint32_t sent, received, dropped, bad;
} mt_link;

/* UDP on 127.0.0.1: bind local_port (0: any free port), send to peer_port (0: reply to
 * whoever sent the last packet). Returns 0 or -1 (errno set). */
int mt_link_udp(mt_link *l, int local_port, int peer_port);
int mt_link_udp_port(const mt_link *l);
/* Create a pseudo-terminal in raw mode; the slave's path goes to name (size n). */
int mt_link_pty(mt_link *l, char *name, size_t n);
/* Open an existing serial line (e.g. the slave of a pty) in raw mode. */
int mt_link_tty(mt_link *l, const char *path);
void mt_link_set_loss(mt_link *l, double p, uint64_t seed);
/* Send a packet; with drop_ok, it is dropped with probability l->loss (counted).
 * Returns 1 sent, 0 dropped on purpose, -1 error. */
int mt_link_send(mt_link *l, const mt_packet *p, int drop_ok);
/* Receive one packet before the absolute CLOCK_MONOTONIC deadline (NULL: wait forever).
 * Returns 1 with *p filled, 0 at the deadline, -1 on error or EOF. */
int mt_link_recv(mt_link *l, mt_packet *p, const struct timespec *deadline);
void mt_link_close(mt_link *l);

/* Time helpers. */
double mt_now(void);                          /* CLOCK_MONOTONIC in s */
void mt_ts_add(struct timespec *t, int64_t ns);
double mt_ts_sec(const struct timespec *t);

#endif

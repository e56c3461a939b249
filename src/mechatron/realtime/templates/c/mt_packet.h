/* Mechatron HIL bridge: the packet format (docs/hil.md, "Packet format").
 *
 * Every sample or command is one 28-byte packet, little-endian:
 *
 *   offset size  field
 *   0      4     magic   'M' 'T' 'H' '1'
 *   4      1     type    MT_SAMPLE, MT_COMMAND, MT_HELLO, MT_STOP
 *   5      1     flags   bit 0: the payload was extrapolated (controller filled a gap)
 *   6      2     reserved (0)
 *   8      4     seq     step number k of the plant (uint32)
 *   12     8     a       SAMPLE: encoder count; COMMAND: PWM duty in [0, 1]
 *   20     8     b       SAMPLE: plant time t_k in s; COMMAND: controller reference
 *
 * Over UDP a datagram carries exactly one packet. Over a byte stream (a pseudo-terminal,
 * a UART) a packet travels in a 32-byte frame: sync bytes 0xA5 0x5A, the packet, and its
 * CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF), low byte first. A receiver that loses
 * sync scans for the next 0xA5 0x5A whose CRC checks.
 *
 * This file and mt_packet.c are freestanding C99 (no OS): the firmware uses them too.
 */
#ifndef MT_PACKET_H
#define MT_PACKET_H

#include <stdint.h>

#define MT_PACKET_SIZE 28
#define MT_FRAME_SIZE 32
#define MT_SYNC0 0xA5u
#define MT_SYNC1 0x5Au

enum { MT_SAMPLE = 1, MT_COMMAND = 2, MT_HELLO = 3, MT_STOP = 4 };

typedef struct {
    uint8_t type;
    uint8_t flags;
    uint32_t seq;
    double a;
    double b;
} mt_packet;

/* Write the 28 bytes of p to buf. */
void mt_packet_encode(const mt_packet *p, uint8_t *buf);
/* Read a packet from 28 bytes; returns 0 on success, -1 if the magic is wrong. */
int mt_packet_decode(const uint8_t *buf, mt_packet *p);

uint16_t mt_crc16(const uint8_t *data, int n);
/* Write the 32-byte frame of p to buf. */
void mt_frame_encode(const mt_packet *p, uint8_t *buf);

/* Incremental frame parser for byte streams. */
typedef struct {
    uint8_t buf[MT_FRAME_SIZE];
    int n;
    uint32_t bad_frames;    /* frames dropped for a wrong CRC or magic */
} mt_frame_parser;

void mt_frame_parser_init(mt_frame_parser *fp);
/* Feed one byte; returns 1 and fills *p when a valid frame is complete, else 0. */
int mt_frame_feed(mt_frame_parser *fp, uint8_t byte, mt_packet *p);

/* Deterministic pseudo-random numbers for loss injection (xorshift64*). */
typedef struct { uint64_t s; } mt_rng;
void mt_rng_seed(mt_rng *r, uint64_t seed);
double mt_rng_uniform(mt_rng *r);   /* in [0, 1) */

#endif

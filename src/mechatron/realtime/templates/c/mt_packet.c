/* Mechatron HIL bridge: packet encoding, stream framing, loss-injection RNG. */
#include "mt_packet.h"

#include <string.h>

static void put_u32(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)v; b[1] = (uint8_t)(v >> 8); b[2] = (uint8_t)(v >> 16);
    b[3] = (uint8_t)(v >> 24);
}

static uint32_t get_u32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16)
           | ((uint32_t)b[3] << 24);
}

static void put_f64(uint8_t *b, double x)
{
    uint64_t u;
    int i;
    memcpy(&u, &x, sizeof u);
    for (i = 0; i < 8; ++i) b[i] = (uint8_t)(u >> (8 * i));
}

static double get_f64(const uint8_t *b)
{
    uint64_t u = 0;
    double x;
    int i;
    for (i = 0; i < 8; ++i) u |= (uint64_t)b[i] << (8 * i);
    memcpy(&x, &u, sizeof x);
    return x;
}

void mt_packet_encode(const mt_packet *p, uint8_t *buf)
{
    buf[0] = 'M'; buf[1] = 'T'; buf[2] = 'H'; buf[3] = '1';
    buf[4] = p->type;
    buf[5] = p->flags;
    buf[6] = 0; buf[7] = 0;
    put_u32(buf + 8, p->seq);
    put_f64(buf + 12, p->a);
    put_f64(buf + 20, p->b);
}

int mt_packet_decode(const uint8_t *buf, mt_packet *p)
{
    if (buf[0] != 'M' || buf[1] != 'T' || buf[2] != 'H' || buf[3] != '1') return -1;
    p->type = buf[4];
    p->flags = buf[5];
    p->seq = get_u32(buf + 8);
    p->a = get_f64(buf + 12);
    p->b = get_f64(buf + 20);
    return 0;
}

uint16_t mt_crc16(const uint8_t *data, int n)
{
    uint16_t crc = 0xFFFFu;
    int i, j;
    for (i = 0; i < n; ++i) {
        crc ^= (uint16_t)((uint16_t)data[i] << 8);
        for (j = 0; j < 8; ++j)
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
    }
    return crc;
}

void mt_frame_encode(const mt_packet *p, uint8_t *buf)
{
    uint16_t crc;
    buf[0] = MT_SYNC0;
    buf[1] = MT_SYNC1;
    mt_packet_encode(p, buf + 2);
    crc = mt_crc16(buf + 2, MT_PACKET_SIZE);
    buf[2 + MT_PACKET_SIZE] = (uint8_t)crc;
    buf[3 + MT_PACKET_SIZE] = (uint8_t)(crc >> 8);
}

void mt_frame_parser_init(mt_frame_parser *fp)
{
    fp->n = 0;
    fp->bad_frames = 0;
}

int mt_frame_feed(mt_frame_parser *fp, uint8_t byte, mt_packet *p)
{
    if (fp->n == 0 && byte != MT_SYNC0) return 0;
    if (fp->n == 1 && byte != MT_SYNC1) {
        fp->n = (byte == MT_SYNC0) ? 1 : 0;
        return 0;
    }
    fp->buf[fp->n++] = byte;
    if (fp->n < MT_FRAME_SIZE) return 0;
    fp->n = 0;
    {
        uint16_t crc = mt_crc16(fp->buf + 2, MT_PACKET_SIZE);
        uint16_t got = (uint16_t)(fp->buf[2 + MT_PACKET_SIZE]
                                  | (fp->buf[3 + MT_PACKET_SIZE] << 8));
        if (crc != got || mt_packet_decode(fp->buf + 2, p) != 0) {
            int i;
            fp->bad_frames++;
            /* resynchronise: restart at the next sync pair inside the rejected bytes */
            for (i = 1; i < MT_FRAME_SIZE - 1; ++i) {
                if (fp->buf[i] == MT_SYNC0 && fp->buf[i + 1] == MT_SYNC1) {
                    int m = MT_FRAME_SIZE - i;
                    memmove(fp->buf, fp->buf + i, (unsigned)m);
                    fp->n = m;
                    break;
                }
            }
            return 0;
        }
    }
    return 1;
}

void mt_rng_seed(mt_rng *r, uint64_t seed)
{
    r->s = seed ? seed : 0x9E3779B97F4A7C15ull;
}

double mt_rng_uniform(mt_rng *r)
{
    uint64_t x = r->s;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    r->s = x;
    return (double)((x * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

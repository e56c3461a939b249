/* PIL firmware: the generated controller on an emulated LM3S6965 (docs/hil.md).
 *
 * UART0 (Stellaris, base 0x4000C000) carries the framed packets of mt_packet.h, polled
 * (no interrupts). At boot the firmware sends HELLO; it then answers each SAMPLE with a
 * COMMAND through ctrl_core.c, exactly as the host controller does. On STOP it writes one
 * JSON line of statistics and exits QEMU through ARM semihosting (SYS_WRITE0, SYS_EXIT).
 */
#include <stdint.h>

#include "ctrl_core.h"
#include "mt_packet.h"

#define UART0_BASE 0x4000C000u
#define UART_DR (*(volatile uint32_t *)(UART0_BASE + 0x000u))
#define UART_FR (*(volatile uint32_t *)(UART0_BASE + 0x018u))
#define UART_LCRH (*(volatile uint32_t *)(UART0_BASE + 0x02Cu))
#define UART_CTL (*(volatile uint32_t *)(UART0_BASE + 0x030u))
#define UART_IM (*(volatile uint32_t *)(UART0_BASE + 0x038u))
#define UART_ICR (*(volatile uint32_t *)(UART0_BASE + 0x044u))
#define NVIC_ISER0 (*(volatile uint32_t *)0xE000E100u)
#define NVIC_ICPR0 (*(volatile uint32_t *)0xE000E280u)
#define UART0_IRQ 5u
#define IM_RX (1u << 4)
#define FR_RXFE (1u << 4)
#define FR_TXFF (1u << 5)
#define LCRH_8N1_FIFO ((3u << 5) | (1u << 4))           /* 8 data bits, FIFOs on */
#define CTL_ENABLE ((1u << 0) | (1u << 8) | (1u << 9))   /* UARTEN, TXE, RXE */

static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void uart_put(uint8_t b)
{
    while (UART_FR & FR_TXFF) {
    }
    UART_DR = b;
}

/* Wait for a byte asleep: with interrupts masked (PRIMASK), a pending UART0 receive
 * interrupt still ends WFI, and QEMU's I/O thread runs while the core sleeps. */
static uint8_t uart_get(void)
{
    while (UART_FR & FR_RXFE) {
        UART_ICR = IM_RX;
        NVIC_ICPR0 = 1u << UART0_IRQ;
        if (UART_FR & FR_RXFE) __asm__ volatile("wfi" ::: "memory");
    }
    return (uint8_t)(UART_DR & 0xFFu);
}

static void send(const mt_packet *p)
{
    uint8_t f[MT_FRAME_SIZE];
    int i;
    mt_frame_encode(p, f);
    for (i = 0; i < MT_FRAME_SIZE; ++i) uart_put(f[i]);
}

static char *put_str(char *s, const char *t)
{
    while (*t) *s++ = *t++;
    return s;
}

static char *put_uint(char *s, uint32_t v)
{
    char tmp[12];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    while (n) *s++ = tmp[--n];
    return s;
}

static mt_ctrl ctrl;

int main(void)
{
    mt_frame_parser fp;
    mt_packet in, out;
    static char line[256];
    char *s;
    UART_LCRH = LCRH_8N1_FIFO;     /* with the FIFO off QEMU takes one byte per loop */
    UART_CTL = CTL_ENABLE;
    __asm__ volatile("cpsid i" ::: "memory");
    UART_IM = IM_RX;
    NVIC_ISER0 = 1u << UART0_IRQ;
    mt_frame_parser_init(&fp);
    if (mt_ctrl_init(&ctrl) != 0) {
        semihost(0x04, "{\"error\": \"controller init failed\"}\n");
        semihost(0x18, (const void *)0x20026);
    }
    out.type = MT_HELLO; out.flags = 0; out.seq = 0; out.a = 0.0; out.b = 0.0;
    send(&out);
    for (;;) {
        int r;
        if (!mt_frame_feed(&fp, uart_get(), &in)) continue;
        r = mt_ctrl_handle(&ctrl, &in, &out);
        if (r == 1) send(&out);
        if (r == 2) break;
    }
    s = line;
    s = put_str(s, "{\"samples\": ");
    s = put_uint(s, ctrl.samples);
    s = put_str(s, ", \"lost_samples\": ");
    s = put_uint(s, ctrl.lost_samples);
    s = put_str(s, ", \"stale_samples\": ");
    s = put_uint(s, ctrl.stale_samples);
    s = put_str(s, ", \"steps\": ");
    s = put_uint(s, ctrl.steps);
    s = put_str(s, ", \"bad_frames\": ");
    s = put_uint(s, fp.bad_frames);
    s = put_str(s, ", \"board\": \"lm3s6965evb\", \"stopped\": true}\n");
    *s = 0;
    semihost(0x04, line);
    semihost(0x18, (const void *)0x20026);    /* ADP_Stopped_ApplicationExit */
    for (;;) {
    }
}

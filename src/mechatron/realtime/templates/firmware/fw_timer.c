/* The reference firmware's board layer for a Cortex-M3 (TI Stellaris LM3S6965, the
 * board QEMU emulates as lm3s6965evb): SysTick at MT_FW_RATE Hz is the fixed-rate timer,
 * UART0 (0x4000C000) the serial line, polled between ticks. Everything else is mt_fw.c.
 *
 * Porting to another microcontroller (the seed used a PIC kit) means rewriting the four
 * functions marked BOARD below: the timer, the UART, and, for the wired set-up, the
 * encoder and the PWM (MT_FW_LOCAL: the controller runs on the board's own encoder count
 * and drives its PWM instead of talking over the serial line).
 */
#include <stdint.h>

#include "mt_fw.h"

#ifndef MT_FW_RATE
#define MT_FW_RATE 10000u            /* controller rate, Hz */
#endif
#ifndef MT_FW_CPU_HZ
#define MT_FW_CPU_HZ 12000000u       /* core clock feeding SysTick */
#endif

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define UART0_BASE 0x4000C000u
#define UART_DR (*(volatile uint32_t *)(UART0_BASE + 0x000u))
#define UART_FR (*(volatile uint32_t *)(UART0_BASE + 0x018u))
#define UART_LCRH (*(volatile uint32_t *)(UART0_BASE + 0x02Cu))
#define UART_CTL (*(volatile uint32_t *)(UART0_BASE + 0x030u))
#define FR_RXFE (1u << 4)
#define FR_TXFF (1u << 5)

static volatile uint32_t g_ticks;
static mt_fw fw;
volatile double mt_fw_duty;          /* BOARD: the PWM compare value would be set here */

void SysTick_Handler(void);
void SysTick_Handler(void)
{
    g_ticks++;
}

/* BOARD: timer */
static void timer_start(void)
{
    SYST_RVR = MT_FW_CPU_HZ / MT_FW_RATE - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 7u;                   /* processor clock, interrupt, enable */
}

/* BOARD: serial line */
static void uart_start(void)
{
    UART_LCRH = (3u << 5) | (1u << 4);                /* 8 data bits, FIFOs on */
    UART_CTL = (1u << 0) | (1u << 8) | (1u << 9);     /* UARTEN, TXE, RXE */
}

static void uart_send(const uint8_t *b, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        while (UART_FR & FR_TXFF) {
        }
        UART_DR = b[i];
    }
}

/* BOARD: encoder count of the quadrature decoder (wired set-up only) */
static double encoder_count(void)
{
    return 0.0;
}

int main(void)
{
    uint8_t frame[MT_FRAME_SIZE];
    uint32_t seen = 0;
    mt_fw_init(&fw);
    uart_start();
    mt_fw_hello(frame);
    uart_send(frame, MT_FRAME_SIZE);
    timer_start();
    for (;;) {
        while (seen == g_ticks) {            /* between ticks: take the bytes that come */
            if (!(UART_FR & FR_RXFE)) mt_fw_rx(&fw, (uint8_t)(UART_DR & 0xFFu));
        }
        seen = g_ticks;
#ifdef MT_FW_LOCAL
        mt_fw_duty = mt_fw_tick_local(&fw, encoder_count());
#else
        (void)encoder_count;
        if (mt_fw_tick(&fw, frame)) uart_send(frame, MT_FRAME_SIZE);
#endif
    }
}

/* Reference firmware core for the microcontroller side of the HIL link (docs/hil.md,
 * "Reference firmware"). Freestanding C99, no OS, no dynamic memory: the board file
 * calls it from its UART receive path and from a fixed-rate timer.
 *
 *   mt_fw_rx(fw, byte)        every byte from the serial line (interrupt or polling):
 *                             the frame parser (mt_packet.c) keeps the newest SAMPLE;
 *   mt_fw_tick(fw, frame)     at every timer tick: when a new sample came since the last
 *                             tick, one step of the generated controller (ctrl_core.c,
 *                             hilctrl.c from mechatron.codegen) and a COMMAND frame to
 *                             send; steps whose samples never came are filled in by the
 *                             controller (valid = 0), so it stays on the plant's clock;
 *   mt_fw_tick_local(fw, c)   the same step with the board's own encoder count (a
 *                             quadrature decoder peripheral), for the wired set-up of
 *                             the seed: the returned duty goes to the PWM.
 */
#ifndef MT_FW_H
#define MT_FW_H

#include <stdint.h>

#include "ctrl_core.h"
#include "mt_packet.h"

typedef struct {
    mt_ctrl ctrl;              /* the generated controller and its bookkeeping */
    mt_frame_parser parser;
    mt_packet sample;          /* the newest SAMPLE received */
    int fresh;                 /* sample not yet used by a tick */
    int stop;                  /* STOP received */
    uint32_t ticks;            /* timer ticks */
    uint32_t idle_ticks;       /* ticks without a new sample */
    uint32_t overwritten;      /* samples replaced by a newer one before a tick */
    uint32_t local_seq;        /* step counter of mt_fw_tick_local */
} mt_fw;

void mt_fw_init(mt_fw *fw);
/* The HELLO frame a board sends once at start. */
void mt_fw_hello(uint8_t frame[MT_FRAME_SIZE]);
void mt_fw_rx(mt_fw *fw, uint8_t byte);
/* Returns 1 with a COMMAND frame in `frame` to send, else 0. */
int mt_fw_tick(mt_fw *fw, uint8_t frame[MT_FRAME_SIZE]);
/* One controller step on a local encoder count; returns the duty in [0, 1]. */
double mt_fw_tick_local(mt_fw *fw, double count);

#endif

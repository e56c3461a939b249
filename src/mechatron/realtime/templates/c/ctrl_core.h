/* The controller side of the HIL bridge, shared by the host controller process (SIL) and
 * the firmware (PIL): sequence-number bookkeeping, gap filling, one generated ctrl_step
 * per plant step. Freestanding C99. */
#ifndef MT_CTRL_CORE_H
#define MT_CTRL_CORE_H

#include <stdint.h>

#include "mt_packet.h"

#define MT_CTRL_MAX_STATES 64
#define MT_CTRL_MAX_GAP 1000     /* a larger jump in seq restarts the sequence */

typedef struct {
    double xc[MT_CTRL_MAX_STATES];
    int nxc;
    uint32_t expected;       /* next seq the controller expects */
    int started;
    uint32_t samples;        /* samples received */
    uint32_t lost_samples;   /* seq numbers never received (filled by extrapolation) */
    uint32_t stale_samples;  /* samples older than one already handled (ignored) */
    uint32_t steps;          /* ctrl_step calls */
    double last_duty;
    double last_ref;
} mt_ctrl;

/* Load the start state (generated ctrl_x0); returns 0, or -1 if the state is too large. */
int mt_ctrl_init(mt_ctrl *c);
/* Handle one packet. For a SAMPLE: run the controller for every step up to its seq
 * (filling lost ones) and write the COMMAND reply to *out; returns 1. Returns 0 when
 * nothing is to be sent (stale sample, other packet types), 2 for STOP. */
int mt_ctrl_handle(mt_ctrl *c, const mt_packet *in, mt_packet *out);

#endif

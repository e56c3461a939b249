/* The controller side of the HIL bridge, shared by the host controller process (SIL) and
 * the firmware (PIL): sequence-number bookkeeping, gap filling, one step of the generated
 * controller model (hilctrl.h, written by mechatron.codegen) per plant step.
 * Freestanding C99. */
#ifndef MT_CTRL_CORE_H
#define MT_CTRL_CORE_H

#include <stdint.h>

#include "hilctrl.h"
#include "mt_packet.h"

#define MT_CTRL_MAX_GAP 1000     /* a larger jump in seq restarts the sequence */

typedef struct {
    hilctrl_model model;     /* the generated controller: all its memory */
    uint32_t expected;       /* next seq the controller expects */
    int started;
    uint32_t samples;        /* samples received */
    uint32_t lost_samples;   /* seq numbers never received (filled by extrapolation) */
    uint32_t stale_samples;  /* samples older than one already handled (ignored) */
    uint32_t steps;          /* controller steps */
    uint32_t bad_inputs;     /* inputs the generated setters refused (never expected) */
    double last_duty;
    double last_ref;
} mt_ctrl;

/* Initialize the generated model (its start state); returns 0. */
int mt_ctrl_init(mt_ctrl *c);
/* Handle one packet. For a SAMPLE: run the controller for every step up to its seq
 * (filling lost ones) and write the COMMAND reply to *out; returns 1. Returns 0 when
 * nothing is to be sent (stale sample, other packet types), 2 for STOP. */
int mt_ctrl_handle(mt_ctrl *c, const mt_packet *in, mt_packet *out);

#endif

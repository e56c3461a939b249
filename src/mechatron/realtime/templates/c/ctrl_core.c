/* Controller core: see ctrl_core.h. */
#include "ctrl_core.h"

int mt_ctrl_init(mt_ctrl *c)
{
    hilctrl_init(&c->model);
    c->expected = 0;
    c->started = 0;
    c->samples = c->lost_samples = c->stale_samples = c->steps = c->bad_inputs = 0;
    c->last_duty = hilctrl_get_duty_y(&c->model);
    c->last_ref = hilctrl_get_ref_y(&c->model);
    return 0;
}

/* Step k of the plant: the model's inputs are set, its step counter is put on the plant's
 * time base (its step k runs from t0 + k DT = (k-1) DT to k DT, and the sample tick at
 * k DT reads the inputs), and one fixed step is taken. */
static void run_step(mt_ctrl *c, double count, uint32_t k, int valid)
{
    if (hilctrl_set_count_value(&c->model, count) != HILCTRL_OK) c->bad_inputs++;
    if (hilctrl_set_valid_value(&c->model, valid ? 1.0 : 0.0) != HILCTRL_OK) c->bad_inputs++;
    c->model.k = (unsigned long)k;
    (void)hilctrl_step(&c->model);
    c->last_duty = hilctrl_get_duty_y(&c->model);
    c->last_ref = hilctrl_get_ref_y(&c->model);
    c->steps++;
}

int mt_ctrl_handle(mt_ctrl *c, const mt_packet *in, mt_packet *out)
{
    uint32_t k;
    uint8_t flags = 0;
    if (in->type == MT_STOP) return 2;
    if (in->type != MT_SAMPLE) return 0;
    if (!c->started || in->seq - c->expected > MT_CTRL_MAX_GAP) {
        c->started = 1;          /* first sample, or a restart: take its seq as the start */
        c->expected = in->seq;
    }
    if (in->seq < c->expected) {
        c->stale_samples++;
        return 0;
    }
    c->samples++;
    for (k = c->expected; k < in->seq; ++k) {   /* lost samples: extrapolate the count */
        run_step(c, 0.0, k, 0);
        c->lost_samples++;
        flags = 1;
    }
    run_step(c, in->a, in->seq, 1);
    c->expected = in->seq + 1;
    out->type = MT_COMMAND;
    out->flags = flags;
    out->seq = in->seq;
    out->a = c->last_duty;
    out->b = c->last_ref;
    return 1;
}

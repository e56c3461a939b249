/* Controller core: see ctrl_core.h. */
#include "ctrl_core.h"

#include "ctrl_model.h"
#include "mt_casadi.h"

int mt_ctrl_init(mt_ctrl *c)
{
    casadi_real *res[1];
    int i;
    c->nxc = MT_DIM_OUT(ctrl_step, 0);
    if (c->nxc > MT_CTRL_MAX_STATES || MT_DIM_OUT(ctrl_x0, 0) != c->nxc) return -1;
    res[0] = c->xc;
    MT_CALL(ctrl_x0, (const casadi_real **)0, res);
    for (i = c->nxc; i < MT_CTRL_MAX_STATES; ++i) c->xc[i] = 0.0;
    c->expected = 0;
    c->started = 0;
    c->samples = c->lost_samples = c->stale_samples = c->steps = 0;
    c->last_duty = 0.5;
    c->last_ref = 0.0;
    return 0;
}

static void run_step(mt_ctrl *c, double count, uint32_t k, int valid)
{
    double xn[MT_CTRL_MAX_STATES];
    double out[4];
    double kk = (double)k, vv = valid ? 1.0 : 0.0;
    const casadi_real *arg[4];
    casadi_real *res[2];
    int i;
    arg[0] = c->xc; arg[1] = &count; arg[2] = &kk; arg[3] = &vv;
    res[0] = xn; res[1] = out;
    MT_CALL(ctrl_step, arg, res);
    for (i = 0; i < c->nxc; ++i) c->xc[i] = xn[i];
    c->last_duty = out[0];
    c->last_ref = out[1];
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

/* Reference firmware core: see mt_fw.h. */
#include "mt_fw.h"

void mt_fw_init(mt_fw *fw)
{
    mt_ctrl_init(&fw->ctrl);
    mt_frame_parser_init(&fw->parser);
    fw->fresh = 0;
    fw->stop = 0;
    fw->ticks = fw->idle_ticks = fw->overwritten = fw->local_seq = 0;
}

void mt_fw_hello(uint8_t frame[MT_FRAME_SIZE])
{
    mt_packet p;
    p.type = MT_HELLO; p.flags = 0; p.seq = 0; p.a = 0.0; p.b = 0.0;
    mt_frame_encode(&p, frame);
}

void mt_fw_rx(mt_fw *fw, uint8_t byte)
{
    mt_packet p;
    if (!mt_frame_feed(&fw->parser, byte, &p)) return;
    if (p.type == MT_SAMPLE) {
        if (fw->fresh) fw->overwritten++;
        fw->sample = p;
        fw->fresh = 1;
    } else if (p.type == MT_STOP) {
        fw->stop = 1;
    }
}

int mt_fw_tick(mt_fw *fw, uint8_t frame[MT_FRAME_SIZE])
{
    mt_packet cmd;
    fw->ticks++;
    if (!fw->fresh) {
        fw->idle_ticks++;
        return 0;
    }
    fw->fresh = 0;
    if (mt_ctrl_handle(&fw->ctrl, &fw->sample, &cmd) != 1) return 0;
    mt_frame_encode(&cmd, frame);
    return 1;
}

double mt_fw_tick_local(mt_fw *fw, double count)
{
    mt_packet s, cmd;
    s.type = MT_SAMPLE; s.flags = 0; s.seq = fw->local_seq++; s.a = count; s.b = 0.0;
    fw->ticks++;
    (void)mt_ctrl_handle(&fw->ctrl, &s, &cmd);
    return fw->ctrl.last_duty;
}

/* Start-up code of the PIL firmware for the LM3S6965 (Cortex-M3): the vector table and a
 * reset handler that copies .data from flash, clears .bss and calls main(). */
#include <stdint.h>

extern uint32_t _data_load, _data_start, _data_end, _bss_start, _bss_end, _stack_top;
int main(void);
void Reset_Handler(void);
void Default_Handler(void);
/* The fixed-rate firmware (fw_timer.c) defines its own; the others keep the default. */
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));

void Default_Handler(void)
{
    for (;;) {
    }
}

void Reset_Handler(void)
{
    uint32_t *src = &_data_load, *dst = &_data_start;
    while (dst < &_data_end) *dst++ = *src++;
    for (dst = &_bss_start; dst < &_bss_end; ++dst) *dst = 0;
    (void)main();
    for (;;) {
    }
}

/* Initial stack pointer, then reset, NMI, hard fault, and the rest of the core vectors. */
__attribute__((section(".isr_vector"), used))
void (*const vector_table[16])(void) = {
    (void (*)(void))(&_stack_top), Reset_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler, 0, 0, 0, 0,
    Default_Handler, Default_Handler, 0, Default_Handler, SysTick_Handler,
};

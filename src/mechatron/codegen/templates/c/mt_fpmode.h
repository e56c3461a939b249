/* mt_fpmode.h: subnormal numbers flushed to zero, as Mechatron's desktop solvers run.
 *
 * A long network keeps many of its far states below the smallest normal double
 * (2.2e-308); many processors compute about a hundred times slower on such operands, which
 * a real-time loop meets as overruns. Mechatron's desktop solvers flush them to zero
 * (mechatron.solvers.fpenv); a program that calls mt_flush_subnormals() once, before its
 * first step, computes the desktop's numbers bit for bit and in steady time. The setting
 * belongs to the calling thread. Where the processor has no such mode (or it is unknown
 * here: a Cortex-M3 computes in software) the call does nothing and the arithmetic keeps
 * its subnormals: results then differ from the desktop's only below about 1e-290.
 */
#ifndef MT_FPMODE_H
#define MT_FPMODE_H

#if defined(__SSE2__) || defined(__x86_64__) || defined(_M_X64)
#include <xmmintrin.h>
static void mt_flush_subnormals(void)
{
    _mm_setcsr(_mm_getcsr() | 0x8040u);     /* MXCSR: FTZ (bit 15) | DAZ (bit 6) */
}
#elif defined(__aarch64__)
static void mt_flush_subnormals(void)
{
    unsigned long fpcr;
    __asm__ __volatile__("mrs %0, fpcr" : "=r"(fpcr));
    fpcr |= 1ul << 24;                       /* FPCR.FZ */
    __asm__ __volatile__("msr fpcr, %0" : : "r"(fpcr));
}
#elif defined(__ARM_FP) && !defined(__SOFTFP__)
static void mt_flush_subnormals(void)
{
    unsigned int fpscr;
    __asm__ __volatile__("vmrs %0, fpscr" : "=r"(fpscr));
    fpscr |= 1u << 24;                       /* FPSCR.FZ */
    __asm__ __volatile__("vmsr fpscr, %0" : : "r"(fpscr));
}
#else
static void mt_flush_subnormals(void)
{
}
#endif

#endif

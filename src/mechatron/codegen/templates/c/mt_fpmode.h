/* mt_fpmode.h: subnormal numbers flushed to zero, as Mechatron's desktop solvers run.
 *
 * A long network keeps many of its far states below the smallest normal double
 * (2.2e-308); many processors compute about a hundred times slower on such operands, which
 * a real-time loop meets as overruns. Mechatron's desktop solvers flush them to zero
 * (mechatron.solvers.fpenv); a program that calls mt_flush_subnormals() once, before its
 * first step, computes the desktop's numbers bit for bit and in steady time. Code that
 * runs in someone else's thread (an FMU's step in its host) flushes for the call only:
 * mt_fpmode_flush() before, mt_fpmode_restore() after. The setting belongs to the calling
 * thread. Where the processor has no such mode (or it is unknown here: a Cortex-M3
 * computes in software) the calls do nothing and the arithmetic keeps its subnormals:
 * results then differ from the desktop's only below about 1e-290.
 */
#ifndef MT_FPMODE_H
#define MT_FPMODE_H

#if defined(__SSE2__) || defined(__x86_64__) || defined(_M_X64)
#include <xmmintrin.h>
#define MT_FPMODE_BITS 0x8040ul             /* MXCSR: FTZ (bit 15) | DAZ (bit 6) */
static inline unsigned long mt_fpmode_get(void) { return _mm_getcsr(); }
static inline void mt_fpmode_set(unsigned long mode) { _mm_setcsr((unsigned int)mode); }
#elif defined(__aarch64__)
#define MT_FPMODE_BITS (1ul << 24)          /* FPCR.FZ */
static inline unsigned long mt_fpmode_get(void)
{
    unsigned long fpcr;
    __asm__ __volatile__("mrs %0, fpcr" : "=r"(fpcr));
    return fpcr;
}
static inline void mt_fpmode_set(unsigned long mode)
{
    __asm__ __volatile__("msr fpcr, %0" : : "r"(mode));
}
#elif defined(__ARM_FP) && !defined(__SOFTFP__)
#define MT_FPMODE_BITS (1ul << 24)          /* FPSCR.FZ */
static inline unsigned long mt_fpmode_get(void)
{
    unsigned int fpscr;
    __asm__ __volatile__("vmrs %0, fpscr" : "=r"(fpscr));
    return fpscr;
}
static inline void mt_fpmode_set(unsigned long mode)
{
    unsigned int fpscr = (unsigned int)mode;
    __asm__ __volatile__("vmsr fpscr, %0" : : "r"(fpscr));
}
#else
#define MT_FPMODE_BITS 0ul
static inline unsigned long mt_fpmode_get(void) { return 0ul; }
static inline void mt_fpmode_set(unsigned long mode) { (void)mode; }
#endif

/* Flush from now on: a program's main, before its first step. */
static inline void mt_flush_subnormals(void)
{
    mt_fpmode_set(mt_fpmode_get() | MT_FPMODE_BITS);
}

/* Flush for one call: returns the caller's mode, to give back with mt_fpmode_restore. */
static inline unsigned long mt_fpmode_flush(void)
{
    unsigned long mode = mt_fpmode_get();
    mt_fpmode_set(mode | MT_FPMODE_BITS);
    return mode;
}

/* The caller's flush bits back; the exception flags raised meanwhile stay raised. */
static inline void mt_fpmode_restore(unsigned long mode)
{
    mt_fpmode_set((mt_fpmode_get() & ~MT_FPMODE_BITS) | (mode & MT_FPMODE_BITS));
}

#endif

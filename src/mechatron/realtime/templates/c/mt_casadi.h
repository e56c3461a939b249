/* Calling CasADi-generated functions (f(arg, res, iw, w, mem)) with static work arrays.
 * Freestanding C99: used by the host programs and the firmware. */
#ifndef MT_CASADI_H
#define MT_CASADI_H

/* Number of rows of input i / output i of generated function f (dense column vectors). */
#define MT_DIM_IN(f, i) ((int)f##_sparsity_in(i)[0])
#define MT_DIM_OUT(f, i) ((int)f##_sparsity_out(i)[0])

/* Call f with argument and result pointer arrays; work arrays sized by the generated
 * f_SZ_* macros (at least one element each, C99 has no zero-length arrays). */
#define MT_CALL(f, args, ress)                                                    \
    do {                                                                          \
        static casadi_int mt_iw_[f##_SZ_IW + 1];                                  \
        static casadi_real mt_w_[f##_SZ_W + 1];                                   \
        f((args), (ress), mt_iw_, mt_w_, 0);                                      \
    } while (0)

#endif

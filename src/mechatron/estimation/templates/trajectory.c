/* Mechatron: the time loop of a sampled trajectory (mechatron.estimation.discretize).

   Appended to the C that CasADi generates for two functions of the trajectory:
     mt_step(xa, [p; u_k; u_k+1; h_k; t_k]) -> (xa_k+1, e_k)   one sample interval
     mt_outputs(t_k, xa_k, p, u_k) -> (y_k[, dy_k])            the outputs at a sample
   and the sizes, defined before this file: MT_NXA (integration state), MT_NP
   (parameters), MT_NU (inputs), MT_NE (convergence measure), MT_NY0 and MT_NY1 (the
   outputs; MT_NY1 is 0 without sensitivities), MT_SZ_ARG, MT_SZ_RES, MT_SZ_IW, MT_SZ_W
   (the work of either function, the larger).

   All arrays are row-major with one row per sample: U (N x MT_NU), XS (N x MT_NXA),
   Y0 (N x MT_NY0), Y1 (N x MT_NY1), E (N-1 x MT_NE). The arguments of a step are the
   ones CasADi's mapaccum would pass, computed the same way, so the numbers are the
   same. Returns 0; k + 1 if the step from sample k failed; N + k + 1 if the outputs
   at sample k failed; -1 if memory ran out. */

#include <stdlib.h>

#define MT_NA (MT_NP + 2 * MT_NU + 2)

int mt_trajectory(long n, const double *xa0, const double *p, const double *u,
                  const double *t, double *xs, double *y0, double *y1, double *e) {
  const casadi_real *arg[MT_SZ_ARG];
  casadi_real *res[MT_SZ_RES];
  casadi_int *iw = (casadi_int *)malloc(sizeof(casadi_int) * (MT_SZ_IW + 1));
  casadi_real *w = (casadi_real *)malloc(sizeof(casadi_real) * (MT_SZ_W + 1));
  double a[MT_NA + 1], tk;
  long k;
  int i, status = 0;
  if (!iw || !w) {
    free(iw);
    free(w);
    return -1;
  }
  for (i = 0; i < MT_NXA; ++i) xs[i] = xa0[i];
  for (i = 0; i < MT_NP; ++i) a[i] = p[i];
  for (k = 0; k + 1 < n; ++k) {
    for (i = 0; i < MT_NU; ++i) {
      a[MT_NP + i] = u[k * MT_NU + i];
      a[MT_NP + MT_NU + i] = u[(k + 1) * MT_NU + i];
    }
    a[MT_NP + 2 * MT_NU] = t[k + 1] - t[k];
    a[MT_NP + 2 * MT_NU + 1] = t[k];
    arg[0] = xs + k * MT_NXA;
    arg[1] = a;
    res[0] = xs + (k + 1) * MT_NXA;
    res[1] = e + k * MT_NE;
    if (mt_step(arg, res, iw, w, 0)) {
      status = (int)(k + 1);
      goto done;
    }
  }
  for (k = 0; k < n; ++k) {
    tk = t[k];
    arg[0] = &tk;
    arg[1] = xs + k * MT_NXA;
    arg[2] = p;
    arg[3] = u + k * MT_NU;
    res[0] = MT_NY0 ? y0 + k * MT_NY0 : 0;
    res[1] = MT_NY1 ? y1 + k * MT_NY1 : 0;
    if (mt_outputs(arg, res, iw, w, 0)) {
      status = (int)(n + k + 1);
      goto done;
    }
  }
done:
  free(iw);
  free(w);
  return status;
}

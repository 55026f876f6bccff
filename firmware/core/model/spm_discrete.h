/*
 * spm_discrete.h - exact discretisation of the SPM current dynamics in a
 * generic (x, y) frame rotating at omega_xy (Rubino 2020, eqs. (6)-(15)):
 *
 *   i(k+1) = A_d i(k) + b_d u(k),  A_d = e^{A Ts},  b_d = int_0^Ts e^{A t} b dt
 *   u_xy   = v_xy - j omega_r lambda_m,xy                      (eq. (8))
 *
 * A_d and b_d have the rotation-matrix structure of (13): [[c_xx, c_xy],
 * [-c_xy, c_xx]]. The generic (x, y) vectors use dq_t (d = x, q = y).
 * The omega-independent preliminaries f_s, k_s (eq. (12)) and the
 * stationary-frame gain b_ab = (1 - k_s)/Rs are computed once at init;
 * spm_discrete_coef() evaluates (14)-(15) for a given omega_xy.
 * Numerics: 1 - k_s is computed with expm1f and 1 - a_xx as
 * (1 - k_s) + 2 k_s sin^2(phi/2), so no cancellation at small f_s Ts.
 */
#ifndef FD_MODEL_SPM_DISCRETE_H
#define FD_MODEL_SPM_DISCRETE_H

#include "math/frames.h"

typedef struct {
  float rs; /* stator resistance [Ohm], > 0 */
  float ls; /* stator inductance [H], > 0 */
  float ts; /* sampling period [s], > 0 */
  /* derived at init (eq. (12) with omega_xy = 0) */
  float fs;          /* Rs/Ls [1/s] */
  float ks;          /* exp(-fs Ts) */
  float one_minus_k; /* 1 - ks */
  float b_ab;        /* (1 - ks)/Rs: b_xx for omega_xy = 0 [A/(V)] */
} spm_discrete_t;

/* Coefficients of (13): A_d = [[a_xx, a_xy], [-a_xy, a_xx]], b_d likewise. */
typedef struct {
  float a_xx, a_xy; /* eq. (14) */
  float b_xx, b_xy; /* eq. (15) [A/V] */
} spm_discrete_coef_t;

/* Returns 0, or -1 (m left zeroed) when rs, ls or ts is not finite and > 0. */
int spm_discrete_init(spm_discrete_t *m, float rs, float ls, float ts);
/* Recomputes the derived constants from rs, ls, ts (no dynamic state). */
void spm_discrete_reset(spm_discrete_t *m);
/* Eqs. (12), (14), (15) for a frame rotating at omega_xy [rad/s]. */
spm_discrete_coef_t spm_discrete_coef(const spm_discrete_t *m, float omega_xy);
/* The same, also giving rot = e^{j phi}, phi = omega_xy Ts, from the same
 * sin/cos evaluation (the frame's rotation over one period), and half =
 * e^{j phi/2}, the evaluation itself (the DFVC's output rotation by half a
 * period reuses it: dfvc.c). */
spm_discrete_coef_t spm_discrete_coef_rot(const spm_discrete_t *m, float omega_xy, sincos_t *rot,
                                          sincos_t *half);
/* Eq. (10): i(k+1) = A_d i(k) + b_d u(k); u from eq. (8). */
dq_t spm_discrete_step(const spm_discrete_coef_t *c, dq_t i, dq_t u);

#endif

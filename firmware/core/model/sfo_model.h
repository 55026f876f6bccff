/*
 * sfo_model.h - the saturated synchronous machine seen from the stator-flux
 * frame (f, tau): the quantities of Varatharajan, Pellegrino, Armando,
 * "Direct Flux Vector Control of Synchronous Motor Drives: Accurate
 * Decoupled Control with Online Adaptive MTPA and MTPV Evaluation", IEEE
 * TIE 69(2), 2022, each a small function of the flux lambda_dq, the current
 * i_dq and the incremental inductance matrix L_d (eq. (2), from the map by
 * finite differences, (25): machine_inductance()).
 *
 * Frame convention. The paper writes the SyR convention (d on the maximum
 * inductance, PM on -q); fluxdrive's rotor frame has d on the PM flux / the
 * minimum inductance (model/machine.h). The two differ by a proper rotation
 * of 90 degrees (x_fd = J x_SyR, L_fd = J L_SyR J^T, delta_fd = delta_SyR +
 * pi/2), under which J, inner products and x^T J y are invariant, so:
 *   (6), (7), (9), (10), (22) (a and b), (23), (32), (34): as printed, no
 *     sign changes (a = u_tau^T L_d^-1 u_f, b = lambda^T J i^a / lambda^2
 *     are frame-free; (22)'s a in l_d, l_q, l_dq and delta takes the same
 *     form in either frame because l_Delta, l_dq and sin 2 delta, cos 2 delta
 *     all change sign together);
 *   (14)-(17), written with the apparent inductances and the PM on -q,
 *     change: with the PM on +d, i_tau = lambda sin(2 delta)/2 (L_d - L_q) /
 *     (L_d L_q) + sin(delta) lambda_m / L_d, so
 *       a' = sin(2 delta)/2 (L_d - L_q)/(L_d L_q)                 (17), as printed
 *       b' = cos(2 delta) (L_d - L_q)/(L_d L_q)
 *            + cos(delta) lambda_m / (lambda L_d)     (17): -sin(delta)/L_q -> cos(delta)/L_d
 *     (delta the fluxdrive load angle, from the PM (d) axis).
 * J = [0 -1; 1 0]: J x = (-x_q, x_d); x^T J y = x_q y_d - x_d y_q.
 *
 * Torque sign. Mirroring q (negative torque) maps lambda^a -> -M lambda^a
 * and i^a -> -M i^a (M = diag(1, -1)): (7), (10), a, b are unchanged, and
 * the auxiliary vectors turn antiparallel to i and lambda. So the phase
 * conditions "in phase" of (7), (10) are taken on the line, modulo pi
 * (sfo_line_angle()), for both torque signs.
 */
#ifndef FD_MODEL_SFO_MODEL_H
#define FD_MODEL_SFO_MODEL_H

#include "math/frames.h"
#include "model/machine.h"

/* The gains of the torque-current loop, s i_tau = a s lambda + b lambda s delta (21). */
typedef struct {
  float a; /* cross-coupling gain [1/H] */
  float b; /* self-axis gain [1/H] */
} sfo_gains_t;

/* J x */
static inline dq_t sfo_j(dq_t x) {
  return (dq_t){-x.q, x.d};
}
/* x^T J y */
static inline float sfo_cross(dq_t x, dq_t y) {
  return x.q * y.d - x.d * y.q;
}

/* Auxiliary-flux vector (6): lambda^a = J lambda - L_d J i [Vs]. */
static inline dq_t sfo_aux_flux(dq_t lambda, dq_t i, machine_ldq_t l) {
  const dq_t ji = sfo_j(i);
  const dq_t jl = sfo_j(lambda);
  return (dq_t){jl.d - (l.dd * ji.d + l.dq * ji.q), jl.q - (l.qd * ji.d + l.qq * ji.q)};
}
/* MTPA condition (7): (lambda^a)^T J i, zero on the MTPA trajectory; the
 * torque derivative dT/dgamma of (5) is 3p/2 times it [Vs A]. */
static inline float sfo_mtpa_cross(dq_t lambda_a, dq_t i) {
  return sfo_cross(lambda_a, i);
}
/* Auxiliary-current vector (9): i^a = J i - L_d^-1 J lambda [A]; a singular
 * L_d (det <= 0) gives (0, 0). Inline, as sfo_gain_a (a call of each cost
 * the decoupled DFVC's ISR more than its body, PIL). */
static inline dq_t sfo_aux_current(dq_t lambda, dq_t i, machine_ldq_t l) {
  const float det = l.dd * l.qq - l.dq * l.qd;
  if (!(det > 0.0f)) {
    return (dq_t){0.0f, 0.0f};
  }
  /* Varatharajan 2022, eq. (9): J i - L^-1 J lambda */
  const dq_t ji = sfo_j(i);
  const dq_t jl = sfo_j(lambda);
  const float inv = 1.0f / det;
  return (dq_t){ji.d - inv * (l.qq * jl.d - l.dq * jl.q), ji.q - inv * (l.dd * jl.q - l.qd * jl.d)};
}
/* MTPV condition (10): lambda^T J i^a, zero on the MTPV trajectory; dT/ddelta
 * of (8) is 3p/2 times it [Vs A]. */
static inline float sfo_mtpv_cross(dq_t lambda, dq_t i_a) {
  return sfo_cross(lambda, i_a);
}
/* Angle between the lines of x and y, in [0, pi/2] [rad]: |angle(y) - angle(x)|
 * modulo pi (the phase error of (7) with x = i, y = lambda^a; of (33), (34)
 * with x = lambda, y = i^a). */
float sfo_line_angle(dq_t x, dq_t y);
/* The proposed gains (22): a = (l_Delta sin 2delta - l_dq cos 2delta) /
 * (l_d l_q - l_dq^2), b = lambda^T J i^a / lambda^2, delta the angle of
 * lambda (l_dq the mean of the two off-diagonal terms). A vanishing flux or
 * a singular L_d gives (0, 0). */
sfo_gains_t sfo_gains(dq_t lambda, dq_t i, machine_ldq_t l);
/* The cross-coupling gain a of (22) alone (b = sfo_mtpv_cross / lambda^2). */
static inline float sfo_gain_a(dq_t lambda, machine_ldq_t l) {
  const float l2 = lambda.d * lambda.d + lambda.q * lambda.q;
  const float ldq = 0.5f * (l.dq + l.qd);
  const float det = l.dd * l.qq - ldq * ldq;
  if (!(l2 > 1e-12f) || !(det > 0.0f)) {
    return 0.0f;
  }
  /* sin 2delta, cos 2delta from the flux components */
  const float s2 = 2.0f * lambda.d * lambda.q / l2;
  const float c2 = (lambda.d * lambda.d - lambda.q * lambda.q) / l2;
  const float l_delta = 0.5f * (l.dd - l.qq);
  /* Varatharajan 2022, eq. (22), a */
  return (l_delta * s2 - ldq * c2) / det;
}
/* The state-of-the-art gains (17) in the fluxdrive frame (header) from the
 * flux amplitude lambda, the load angle (sin, cos) and the apparent
 * inductances L_d, L_q [H] with the PM flux lambda_m [Vs]. */
sfo_gains_t sfo_gains_sota(float lambda, sincos_t sc_delta, float l_app_d, float l_app_q,
                           float lambda_m);
/* Apparent inductances of (3) at i from the current-model flux lambda_i =
 * Lambda(i): L_d = (lambda_d - lambda_m)/i_d, L_q = lambda_q / i_q, each
 * replaced by the given fallback (the unsaturated value) where its current
 * is below i_min in magnitude (the ratio is 0/0 there). */
void sfo_apparent(dq_t lambda_i, dq_t i, float lambda_m, float i_min, float l0_d, float l0_q,
                  float *l_d, float *l_q);
/* The transformation (23) applied to a vector (x_f, x_tau) of the controlled
 * variables' rates: (x_f, (x_tau - a x_f) / b). b must not be 0 (callers
 * floor it: the MTPV margin). */
static inline dq_t sfo_transform(sfo_gains_t g, dq_t x) {
  return (dq_t){x.d, (x.q - g.a * x.d) / g.b};
}
/* Its inverse (21): (y_f, a y_f + b y_tau). */
static inline dq_t sfo_transform_inv(sfo_gains_t g, dq_t y) {
  return (dq_t){y.d, g.a * y.d + g.b * y.q};
}

#endif

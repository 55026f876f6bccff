/*
 * kf_mech.h - the linear Kalman filter on the rotor's mechanics (Fabbri
 * 2022, section 4.1.1 and 4.1.4): state x = (omega_e, theta_e, T_l), the
 * electrical speed, the electrical angle and the load torque, input the
 * electromagnetic torque, measurement the angle of a position algorithm
 * (DFC or IVD).
 *
 * Model (4.46)-(4.48), with the pole pairs p made explicit (the thesis
 * writes the torque in electrical units) and the mechanical equation
 * J dw_m/dt = T_e - T_l - B w_m:
 *   omega(k+1) = (1 - T B/J) omega(k) + T p/J (T_e(k) - T_l(k))
 *   theta(k+1) = theta(k) + T omega(k)                 (wrapped to (-pi, pi])
 *   T_l(k+1)   = T_l(k)                                 (4.45)
 * Prediction (4.15)-(4.16): x- = F x + G u, P- = F P F^T + Q (the printed
 * (4.16) transposes F: a typo; the covariance propagates as F P F^T).
 * Update (4.17)-(4.20) with H = [0 1 0]: the innovation wrapped to
 * (-pi, pi], K = P- H^T / (H P- H^T + R), and the covariance in Joseph
 * form P+ = (I - K H) P- (I - K H)^T + K R K^T, kept symmetric by storing
 * its upper triangle (no loss of positive definiteness in float).
 * R: the caller's (R_k of (4.29)/(4.31), or the speed-dependent (4.42)/
 * (4.43): kf_mech_r_speed). Q: diagonal (4.49), (5.1) by default.
 * Fixed size, no allocation, no libm (the angle wrap is a compare and an
 * add).
 */
#ifndef FD_ESTIMATION_KF_MECH_H
#define FD_ESTIMATION_KF_MECH_H

#include <math.h>
#include <stdbool.h>

typedef struct {
  float ts;         /* period T [s] */
  float pole_pairs; /* p */
  float inertia;    /* J [kg m^2] */
  float friction;   /* B [N m s/rad] */
  float q[3];       /* Q diagonal (4.49): omega [(rad/s)^2], theta [rad^2], T_l [(N m)^2] */
} kf_mech_cfg_t;

typedef struct {
  kf_mech_cfg_t cfg;
  float f11, f13, g1; /* F and G of (4.48) */
  float x[3];         /* omega_e [rad/s], theta_e [rad], T_l [N m] */
  float p[6];         /* P upper triangle: p11 p12 p13 p22 p23 p33 */
} kf_mech_t;

/* false when cfg is not usable (non-positive period or inertia, negative
 * covariances, non-finite values). */
bool kf_mech_init(kf_mech_t *k, const kf_mech_cfg_t *cfg);
/* State and covariance from a known angle and speed: P diagonal p0. */
void kf_mech_reset(kf_mech_t *k, float theta, float omega, const float p0[3]);
/* (4.47): one period ahead with the electromagnetic torque t_e [N m]. */
void kf_mech_predict(kf_mech_t *k, float t_e);
/* (4.17)-(4.20) with the measured angle and its variance r [rad^2];
 * false (nothing changed) when they are not finite or r <= 0. */
bool kf_mech_update(kf_mech_t *k, float theta_meas, float r);
/* The angle's variance P_22 [rad^2] (after a prediction: the prior's). */
static inline float kf_mech_var_theta(const kf_mech_t *k) {
  return k->p[3]; /* P22 */
}
/* The EKF's update on the DFC signals themselves (4.35)-(4.41): the
 * measurement (g_al, g_be) (normalised as in dfc.h) against
 * h(theta) = (-a cos 2theta + b q_r, a sin 2theta - b q_i) with
 * q = km (cos 4theta, -sin 4theta), km the sequentiality map of the 4theta
 * term (dfc_vec_t.k, row-major; the identity gives (4.35):
 * (-a cos 2theta + b cos 4theta, a sin 2theta + b sin 4theta)),
 * H = dh/dx (4.36) on the predicted angle, R = r I (4.38), Joseph form.
 * false (nothing changed) for non-finite inputs or r <= 0. The prediction
 * is kf_mech_predict's (the model is linear). */
bool kf_mech_update_ekf(kf_mech_t *k, float g_al, float g_be, float a, float b, const float km[4],
                        float r);
/* (4.42) and (4.43) in one: r0 + m max(|omega| - omega_f, 0) + m2 omega^2
 * (inline: every period's measurement variance, pos_track.c). */
static inline float kf_mech_r_speed(float r0, float m, float omega_f, float m2, float omega) {
  const float w = fabsf(omega);
  const float lin = w > omega_f ? m * (w - omega_f) : 0.0f;
  return r0 + lin + m2 * w * w;
}

#endif

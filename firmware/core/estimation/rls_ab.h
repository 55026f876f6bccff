/*
 * rls_ab.h - recursive least squares identification of the DFC amplitudes
 * a and b (Fabbri 2022, section 4.2.1, (4.51)-(4.57)) from the signal
 * vector and a known angle (the encoder's, or the IVD's in the loop of
 * Fig. 4.4).
 *
 * Model (4.51): Gamma = H(theta) x, x = (a, b),
 *   H = [-cos 2theta  cos 4theta; sin 2theta  sin 4theta]          (4.54)
 * Update (4.55)-(4.57) with the covariance propagated as a recursive least
 * squares with forgetting factor lambda (the thesis keeps P fixed, "tuned":
 * lambda = 1 and p_min = p_max reproduce that):
 *   K = P H^T (H P H^T + R)^-1,  x += K (Gamma - H x),
 *   P = (P - K H P) / lambda, symmetric, its diagonal held in
 *   [p_min, p_max] (the covariance limits: no wind-up while the rotor
 *   stands still and the signals carry no information about b).
 * The caller passes the angle's harmonics as a unit vector (cos, sin of 2
 * theta): the squares give those of 4 theta, no trigonometry here.
 */
#ifndef FD_ESTIMATION_RLS_AB_H
#define FD_ESTIMATION_RLS_AB_H

#include <stdbool.h>

typedef struct {
  float lambda;       /* forgetting factor, (0, 1] */
  float r;            /* R_Gamma: variance of each signal component (4.53) */
  float p_min, p_max; /* limits of the covariance's diagonal */
} rls_ab_cfg_t;

typedef struct {
  rls_ab_cfg_t cfg;
  float x[2]; /* a, b */
  float p[3]; /* P upper triangle: p11 p12 p22 */
} rls_ab_t;

/* false when cfg is not usable (lambda outside (0, 1], r <= 0, limits not
 * 0 < p_min <= p_max, non-finite). */
bool rls_ab_init(rls_ab_t *k, const rls_ab_cfg_t *cfg);
/* From estimates a0, b0 with covariance p0 I (within the limits). */
void rls_ab_reset(rls_ab_t *k, float a0, float b0, float p0);
/* One update from the signal vector (g_al, g_be) (normalised as in
 * dfc.h) at the angle whose double is the unit vector (c2, s2); km: the
 * map of the 4theta term of a vector corrected for sequentiality
 * (dfc_vec_t.k: the b column of (4.54) becomes the 4theta term as that
 * vector carries it), NULL for the plain (4.54). false (nothing changed)
 * for non-finite inputs. */
bool rls_ab_update(rls_ab_t *k, float g_al, float g_be, float c2, float s2, const float *km);

#endif

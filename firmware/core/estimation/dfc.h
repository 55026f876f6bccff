/*
 * dfc.h - rotor position from the star point: Direct Flux Control with
 * Iterative Vector Decoupling (Fabbri 2022, chapters 2.3 and 3).
 *
 * Signals. A short test vector v1, v3 or v5 at the start of a PWM period
 * (docs/dfc.md) switches one leg X from 0 to v_dc; the star-point voltage
 * sampled just before and just after that edge gives one component of the
 * DFC signal vector (2.96)-(2.101):
 *   Gamma_x = v_NV(t1+) - v_NV(t1-) = (v_NO(t1+) - v_NO(t1-)) - v_dc / 3,
 * kept here normalised to v_dc (Gamma_x / v_dc = L_Sigma,x / sum L_Sigma -
 * 1/3), so that a, b below do not depend on the DC link. One component
 * arrives per period: a complete vector every three periods, the other two
 * held from the periods before. Sequentiality: the three were taken at
 * three rotor angles (2 theta advances by 2 omega_e Ts between them, 0.05
 * rad at 500 rpm on 8 pole pairs at 16 kHz); taken together by the plain
 * Clarke transform they give an error pattern repeating every three
 * periods. dfc_signals_vector() removes it: the 2theta term rotates at
 * -2 omega_e, so a component taken dt before the newest is the projection
 * of the newest vector on its phase axis turned by 2 omega_e dt; the
 * vector is the least-squares solution of the three projections (for
 * omega_e = 0 exactly the Clarke transform). The 4theta term turns the
 * other way (+4 omega_e): the same least squares maps it through a 2x2
 * matrix K (the identity at standstill), which the IVD applies to the
 * b term it subtracts, so that both terms are decoupled at the newest
 * instant (dfc_vec_t).
 *
 * Angle. With the amplitude-invariant Clarke transform, (3.6):
 *   Gamma_alpha = -a cos(2 theta_e) + b cos(4 theta_e)
 *   Gamma_beta  =  a sin(2 theta_e) + b sin(4 theta_e),   p = b / a  (3.7)
 * i.e. zeta = (-Gamma_alpha + j Gamma_beta) / a = e^{j2theta} - p e^{-j4theta}:
 *   standard DFC  2theta_0 = angle(zeta)                              (3.8)-(3.10)
 *   inverse DFC   2theta = angle of the Clarke vector of
 *                 kappa_x = 1 / (Gamma_x / v_dc + 1/3), conjugated    (3.15)-(3.16)
 *   IVD           2theta_k = angle(zeta + p e^{-j4theta_{k-1}})       (3.76)
 *   Full IVD      2theta_k = angle(zeta + p e^{-j(4theta_{k-1} + phi_b)}) - phi_a
 *                 with phi_a, phi_b linear in i_q                     (3.100)
 * The iterations run on unit vectors (u_k = e^{j2theta_k}: e^{-j4theta} =
 * conj(u)^2), so an iteration costs a complex square, a multiply-add and a
 * normalisation, no trigonometry; one atan2 (the CORDIC,
 * math/cordic_q31.h) gives the final angle. This is (3.76) / (3.100)
 * exactly (tests/core/test_dfc.c against their atan2 form, and an Eigen
 * double reference, tests/core/ref_dfc.cpp).
 * Theorem 1: the IVD converges iff |p| < 1/2; dfc_check() refuses an IVD
 * configuration with |p| >= 1/2 (DFC_ERR_P).
 * The estimate is 2 theta_e: theta_e is known modulo pi (the magnet's
 * polarity is resolved by the position source, app/pos_dfc.c).
 */
#ifndef FD_ESTIMATION_DFC_H
#define FD_ESTIMATION_DFC_H

#include <stdbool.h>
#include <stdint.h>

#define DFC_ITER_MAX 8u /* IVD iterations at most (build time bound) */

typedef enum {
  DFC_STANDARD = 0, /* (3.8)-(3.10) */
  DFC_INVERSE = 1,  /* (3.15)-(3.16) */
  DFC_IVD = 2,      /* (3.76) */
  DFC_FULL_IVD = 3  /* (3.100) */
} dfc_method_t;

typedef struct {
  dfc_method_t method;
  float a, b;          /* (3.7), normalised to v_dc (a != 0) */
  float phi_a, phi_b;  /* Full IVD: phase shifts per A of i_q [rad/A] (3.97) */
  uint32_t iterations; /* n of (3.76) / (3.100): 0 .. DFC_ITER_MAX */
} dfc_cfg_t;

enum {
  DFC_OK = 0,
  DFC_ERR_METHOD = -1, /* unknown method */
  DFC_ERR_A = -2,      /* a zero or not finite, or b not finite */
  DFC_ERR_P = -3,      /* IVD with |p| >= 1/2: Theorem 1, no convergence */
  DFC_ERR_ITER = -4,   /* iterations > DFC_ITER_MAX */
  DFC_ERR_PHI = -5     /* phase shifts not finite or |phi| > 1 rad/A */
};

/* Whether c can run: DFC_OK or the first DFC_ERR_*. */
int dfc_check(const dfc_cfg_t *c);
/* Its reason in words. */
const char *dfc_strerror(int err);

/* The DFC signal vector, one component per period. */
typedef struct {
  float g[3];   /* Gamma_a, Gamma_b, Gamma_c / v_dc (2.101) */
  float t[3];   /* their instants (any time base, s) */
  uint8_t have; /* bit x: component x received since the reset */
  uint8_t last; /* the newest component */
} dfc_signals_t;

void dfc_signals_reset(dfc_signals_t *s);
/* The component of test vector tv (1: v1 -> a, 3: v3 -> b, 5: v5 -> c)
 * from the star-point samples before and after its edge and the DC-link
 * voltage (2.96)-(2.101). false (nothing stored) for another tv or a
 * non-finite or non-positive input. */
bool dfc_signals_push(dfc_signals_t *s, uint8_t tv, float v_before, float v_after, float v_dc,
                      float t);
/* The signal vector at the newest component's instant. */
typedef struct {
  float al, be; /* alpha-beta vector (the 2theta term exact) */
  float k[4];   /* the map of the 4theta term, row-major, conjugated
                   (C K C, C = diag(1, -1)): what the IVD applies to
                   e^{-j(4theta + phi_b)} (identity: no sequentiality) */
} dfc_vec_t;
/* From the signals, the held components turned by 2 omega_e (t_newest -
 * t_x) (see above): w2 = 2 omega_e [rad/s]; w2 = 0 gives the plain Clarke
 * transform and K = I. The turns are series to the fourth / fifth order
 * (within 3e-5 up to 0.5 rad of 2 omega_e dt: 1800 rpm on 8 pole pairs at
 * 16 kHz). */
void dfc_signals_vector(const dfc_signals_t *s, float w2, dfc_vec_t *v);
/* The plain Clarke vector of g (K = I). */
void dfc_vec_plain(const float g[3], dfc_vec_t *v);
/* All three components received since the reset. */
static inline bool dfc_signals_complete(const dfc_signals_t *s) {
  return s->have == 7u;
}

/* The unit vector e^{j 2 theta_e} estimated by the method of c
 * (dfc_check(c) == DFC_OK) from the normalised signals g (the inverse
 * DFC) or their alpha-beta vector (al, be) (the others), i_q the q current
 * for the Full IVD's phase shifts. trace (may be NULL) receives e^{j 2 theta_k}
 * after each step k = 0 .. iterations (2 * (iterations + 1) floats:
 * cos, sin). Returns false when the signal vector has no direction (zero
 * or not finite): *c2, *s2 are then 1, 0. */
bool dfc_vector2(const dfc_cfg_t *c, const float g[3], const dfc_vec_t *v, float i_q, float *c2,
                 float *s2, float *trace);
/* The IVD (3.76) / Full IVD (3.100) of c (c->iterations steps; IVD
 * methods) started from the unit vector (*c2, *s2), a tracker's predicted
 * e^{j 2 theta}, instead of the raw estimate (3.8): the error left after n
 * steps is (2|p|)^n times the start's (Theorem 1, (3.81)), so a start that
 * already carries the last periods' iterations continues them. trace (may
 * be NULL): e^{j 2 theta_k} after step k = 1 .. iterations, as
 * dfc_vector2's (its entry 0, the start, is left). false (and *c2, *s2
 * unchanged) for another method or a vector with no direction. */
bool dfc_ivd_from(const dfc_cfg_t *c, const dfc_vec_t *v, float i_q, float *c2, float *s2,
                  float *trace);
/* The same as an angle: 2 theta_e in [-pi, pi] (one CORDIC atan2), from
 * the plain Clarke vector of g. */
float dfc_angle2(const dfc_cfg_t *c, const float g[3], float i_q, bool *ok);

/* One IVD iteration on unit vectors (exposed for the cost benchmark):
 * u <- normalise(zeta + p K r_b conj(u)^2) r_a, with r_a = e^{-j phi_a},
 * r_b = e^{-j phi_b} (NULL, NULL for the plain IVD: no turn), K of
 * dfc_vec_t. false: no direction. */
bool dfc_ivd_step(float zr, float zi, float p, const float k[4], const float rb[2],
                  const float ra[2], float *ur, float *ui);

#endif

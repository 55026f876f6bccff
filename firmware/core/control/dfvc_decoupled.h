/*
 * dfvc_decoupled.h - Direct Flux Vector Control of saturated synchronous machines
 * (reluctance, interior PM; any machine_t, flux map or linear) after
 * Varatharajan, Pellegrino, Armando, IEEE TIE 69(2), 2022. One entry point
 * composes:
 *   estimation/flux_observer  hybrid observer (24) with the machine model
 *                             (the map) as current model, gain g
 *   model/sfo_model           L_d (25), lambda^a (6), i^a (9), (7), (10),
 *                             a, b (22), a', b' (17), T (23)
 *   control/dfvc_decoupled_refs     references, LUT (29)-(31) or online (32), (34)
 *   control/dfvc_decoupled_pi       PI (26) / decoupled (27) regulators, (28)
 *
 * Timing as the SPM laws (dfvc.h): samples at tau, in.v_ab_applied the
 * voltage over [tau, tau+1), out.v_ab_ref for [tau+1, tau+2).
 *
 * Gain sets (the transformation T_hat of (27)):
 *   DFVC_DECOUPLED_GAINS_PROPOSED  (a, b) of (22) from the map and the observed flux
 *   DFVC_DECOUPLED_GAINS_SOTA      (a', b') of (17), apparent inductances of the map
 *   DFVC_DECOUPLED_GAINS_CONSTANT  (0, b0): the constant-gain PI DFVC (26), the
 *                            i_tau loop tuned for b0 = b at the design point
 *                            (MTPA at half the current limit)
 * b_hat is floored at b_floor_frac * b0 (the singularity b = 0 of the MTPV
 * trajectory; the references keep the margin k_T from it).
 *
 * Current-model error (sensitivity test, Fig. 14): in.cm_scale multiplies
 * the map's lambda_d, lambda_q (and the rows of L_d) wherever the
 * controller uses its model; 1, 1 is the map itself.
 */
#ifndef FD_CONTROL_DFVC_DECOUPLED_H
#define FD_CONTROL_DFVC_DECOUPLED_H

#include <stdint.h>

#include "control/dfvc_decoupled_pi.h"
#include "control/dfvc_decoupled_refs.h"
#include "estimation/flux_observer.h"
#include "model/sfo_model.h"

typedef enum {
  DFVC_DECOUPLED_GAINS_PROPOSED = 0,
  DFVC_DECOUPLED_GAINS_SOTA = 1,
  DFVC_DECOUPLED_GAINS_CONSTANT = 2,
  DFVC_DECOUPLED_GAINS_COUNT
} dfvc_decoupled_gains_t;

typedef struct {
  const machine_t *machine;
  float ts;           /* [s] */
  float g;            /* observer gain [rad/s] (paper: 2 pi 5) */
  float omega;        /* regulator bandwidth Omega [rad/s] (paper: 2 pi 100 .. 200) */
  float v_f_max;      /* flux-axis voltage limit [V] */
  float rot_advance;  /* [0, 1]: output rotation advanced by this many omega_r Ts (dfvc.h) */
  float b_floor_frac; /* b_hat >= this * b0 (0.1) */
  dfvc_decoupled_gains_t gains;
  dfvc_decoupled_refs_mode_t refs_mode;
  float i_max, lambda_min, k_v, k_t, k_a; /* references (dfvc_decoupled_refs.h) */
} dfvc_decoupled_cfg_t;

typedef struct {
  ab_t i_ab;         /* measured current at tau [A] */
  ab_t v_ab_applied; /* voltage applied over [tau, tau+1) [V] */
  float theta_r;     /* [rad] */
  float omega_r;     /* [rad/s] */
  float v_lin;       /* [V] */
  float torque_ref;  /* [N m] */
  float lambda_ref;  /* flux override [Vs]; 0 = automatic */
  dq_t cm_scale;     /* current-model error factors (1, 1: none) */
} dfvc_decoupled_in_t;

enum { DFVC_DECOUPLED_FAULT_INPUT = 1u << 0, DFVC_DECOUPLED_FAULT_STATE = 1u << 1 };

typedef struct {
  ab_t v_ab_ref;  /* [V] */
  ab_t i_ab_mid;  /* the references' current over [tau+1, tau+2) (dead-time comp.) [A] */
  dq_t i_dq;      /* rotor-frame current at tau [A] */
  float lambda_s; /* observed flux amplitude [Vs] */
  dq_t lambda_dq; /* observed flux in the rotor frame [Vs]: the load angle's (telemetry: its
                     readers take the angle, not the ISR) */
  dq_t i_ft;      /* (i_f, i_tau) at tau [A] */
  float torque;   /* 3/2 p lambda_hat i_tau [N m] */
  float obs_err;  /* |lambda_hat - lambda^i| [Vs] */
  dfvc_decoupled_refs_out_t r;
  dq_t v_ft;      /* [V] */
  uint32_t sat;   /* DFVC_DECOUPLED_PI_SAT_* */
  uint32_t fault; /* DFVC_DECOUPLED_FAULT_* */
} dfvc_decoupled_out_t;

/* What the last step found beyond dfvc_decoupled_out_t's telemetry, kept in the
 * state for the SIL's log (read in lock-step after the ISR). */
typedef struct {
  float flux_mtpa;   /* (29) or (32) [Vs] */
  float torque_mtpv; /* (31) or (34) [N m] */
  float gain_a;      /* a_hat in use [1/H] */
  float gain_b;      /* b_hat in use [1/H] */
  dq_t mtpa_la;      /* lambda^a (6) [Vs] and i [A] of (7): the sine of the */
  dq_t mtpa_i;       /* MTPA phase error where it is read, dfvc_decoupled_tm_mtpa_angle */
  float mtpv_angle;  /* MTPV angle of (34) [rad] (online references) */
} dfvc_decoupled_tm_t;

/* The sine of the MTPA phase error of the last step, |(7)| / (|lambda^a| |i|)
 * (0 at zero current): telemetry, computed where it is read, not in the ISR. */
float dfvc_decoupled_tm_mtpa_angle(const dfvc_decoupled_tm_t *tm);

typedef struct {
  dfvc_decoupled_cfg_t cfg;
  flux_observer_t obs;
  dfvc_decoupled_refs_t refs;
  dfvc_decoupled_pi_t pi;
  float b0;      /* b at the design point [1/H] */
  float b_floor; /* [1/H] */
  float seed;    /* start-up flux of an unmagnetised machine, 1 % of lambda_min [Vs] */
  dq_t seed_dq;  /* along the magnetising axis [Vs] */
  dfvc_decoupled_tm_t tm;
} dfvc_decoupled_t;

void dfvc_decoupled_cfg_defaults(dfvc_decoupled_cfg_t *cfg, const machine_t *machine);
/* Returns 0, or -1 if a parameter is invalid. */
/* The largest stator flux amplitude the machine reaches on the current
 * limit circle |i| = i_max (32 points): the references' ceiling; a flux
 * floor (lambda_min) above it is refused by dfvc_decoupled_init. */
float dfvc_decoupled_flux_cap(const machine_t *m, float i_max);
int dfvc_decoupled_init(dfvc_decoupled_t *c, const dfvc_decoupled_cfg_t *cfg);
void dfvc_decoupled_reset(dfvc_decoupled_t *c);
void dfvc_decoupled_step(dfvc_decoupled_t *c, const dfvc_decoupled_in_t *in,
                         dfvc_decoupled_out_t *out);

/* The model quantities at a rotor-frame flux and current with the
 * controller's (scaled) map: the blocks of the step, for tests and tools. */
typedef struct {
  dq_t lambda_i;    /* current model Lambda(i) [Vs] */
  machine_ldq_t l;  /* L_d (25) [H] */
  sfo_gains_t prop; /* (22) */
  sfo_gains_t sota; /* (17) */
  dq_t lambda_a;    /* auxiliary flux (6) [Vs] */
  float mtpa_cross, mtpv_cross, mtpa_angle, mtpv_angle;
} dfvc_decoupled_model_t;
void dfvc_decoupled_model(const machine_t *m, dq_t cm_scale, dq_t lambda, dq_t i,
                          dfvc_decoupled_model_t *q);

#endif

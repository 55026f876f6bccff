/*
 * dfvc.h - Direct Flux Vector Control of SPM machines, deadbeat (DB-DFVC)
 * and PI (PI-DFVC) laws, after Rubino, Bojoi, Armando, Tenconi, "Deadbeat
 * Direct Flux Vector Control of Surface Permanent Magnet Motor Drives",
 * IEEE TIA 56(3), 2020. One entry point composes:
 *   estimation/flux_observer     hybrid observer + flux prediction, Fig. 3, (19)-(20)
 *   estimation/current_predictor MPE, eq. (21)
 *   control/dfvc_refs            references, Fig. 5, (22)-(26)
 *   control/dfvc_deadbeat        deadbeat laws (28)-(33)
 *   control/dfvc_pi              PI-DFVC baseline, section IV.7
 * Dead-time compensation (control/deadtime_comp.h, Fig. 8) is applied by the
 * caller on the duties, with the predicted currents reported here.
 *
 * Timing (ARCHITECTURE.md, paper eq. (28)): call dfvc_step() once per
 * period with the samples taken at tau. in.v_applied is the voltage that
 * the modulator applies over [tau, tau+1), i.e. the previous call's
 * out.v_ab_ref as actually applied (modulation_out_t.v_applied). The
 * returned out.v_ab_ref is to be applied over [tau+1, tau+2).
 *
 * Frames: rotor frame d on the PM flux; stator-flux frame ds along
 * lambda_s; load angle delta = theta_s - theta_r (from d to ds).
 *
 * Typical use per ISR:
 *   in.i_ab = measured; in.v_applied = mod.v_applied (from last period);
 *   dfvc_step(&c, DFVC_LAW_DEADBEAT, &in, &out, &telemetry);
 *   mod = modulation_minmax(out.v_ab_ref, v_dc, duty_min, duty_max);
 *   deadtime_comp_apply(&dt, mod.duty, frames_clarke_inv(out.i_ab_mid), duty);
 *   if (out.fault) -> app decides (gates off, latch)
 *
 * Constants the paper leaves open, and the choices (dfvc_cfg_defaults()):
 *  - omega_s_bw = 1000 rad/s: low-pass of the omega_s derivative (used by
 *    the PI feed-forward and telemetry only).
 *  - lambda_min = 0.2 lambda_m (paper: below the flux needed at top speed
 *    and minimum DC link; Table I: 0.038 Vs < 0.052 Vs at 1200 rpm, 250 V).
 *  - lambda_collapse = 0.5 lambda_min: observed flux below it is a fault.
 *  - v_margin = 0.95 of the modulator's linear range v_lin (v_dc/sqrt(3)
 *    for duties over [0, 1]) in the flux-weakening law (23); the output
 *    voltage may use the whole linear range.
 *  - i_max = 2.5 sqrt(2) A (Table I rated rms current, as amplitude).
 *  - MPE form: exact back-EMF term (current_predictor.h) instead of the
 *    back-EMF held at tau; CURRENT_PREDICTOR_EQ21 gives the printed (21).
 *  - flux prediction (19): resistive drop averaged over the period with the
 *    MPE current (flux_observer.h); the printed Rs i(tau) is a 0.1 % (100 rpm)
 *    to 1.5 % (1200 rpm) flux bias.
 *  - PI-DFVC anti-windup: integral tracks its steady-state value while
 *    saturated (dfvc_pi.h); math/pi_ctrl is not used.
 *  - omega_delta in (33): predicted from the i_qs reference (see
 *    dfvc_deadbeat.h); DFVC_OMEGA_DELTA_OBSERVED gives the observed rate.
 *  - rot_advance = 0.5: the (ds, qs) -> (alpha, beta) rotation uses
 *    theta_s(tau+1) + 0.5 omega_r Ts, the flux angle in the middle of the
 *    interval the voltage acts, which removes the O((omega Ts)^2) bias of
 *    the forward-Euler laws (29), (33) (+1.4 % flux at 1200 rpm with 0).
 *    0 is the paper's rotation by theta_s(tau+1).
 *  - omega_r(tau+1) = omega_r(tau), theta_r(tau+1) = theta_r + omega_r Ts.
 *  - PI-DFVC bandwidths 2 pi 1000 rad/s (paper: 1 kHz); design in dfvc_pi.h.
 *  - (23) also at the limited i_qs* (smaller flux kept) and (25) at tau+2
 *    from the MPE current (dfvc_refs.h): without them the DB-DFVC loses
 *    torque control at v_margin = 1 and the current limit (25) oscillates.
 */
#ifndef FD_CONTROL_DFVC_H
#define FD_CONTROL_DFVC_H

#include <stdbool.h>
#include <stdint.h>

#include "control/dfvc_deadbeat.h"
#include "control/dfvc_pi.h"
#include "control/dfvc_refs.h"
#include "control/law_io.h"
#include "estimation/current_predictor.h"
#include "estimation/flux_observer.h"
#include "math/frames.h"

typedef enum { DFVC_LAW_DEADBEAT = 0, DFVC_LAW_PI = 1 } dfvc_law_t;

typedef enum {
  DFVC_OMEGA_DELTA_TARGET = 0,  /* (asin(Ls i_qs* / lambda_m) - delta(t+1))/Ts (default) */
  DFVC_OMEGA_DELTA_OBSERVED = 1 /* (delta(t+1) - delta(t))/Ts */
} dfvc_omega_delta_t;

typedef struct {
  /* the machine: an isotropic PM machine (Table I: 7.1 Ohm, 57 mH,
   * 0.19 Vs, 21 pole pairs); every block below references it */
  const machine_t *machine;
  float ts; /* sampling = PWM period [s] (62.5 us) */
  /* observer */
  float omega_c;    /* crossover current model / back-EMF [rad/s] (125) */
  float omega_s_bw; /* omega_s derivative filter [rad/s] (1000) */
  /* limits and references */
  float i_max;           /* phase current amplitude limit [A] */
  float delta_max;       /* load-angle limit [rad] (80 deg) */
  float v_sd_max;        /* d_s voltage limit [V] (60) */
  float lambda_min;      /* minimum flux reference [Vs] */
  float lambda_collapse; /* observed flux below this is a fault [Vs] */
  float v_margin;        /* fraction of v_lin used by the flux-weakening law (0.95) */
  /* PI-DFVC */
  float pi_bw_flux; /* [rad/s] (2 pi 1000) */
  float pi_bw_iqs;  /* [rad/s] (2 pi 1000) */
  /* implementation choices (see above) */
  current_predictor_mode_t mpe_mode;
  dfvc_omega_delta_t omega_delta_mode;
  float rot_advance; /* [0, 1], fraction of omega_r Ts added to theta_s(t+1) */
} dfvc_cfg_t;

/* The period's inputs, the core's law input (control/law_io.h), read in
 * place: i_ab = measured current at tau [A]; v_applied = voltage applied
 * over [tau, tau+1) [V]; theta_e, omega_e = electrical rotor angle and
 * speed at tau; v_lin = linear voltage range of the modulator now
 * (v_dc/sqrt(3)) [V]; torque_ref = T* [N m]; flux_ref = flux reference
 * override [Vs], 0 = automatic (MTPA/FW). current, id_ref, iq_ref: not
 * read. */
typedef law_in_t dfvc_in_t;

/* Fault bits (values only; nothing is latched or switched off here). */
enum {
  DFVC_FAULT_INPUT = 1u << 0,        /* non-finite input or unknown law: output 0, state held */
  DFVC_FAULT_STATE = 1u << 1,        /* non-finite internal result: output 0, states reset */
  DFVC_FAULT_FLUX_COLLAPSE = 1u << 2 /* observed |lambda_s| < lambda_collapse */
};

/* Limit bits: DFVC_REFS_* (bits 0-3) and these. */
enum {
  DFVC_LIMIT_VD = 1u << 4, /* v_ds on its limit */
  DFVC_LIMIT_VQ = 1u << 5  /* v_qs on what remains of the voltage circle */
};

typedef struct {
  ab_t v_ab_ref; /* voltage to apply over [tau+1, tau+2) [V], |v| <= v_lin */
  /* mean of the MPE currents at tau+1 and at tau+2 with v_ab_ref: over
   * [tau+1, tau+2), for dead-time comp [A]. The two predictions, the
   * predicted flux and torque and the flux angle and speed are not outputs
   * (nothing read them; their stores cost the ISR, issue 24 point 8) */
  ab_t i_ab_mid;
  float i_qs_pred;              /* predicted at tau+1 [A] */
  dq_t i_dq_r;                  /* rotor-frame currents at tau [A] */
  float torque_min, torque_max; /* deliverable now [N m] (dfvc_refs.h) */
  dq_t v_dqs;                   /* (ds, qs) voltage reference [V] */
  uint32_t limits;              /* DFVC_REFS_* | DFVC_LIMIT_* */
  uint32_t fault;               /* DFVC_FAULT_* */
} dfvc_out_t;

typedef struct {
  dfvc_cfg_t cfg;
  flux_observer_t obs;
  current_predictor_t mpe;
  dfvc_refs_t refs;
  dfvc_deadbeat_t db;
  dfvc_pi_t pi;
  dfvc_law_t last_law;
  bool adv_half; /* rot_advance = 0.5: the output rotation is the MPE's half-angle sin/cos */
} dfvc_t;

/* Paper constants for the given machine (lambda_min from its PM flux). */
void dfvc_cfg_defaults(dfvc_cfg_t *cfg, const machine_t *machine);
/* Returns 0, or -1 if a parameter is invalid (the state is then unusable). */
int dfvc_init(dfvc_t *c, const dfvc_cfg_t *cfg);
/* Observer restarts from the current model, PI integrals cleared. */
void dfvc_reset(dfvc_t *c);
/* One control period of the voltage law `law` (DFVC_LAW_DEADBEAT or
 * DFVC_LAW_PI; may change between calls); out is fully written, and the
 * telemetry in place at tm, where the caller publishes it (every field,
 * each period; zeroed with the outputs on a fault): flux = observed
 * |lambda_s| at tau, flux_ref = lambda*, delta = load angle, i_ds, i_qs =
 * stator-flux frame currents, i_qs_ref = limited i_qs*, torque = 3/2 p
 * lambda_s i_qs, obs_err = |lambda_hat - lambda_cm| at tau (observer vs
 * current model); lam_d, lam_q 0, delta_lazy false. */
void dfvc_step(dfvc_t *c, dfvc_law_t law, const dfvc_in_t *in, dfvc_out_t *out,
               law_telemetry_t *tm);

#endif

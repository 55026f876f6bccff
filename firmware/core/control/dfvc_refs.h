/*
 * dfvc_refs.h - reference generation of the DFVC for SPM machines
 * (Rubino 2020, Fig. 5, eqs. (22)-(26)).
 *
 *   lambda_MTPA = lambda_m sqrt(1 + 4/9 (Ls T* / (p lambda_m^2))^2)       (22)
 *   lambda_vlim = (sqrt(v_max^2 - (Rs i_ds)^2) - Rs i_qs sgn(w_r)) / |w_r| (23)
 *                 v_max = v_lin v_margin (v_lin: the modulator's linear range,
 *                 v_dc/sqrt(3) over duties [0, 1]), omega_s replaced by omega_r
 *                 as the paper does
 *   lambda*     = max(min(lambda_MTPA, lambda_vlim), lambda_min)
 *   i_qs*       = T* / (1.5 p lambda*)                                    (24)
 *   |i_qs*|    <= sqrt(I_max^2 - i_ds^2)                                  (25)
 *   |i_qs*|    <= lambda_m / Ls sin(delta_max)                            (26)
 *
 * Choices where the paper is silent (see also dfvc.h):
 *  - (22) is evaluated on |T*| clamped to the MTPA torque at I_max,
 *    1.5 p lambda_m I_max, so that an unreachable torque demand cannot ask
 *    for a flux the current limit cannot build (the LUT of Fig. 5 ends there).
 *  - A positive flux override replaces lambda_MTPA; the voltage limit and
 *    lambda_min still apply.
 *  - (23): |omega_r| is floored at 1 rad/s (no division by zero at
 *    standstill); a negative radicand gives lambda_vlim = 0 (then lambda_min).
 *  - (25): a negative radicand (|i_ds| > I_max) gives 0.
 *  - The torque limits reported are +-1.5 p lambda* i_qs,lim with the
 *    present flux reference and limits (what the law can deliver now); the
 *    speed loop may use them for its anti-windup.
 */
#ifndef FD_CONTROL_DFVC_REFS_H
#define FD_CONTROL_DFVC_REFS_H

#include "model/machine.h"

typedef struct {
  const machine_t *machine; /* SPM: Rs, Ls = machine_ls(), lambda_m > 0, p */
  float i_max;              /* phase current amplitude limit [A] */
  float delta_max;          /* load-angle limit [rad], (0, pi/2] */
  float lambda_min;         /* lower flux limit [Vs] */
  float v_margin;           /* fraction of the linear range v_lin used in (23), (0, 1] */
} dfvc_refs_cfg_t;

typedef struct {
  dfvc_refs_cfg_t cfg;
  float iqs_max_delta;   /* eq. (26) [A] */
  float torque_mtpa_max; /* 1.5 p lambda_m I_max [N m] */
} dfvc_refs_t;

typedef struct {
  float torque_ref;      /* T* [N m] */
  float lambda_override; /* > 0: replaces lambda_MTPA [Vs]; 0 = automatic */
  float omega_r;         /* electrical rotor speed [rad/s] */
  float v_lin;           /* linear voltage range of the modulator [V] */
  float i_ds, i_qs;      /* stator-flux frame currents at tau [A] */
} dfvc_refs_in_t;

enum {
  DFVC_REFS_FLUX_VLIM = 1u << 0, /* lambda* set by the voltage limit (23) */
  DFVC_REFS_FLUX_MIN = 1u << 1,  /* lambda* set by lambda_min */
  DFVC_REFS_IQS_IMAX = 1u << 2,  /* i_qs* clipped by the current limit (25) */
  DFVC_REFS_IQS_DELTA = 1u << 3  /* i_qs* clipped by the load-angle limit (26) */
};

typedef struct {
  float lambda_mtpa;   /* eq. (22) or the override [Vs] */
  float lambda_vlim;   /* eq. (23) [Vs] */
  float lambda_ref;    /* lambda* [Vs] */
  float iqs_unlimited; /* eq. (24) [A] */
  float iqs_max_i;     /* eq. (25) [A] */
  float iqs_max_delta; /* eq. (26) [A] */
  float iqs_ref;       /* limited i_qs* [A] */
  float torque_max;    /* >= 0 [N m] */
  float torque_min;    /* = -torque_max [N m] */
  unsigned limits;     /* DFVC_REFS_* bits */
} dfvc_refs_out_t;

/* Returns 0, or -1 for invalid parameters. */
int dfvc_refs_init(dfvc_refs_t *r, const dfvc_refs_cfg_t *cfg);
/* No dynamic state: recomputes the derived limits from cfg. */
void dfvc_refs_reset(dfvc_refs_t *r);
/* Eqs. (22)-(23) only (useful to callers and tests). */
float dfvc_refs_lambda_mtpa(const dfvc_refs_t *r, float torque_ref);
float dfvc_refs_lambda_vlim(const dfvc_refs_t *r, float v_lin, float omega_r, float i_ds,
                            float i_qs);
void dfvc_refs_update(const dfvc_refs_t *r, const dfvc_refs_in_t *in, dfvc_refs_out_t *out);

#endif

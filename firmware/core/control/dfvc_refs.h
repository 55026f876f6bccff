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
 * Two departures from the printed (23), (25), both for the deadbeat of
 * (28), which sets lambda_s and i_qs at tau+2, not at tau:
 *  - (23) is evaluated twice, with i_qs(tau) as printed and with the
 *    limited i_qs* (the q_s current (33) imposes at tau+2); the smaller
 *    flux is kept. With i_qs(tau) alone the steady state of (23) leaves
 *    the q_s axis exactly the voltage that holds the present i_qs: when
 *    v_qs saturates (no headroom, v_margin -> 1) a lagging i_qs raises
 *    lambda* instead of being restored, and any unmodelled volt (observer
 *    bias, dead time) drives i_qs and delta away (loss of torque control
 *    at v_margin = 1 on the Rubino ramp). With i_qs* the flux leaves
 *    Rs (i_qs* - i_qs) for the q_s axis: i_qs returns with Ls / Rs.
 *  - (25) bounds the current at tau+2: i_ds(tau+2) is predicted from the
 *    MPE current at tau+1 along the constant-flux line of the SPM
 *    magnetic model (30) with the q_s row of (16), d i_ds / d i_qs =
 *    tan(delta): i_ds(tau+2) = i_ds(tau+1) + tan|delta(tau+1)| (|i_qs*| -
 *    |i_qs(tau+1)|) (i_ds is even in i_qs at a given flux, so the bound is
 *    the same for both torque signs), and |i_qs*| is where that line meets
 *    the circle I_max; tan|delta| is capped at tan(delta_max). The printed
 *    form, with i_ds(tau), closes the loop i_qs* -> i_qs(tau+2) ->
 *    i_ds(tau+2) -> i_qs* through the two-period delay of (28):
 *    z^2 = -G, G = (i_ds / i_qs) tan(delta) = Ls i_ds / (lambda_s - Ls i_ds).
 *    For i_ds > lambda_s / (2 Ls) (G > 1: from ~300 rpm on the Rubino ramp)
 *    it oscillates near fs/4, bounded only by the voltage limit, and the
 *    sampled current crosses I_max. For i_ds(tau+1) < 0, |G| < 1 and |i_ds|
 *    falls as |i_qs| grows: there the smaller of the line bound and the
 *    printed bound at i_ds(tau+1) is kept, as the line alone would let a
 *    large i_qs* step through in deep flux weakening, where the omega_delta
 *    term of (33) (target estimate, dfvc_deadbeat.h) can stall i_qs.
 *    With i(tau+1) = i(tau) and delta = 0 this is (25) itself.
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

#include "math/frames.h"
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
  float cos_delta_max;   /* cos(delta_max) [-] */
  float tan_delta_max;   /* tan(delta_max), cap of the slope in (25) [-] */
  float torque_mtpa_max; /* 1.5 p lambda_m I_max [N m] */
  /* the last MTPA flux (22): the torque reference changes at the speed
   * loop's rate or with a command, so (22) is reused in between */
  float mtpa_t;      /* its torque reference [N m] (NaN: none) */
  float mtpa_lambda; /* dfvc_refs_lambda_mtpa(r, mtpa_t) [Vs] */
} dfvc_refs_t;

typedef struct {
  float torque_ref;       /* T* [N m] */
  float lambda_override;  /* > 0: replaces lambda_MTPA [Vs]; 0 = automatic */
  float omega_r;          /* electrical rotor speed [rad/s] */
  float v_lin;            /* linear voltage range of the modulator [V] */
  float i_ds, i_qs;       /* stator-flux frame currents at tau [A] */
  dq_t i_dqs_next;        /* MPE current at tau+1 in the flux frame at tau+1 [A], (25) */
  sincos_t sc_delta_next; /* sin, cos of the load angle at tau+1, (25) */
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
/* Recomputes the derived limits from cfg and forgets the MTPA point. */
void dfvc_refs_reset(dfvc_refs_t *r);
/* Eqs. (22)-(23) only (useful to callers and tests). */
float dfvc_refs_lambda_mtpa(const dfvc_refs_t *r, float torque_ref);
float dfvc_refs_lambda_vlim(const dfvc_refs_t *r, float v_lin, float omega_r, float i_ds,
                            float i_qs);
/* One period; r is written only by the MTPA point's cache. */
void dfvc_refs_update(dfvc_refs_t *r, const dfvc_refs_in_t *in, dfvc_refs_out_t *out);

#endif

/*
 * dfvc_decoupled_refs.h - flux and torque-current references of the DFVC of a
 * saturated machine (Varatharajan 2022, section V), from the map's tables
 * (LUT) or adapted online.
 *
 * LUT (Fig. 7):
 *   lambda_MTPA = f_lambda(|T*|)                      (29) flux_map_mtpa_flux
 *   lambda_max  = (k_v v_lin - Rs |i|) / |omega_r|    (30) v_lin = v_dc/sqrt(3)
 *                 on the full duty range; the resistive drop is this
 *                 implementation's: on the 1.1 kW SyR (6.8 Ohm) Rs i_max is
 *                 33 V, 17 % of the 196 V a 340 V link gives, more than the
 *                 margin k_v = 0.9 leaves, and without it the tau axis
 *                 saturated in flux weakening (torque 7.0 for 12.0 N m);
 *                 |i| low-passed with 10 ms: taken at each sample it
 *                 closed a loop |i| -> lambda_max -> flux -> |i| that swung
 *                 the current 2.4 .. 5.1 A at 500 Hz near MTPV (Fig. 12)
 *   lambda*     = max(min(lambda_MTPA, lambda_max), lambda_min)
 *   T_max       = k_T f_T(lambda*)                    (31) flux_map_mtpv_torque
 * Online (Fig. 8):
 *   lambda_MTPA = -k_A / s (lambda^a)^T J i           (32) integrated while
 *                 lambda_MTPA < lambda_max (held in flux weakening) and the
 *                 observed flux is within 5 % of the last lambda* (held while
 *                 the flux loop is still on its way: the product of (7) is
 *                 taken at the present flux, and integrating it then ran
 *                 lambda_MTPA to 2.2 Vs during a start at the current
 *                 limit) and |i_tau| > 3 % of I_max (at zero torque (7) holds
 *                 on both axes: on a PM machine kept at lambda_min > lambda_m
 *                 by a d current its sign asks for more flux, and the flux
 *                 ran to its cap), bounded to [lambda_min, min(lambda_max,
 *                 lambda_cap)], lambda_cap the largest flux amplitude on the
 *                 current-limit circle (32 points, at init)
 *   T_max       = k_T (|T_hat| + 3p/2 lambda^T J i^a |angle(i^a) - delta|)  (34)
 *                 (the angle on the line, modulo pi: sfo_model.h)
 * Both:
 *   T*          clipped to +-T_max
 *   i_tau*      = T* / (3/2 p lambda*)                (13)
 *   |i_tau*|   <= sqrt(I_max^2 - i_f^2)               current limit (Fig. 7)
 *   torque_max  = min(T_max, 3/2 p lambda* i_tau,max) reported to the speed
 *                 loop (its anti-windup, section V.A)
 *
 * The sign of (32). With gamma as (5) defines it (d i/d gamma = J i,
 * counter-clockwise), (lambda^a)^T J i = (2/3p) dT/dgamma > 0 where the
 * current lies nearer the magnetising axis than on MTPA, i.e. where the
 * flux is above the MTPA flux for the torque (both torque signs: the
 * product is even in the q mirror, sfo_model.h). The flux must then fall,
 * so the integrator takes -k_A; with +k_A as printed the flux ran away
 * (3.8 Vs at standstill, then a loss-of-control trip, in the SIL). Fig. 2,
 * which defines gamma, is not in the text: its gamma may run the other way.
 *
 * Choices where the paper is silent: lambda_min (parameter flux_min) keeps a
 * magnetised machine at light load (the map's MTPA flux goes to 0 with the
 * torque on a reluctance machine); |omega_r| is floored at 1 rad/s in (30);
 * a flux override (> 0) replaces lambda_MTPA; the online integrator starts
 * at the no-load flux max(lambda_min, lambda_0) (at lambda_min < lambda_m a
 * PM machine would be demagnetised at standstill: 25 A and a trip on the
 * interior-PM preset); (34) with a non-finite or negative margin gives |T_hat| k_T.
 */
#ifndef FD_CONTROL_DFVC_DECOUPLED_REFS_H
#define FD_CONTROL_DFVC_DECOUPLED_REFS_H

#include "model/machine.h"

typedef enum {
  DFVC_DECOUPLED_REFS_LUT = 0,
  DFVC_DECOUPLED_REFS_ONLINE = 1
} dfvc_decoupled_refs_mode_t;

typedef struct {
  const machine_t *machine; /* LUT mode: a flux-map machine */
  dfvc_decoupled_refs_mode_t mode;
  float ts;         /* [s] */
  float i_max;      /* current amplitude limit [A] */
  float lambda_min; /* [Vs] */
  float k_v;        /* voltage margin of (30), (0, 1] (paper: ~0.9) */
  float k_t;        /* torque margin of (31), (34), (0, 1] (paper: ~0.9) */
  float k_a;        /* MTPA adaptation gain of (32) [1/(A s)] (paper: 60) */
  float lambda_0;   /* the flux at zero current (PM) [Vs]: the online
                     * MTPA starts at max(lambda_min, lambda_0) */
  float lambda_cap; /* upper bound of the adapted flux: the flux the current
                     * limit builds on the magnetising axis [Vs] */
} dfvc_decoupled_refs_cfg_t;

typedef struct {
  dfvc_decoupled_refs_cfg_t cfg;
  float lambda_mtpa; /* online: the integrator of (32) [Vs] */
  float lambda_ref;  /* lambda* of the last update [Vs] */
  float i_amp_f;     /* current amplitude, low-passed (10 ms), for (30) [A] */
  float i_alpha;     /* its filter's gain per period */
  float kt;          /* 3/2 p, the torque per flux and current of (13) (init) */
} dfvc_decoupled_refs_t;

typedef struct {
  float torque_ref;      /* T* [N m] */
  float lambda_override; /* > 0 replaces lambda_MTPA [Vs] */
  float omega_r;         /* [rad/s] */
  float v_lin;           /* [V] */
  float i_f;             /* flux-axis current [A] */
  float i_tau;           /* torque current [A] */
  float i_amp;           /* current amplitude [A], (30) */
  float lambda_hat;      /* observed flux amplitude [Vs] */
  float torque_est;      /* T_hat = 3/2 p lambda_hat i_tau [N m] */
  float mtpa_cross;      /* (lambda^a)^T J i, eq. (7) [Vs A] */
  float mtpv_cross;      /* lambda^T J i^a, eq. (10) [Vs A] */
  float mtpv_angle;      /* |angle(i^a) - delta| on the line [rad] */
  int adapt;             /* 1: the drive runs (the online MTPA integrates) */
} dfvc_decoupled_refs_in_t;

enum {
  DFVC_DECOUPLED_REFS_FLUX_VLIM = 1u << 0, /* lambda* from (30) */
  DFVC_DECOUPLED_REFS_FLUX_MIN = 1u << 1,  /* lambda* = lambda_min */
  DFVC_DECOUPLED_REFS_TMAX = 1u << 2,      /* T* clipped by the MTPV limit (31)/(34) */
  DFVC_DECOUPLED_REFS_IMAX = 1u << 3       /* i_tau* clipped by the current limit */
};

typedef struct {
  float lambda_mtpa; /* (29) or (32) [Vs] */
  float lambda_max;  /* (30) [Vs] */
  float lambda_ref;  /* [Vs] */
  float torque_mtpv; /* T_max of (31) or (34) [N m] */
  float itau_ref;    /* [A] */
  float torque_max;  /* >= 0, what the drive can deliver now [N m] */
  unsigned limits;   /* DFVC_DECOUPLED_REFS_* */
} dfvc_decoupled_refs_out_t;

/* Returns 0, or -1 for invalid parameters (LUT mode without a map). */
int dfvc_decoupled_refs_init(dfvc_decoupled_refs_t *r, const dfvc_decoupled_refs_cfg_t *cfg);
void dfvc_decoupled_refs_reset(dfvc_decoupled_refs_t *r);
void dfvc_decoupled_refs_update(dfvc_decoupled_refs_t *r, const dfvc_decoupled_refs_in_t *in,
                                dfvc_decoupled_refs_out_t *out);

#endif

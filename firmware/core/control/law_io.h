/*
 * law_io.h - what a control law reads each period and what it reports
 * besides its voltage, as types only (no state, no step). The laws of
 * control/ read the sample where their caller filled it and write the
 * telemetry where their caller publishes it: the period pays no copy of
 * either (issue 24 point 8). The app's law table names them ctrl_in_t and
 * ctrl_telemetry_t (firmware/app/ctrl.h).
 */
#ifndef FD_CONTROL_LAW_IO_H
#define FD_CONTROL_LAW_IO_H

#include <stdbool.h>

#include "math/frames.h"

/* One period's sample and references. */
typedef struct {
  ab_t i_ab;            /* measured currents at the sampling instant [A] */
  ab_t v_applied;       /* voltage applied over the period ending at the sample [V] */
  float theta_e;        /* electrical (rotor) angle at the sampling instant [rad] */
  float omega_e;        /* electrical speed [rad/s] */
  float v_lin;          /* voltage amplitude the modulator can apply linearly now [V] */
  float torque_ref;     /* [N m] */
  float flux_ref;       /* stator flux amplitude, 0 = automatic [Vs] */
  bool current;         /* current mode: id_ref, iq_ref in force instead of torque_ref */
  float id_ref, iq_ref; /* current mode [A] */
} law_in_t;

/* What a law reports besides its voltage: the stator-flux quantities the
 * caller publishes (logs, CAN) and checks (loss of control), zero where a
 * law has no such quantity. */
typedef struct {
  float flux;     /* stator flux amplitude estimate [Vs] */
  float flux_ref; /* [Vs] */
  float delta;    /* load angle [rad], unless delta_lazy (ctrl_tm_delta) */
  float lam_d;    /* delta_lazy: the flux in the rotor frame whose angle it is [Vs] */
  float lam_q;
  bool delta_lazy; /* a law whose period needs no load angle leaves it to the readers */
  float i_ds;      /* stator-flux frame currents [A] */
  float i_qs;
  float i_qs_ref;
  float torque;  /* torque estimate [N m] */
  float obs_err; /* |observer flux - current-model flux| [Vs] (flux laws) */
} law_telemetry_t;

#endif

/*
 * pos_source.h - where the rotor angle comes from, behind one table of
 * sources {capabilities, init, reset, update, align, check, hold} and the
 * star point's columns {method, tracker, identification}; one row per
 * entry of POS_SOURCE_LIST (drive_enums.h, table in pos_sources.c): the
 * encoder (pos_encoder.c) and the star point (pos_dfc.c), whose rows
 * combine a method (pos_method.c: DFC, inverse DFC, IVD / Full IVD), a
 * tracker (pos_track.c: PLL, Kalman filter, EKF on the DFC signals) and an
 * identification (none, or pos_rls.c: the RLS of a, b).
 *
 * Every period the source turns the HAL's sample set into an estimate
 * {theta, omega, t, valid, health}: the electrical angle at instant t of the
 * period (relative to its start, as the HAL's timestamps), the electrical
 * speed, whether the estimate can be used, and the distance of this
 * period's measurement from the source's own prediction (a plausibility
 * measure: the drive raises the `position` fault beyond pos_err_max).
 */
#ifndef FLUXDRIVE_POS_SOURCE_H
#define FLUXDRIVE_POS_SOURCE_H

#include <stdbool.h>
#include <stdint.h>

#include "drive_config.h"
#include "estimation/angle_pll.h"
#include "estimation/dfc.h"
#include "estimation/kf_mech.h"
#include "estimation/rls_ab.h"
#include "hal.h"
#include "signal_row.h"

typedef struct {
  float theta;  /* electrical angle at t [rad], (-pi, pi] */
  float omega;  /* electrical speed [rad/s] (smooth: protections, laws) */
  float rate;   /* angle rate over the last period [rad/s] (no lag; average it) */
  float t;      /* instant of theta after the period start [s] */
  bool valid;   /* false: no usable measurement this period */
  float health; /* |measurement - prediction| [rad electrical] */
  float load;   /* load torque estimate [N m]: written by the Kalman filter sources only
                   (the drive zeroes it when it starts a source) */
  bool rls_ok;  /* ivd+kf+rls: the identified a, b have settled (pos_rls.c, rls_health);
                   written by that source only (the drive clears it when it starts a source) */
} pos_estimate_t;

/* What the drive knows of the last period, for the sources' models. */
typedef struct {
  float i_q;    /* rotor-frame q current [A] (the Full IVD's phase shifts) */
  float torque; /* electromagnetic torque estimate [N m] (the Kalman filter's input) */
  bool busy;    /* the drive's slow-rate rows run in this ISR (drive_schedule): a source
                   puts off what can wait a period (pos_rls.c) */
} pos_input_t;

/* A source's input and estimate, one argument (the update's fourth: all
 * in registers) */
typedef struct {
  pos_input_t in;
  pos_estimate_t out;
} pos_io_t;

/* The star point's columns (defined in pos_star.h) */
typedef struct pos_method_s pos_method_t;
typedef struct pos_tracker_s pos_tracker_t;
typedef struct pos_ident_s pos_ident_t;

enum {
  POS_CAP_ALIGN = 1u << 0, /* the angle offset can be found by an alignment */
  POS_CAP_GATED = 1u << 1  /* measures only with the gates on, through the DFC
                              window of the pattern (dfc_window.h): invalid in
                              offset calibration, resolved by the alignment */
};

/* The star point's state, in the parts its row's columns own (pos_star.h):
 * the measurement (the method's: DFC signals and angle), the tracker
 * (PLL, Kalman filter, EKF), the identification (RLS of a, b) and the
 * polarity evidence of the alignment (pos_dfc.c). */
typedef struct {
  dfc_cfg_t dc; /* the method and its a, b in force (the identification's when it runs) */
  dfc_signals_t sig;
  /* the last estimate, for logs: e^{j 2 theta_k} after step k (cos, sin)
   * and the instant it belongs to (relative to the period start) */
  float trace[2u * (DFC_ITER_MAX + 1u)];
  float t;
  uint32_t n;   /* periods since the reset (the components' time base) */
  uint8_t miss; /* periods since the last component (saturates) */
} pos_meas_t;

typedef struct {
  union { /* the tracker's own (the row's tracker column says which) */
    angle_pll_t pll;
    kf_mech_t kf;                               /* the Kalman filter and the EKF */
    float f[sizeof(kf_mech_t) / sizeof(float)]; /* its floats, read by index (pos_star.h) */
  } u;
  bool started; /* the tracker follows a branch since reset */
  float r;      /* the measurement variance of the last update (rad^2, or Gamma^2 for the EKF) */
} pos_track_state_t;

typedef struct {
  rls_ab_t rls;
  float avg[2];    /* a, b low-passed over the RLS's updates (pos_rls.c, rls_health) */
  float warm2;     /* ((2|p|)^n)^2 of the warm-started IVD at the RLS's a, b (pos_rls.c) */
  bool health_due; /* an update's a, b, warm gain and health wait for their period (pos_rls.c) */
  bool upd_due;    /* a refresh's update waits for a period without slow-rate rows (pos_rls.c) */
  struct {         /* its regressor, as the refresh's period had it (dfc_vec_t, sincos_t) */
    float al, be, c, s, k[4];
  } held;
} pos_ident_state_t;

typedef struct {
  /* sum of the speed change times -sin(theta) while the alignment pulls
   * the rotor towards 0 (pos_dfc.c) */
  float acc, w_prev;
  /* and the energy evidence: cos(theta) - cos(theta_0), its sum and its
   * recent value (a low-pass of cos(theta)) */
  float e_c0, e_acc, e_lp;
  uint32_t e_n0, e_n;
  bool aligned; /* the alignment has resolved the polarity */
} pos_polarity_t;

typedef union {
  struct {
    angle_pll_t pll;
    float offset; /* electrical angle at encoder zero in force [rad] */
    float half;   /* half a count [rad mechanical] */
    bool started; /* the PLL has seen a measurement since reset */
  } enc;
  struct {
    /* the row's columns, taken at init (pos_star.h) */
    const pos_method_t *method;
    const pos_tracker_t *tracker;
    const pos_ident_t *ident; /* NULL: none */
    pos_meas_t meas;
    pos_track_state_t trk;
    pos_ident_state_t id;
    pos_polarity_t pol;
  } star;
} pos_state_t;

/* A row: the drive's interface (caps and the functions), and the star
 * point's columns (NULL for the encoder, whose functions are its own):
 * how the angle is measured, what tracks it, what identifies the model
 * online. Rows: pos_sources.c; adding one: docs/architecture.md. */
typedef struct pos_source_row_s {
  uint32_t caps;      /* POS_CAP_* */
  unsigned n_signals; /* the number of signals (below); beside caps: no padding */
  void (*init)(pos_state_t *s, const drive_config_t *cfg);
  void (*reset)(pos_state_t *s);
  void (*update)(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp, pos_io_t *io);
  /* The rotor is held at electrical angle theta: take it as the reference
   * (alignment). Only for POS_CAP_ALIGN. */
  void (*align)(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp, float theta);
  /* Whether cfg can run this source: NULL, or the reason with *field set
   * to the parameter (NULL: nothing to check). */
  const char *(*check)(const drive_config_t *cfg, const char **field);
  /* The held start (start_mode 1, proc_hold.c) knows the rotor is at
   * electrical angle theta to within a quarter turn (the polarity from the
   * d-axis saturation pulses): take the branch of the estimate nearest it.
   * NULL: the source cannot start held (it has no angle at standstill). */
  void (*hold)(pos_state_t *s, float theta);
  /* the source's own signals (logs, docs/log-format.md): getters on its
   * pos_state_t, read after the ISR; NULL, 0: none */
  const signal_row_t *signals;
  /* the star point's columns (pos_star.h) */
  const pos_method_t *method;   /* DFC, inverse DFC, IVD (Full IVD with phase shifts) */
  const pos_tracker_t *tracker; /* PLL, Kalman filter, EKF */
  const pos_ident_t *ident;     /* NULL, or the RLS of a, b */
} pos_source_row_t;

/* The row of a source (NULL out of range). */
const pos_source_row_t *pos_source(pos_source_t src);

#endif

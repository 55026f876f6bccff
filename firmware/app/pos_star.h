/*
 * pos_star.h - the star point's position sources as data: a row of
 * pos_sources.c combines three columns, each a small const table,
 *   method          how the angle is measured from the DFC signal vector
 *                   (pos_method.c: DFC, inverse DFC, IVD / Full IVD)
 *   tracker         what follows it, angle and speed, and dates it
 *                   (pos_track.c: PLL, Kalman filter, EKF)
 *   identification  what identifies the model's a, b online (pos_rls.c:
 *                   the RLS; NULL: none, a and b are dfc_a, dfc_b)
 * and the source's functions (pos_dfc.c) decode them: no test of the
 * row's identity. Each column owns its part of pos_state_t.star (pos_meas_t,
 * pos_track_state_t, pos_ident_state_t); the polarity evidence of the
 * alignment is the source's own (pos_dfc.c).
 */
#ifndef FLUXDRIVE_POS_STAR_H
#define FLUXDRIVE_POS_STAR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "math/fd_math.h"
#include "math/frames.h"
#include "pos_source.h"

struct pos_method_s {
  dfc_method_t plain;   /* the method without phase shifts */
  dfc_method_t shifted; /* with dfc_phi_a or dfc_phi_b non-zero (the IVD's: the Full IVD) */
  /* the b term removed (IVD): the Kalman filter's R_k is (4.30), not
   * (4.29), and each iteration contracts the method's own error (Theorem
   * 1, pos_track.c meas_r_sys) */
  bool decoupled;
};

/* The index of a float member of a tracker's state in pos_track_state_t.u.f */
#define POS_TRACK_AT(type, member) ((uint8_t)(offsetof(type, member) / sizeof(float)))

struct pos_tracker_s {
  /* where its angle, speed and angle rate are: indices in u.f */
  uint8_t theta, omega, rate;
  /* its state is predicted to each period's edge (the Kalman filters): the
   * estimate's instant does not age without a component (pos_dfc.c) */
  bool at_edge;
  /* the period's prediction with the last period's torque; NULL: none */
  void (*predict)(pos_state_t *s, const drive_config_t *cfg, float torque);
  /* this period's measurement th (the branch of the method's angle nearest
   * the prediction; v the signal vector) into the estimate; a fresh
   * component: s->star.meas.miss == 0 */
  void (*measure)(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, float th,
                  pos_estimate_t *out);
  /* no measurement: coast, and the estimate from the state */
  void (*coast)(pos_state_t *s, pos_estimate_t *out);
  /* (re)start at angle theta and speed omega */
  void (*start)(pos_state_t *s, float theta, float omega);
  /* the first angle, from the method's theta0 on the vector v; NULL: theta0 */
  float (*first)(const pos_state_t *s, const dfc_vec_t *v, float theta0);
  /* the alignment's branch th replaces the tracked one */
  void (*branch)(pos_state_t *s, float th);
  /* at an enable (not in a period); NULL: nothing (the first measurement starts it) */
  void (*restart)(pos_state_t *s);
  void (*init)(pos_state_t *s, const drive_config_t *cfg);
  /* NULL, or the reason cfg cannot run it (*field: the parameter) */
  const char *(*check)(const drive_config_t *cfg, const char **field);
};

/* With an identification, once aligned, the IVD's iterations start from
 * the tracker's prediction (warm), not from the raw estimate (pos_dfc.c). */
struct pos_ident_s {
  /* the identification's a, b into s->star.meas.dc, and its state */
  void (*init)(pos_state_t *s, const drive_config_t *cfg);
  /* one period on the vector v at the prediction w (e^{j 2 theta}); when
   * a, b moved, whether they have settled into out->rls_ok; busy: the
   * drive's slow-rate rows run in this period (pos_input_t.busy) */
  void (*step)(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, const sincos_t *w,
               bool busy, pos_estimate_t *out);
  /* the alignment has ended (the warm start's gain) */
  void (*aligned)(pos_state_t *s);
  const char *(*check)(const drive_config_t *cfg, const char **field);
};

/* The columns (pos_method.c, pos_track.c, pos_rls.c) */
extern const pos_method_t pos_method_dfc, pos_method_dfc_inv, pos_method_ivd;
extern const pos_tracker_t pos_tracker_pll, pos_tracker_kf, pos_tracker_ekf;
extern const pos_ident_t pos_ident_rls;

/* The tracker's angle and speed */
static inline float pos_track_theta(const pos_state_t *s) {
  return s->star.trk.u.f[s->star.tracker->theta];
}
static inline float pos_track_omega(const pos_state_t *s) {
  return s->star.trk.u.f[s->star.tracker->omega];
}

/* The method's configuration from cfg (its a, b: dfc_a, dfc_b); every
 * period (the live parameters), inlined */
static inline dfc_cfg_t pos_method_cfg(const pos_method_t *m, const drive_config_t *cfg) {
  const bool shifted = fabsf(cfg->dfc_phi_a) > 0.0f || fabsf(cfg->dfc_phi_b) > 0.0f;
  const dfc_cfg_t d = {shifted ? m->shifted : m->plain,
                       cfg->dfc_a,
                       cfg->dfc_b,
                       cfg->dfc_phi_a,
                       cfg->dfc_phi_b,
                       cfg->dfc_iter};
  return d;
}

/* The star point's functions, for the rows (pos_dfc.c) */
void pos_star_init(pos_state_t *s, const drive_config_t *cfg);
void pos_star_reset(pos_state_t *s);
void pos_star_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                     pos_io_t *io);
void pos_star_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                    float theta);
const char *pos_star_check(const drive_config_t *cfg, const char **field);
void pos_star_hold(pos_state_t *s, float theta);

#endif

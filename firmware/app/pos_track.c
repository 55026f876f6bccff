/*
 * pos_track.c - the tracker column of the star-point sources (pos_star.h):
 * what follows the method's angle (Fabbri 2022 chapter 4, on
 * estimation/angle_pll.h and estimation/kf_mech.h):
 *   pll  the angle PLL on the method's angle, dated at the newest
 *        component's edge (it ages a period per period without one)
 *   kf   the Kalman filter on the rotor's mechanics (4.46)-(4.49), on the
 *        method's angle: speed, angle and load torque; R_k of (4.29) (DFC:
 *        the measured |Gamma|, the b term included, (4.31)) or (4.30)
 *        (IVD: the b term removed, |Gamma| -> a), with the speed-dependent
 *        signal variance (4.42)/(4.43), plus kf_r_sys times the method's
 *        own angle error ((3.13), Theorem 1: meas_r_sys), times kf_r_scale
 *   ekf  the same filter updated on the signal vector itself
 *        (4.35)-(4.41), a and b known
 * The Kalman filter's state is the angle at the newest component's edge:
 * it predicts one period every period (the edges recur at the same point
 * of the pattern) with the last period's torque estimate as input.
 */
#include <stddef.h>

#include "math/cordic_q31.h"
#include "math/fd_math.h"
#include "pos_star.h"

_Static_assert(sizeof(angle_pll_t) <= sizeof(kf_mech_t),
               "pos_track_state_t.u.f covers the PLL's state as the filter's");

static kf_mech_cfg_t kf_cfg_of(const drive_config_t *cfg) {
  const kf_mech_cfg_t k = {cfg->ts,
                           cfg->pole_pairs,
                           cfg->inertia,
                           cfg->friction,
                           {cfg->kf_q_omega, cfg->kf_q_theta, cfg->kf_q_load}};
  return k;
}

/* The Kalman filter's covariance at a (re)start: speed within 30 rad/s,
 * angle within 0.3 rad, load within 0.3 N m (1 sigma). */
static const float kf_p0[3] = {900.0f, 0.09f, 0.09f};

/* ---- the PLL ---- */

FD_COLD static void trk_pll_init(pos_state_t *s, const drive_config_t *cfg) {
  angle_pll_init(&s->star.trk.u.pll, cfg->pll_bw, cfg->ts);
}

static void trk_pll_start(pos_state_t *s, float theta, float omega) {
  angle_pll_reset(&s->star.trk.u.pll, theta, omega);
}

/* the alignment's branch: the PLL restarts on it at its speed */
FD_COLD static void trk_pll_branch(pos_state_t *s, float th) {
  angle_pll_reset(&s->star.trk.u.pll, th, s->star.trk.u.pll.omega);
}

static void trk_pll_measure(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, float th,
                            pos_estimate_t *out) {
  (void)cfg;
  (void)v;
  angle_pll_t *pll = &s->star.trk.u.pll;
  angle_pll_update(pll, th);
  out->theta = th;
  out->omega = pll->omega;
  out->rate = pll->omega_rate;
}

static void trk_pll_coast(pos_state_t *s, pos_estimate_t *out) {
  angle_pll_t *pll = &s->star.trk.u.pll;
  angle_pll_update(pll, NAN);
  out->theta = pll->theta;
  out->omega = pll->omega;
  out->rate = pll->omega_rate;
}

const pos_tracker_t pos_tracker_pll = {POS_TRACK_AT(angle_pll_t, theta),
                                       POS_TRACK_AT(angle_pll_t, omega),
                                       POS_TRACK_AT(angle_pll_t, omega_rate),
                                       false,
                                       NULL,
                                       trk_pll_measure,
                                       trk_pll_coast,
                                       trk_pll_start,
                                       NULL,
                                       trk_pll_branch,
                                       NULL,
                                       trk_pll_init,
                                       NULL};

/* ---- the Kalman filter (kf, ekf) ---- */

FD_COLD static void trk_kf_init(pos_state_t *s, const drive_config_t *cfg) {
  const kf_mech_cfg_t kc = kf_cfg_of(cfg);
  (void)kf_mech_init(&s->star.trk.u.kf, &kc); /* trk_kf_check: usable */
}

FD_COLD static void trk_kf_restart(pos_state_t *s) {
  kf_mech_reset(&s->star.trk.u.kf, 0.0f, 0.0f, kf_p0);
}

static void trk_kf_start(pos_state_t *s, float theta, float omega) {
  kf_mech_reset(&s->star.trk.u.kf, theta, omega, kf_p0);
}

/* one period ahead: this period's edge (header), at the live tuning */
static void trk_kf_predict(pos_state_t *s, const drive_config_t *cfg, float torque) {
  kf_mech_t *kf = &s->star.trk.u.kf;
  kf->cfg.q[0] = cfg->kf_q_omega;
  kf->cfg.q[1] = cfg->kf_q_theta;
  kf->cfg.q[2] = cfg->kf_q_load;
  /* mut: kf_torque_input_dropped */
  kf_mech_predict(kf, torque);
}

static void trk_kf_out(const kf_mech_t *kf, pos_estimate_t *out) {
  out->theta = kf->x[1];
  out->omega = kf->x[0];
  out->rate = kf->x[0];
  out->load = kf->x[2];
}

static void trk_kf_coast(pos_state_t *s, pos_estimate_t *out) {
  trk_kf_out(&s->star.trk.u.kf, out); /* the prediction's */
}

/* The variance of the method's own angle error, the part (4.29) leaves
 * out: the standard DFC's 4theta term turns 2theta by Delta_0 of (3.13),
 * at most atan(|p| / sqrt(1 - p^2)) = asin|p|, p = b/a (3.7); each IVD
 * iteration contracts it, |tan Delta_k| <= 2|p| |tan Delta_k-1| (Theorem
 * 1, (3.81)). A periodic error of 2theta peak D is one of theta peak D/2,
 * variance D^2/8. Without it the filter took the angle's error for 5 to
 * 11 times smaller than it was (std; drawn star machines of |p| 0.2-0.4):
 * its speed follows the systematic error, the speed loop saturates, the
 * drive trips overspeed, overcurrent or lost_control (docs/machines.md). */
#define POS_DFC_P_SYS 0.999f /* |p| held below 1: tan Delta_0 finite */
static float meas_r_sys(const pos_state_t *s) {
  const dfc_cfg_t *dc = &s->star.meas.dc;
  const float p = fd_minf(fabsf(dc->b) / fd_maxf(fabsf(dc->a), 1e-12f), POS_DFC_P_SYS);
  float tn = p / sqrtf((1.0f - p) * (1.0f + p)); /* tan Delta_0 (3.13) */
  if (s->star.method->decoupled) {
    for (unsigned k = 0u; k < dc->iterations && k < DFC_ITER_MAX; ++k) {
      tn *= 2.0f * p; /* Theorem 1 */
    }
  }
  /* atan(tn) to 0.005 rad (x / (1 + 0.28125 x^2), and its complement
   * above 1): a variance, no CORDIC call */
  const float d =
      tn <= 1.0f ? tn / (1.0f + 0.28125f * tn * tn) : 0.5f * FRAMES_PI - tn / (tn * tn + 0.28125f);
  /* mut: kf_r_method_error_tenth */
  return 0.125f * d * d;
}

/* The signal variance (4.42)/(4.43) at the filter's speed */
static float meas_var(const pos_state_t *s, const drive_config_t *cfg) {
  const float s2 = cfg->dfc_sigma * cfg->dfc_sigma;
  return kf_mech_r_speed(s2, cfg->kf_r_m * s2, cfg->kf_r_wf, cfg->kf_r_m2 * s2,
                         s->star.trk.u.kf.x[0]);
}

/* The measurement variance of the angle (4.29)-(4.31) plus kf_r_sys times
 * the method's own error, with (4.42)/(4.43), times kf_r_scale. The
 * method's error: from a raw start the bound of meas_r_sys; from the
 * filter's prediction (the warm-started IVD of an identification, once
 * aligned, whose fixed point is the angle itself) what the iterations
 * leave of the prediction's error, (2|p|)^2n P_22. Not nothing: right
 * after the alignment's branch flip the reset filter's P_22 is 0.09
 * rad^2, and without the term the filter took that period's angle as exact
 * (R 1.5e-7 rad^2) and its speed jumped by 2000 rad/s (drawn star seed 1
 * from 3.1 and 3.2 rad, tests/python/test_start_polarity.py). */
static float meas_r(const pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v) {
  const float var = meas_var(s, cfg);
  const bool warm = s->star.ident != NULL && s->star.pol.aligned; /* pos_star.h */
  /* (4.29): |Gamma|^2, the b term in it (4.31); the IVD has removed it (4.30) */
  const float g2 = s->star.method->decoupled ? s->star.meas.dc.a * s->star.meas.dc.a
                                             : v->al * v->al + v->be * v->be;
  /* mut: kf_r_warm_ivd_exact */
  const float sys = cfg->kf_r_sys * (warm ? s->star.id.warm2 * kf_mech_var_theta(&s->star.trk.u.kf)
                                          /* mut: kf_r_without_the_method_error */
                                          : meas_r_sys(s));
  return cfg->kf_r_scale * (0.25f * var / fd_maxf(g2, 1e-12f) + sys);
}

static void trk_kf_measure(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, float th,
                           pos_estimate_t *out) {
  kf_mech_t *kf = &s->star.trk.u.kf;
  if (s->star.meas.miss == 0u) { /* a fresh component */
    s->star.trk.r = meas_r(s, cfg, v);
    (void)kf_mech_update(kf, th, s->star.trk.r);
  }
  trk_kf_out(kf, out);
}

FD_COLD static void trk_kf_branch(pos_state_t *s, float th) {
  trk_kf_start(s, th, s->star.trk.u.kf.x[0]);
}

FD_COLD static const char *trk_kf_check(const drive_config_t *cfg, const char **field) {
  const kf_mech_cfg_t kc = kf_cfg_of(cfg);
  kf_mech_t k;
  if (!kf_mech_init(&k, &kc)) {
    *field = "inertia";
    return "the Kalman filter's model needs a finite inertia, pole pairs and friction";
  }
  return NULL;
}

const pos_tracker_t pos_tracker_kf = {POS_TRACK_AT(kf_mech_t, x[1]),
                                      POS_TRACK_AT(kf_mech_t, x[0]),
                                      POS_TRACK_AT(kf_mech_t, x[0]),
                                      true,
                                      trk_kf_predict,
                                      trk_kf_measure,
                                      trk_kf_coast,
                                      trk_kf_start,
                                      NULL,
                                      trk_kf_branch,
                                      trk_kf_restart,
                                      trk_kf_init,
                                      trk_kf_check};

/* ---- the EKF ---- */

static void trk_ekf_measure(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, float th,
                            pos_estimate_t *out) {
  (void)th;
  kf_mech_t *kf = &s->star.trk.u.kf;
  if (s->star.meas.miss == 0u) {                        /* a fresh component */
    s->star.trk.r = cfg->kf_r_scale * meas_var(s, cfg); /* (4.38) */
    (void)kf_mech_update_ekf(kf, v->al, v->be, s->star.meas.dc.a, s->star.meas.dc.b, v->k,
                             s->star.trk.r);
  }
  trk_kf_out(kf, out);
}

/* The EKF's first angle: the model (4.35) inverted on the whole turn, by
 * the IVD run to convergence (3.76) (Theorem 1: |p| < 1/2, pos_star_check),
 * not the standard DFC's angle, off by up to asin|p| / 2 (0.23 rad at
 * |p| = 0.45): near a corner of h (|h'| = 2|a| |1 + 2p e^{-j6theta}|, down
 * to 2|a| (1 - 2|p|)) that start lies on the other arm of the fold, the
 * linearised update (4.36) pulls it away from the rotor's angle, and the
 * angle's jumps between updates go into the speed (prior 30 rad/s). */
static float trk_ekf_start_angle(const pos_state_t *s, const dfc_vec_t *v, float theta0) {
  dfc_cfg_t d = s->star.meas.dc;
  d.method = DFC_IVD;
  /* mut: ekf_start_on_standard_dfc_angle */
  d.iterations = DFC_ITER_MAX;
  float c2, s2;
  if (!dfc_vector2(&d, s->star.meas.sig.g, v, 0.0f, &c2, &s2, NULL)) {
    return theta0;
  }
  return 0.5f * fd_cordic_atan2f(s2, c2);
}

/* h(theta) (4.35) is pi-periodic: the branch is a relabelling, not a new
 * measurement; the covariance the filter has built stays (reset to kf_p0,
 * its next updates took steps of the angle's prior, 0.3 rad, on a
 * linearisation valid over a tenth of that near the corners of h at high
 * |p|: the jump of issue 23 point 4) */
FD_COLD static void trk_ekf_branch(pos_state_t *s, float th) {
  /* mut: ekf_branch_flip_resets_covariance */
  s->star.trk.u.kf.x[1] = th;
}

/* |b/a| the EKF is given at most: measured on the Fig. 3.3 machine, where
 * it works to |p| = 0.36 (0.40 with the star channel unclipped) and not
 * from 0.37 (0.41); docs/dfc.md, "EKF: the range of p" */
#define POS_DFC_EKF_P_MAX 0.35f

FD_COLD static const char *trk_ekf_check(const drive_config_t *cfg, const char **field) {
  /* mut: ekf_p_limit_off */
  if (!(fabsf(cfg->dfc_b) <= POS_DFC_EKF_P_MAX * fabsf(cfg->dfc_a))) {
    *field = "dfc_b";
    return "the EKF needs |p| = |dfc_b / dfc_a| <= 0.35: its update (4.36) is linearised on "
           "h(theta), whose slope falls to 2 |a| (1 - 2|p|) at the corners of h, where beyond "
           "that the filter stops on the wrong side (docs/dfc.md, \"EKF: the range of p\"); "
           "use ivd+kf";
  }
  return trk_kf_check(cfg, field);
}

const pos_tracker_t pos_tracker_ekf = {POS_TRACK_AT(kf_mech_t, x[1]),
                                       POS_TRACK_AT(kf_mech_t, x[0]),
                                       POS_TRACK_AT(kf_mech_t, x[0]),
                                       true,
                                       trk_kf_predict,
                                       trk_ekf_measure,
                                       trk_kf_coast,
                                       trk_kf_start,
                                       trk_ekf_start_angle,
                                       trk_ekf_branch,
                                       trk_kf_restart,
                                       trk_kf_init,
                                       trk_ekf_check};

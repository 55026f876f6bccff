/*
 * pos_dfc.c - the star point as a position source: Direct Flux Control
 * (standard, inverse) and Iterative Vector Decoupling (IVD, Full IVD),
 * Fabbri 2022 chapter 3, on estimation/dfc.h; angle and speed tracked by
 * the angle PLL or by the Kalman filter on the rotor's mechanics (chapter
 * 4: estimation/kf_mech.h), which also estimates the load torque:
 *   dfc, dfc_inv, ivd   the method's angle, PLL
 *   dfc+kf, ivd+kf      the method's angle, Kalman filter (4.46)-(4.49),
 *                       R_k of (4.29) (DFC: the measured |Gamma|, the b
 *                       term included, (4.31)) or (4.30) (IVD: the b term
 *                       removed, |Gamma| -> a), with the speed-dependent
 *                       signal variance (4.42)/(4.43), plus kf_r_sys
 *                       times the method's own angle error ((3.13),
 *                       Theorem 1: meas_r_sys), times kf_r_scale
 *   ekf                 the Kalman filter updated on the signal vector
 *                       itself (4.35)-(4.41), a and b known
 *   ivd+kf+rls          ivd+kf with a, b identified online by the RLS of
 *                       (4.51)-(4.57), the loop of Fig. 4.4: the IVD uses
 *                       the identified a, b (held in the IVD's convergence
 *                       region |b/a| <= 0.45 and within a factor 4 of
 *                       dfc_a) and, once aligned, starts its
 *                       iterations from the filter's prediction (from
 *                       the raw estimate their residual error biased b:
 *                       issue 23 point 5); the RLS regressor is the filter's
 *                       predicted angle (a priori: free of this period's
 *                       signal noise, which the IVD angle carries - no
 *                       errors-in-variables bias); it identifies only above
 *                       rls_w_min, where the 2theta and 4theta columns are
 *                       separable, and never with the EKF: the EKF's angle
 *                       is itself a function of a and b, the thesis's
 *                       non-observable combination (5.1.3), so no source
 *                       offers it.
 * The Kalman filter's state is the angle at the newest component's edge:
 * it predicts one period every period (the edges recur at the same point
 * of the pattern) with the last period's torque estimate as input.
 *
 * Each period brings one component of the DFC signal vector (the test
 * vector of the last window, hal_sample_t.test_vector, and the star-point
 * samples around its edge); the others are held, so the vector mixes three
 * consecutive periods. The held components are turned to the newest one's
 * instant with the tracker's speed (dfc_signals_vector: the sequentiality
 * effect, docs/dfc.md); the estimate is dated at that edge, and the drive
 * extrapolates the angle from it to the current sample.
 * The estimate is 2 theta_e. The branch (theta or theta + pi) follows the
 * tracker's (PLL's or filter's) prediction; the magnet's polarity is resolved once, by the
 * alignment (Fabbri 2022, 3.1.3; hence align_time > 0): the d current
 * along theta = 0 pulls the rotor with a torque of the sign of
 * -sin(theta). The tracked estimate is theta or theta + pi. First
 * evidence, the energy: the torque derives from the potential -k cos
 * theta, so from rest cos(theta) - cos(theta_0) >= 0 on the right branch
 * (pol_energy). Second, where that shows no motion: the sum of the
 * change of its speed times -sin(estimate), positive when the estimate is
 * theta (the rotor accelerates the way the torque pulls), negative when it
 * is theta + pi. A rotor that does not move (already at 0, or held)
 * leaves both near zero: then the branch nearest 0 is taken, where the
 * current holds the north pole. A light rotor swinging through the
 * alignment is thus resolved as well as one that settles (tests: both
 * magnet polarities; docs/dfc.md).
 */
#include <stddef.h>

#include "math/cordic_q31.h"
#include "math/fd_math.h"
#include "math/frames.h"
#include "pos_dfc_signals.h"
#include "pos_source.h"

enum { TRACK_PLL = 0, TRACK_KF = 1, TRACK_EKF = 2 };

/* a mask, inlined: called on every period's estimate */
#define POS_DFC_IVD_MASK                                                                           \
  ((1u << POS_SOURCE_IVD) | (1u << POS_SOURCE_IVD_KF) | (1u << POS_SOURCE_IVD_KF_RLS))
static inline bool is_ivd(pos_source_t src) {
  return (unsigned)src < 32u && ((1u << (unsigned)src) & POS_DFC_IVD_MASK) != 0u;
}

static uint8_t track_of(pos_source_t src) {
  if (src == POS_SOURCE_EKF) {
    return TRACK_EKF;
  }
  return (src == POS_SOURCE_DFC_KF || src == POS_SOURCE_IVD_KF || src == POS_SOURCE_IVD_KF_RLS)
             ? TRACK_KF
             : TRACK_PLL;
}

static dfc_method_t method_of(pos_source_t src, const drive_config_t *cfg) {
  if (src == POS_SOURCE_DFC_INV) {
    return DFC_INVERSE;
  }
  if (is_ivd(src)) {
    return (fabsf(cfg->dfc_phi_a) > 0.0f || fabsf(cfg->dfc_phi_b) > 0.0f) ? DFC_FULL_IVD : DFC_IVD;
  }
  return DFC_STANDARD;
}

static dfc_cfg_t cfg_of(const drive_config_t *cfg) {
  const dfc_cfg_t d = {method_of(cfg->pos_source, cfg),
                       cfg->dfc_a,
                       cfg->dfc_b,
                       cfg->dfc_phi_a,
                       cfg->dfc_phi_b,
                       cfg->dfc_iter};
  return d;
}

static kf_mech_cfg_t kf_cfg_of(const drive_config_t *cfg) {
  const kf_mech_cfg_t k = {cfg->ts,
                           cfg->pole_pairs,
                           cfg->inertia,
                           cfg->friction,
                           {cfg->kf_q_omega, cfg->kf_q_theta, cfg->kf_q_load}};
  return k;
}

static rls_ab_cfg_t rls_cfg_of(const drive_config_t *cfg) {
  const rls_ab_cfg_t r = {cfg->rls_lambda, cfg->dfc_sigma * cfg->dfc_sigma, cfg->rls_p_min,
                          cfg->rls_p_max};
  return r;
}

/* The Kalman filter's covariance at a (re)start: speed within 30 rad/s,
 * angle within 0.3 rad, load within 0.3 N m (1 sigma). */
static const float kf_p0[3] = {900.0f, 0.09f, 0.09f};

#define POS_DFC_P_MAX 0.45f /* |b/a| the IVD is given at most (Theorem 1: < 1/2) */
/* The IVD's a, b: the RLS's within the guards (header). */
static void rls_guarded(const rls_ab_t *r, const drive_config_t *cfg, dfc_cfg_t *dc) {
  const float a0 = fabsf(cfg->dfc_a);
  const float am = fd_clampf(fabsf(r->x[0]), 0.25f * a0, 4.0f * a0);
  dc->a = cfg->dfc_a < 0.0f ? -am : am;
  dc->b = fd_clampf(r->x[1], -POS_DFC_P_MAX * am, POS_DFC_P_MAX * am);
}

static void pol_reset(pos_state_t *s) {
  s->dfc.pol_acc = 0.0f;
  s->dfc.w_prev = 0.0f;
  s->dfc.e_c0 = 0.0f;
  s->dfc.e_acc = 0.0f;
  s->dfc.e_lp = 0.0f;
  s->dfc.e_n0 = 0u;
  s->dfc.e_n = 0u;
  s->dfc.aligned = false;
}

FD_COLD static void pdfc_init(pos_state_t *s, const drive_config_t *cfg) {
  angle_pll_init(&s->dfc.pll, cfg->pll_bw, cfg->ts);
  s->dfc.track = track_of(cfg->pos_source);
  s->dfc.rls_on = cfg->pos_source == POS_SOURCE_IVD_KF_RLS;
  const kf_mech_cfg_t kc = kf_cfg_of(cfg);
  (void)kf_mech_init(&s->dfc.kf, &kc); /* pdfc_check_cfg: usable */
  const rls_ab_cfg_t rc = rls_cfg_of(cfg);
  (void)rls_ab_init(&s->dfc.rls, &rc);
  rls_ab_reset(&s->dfc.rls, cfg->dfc_a, cfg->dfc_b, cfg->rls_p_max);
  s->dfc.rls_avg[0] = 0.0f; /* not settled before its updates (rls_health) */
  s->dfc.rls_avg[1] = 0.0f;
  s->dfc.r = 0.0f;
  s->dfc.warm2 = 1.0f;
  s->dfc.miss = 0u;
  s->dfc.dc = cfg_of(cfg);
  if (s->dfc.rls_on) {
    rls_guarded(&s->dfc.rls, cfg, &s->dfc.dc); /* the RLS's start, guarded */
  }
  dfc_signals_reset(&s->dfc.sig);
  s->dfc.started = false;
  s->dfc.t = 0.0f;
  s->dfc.n = 0u;
  pol_reset(s);
  for (unsigned k = 0u; k < 2u * (DFC_ITER_MAX + 1u); ++k) {
    s->dfc.trace[k] = 0.0f;
  }
}

FD_COLD static void pdfc_reset(pos_state_t *s) { /* at an enable, not in a period */
  kf_mech_reset(&s->dfc.kf, 0.0f, 0.0f, kf_p0);
  s->dfc.miss = 0u;
  dfc_signals_reset(&s->dfc.sig);
  s->dfc.started = false;
  s->dfc.n = 0u;
  pol_reset(s);
}

/* The branch of 2 theta / 2 nearest ref. */
static float nearest_branch(float theta0, float ref) {
  const float d = frames_wrap_pi(theta0 - ref);
  return (d > 0.5f * FRAMES_PI || d < -0.5f * FRAMES_PI) ? frames_wrap_pi(theta0 + FRAMES_PI)
                                                         : theta0;
}

#define POS_DFC_COAST 16u /* periods without a component before the filter holds */

/* The tracker's angle and speed: the PLL's or the Kalman filter's. */
static float trk_theta(const pos_state_t *s) {
  return s->dfc.track == TRACK_PLL ? s->dfc.pll.theta : s->dfc.kf.x[1];
}

static float trk_omega(const pos_state_t *s) {
  return s->dfc.track == TRACK_PLL ? s->dfc.pll.omega : s->dfc.kf.x[0];
}

static void trk_reset(pos_state_t *s, float theta, float omega) {
  if (s->dfc.track == TRACK_PLL) {
    angle_pll_reset(&s->dfc.pll, theta, omega);
  } else {
    kf_mech_reset(&s->dfc.kf, theta, omega, kf_p0);
  }
}

/* (2|p|)^2n: the warm-started IVD's n iterations contract the
 * prediction's error of 2theta by (2|p|)^n (Theorem 1, (3.81)); its
 * square scales the prediction's variance into the measurement's
 * (meas_r). Taken when the RLS moves a, b (every third period at most). */
static void warm_gain(pos_state_t *s) {
  const float p = fd_minf(fabsf(s->dfc.dc.b) / fd_maxf(fabsf(s->dfc.dc.a), 1e-12f), 0.5f);
  float c = 1.0f;
  for (unsigned k = 0u; k < s->dfc.dc.iterations && k < DFC_ITER_MAX; ++k) {
    c *= 2.0f * p;
  }
  s->dfc.warm2 = c * c;
}

/* The RLS of a, b (4.51)-(4.57) on this vector at the filter's predicted
 * angle, and the IVD's a, b from it, within the guards (header). One
 * update per refresh of the whole vector (when component a is the newest:
 * every third period, 5.3 kHz, the thesis's DFC rate): successive updates
 * then share no sample, as the RLS's independent noise assumes. */
static bool rls_step(pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v, bool fresh,
                     const sincos_t *u /* the prediction, used once aligned */) {
  rls_ab_t *r = &s->dfc.rls;
  bool upd = false;
  if (u != NULL && fresh && s->dfc.sig.last == 0u && s->dfc.aligned &&
      fabsf(s->dfc.kf.x[0]) > cfg->rls_w_min) {
    r->cfg = rls_cfg_of(cfg); /* the live tuning, for this update and rls_health */
    upd = rls_ab_update(r, v->al, v->be, u->c, u->s, v->k);
  }
  if (upd) { /* the IVD's a, b move only here (pdfc_update keeps them) */
    rls_guarded(r, cfg, &s->dfc.dc);
    warm_gain(s);
  }
  return upd;
}

/* The RLS's health (rls_ok), after each update: its a and b have settled
 * within the band, each of them
 *   steady: the distance it still has to go within POS_DFC_RLS_BAND:
 *     its distance from its own low-pass over the updates (1 /
 *     POS_DFC_RLS_AVG updates; from 0 at the start: no update, no
 *     information, not settled) is the rate it moves at times that lag,
 *     and an RLS at its covariance P converges with a time constant of
 *     about 1 + R / P updates (gain P / (P + R)): the distance left is the
 *     rate times that time constant when it is the longer,
 *   known: twice the standard deviation its covariance states, sqrt(2 P)
 *     (the floor-limited RLS's estimate has a variance of about P / 2),
 *     within the band (a small b against the floor: p too small),
 * and neither held at the IVD's guards (rls_guarded). A bias the model
 * itself carries is not seen (docs/dfc.md). */
#define POS_DFC_RLS_BAND 0.05f       /* issue 23 point 5: the 5 % band */
#define POS_DFC_RLS_AVG  0.00390625f /* 1/256 per update: 48 ms at 5.3 kHz */
static bool rls_health(pos_state_t *s, const drive_config_t *cfg) {
  const rls_ab_t *r = &s->dfc.rls;
  bool ok = true;
  for (unsigned j = 0u; j < 2u; ++j) {
    s->dfc.rls_avg[j] += POS_DFC_RLS_AVG * (r->x[j] - s->dfc.rls_avg[j]);
    const float tol = POS_DFC_RLS_BAND * fabsf(r->x[j]);
    const float pjj = r->p[(size_t)2u * j];
    const float t_rls = 1.0f + r->cfg.r / pjj; /* updates; P >= p_min > 0 */
    const float go = fabsf(r->x[j] - s->dfc.rls_avg[j]) * fd_maxf(1.0f, POS_DFC_RLS_AVG * t_rls);
    ok = ok && go <= tol && 2.0f * pjj <= tol * tol;
  }
  const float a0 = fabsf(cfg->dfc_a), am = fabsf(r->x[0]);
  return ok && am > 0.25f * a0 && am < 4.0f * a0 && fabsf(r->x[1]) < POS_DFC_P_MAX * am;
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
static float meas_r_sys(const pos_state_t *s, const drive_config_t *cfg) {
  const float p = fd_minf(fabsf(s->dfc.dc.b) / fd_maxf(fabsf(s->dfc.dc.a), 1e-12f), POS_DFC_P_SYS);
  float tn = p / sqrtf((1.0f - p) * (1.0f + p)); /* tan Delta_0 (3.13) */
  if (is_ivd(cfg->pos_source)) {
    for (unsigned k = 0u; k < s->dfc.dc.iterations && k < DFC_ITER_MAX; ++k) {
      tn *= 2.0f * p; /* Theorem 1 */
    }
  }
  /* atan(tn) to 0.005 rad (x / (1 + 0.28125 x^2), and its complement
   * above 1): a variance, no CORDIC call */
  const float d =
      tn <= 1.0f ? tn / (1.0f + 0.28125f * tn * tn) : 0.5f * FRAMES_PI - tn / (tn * tn + 0.28125f);
  return 0.125f * d * d;
}

/* The measurement variance of the angle (4.29)-(4.31) plus kf_r_sys times
 * the method's own error, or of the signals (4.38), with (4.42)/(4.43),
 * times kf_r_scale. The method's error: from a raw start the bound of
 * meas_r_sys; from the filter's prediction (the warm-started IVD of
 * ivd+kf+rls once aligned, whose fixed point is the angle itself) what the
 * iterations leave of the prediction's error, (2|p|)^2n P_22. Not nothing:
 * right after the alignment's branch flip the reset filter's P_22 is 0.09
 * rad^2, and without the term the filter took that period's angle as exact
 * (R 1.5e-7 rad^2) and its speed jumped by 2000 rad/s (drawn star seed 1
 * from 3.1 and 3.2 rad, tests/python/test_start_polarity.py). */
static float meas_r(const pos_state_t *s, const drive_config_t *cfg, const dfc_vec_t *v,
                    bool warm) {
  const float s2 = cfg->dfc_sigma * cfg->dfc_sigma;
  const float var =
      kf_mech_r_speed(s2, cfg->kf_r_m * s2, cfg->kf_r_wf, cfg->kf_r_m2 * s2, s->dfc.kf.x[0]);
  if (s->dfc.track == TRACK_EKF) {
    return cfg->kf_r_scale * var; /* (4.38) */
  }
  /* (4.29): |Gamma|^2, the b term in it (4.31); the IVD has removed it (4.30) */
  const float g2 =
      is_ivd(cfg->pos_source) ? s->dfc.dc.a * s->dfc.dc.a : v->al * v->al + v->be * v->be;
  const float sys =
      cfg->kf_r_sys * (warm ? s->dfc.warm2 * kf_mech_var_theta(&s->dfc.kf) : meas_r_sys(s, cfg));
  return cfg->kf_r_scale * (0.25f * var / fd_maxf(g2, 1e-12f) + sys);
}

/* The energy evidence: the rotor starts at rest and the alignment's torque
 * -k sin(theta) derives from the potential -k cos(theta), so on the right
 * branch k (cos theta(t) - cos theta_0) = kinetic energy + friction's loss
 * >= 0 at every instant, and <= 0 on the branch pi off. Positions only: no
 * speed estimate's ringing in it. cos(theta_0): the mean over the first
 * POS_DFC_E_REF periods (the rotor has not moved yet). The evidence is the
 * mean over the alignment plus the recent value (a low-pass over
 * POS_DFC_E_REF periods): both >= 0 on the right branch; the mean holds a
 * rotor swinging about 0 (the recent value may meet a turning point), the
 * recent value one falling away from the unstable point pi (most of its
 * motion comes at the end). */
#define POS_DFC_E_REF 32u
static void pol_energy(pos_state_t *s, float c) {
  if (s->dfc.e_n0 < POS_DFC_E_REF) {
    s->dfc.e_c0 += c;
    if (++s->dfc.e_n0 == POS_DFC_E_REF) {
      s->dfc.e_c0 *= 1.0f / (float)POS_DFC_E_REF;
      s->dfc.e_lp = s->dfc.e_c0;
    }
  } else if (s->dfc.e_n < UINT32_MAX) {
    s->dfc.e_acc += c - s->dfc.e_c0;
    s->dfc.e_lp += (c - s->dfc.e_lp) * (1.0f / (float)POS_DFC_E_REF);
    s->dfc.e_n++;
  }
}

/* The EKF's first angle: the model (4.35) inverted on the whole turn, by
 * the IVD run to convergence (3.76) (Theorem 1: |p| < 1/2, pdfc_check_cfg),
 * not the standard DFC's angle, off by up to asin|p| / 2 (0.23 rad at
 * |p| = 0.45): near a corner of h (|h'| = 2|a| |1 + 2p e^{-j6theta}|, down
 * to 2|a| (1 - 2|p|)) that start lies on the other arm of the fold, the
 * linearised update (4.36) pulls it away from the rotor's angle, and the
 * angle's jumps between updates go into the speed (prior 30 rad/s). */
static float ekf_start_angle(const pos_state_t *s, const dfc_vec_t *v, float theta0) {
  dfc_cfg_t d = s->dfc.dc;
  d.method = DFC_IVD;
  d.iterations = DFC_ITER_MAX;
  float c2, s2;
  if (!dfc_vector2(&d, s->dfc.sig.g, v, 0.0f, &c2, &s2, NULL)) {
    return theta0;
  }
  return 0.5f * fd_cordic_atan2f(s2, c2);
}

static void pdfc_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                        pos_io_t *io) {
  const pos_input_t *in = &io->in;
  pos_estimate_t *out = &io->out;
  angle_pll_t *pll = &s->dfc.pll;
  kf_mech_t *kf = &s->dfc.kf;
  const bool kalman = s->dfc.track != TRACK_PLL;
  /* the live parameters (b, iterations, phase shifts) in force */
  const float rls_a = s->dfc.dc.a, rls_b = s->dfc.dc.b;
  s->dfc.dc = cfg_of(cfg);
  if (s->dfc.rls_on) { /* the RLS's a, b, guarded at its updates (rls_step) */
    s->dfc.dc.a = rls_a;
    s->dfc.dc.b = rls_b;
  }
  /* one period ahead: this period's edge (header); not without signals
   * for POS_DFC_COAST periods (gates off: the state is held, not run away
   * on a stale torque and load) */
  if (kalman && s->dfc.miss < POS_DFC_COAST) {
    kf->cfg.q[0] = cfg->kf_q_omega;
    kf->cfg.q[1] = cfg->kf_q_theta;
    kf->cfg.q[2] = cfg->kf_q_load;
    kf_mech_predict(kf, in->torque);
  }
  /* the component's instant: the edge, between the two samples; counted
   * in periods since the reset (isr) so that the held ones keep theirs */
  s->dfc.n++;
  const float t_edge = 0.5f * (smp->t_star[0] + smp->t_star[1]);
  bool fresh = false;
  if (smp->n_star >= 2u && dfc_signals_push(&s->dfc.sig, smp->test_vector, smp->v_star[0],
                                            smp->v_star[1], smp->v_dc, t_edge)) {
    s->dfc.sig.t[s->dfc.sig.last] = (float)s->dfc.n * cfg->ts + t_edge;
    s->dfc.t = t_edge;
    fresh = true;
  } else if (!kalman) {
    s->dfc.t -= cfg->ts; /* the newest component ages by a period */
  }
  s->dfc.miss = fresh ? 0u : (s->dfc.miss < 255u ? (uint8_t)(s->dfc.miss + 1u) : 255u);
  out->t = s->dfc.t; /* the filter's state is at the edge's point of this period */
  if (kalman) {
    out->load = kf->x[2]; /* the prediction's, until an update below */
  }
  float c2 = 1.0f, s2 = 0.0f;
  dfc_vec_t v;
  const bool full = dfc_signals_complete(&s->dfc.sig);
  /* ivd+kf+rls, once aligned: the IVD's iterations start from the
   * filter's prediction (warm), not from the raw estimate (3.8).
   * The filter follows the IVD's angle and the RLS regresses at the
   * filter's prediction. From the raw estimate dfc_iter iterations leave
   * (2|p|)^n of its error p sin 6theta (Theorem 1, (3.81): 0.7 of it for
   * one at p = 0.35); at the regressor that error turns into a bias of b
   * (the 6theta error times e^{j2theta} carries an e^{-j4theta} term:
   * b - a eps / 2, eps its amplitude on 2theta; issue 23 point 5,
   * docs/dfc.md). From the prediction they continue the last periods'
   * iterations: the error left is (2|p|)^n times the prediction's. */
  const bool warm = s->dfc.rls_on && s->dfc.aligned;
  bool ok = false;
  if (full) { /* sequentiality: the held components turned to the newest */
    dfc_signals_vector(&s->dfc.sig, 2.0f * trk_omega(s), &v);
    if (warm) {
      const sincos_t w = frames_sincos(2.0f * trk_theta(s)); /* the prediction */
      if (rls_step(s, cfg, &v, fresh, &w)) {
        out->rls_ok = rls_health(s, cfg);
      }
      c2 = w.c;
      s2 = w.s;
      s->dfc.trace[0] = c2; /* the start, for logs */
      s->dfc.trace[1] = s2;
      ok = dfc_ivd_from(&s->dfc.dc, &v, in->i_q, &c2, &s2, s->dfc.trace);
    } else {
      ok = dfc_vector2(&s->dfc.dc, s->dfc.sig.g, &v, in->i_q, &c2, &s2, s->dfc.trace);
    }
  }
  out->valid = ok;
  if (!ok) {
    if (!kalman) {
      angle_pll_update(pll, NAN); /* coast */
    }
    out->theta = trk_theta(s);
    out->omega = trk_omega(s);
    out->rate = kalman ? out->omega : pll->omega_rate;
    out->health = 0.0f;
    return;
  }
  const float theta0 = 0.5f * fd_cordic_atan2f(s2, c2); /* (3.10), branch 0 */
  if (!s->dfc.started) {
    /* polarity: the alignment decides */
    trk_reset(s, s->dfc.track == TRACK_EKF ? ekf_start_angle(s, &v, theta0) : theta0, 0.0f);
    s->dfc.started = true;
  }
  const float pred = trk_theta(s); /* the prediction, before this period's measurement */
  const float th = nearest_branch(theta0, pred);
  out->health = fabsf(frames_wrap_pi(th - pred)); /* measured - predicted */
  if (!kalman) {
    angle_pll_update(pll, th);
    out->theta = th;
    out->omega = pll->omega;
    out->rate = pll->omega_rate;
  } else {
    if (fresh) {
      s->dfc.r = meas_r(s, cfg, &v, warm);
      if (s->dfc.track == TRACK_EKF) {
        (void)kf_mech_update_ekf(kf, v.al, v.be, s->dfc.dc.a, s->dfc.dc.b, v.k, s->dfc.r);
      } else {
        (void)kf_mech_update(kf, th, s->dfc.r);
      }
    }
    out->theta = kf->x[1];
    out->omega = kf->x[0];
    out->rate = kf->x[0];
    out->load = kf->x[2];
  }
  /* the polarity evidence, until the alignment has used it: on the
   * predicted angle, which this period's measurement noise has not reached
   * (on the measured one, the noise that moves the speed update also moves
   * the sine: a bias towards theta + pi that wins where the rotor hardly
   * moves, near the alignment angle; docs/dfc.md) */
  if (!s->dfc.aligned) {
    const sincos_t u = frames_sincos(pred);
    s->dfc.pol_acc -= (out->omega - s->dfc.w_prev) * u.s;
    s->dfc.w_prev = out->omega;
    pol_energy(s, u.c);
  }
}

/* The alignment towards electrical angle theta (0) ends: the polarity
 * from the motion it caused, or, without motion, the branch nearest it.
 * Once per start, not in a period: FD_COLD (flash), as pdfc_reset. */
#define POS_DFC_POL_MIN 2.0f  /* rad/s electrical: evidence of motion */
#define POS_DFC_E_MIN   0.02f /* cos(theta) - cos(theta_0), mean + recent: evidence of motion */
FD_COLD static void pdfc_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                               float theta) {
  (void)cfg;
  (void)smp;
  const float acc = s->dfc.pol_acc;
  const float now = trk_theta(s);
  const float e =
      s->dfc.e_n > 0u ? s->dfc.e_acc / (float)s->dfc.e_n + (s->dfc.e_lp - s->dfc.e_c0) : 0.0f;
  /* the energy first (the rotor went down the potential: theta), then the
   * speed change (the estimate moved as the torque pulled: theta) */
  const bool e_says = e > POS_DFC_E_MIN || e < -POS_DFC_E_MIN;
  const bool a_says = acc > POS_DFC_POL_MIN || acc < -POS_DFC_POL_MIN;
  float th;
  if (e_says || a_says) {
    const bool theta_right = e_says ? e > 0.0f : acc > 0.0f;
    th = theta_right ? now : frames_wrap_pi(now + FRAMES_PI); /* theta + pi */
  } else {
    th = nearest_branch(now, theta);
  }
  if (s->dfc.track == TRACK_EKF) {
    /* h(theta) (4.35) is pi-periodic: the branch is a relabelling, not a
     * new measurement; the covariance the filter has built stays (reset to
     * kf_p0, its next updates took steps of the angle's prior, 0.3 rad,
     * on a linearisation valid over a tenth of that near the corners of
     * h at high |p|: the jump of issue 23 point 4) */
    s->dfc.kf.x[1] = th;
  } else {
    trk_reset(s, th, trk_omega(s));
  }
  s->dfc.started = true;
  pol_reset(s);
  s->dfc.aligned = true;
  warm_gain(s); /* the warm start's, at the a, b in force */
}

/* The held start (drive_hold.c): the estimate's branch nearest theta, the
 * polarity resolved; the evidence of an alignment is not used (the rotor
 * was held, a load may have moved it a little). */
static void pdfc_hold(pos_state_t *s, float theta) {
  trk_reset(s, nearest_branch(trk_theta(s), theta), trk_omega(s));
  s->dfc.started = true;
  pol_reset(s);
  s->dfc.aligned = true;
}

/* |b/a| the EKF is given at most: measured on the Fig. 3.3 machine, where
 * it works to |p| = 0.36 (0.40 with the star channel unclipped) and not
 * from 0.37 (0.41); docs/dfc.md, "EKF: the range of p" */
#define POS_DFC_EKF_P_MAX 0.35f

FD_COLD static const char *pdfc_check_cfg(const drive_config_t *cfg, const char **field) {
  const dfc_cfg_t d = cfg_of(cfg);
  const int e = dfc_check(&d);
  if (e != DFC_OK) {
    *field = e == DFC_ERR_P ? "dfc_b" : (e == DFC_ERR_PHI ? "dfc_phi_a" : "dfc_a");
    return dfc_strerror(e);
  }
  if (track_of(cfg->pos_source) == TRACK_EKF &&
      !(fabsf(cfg->dfc_b) <= POS_DFC_EKF_P_MAX * fabsf(cfg->dfc_a))) {
    *field = "dfc_b";
    return "the EKF needs |p| = |dfc_b / dfc_a| <= 0.35: its update (4.36) is linearised on "
           "h(theta), whose slope falls to 2 |a| (1 - 2|p|) at the corners of h, where beyond "
           "that the filter stops on the wrong side (docs/dfc.md, \"EKF: the range of p\"); "
           "use ivd+kf";
  }
  if (track_of(cfg->pos_source) != TRACK_PLL) {
    const kf_mech_cfg_t kc = kf_cfg_of(cfg);
    kf_mech_t k;
    if (!kf_mech_init(&k, &kc)) {
      *field = "inertia";
      return "the Kalman filter's model needs a finite inertia, pole pairs and friction";
    }
  }
  if (cfg->pos_source == POS_SOURCE_IVD_KF_RLS && !(cfg->rls_p_min <= cfg->rls_p_max)) {
    *field = "rls_p_min";
    return "the RLS covariance limits need rls_p_min <= rls_p_max";
  }
  if (cfg->start_mode == 0u && !(cfg->align_time > 0.0f)) {
    *field = "align_time";
    return "a star-point source resolves the magnet's polarity by the alignment: align_time > 0 "
           "(or the held start, start_mode 1)";
  }
  return NULL;
}

#define POS_DFC_ROW(n)                                                                             \
  const pos_source_row_t pos_source_##n = {POS_CAP_ALIGN | POS_CAP_GATED,                          \
                                           pdfc_init,                                              \
                                           pdfc_reset,                                             \
                                           pdfc_update,                                            \
                                           pdfc_align,                                             \
                                           pdfc_check_cfg,                                         \
                                           pdfc_hold,                                              \
                                           pos_dfc_signals,                                        \
                                           POS_DFC_N_SIGNALS}
POS_DFC_ROW(dfc);
POS_DFC_ROW(dfc_inv);
POS_DFC_ROW(ivd);
POS_DFC_ROW(dfc_kf);
POS_DFC_ROW(ivd_kf);
POS_DFC_ROW(ekf);
POS_DFC_ROW(ivd_kf_rls);

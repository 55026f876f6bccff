/*
 * pos_dfc.c - the star point as a position source: Direct Flux Control
 * (standard, inverse) and Iterative Vector Decoupling (IVD, Full IVD),
 * Fabbri 2022 chapter 3, on estimation/dfc.h; speed by the angle PLL until
 * a Kalman filter replaces it.
 *
 * Each period brings one component of the DFC signal vector (the test
 * vector of the last window, hal_sample_t.test_vector, and the star-point
 * samples around its edge); the others are held, so the vector mixes three
 * consecutive periods. The held components are turned to the newest one's
 * instant with the PLL's speed (dfc_signals_vector: the sequentiality
 * effect, docs/dfc.md); the estimate is dated at that edge, and the drive
 * extrapolates the angle from it to the current sample.
 * The estimate is 2 theta_e. The branch (theta or theta + pi) follows the
 * PLL's prediction; the magnet's polarity is resolved once, by the
 * alignment (Fabbri 2022, 3.1.3; hence align_time > 0): the d current
 * along theta = 0 pulls the rotor with a torque of the sign of
 * -sin(theta). The tracked estimate is theta or theta + pi; over the
 * alignment the source sums the change of its speed times -sin(estimate):
 * positive when the estimate is theta (the rotor accelerates the way the
 * torque pulls), negative when it is theta + pi. A rotor that does not
 * move (already at 0, or held) leaves the sum near zero: then the branch
 * nearest 0 is taken, where the current holds the north pole. A light
 * rotor swinging through the alignment is thus resolved as well as one
 * that settles (tests: both magnet polarities).
 */
#include <stddef.h>

#include "math/cordic_q31.h"
#include "math/fd_math.h"
#include "math/frames.h"
#include "pos_source.h"

static dfc_method_t method_of(pos_source_t src, const drive_config_t *cfg) {
  if (src == POS_SOURCE_DFC_INV) {
    return DFC_INVERSE;
  }
  if (src == POS_SOURCE_IVD) {
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

static void pdfc_init(pos_state_t *s, const drive_config_t *cfg) {
  angle_pll_init(&s->dfc.pll, cfg->pll_bw, cfg->ts);
  s->dfc.dc = cfg_of(cfg);
  dfc_signals_reset(&s->dfc.sig);
  s->dfc.started = false;
  s->dfc.t = 0.0f;
  s->dfc.n = 0u;
  s->dfc.pol_acc = 0.0f;
  s->dfc.w_prev = 0.0f;
  s->dfc.aligned = false;
  for (unsigned k = 0u; k < 2u * (DFC_ITER_MAX + 1u); ++k) {
    s->dfc.trace[k] = 0.0f;
  }
}

static void pdfc_reset(pos_state_t *s) {
  dfc_signals_reset(&s->dfc.sig);
  s->dfc.started = false;
  s->dfc.n = 0u;
  s->dfc.pol_acc = 0.0f;
  s->dfc.w_prev = 0.0f;
  s->dfc.aligned = false;
}

/* The branch of 2 theta / 2 nearest ref. */
static float nearest_branch(float theta0, float ref) {
  const float d = frames_wrap_pi(theta0 - ref);
  return (d > 0.5f * FRAMES_PI || d < -0.5f * FRAMES_PI) ? frames_wrap_pi(theta0 + FRAMES_PI)
                                                         : theta0;
}

static void pdfc_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                        float i_q, pos_estimate_t *out) {
  angle_pll_t *pll = &s->dfc.pll;
  /* the live parameters (b, iterations, phase shifts) in force */
  s->dfc.dc = cfg_of(cfg);
  /* the component's instant: the edge, between the two samples; counted
   * in periods since the reset (isr) so that the held ones keep theirs */
  s->dfc.n++;
  const float t_edge = 0.5f * (smp->t_star[0] + smp->t_star[1]);
  if (smp->n_star >= 2u && dfc_signals_push(&s->dfc.sig, smp->test_vector, smp->v_star[0],
                                            smp->v_star[1], smp->v_dc, t_edge)) {
    s->dfc.sig.t[s->dfc.sig.last] = (float)s->dfc.n * cfg->ts + t_edge;
    s->dfc.t = t_edge;
  } else {
    s->dfc.t -= cfg->ts; /* the newest component ages by a period */
  }
  out->t = s->dfc.t;
  float c2 = 1.0f, s2 = 0.0f;
  dfc_vec_t v;
  const bool full = dfc_signals_complete(&s->dfc.sig);
  if (full) { /* sequentiality: the held components turned to the newest */
    dfc_signals_vector(&s->dfc.sig, 2.0f * pll->omega, &v);
  }
  const bool ok = full && dfc_vector2(&s->dfc.dc, s->dfc.sig.g, &v, i_q, &c2, &s2, s->dfc.trace);
  out->valid = ok;
  if (!ok) {
    angle_pll_update(pll, NAN); /* coast */
    out->theta = pll->theta;
    out->omega = pll->omega;
    out->rate = pll->omega_rate;
    out->health = 0.0f;
    return;
  }
  const float theta0 = 0.5f * fd_cordic_atan2f(s2, c2); /* (3.10), branch 0 */
  if (!s->dfc.started) {
    angle_pll_reset(pll, theta0, 0.0f); /* polarity: the alignment decides */
    s->dfc.started = true;
  }
  const float th = nearest_branch(theta0, pll->theta);
  out->health = fabsf(frames_wrap_pi(th - pll->theta)); /* measured - predicted */
  angle_pll_update(pll, th);
  out->theta = th;
  out->omega = pll->omega;
  out->rate = pll->omega_rate;
  /* the polarity evidence, until the alignment has used it */
  if (!s->dfc.aligned) {
    s->dfc.pol_acc -= (pll->omega - s->dfc.w_prev) * frames_sincos(th).s;
    s->dfc.w_prev = pll->omega;
  }
}

/* The alignment towards electrical angle theta (0) ends: the polarity
 * from the motion it caused, or, without motion, the branch nearest it. */
#define POS_DFC_POL_MIN 2.0f /* rad/s electrical: evidence of motion */
static void pdfc_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                       float theta) {
  (void)cfg;
  (void)smp;
  angle_pll_t *pll = &s->dfc.pll;
  const float acc = s->dfc.pol_acc;
  float th;
  if (acc > POS_DFC_POL_MIN) {
    th = pll->theta; /* the estimate moved as the torque pulled: theta */
  } else if (acc < -POS_DFC_POL_MIN) {
    th = frames_wrap_pi(pll->theta + FRAMES_PI); /* theta + pi */
  } else {
    th = nearest_branch(pll->theta, theta);
  }
  angle_pll_reset(pll, th, pll->omega);
  s->dfc.started = true;
  s->dfc.aligned = true;
  s->dfc.pol_acc = 0.0f;
}

static const char *pdfc_check_cfg(const drive_config_t *cfg, const char **field) {
  const dfc_cfg_t d = cfg_of(cfg);
  const int e = dfc_check(&d);
  if (e != DFC_OK) {
    *field = e == DFC_ERR_P ? "dfc_b" : (e == DFC_ERR_PHI ? "dfc_phi_a" : "dfc_a");
    return dfc_strerror(e);
  }
  if (!(cfg->align_time > 0.0f)) {
    *field = "align_time";
    return "a star-point source resolves the magnet's polarity by the alignment: align_time > 0";
  }
  return NULL;
}

#define POS_DFC_ROW(n)                                                                             \
  const pos_source_row_t pos_source_##n = {#n,                                                     \
                                           POS_CAP_ALIGN | POS_CAP_GATED,                          \
                                           pdfc_init,                                              \
                                           pdfc_reset,                                             \
                                           pdfc_update,                                            \
                                           pdfc_align,                                             \
                                           pdfc_check_cfg}
POS_DFC_ROW(dfc);
POS_DFC_ROW(dfc_inv);
POS_DFC_ROW(ivd);

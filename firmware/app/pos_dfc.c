/*
 * pos_dfc.c - the star point as a position source: the functions of its
 * rows (pos_sources.c), which decode the row's columns (pos_star.h): the
 * method (pos_method.c: DFC, inverse DFC, IVD / Full IVD, Fabbri 2022
 * chapter 3, on estimation/dfc.h), the tracker (pos_track.c: the angle
 * PLL, or the Kalman filter on the rotor's mechanics of chapter 4, which
 * also estimates the load torque, updated on the method's angle or, the
 * EKF, on the signal vector itself) and the identification (none, or
 * pos_rls.c: a, b by the RLS of (4.51)-(4.57), the loop of Fig. 4.4, the
 * IVD started from the tracker's prediction once aligned).
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
#include "pos_star.h"

static void pol_reset(pos_state_t *s) {
  s->star.pol.acc = 0.0f;
  s->star.pol.w_prev = 0.0f;
  s->star.pol.e_c0 = 0.0f;
  s->star.pol.e_acc = 0.0f;
  s->star.pol.e_lp = 0.0f;
  s->star.pol.e_n0 = 0u;
  s->star.pol.e_n = 0u;
  s->star.pol.aligned = false;
}

/* The row's columns into the state, each column's part initialised */
FD_COLD void pos_star_init(pos_state_t *s, const drive_config_t *cfg) {
  const pos_source_row_t *row = pos_source(cfg->pos_source);
  s->star.method = row->method;
  s->star.tracker = row->tracker;
  s->star.ident = row->ident;
  s->star.tracker->init(s, cfg); /* pos_star_check: usable */
  s->star.trk.r = 0.0f;
  s->star.meas.miss = 0u;
  s->star.meas.dc = pos_method_cfg(s->star.method, cfg);
  if (s->star.ident != NULL) {
    s->star.ident->init(s, cfg); /* its a, b in dc */
  }
  dfc_signals_reset(&s->star.meas.sig);
  s->star.trk.started = false;
  s->star.meas.t = 0.0f;
  s->star.meas.n = 0u;
  pol_reset(s);
  for (unsigned k = 0u; k < 2u * (DFC_ITER_MAX + 1u); ++k) {
    s->star.meas.trace[k] = 0.0f;
  }
}

FD_COLD void pos_star_reset(pos_state_t *s) { /* at an enable, not in a period */
  if (s->star.tracker->restart != NULL) {
    s->star.tracker->restart(s);
  }
  s->star.meas.miss = 0u;
  dfc_signals_reset(&s->star.meas.sig);
  s->star.trk.started = false;
  s->star.meas.n = 0u;
  pol_reset(s);
}

/* The branch of 2 theta / 2 nearest ref. */
static float nearest_branch(float theta0, float ref) {
  const float d = frames_wrap_pi(theta0 - ref);
  return (d > 0.5f * FRAMES_PI || d < -0.5f * FRAMES_PI) ? frames_wrap_pi(theta0 + FRAMES_PI)
                                                         : theta0;
}

/* atan2(y, x) of a vector near the +x axis, the warm measurement's
 * innovation (pos_star_update): for |y| <= x / 4 the series of atan t, t =
 * y / x, to t^9 (error below t^11 / 11 < 2.2e-8 rad), one division and a
 * polynomial inline: cheaper than fd_atan2f (42 instructions in software;
 * 63 on the G474's co-processor binding) and than the Q31 CORDIC (317 /
 * 98); elsewhere fd_atan2f */
static inline float innov_atan2(float y, float x) {
  if (!(x > 0.0f && fabsf(y) <= 0.25f * x)) {
    return fd_atan2f(y, x);
  }
  const float t = y / x, z = t * t;
  return t * (1.0f - z * ((1.0f / 3.0f) - z * (0.2f - z * ((1.0f / 7.0f) - z * (1.0f / 9.0f)))));
}

#define POS_DFC_COAST 16u /* periods without a component before the filter holds */

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
  if (s->star.pol.e_n0 < POS_DFC_E_REF) {
    s->star.pol.e_c0 += c;
    if (++s->star.pol.e_n0 == POS_DFC_E_REF) {
      s->star.pol.e_c0 *= 1.0f / (float)POS_DFC_E_REF;
      s->star.pol.e_lp = s->star.pol.e_c0;
    }
  } else if (s->star.pol.e_n < UINT32_MAX) {
    s->star.pol.e_acc += c - s->star.pol.e_c0;
    s->star.pol.e_lp += (c - s->star.pol.e_lp) * (1.0f / (float)POS_DFC_E_REF);
    s->star.pol.e_n++;
  }
}

void pos_star_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                     pos_io_t *io) {
  const pos_input_t *in = &io->in;
  pos_estimate_t *out = &io->out;
  const pos_tracker_t *trk = s->star.tracker;
  pos_meas_t *m = &s->star.meas;
  /* the live parameters (b, iterations, phase shifts) in force */
  const float id_a = m->dc.a, id_b = m->dc.b;
  m->dc = pos_method_cfg(s->star.method, cfg);
  /* mut: ivd_kf_without_iterations */
  if (s->star.ident != NULL) { /* the identification's a, b, guarded at its steps */
    m->dc.a = id_a;
    m->dc.b = id_b;
  }
  /* one period ahead: this period's edge (pos_track.c); not without signals
   * for POS_DFC_COAST periods (gates off: the state is held, not run away
   * on a stale torque and load) */
  if (trk->predict != NULL && m->miss < POS_DFC_COAST) {
    trk->predict(s, cfg, in->torque);
  }
  /* the component's instant: the edge, between the two samples; counted
   * in periods since the reset (isr) so that the held ones keep theirs */
  m->n++;
  const float t_edge = 0.5f * (smp->t_star[0] + smp->t_star[1]);
  bool fresh = false;
  if (smp->n_star >= 2u && dfc_signals_push(&m->sig, smp->test_vector, smp->v_star[0],
                                            smp->v_star[1], smp->v_dc, t_edge)) {
    m->sig.t[m->sig.last] = (float)m->n * cfg->ts + t_edge;
    m->t = t_edge;
    fresh = true;
  } else if (!trk->at_edge) {
    m->t -= cfg->ts; /* the newest component ages by a period */
  }
  m->miss = fresh ? 0u : (m->miss < 255u ? (uint8_t)(m->miss + 1u) : 255u);
  out->t = m->t; /* the filter's state is at the edge's point of this period */
  float c2 = 1.0f, s2 = 0.0f;
  dfc_vec_t v;
  const bool full = dfc_signals_complete(&m->sig);
  /* an identification, once aligned: the IVD's iterations start from the
   * tracker's prediction (warm), not from the raw estimate (3.8).
   * The filter follows the IVD's angle and the RLS regresses at the
   * filter's prediction. From the raw estimate dfc_iter iterations leave
   * (2|p|)^n of its error p sin 6theta (Theorem 1, (3.81): 0.7 of it for
   * one at p = 0.35); at the regressor that error turns into a bias of b
   * (the 6theta error times e^{j2theta} carries an e^{-j4theta} term:
   * b - a eps / 2, eps its amplitude on 2theta; issue 23 point 5,
   * docs/dfc.md). From the prediction they continue the last periods'
   * iterations: the error left is (2|p|)^n times the prediction's. */
  const pos_ident_t *id = s->star.ident;
  const bool warm = id != NULL && s->star.pol.aligned;
  bool ok = false;
  sincos_t w = {0.0f, 1.0f}; /* warm: e^{j 2 pred}, the prediction */
  if (full) {                /* sequentiality: the held components turned to the newest */
    dfc_signals_vector(&m->sig, 2.0f * pos_track_omega(s), &v);
    if (warm) {
      w = frames_sincos(2.0f * pos_track_theta(s));
      id->step(s, cfg, &v, &w, in->busy, out);
      c2 = w.c;
      s2 = w.s;
      m->trace[0] = c2; /* the start, for logs */
      m->trace[1] = s2;
      /* mut: rls_ivd_raw_start */
      ok = dfc_ivd_from(&m->dc, &v, in->i_q, &c2, &s2, m->trace);
    } else {
      ok = dfc_vector2(&m->dc, m->sig.g, &v, in->i_q, &c2, &s2, m->trace);
    }
  }
  out->valid = ok;
  if (!ok) {
    trk->coast(s, out);
    out->health = 0.0f;
    return;
  }
  float pred, th;
  if (warm) { /* started (pos_star_align, pos_star_hold) */
    /* the measurement relative to the prediction: e^{j 2 (theta - pred)} =
     * e^{j 2 theta} e^{-j 2 pred}, its half angle in (-pi/2, pi/2] the
     * innovation on the branch nearest pred (nearest_branch's): no angle
     * of its own, and the atan2 of a vector near (1, 0) (innov_atan2),
     * not the CORDIC's 26 steps */
    pred = pos_track_theta(s);
    const float d = 0.5f * innov_atan2(s2 * w.c - c2 * w.s, c2 * w.c + s2 * w.s);
    th = frames_wrap_pi(pred + d);
    out->health = fabsf(d); /* measured - predicted */
  } else {
    const float theta0 = 0.5f * fd_cordic_atan2f(s2, c2); /* (3.10), branch 0 */
    if (!s->star.trk.started) {
      /* polarity: the alignment decides */
      trk->start(s, trk->first != NULL ? trk->first(s, &v, theta0) : theta0, 0.0f);
      s->star.trk.started = true;
    }
    pred = pos_track_theta(s); /* the prediction, before this period's measurement */
    th = nearest_branch(theta0, pred);
    out->health = fabsf(frames_wrap_pi(th - pred)); /* measured - predicted */
  }
  trk->measure(s, cfg, &v, th, out);
  /* the polarity evidence, until the alignment has used it: on the
   * predicted angle, which this period's measurement noise has not reached
   * (on the measured one, the noise that moves the speed update also moves
   * the sine: a bias towards theta + pi that wins where the rotor hardly
   * moves, near the alignment angle; docs/dfc.md) */
  if (!s->star.pol.aligned) {
    const sincos_t u = frames_sincos(pred);
    /* mut: polarity_evidence_on_measured_angle */
    s->star.pol.acc -= (out->omega - s->star.pol.w_prev) * u.s;
    s->star.pol.w_prev = out->omega;
    pol_energy(s, u.c);
  }
}

/* The alignment towards electrical angle theta (0) ends: the polarity
 * from the motion it caused, or, without motion, the branch nearest it.
 * Once per start, not in a period: FD_COLD (flash), as pos_star_reset. */
#define POS_DFC_POL_MIN 2.0f  /* rad/s electrical: evidence of motion */
#define POS_DFC_E_MIN   0.02f /* cos(theta) - cos(theta_0), mean + recent: evidence of motion */
FD_COLD void pos_star_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                            float theta) {
  (void)cfg;
  (void)smp;
  const pos_polarity_t *pol = &s->star.pol;
  const float acc = pol->acc;
  const float now = pos_track_theta(s);
  /* mut: polarity_energy_evidence_off */
  const float e = pol->e_n > 0u ? pol->e_acc / (float)pol->e_n + (pol->e_lp - pol->e_c0) : 0.0f;
  /* the energy first (the rotor went down the potential: theta), then the
   * speed change (the estimate moved as the torque pulled: theta) */
  const bool e_says = e > POS_DFC_E_MIN || e < -POS_DFC_E_MIN;
  const bool a_says = acc > POS_DFC_POL_MIN || acc < -POS_DFC_POL_MIN;
  float th;
  if (e_says || a_says) {
    const bool theta_right = e_says ? e > 0.0f : acc > 0.0f;
    /* mut: dfc_polarity_ignored */
    th = theta_right ? now : frames_wrap_pi(now + FRAMES_PI); /* theta + pi */
  } else {
    th = nearest_branch(now, theta);
  }
  s->star.tracker->branch(s, th);
  s->star.trk.started = true;
  pol_reset(s);
  s->star.pol.aligned = true;
  if (s->star.ident != NULL) {
    s->star.ident->aligned(s);
  }
}

/* The held start (proc_hold.c): the estimate's branch nearest theta, the
 * polarity resolved; the evidence of an alignment is not used (the rotor
 * was held, a load may have moved it a little). Once per start: FD_COLD. */
FD_COLD void pos_star_hold(pos_state_t *s, float theta) {
  s->star.tracker->start(s, nearest_branch(pos_track_theta(s), theta), pos_track_omega(s));
  s->star.trk.started = true;
  pol_reset(s);
  s->star.pol.aligned = true;
}

/* Whether cfg can run its row: the method's a, b, the tracker's and the
 * identification's own checks, the polarity's alignment. */
FD_COLD const char *pos_star_check(const drive_config_t *cfg, const char **field) {
  const pos_source_row_t *row = pos_source(cfg->pos_source);
  const dfc_cfg_t d = pos_method_cfg(row->method, cfg);
  const int e = dfc_check(&d);
  if (e != DFC_OK) {
    *field = e == DFC_ERR_P ? "dfc_b" : (e == DFC_ERR_PHI ? "dfc_phi_a" : "dfc_a");
    return dfc_strerror(e);
  }
  const char *why = row->tracker->check != NULL ? row->tracker->check(cfg, field) : NULL;
  if (why == NULL && row->ident != NULL) {
    why = row->ident->check(cfg, field);
  }
  if (why != NULL) {
    return why;
  }
  if (cfg->start_mode == 0u && !(cfg->align_time > 0.0f)) {
    *field = "align_time";
    return "a star-point source resolves the magnet's polarity by the alignment: align_time > 0 "
           "(or the held start, start_mode 1)";
  }
  return NULL;
}

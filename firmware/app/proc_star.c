/*
 * proc_star.c - identification of the star point's a and b of (3.7)
 * (Fabbri 2022; issue 25, procedure h), rotor free, no encoder.
 *
 * Why the rotor must turn. The three DFC signals of v1, v3, v5 at one
 * rotor angle are, normalised to v_dc, (3.6) with the amplitude-invariant
 * Clarke transform:
 *   Gamma_alpha = -a cos 2theta + b cos 4theta,  Gamma_beta = a sin 2theta + b sin 4theta,
 *   Gamma_gamma = 0,
 * so with y = -Gamma_alpha + j Gamma_beta and s = e^{j2theta} (dfc.h):
 *   y = a s - b conj(s)^2.                                               (3.6)
 * Their mean (the zero sequence) is 0 and one angle gives one complex
 * number for three unknowns (a, b, theta): |y| = |a - b e^{-j6theta}|
 * alone mixes a and b. The thesis says as much: a and b are found with a
 * known angle (4.51)-(4.57) or online at speed (Fig. 4.4); the drive's
 * RLS runs only above rls_w_min. Here the rotor is turned slowly by a
 * current vector through half an electrical turn (2theta one turn, 6theta
 * three), so the signals trace the whole curve of (3.6).
 *
 * Sequence (phases): 0 alignment: the current vector id_star_current i_max
 * along theta = 0, ramped up over a quarter of id_star_time and held for a
 * quarter; 1 sweep: the vector turns from 0 to +-pi (electrical) at
 * constant rate in id_star_time, the signals averaged in PROC_STAR_BINS
 * bins of the vector's angle; 2 fit of that sweep (the vector held); 3
 * sweep back to 0; 4 fit of it; done: a, b the mean of the two sweeps'
 * fits, their difference published as the check. The sweeps turn back the
 * way the alignment moved the rotor (the sign of the source's speed
 * integrated over the alignment), so the rotor stays within half an
 * electrical turn of where it started, plus the damped overshoot and
 * the lag: the bound stated is 1.25 pi electrical (1.25 pi / pole_pairs
 * mechanical; docs/commissioning.md).
 *
 * The current and the damping. The core's current loop (current_ctrl.h,
 * current_bw) in the stator frame, as the alignment's (proc_align.c).
 * The free rotor swings about the vector at w_n = p sqrt(1.5 lambda_m i /
 * J) with almost no damping (friction only; the back-EMF's currents the
 * loop cancels): on fabbri2022_t51 +-0.4 rad electrical through the whole
 * sweep even under a fed-forward voltage (a first version, which kept
 * some of the back-EMF's damping), which smears the bins unevenly. As the encoder's alignment does,
 * the vector's angle is led by -k_d omega_e, k_d = 2 zeta / w_n (zeta
 * PROC_STAR_ZETA, from the parameter set's pole_pairs, lambda_m, inertia),
 * here with the position source's speed (its PLL's or filter's on the
 * star point: the speed needs neither a's sign nor the polarity); the
 * lead is clamped to +-pi/4.
 *
 * The fit of one sweep (maximum likelihood for white noise on the bins):
 * minimise sum_k |y_k - a s_k + b conj(s_k)^2|^2 over a, b and the bins'
 * angles s_k = e^{j x_k}. The start (pass 0): the vector's angle phi_k with
 * a constant lag delta (the rotor trails the vector), y = A e^{j2phi} - B
 * e^{-j4phi}: the two regressors are orthogonal over the bins (6 phi
 * turns three times), so A and B are the bins' projections, a = |A| with
 * the sign of Re A (the lag is below pi/4: the rotor's north pole follows
 * the vector, which fixes the sign of a that the signals alone cannot:
 * docs/dfc.md, controller.dfc_a), e^{-j2delta} = A / a, b = Re(B e^{-j4 delta}).
 * Then PROC_STAR_PASSES Gauss-Newton passes on the reduced problem
 * (variable projection): per bin, x_k by PROC_STAR_INNER Gauss-Newton
 * steps from the vector's angle less the lag, then the 2x2 normal
 * equations of (a, b) with x_k eliminated (Schur complement). One bin per
 * period: the fit costs a few hundred instructions an ISR (an estimate:
 * not measured in PIL).
 *
 * The bins' averages. A bin averages the signals over the angles the
 * rotor passes in it, pi / PROC_STAR_BINS electrical: for a uniform turn
 * the mean of e^{j2theta} is sinc(pi / K) e^{j2theta_c} and that of
 * e^{-j4theta} sinc(2 pi / K) e^{-j4theta_c} (sinc x = sin x / x): the
 * bins follow (3.6) exactly with a and b scaled by these, divided out at
 * the end (0.16 % and 0.64 % at K = 32).
 *
 * Bounded: the current is id_star_current i_max <= i_max; a measured
 * current beyond it by PROC_STAR_TRIP of the way to i_max fails the
 * procedure with the overcurrent fault; the voltage is clamped to v_max.
 * A bin without all three test vectors' signals (no star-point samples),
 * a fit that is not finite or one that leaves a residual above
 * PROC_STAR_RES_MAX fails it with the position fault. It hands
 * nothing over: the host writes dfc_a and dfc_b.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"

#define PROC_STAR_ZETA 0.7f /* the damping ratio of the rotor about the vector */
/* the sweep's rate at most w_n / PROC_STAR_SLOW (drawn star seeds 7 and 12,
 * w_n 17 and 12 rad/s: at 0.4 s a sweep the rotor could not follow and the
 * fit's residual failed them), its time at most PROC_STAR_T_MAX [s] */
#define PROC_STAR_SLOW  8.0f
#define PROC_STAR_T_MAX 10.0f
/* a measured current beyond the test current by this part of the way to
 * i_max fails (the window's pulses leave a ripple repeating every three
 * periods in the sample: 0.25 i_max on drawn star seed 5, L 0.19 mH) */
#define PROC_STAR_TRIP   0.5f
#define PROC_STAR_INNER  3u /* Gauss-Newton steps of each bin's angle */
#define PROC_STAR_PASSES 6u /* Gauss-Newton passes of (a, b) after the start */
/* a sweep whose fit leaves an rms residual above this part of |a| fails:
 * the rotor did not follow the vector (a load, a stuck rotor) or the
 * signals are not (3.6)'s (a clipped star channel); 0.041 at most on the
 * presets and drawn machines (tests/python/test_commission_star.py), 3.3
 * with a current too small to turn drawn star seed 5 */
#define PROC_STAR_RES_MAX 0.2f

enum { PH_ALIGN = 0, PH_SWEEP = 1, PH_FIT = 2, PH_BACK = 3, PH_FIT_BACK = 4 };

FD_COLD static float star_current(const drive_config_t *c) {
  return fd_clampf(c->id_star_current, 0.0f, 1.0f) * c->i_max;
}

/* The rotor's natural frequency about the vector, w_n^2 = 1.5 p^2
 * lambda_m i / J [rad^2/s^2] (the PM torque 1.5 p lambda_m i sin(delta),
 * as proc_align_timing), from the parameter set. */
FD_COLD static float star_wn2(const drive_config_t *c) {
  return 1.5f * c->pole_pairs * c->pole_pairs * c->lambda_m * star_current(c) / c->inertia;
}

/* A sweep's periods: id_star_time, longer where the rotor is slow to
 * follow (the sweep's rate pi / T at most w_n / PROC_STAR_SLOW). */
FD_COLD static uint32_t star_sweep_periods(const drive_config_t *c) {
  const float wn2 = star_wn2(c);
  const float t_min = wn2 > 0.0f ? PROC_STAR_SLOW * FRAMES_PI / sqrtf(wn2) : 0.0f;
  return (uint32_t)(fd_minf(fd_maxf(c->id_star_time, t_min), PROC_STAR_T_MAX) / c->ts) + 1u;
}

/* The bins' centres phi_k = dir (k + 1/2) pi / K [rad electrical]. */
FD_COLD static float star_bin_phi(const proc_star_t *t, unsigned k) {
  return t->dir * FRAMES_PI * ((float)k + 0.5f) / (float)PROC_STAR_BINS;
}

/* e^{j2phi_k}. */
FD_COLD static sincos_t star_bin_dir(const proc_star_t *t, unsigned k) {
  return frames_sincos(2.0f * star_bin_phi(t, k));
}

FD_COLD static const char *star_check(const proc_setup_t *su, const char **field) {
  if (!su->gated) {
    *field = "pos_source";
    return "the star point's a, b need a star-point position source (the DFC window's "
           "samples: dfc, dfc_inv, ivd, dfc+kf, ivd+kf, ekf, ivd+kf+rls) on a board with "
           "star-point samples";
  }
  return NULL;
}

FD_COLD static void star_bin_reset(proc_star_t *t) {
  for (int x = 0; x < 3; ++x) {
    t->g_acc[x] = 0.0f;
    t->g_n[x] = 0u;
  }
}

FD_COLD static void star_init(proc_state_t *st, const proc_setup_t *su) {
  proc_star_t *t = &st->star;
  *t = (proc_star_t){0};
  t->bin = 0xffu;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&t->cc, &ccfg);
}

/* The bin in force closes: its mean vector y = -Gamma_alpha + j
 * Gamma_beta; false without all three components. */
FD_COLD static bool star_bin_close(proc_star_t *t) {
  if (t->bin >= PROC_STAR_BINS) {
    return true; /* none open */
  }
  if (t->g_n[0] == 0u || t->g_n[1] == 0u || t->g_n[2] == 0u) {
    return false;
  }
  const ab_t g =
      frames_clarke((abc_t){t->g_acc[0] / (float)t->g_n[0], t->g_acc[1] / (float)t->g_n[1],
                            t->g_acc[2] / (float)t->g_n[2]});
  t->y[t->bin][0] = -g.alpha;
  t->y[t->bin][1] = g.beta;
  return true;
}

/* One period's star-point component into the bin in force (2.101). */
FD_COLD static void star_take(proc_star_t *t, const hal_sample_t *s) {
  if (s->n_star < 2u || s->test_vector == 0u || s->test_vector > 5u ||
      (s->test_vector & 1u) == 0u || !(s->v_dc > 0.0f)) {
    return;
  }
  const float g = (s->v_star[1] - s->v_star[0]) / s->v_dc - (1.0f / 3.0f);
  if (!fd_isfinite(g)) {
    return;
  }
  const unsigned x = (unsigned)(s->test_vector - 1u) / 2u;
  t->g_acc[x] += g;
  t->g_n[x]++;
}

/* The fit's start (pass 0), one bin: the projections on e^{j2phi} and
 * -e^{-j4phi}. */
FD_COLD static void star_fit_start(proc_star_t *t, unsigned k) {
  const sincos_t e2 = star_bin_dir(t, k);
  const float e4c = e2.c * e2.c - e2.s * e2.s;
  const float e4s = 2.0f * e2.c * e2.s;
  const float yr = t->y[k][0];
  const float yi = t->y[k][1];
  /* A += y e^{-j2phi}, B += -y e^{j4phi} */
  t->acc[0] += yr * e2.c + yi * e2.s;
  t->acc[1] += yi * e2.c - yr * e2.s;
  t->acc[2] -= yr * e4c - yi * e4s;
  t->acc[3] -= yr * e4s + yi * e4c;
}

FD_COLD static bool star_fit_start_end(proc_star_t *t) {
  const float n = (float)PROC_STAR_BINS;
  const float ar = t->acc[0] / n;
  const float ai = t->acc[1] / n;
  const float br = t->acc[2] / n;
  const float bi = t->acc[3] / n;
  const float mag = sqrtf(ar * ar + ai * ai);
  if (!(mag > 0.0f) || !fd_isfinite(mag + br + bi)) {
    return false;
  }
  /* mut: star_a_sign_unresolved */
  const float a = ar >= 0.0f ? mag : -mag;
  /* e^{-j2delta} = A / a; b = Re(B e^{-j4delta}) */
  t->lag[0] = ar / a;
  t->lag[1] = ai / a;
  const float l4r = t->lag[0] * t->lag[0] - t->lag[1] * t->lag[1];
  const float l4i = 2.0f * t->lag[0] * t->lag[1];
  t->a = a;
  t->b = br * l4r - bi * l4i;
  return true;
}

/* One Gauss-Newton pass, one bin: its angle (x_k: s = e^{jx_k}) by
 * PROC_STAR_INNER steps on |r|^2, r = y - a s + b conj(s)^2 (3.6), then
 * the bin's share of the reduced normal equations of (a, b):
 * dr/da = -s, dr/db = conj(s)^2, dr/dx = -j (a s + 2 b conj(s)^2). */
FD_COLD static void star_fit_pass(proc_star_t *t, unsigned k) {
  const sincos_t e2 = star_bin_dir(t, k);
  /* the start: e^{j2phi} e^{-j2delta} */
  float sr = e2.c * t->lag[0] - e2.s * t->lag[1];
  float si = e2.c * t->lag[1] + e2.s * t->lag[0];
  const float a = t->a;
  const float b = t->b;
  const float yr = t->y[k][0];
  const float yi = t->y[k][1];
  float qr = 0.0f, qi = 0.0f, rr = 0.0f, ri = 0.0f, jr = 0.0f, ji = 0.0f, den = 1.0f;
  for (unsigned it = 0; it <= PROC_STAR_INNER; ++it) {
    qr = sr * sr - si * si; /* conj(s)^2 */
    qi = -2.0f * sr * si;
    /* mut: star_model_b_sign */
    rr = yr - a * sr + b * qr;
    ri = yi - a * si + b * qi;
    const float wr = a * sr + 2.0f * b * qr;
    const float wi = a * si + 2.0f * b * qi;
    jr = wi; /* -j w */
    ji = -wr;
    den = wr * wr + wi * wi;
    if (it == PROC_STAR_INNER || !(den > 0.0f)) {
      break;
    }
    const float dx = -(jr * rr + ji * ri) / den;
    const float nr = sr - dx * si;
    const float ni = si + dx * sr;
    const float inv = 1.0f / sqrtf(nr * nr + ni * ni);
    sr = nr * inv;
    si = ni * inv;
  }
  if (!(den > 0.0f)) {
    den = 1.0f;
  }
  /* the reduced normal equations: H = Jg'Jg - Jg'Jx Jx'Jg / |Jx|^2, g likewise */
  const float e0 = -(sr * jr + si * ji); /* Re(conj(-s) Jx) */
  const float e1 = qr * jr + qi * ji;    /* Re(conj(q) Jx) */
  const float xr = jr * rr + ji * ri;    /* Re(conj(Jx) r) */
  const float c01 = -(sr * qr + si * qi);
  t->h[0] += 1.0f - e0 * e0 / den;
  t->h[1] += c01 - e0 * e1 / den;
  t->h[2] += 1.0f - e1 * e1 / den;
  t->acc[0] += -(sr * rr + si * ri) - e0 * xr / den;
  t->acc[1] += (qr * rr + qi * ri) - e1 * xr / den;
  /* the lag for the next pass: sum of s e^{-j2phi} */
  t->acc[2] += sr * e2.c + si * e2.s;
  t->acc[3] += si * e2.c - sr * e2.s;
  t->res2 += rr * rr + ri * ri;
  if (k == (t->phase == PH_FIT ? PROC_STAR_BINS - 1u : 0u)) {
    /* the rotor where the sweep ended: theta = phi_k - delta_k */
    const float dl = -0.5f * fd_atan2f(si * e2.c - sr * e2.s, sr * e2.c + si * e2.s);
    t->theta_end = star_bin_phi(t, k) - dl;
  }
}

FD_COLD static bool star_fit_pass_end(proc_star_t *t) {
  const float det = t->h[0] * t->h[2] - t->h[1] * t->h[1];
  if (!(det > 0.0f)) {
    return false;
  }
  const float da = -(t->h[2] * t->acc[0] - t->h[1] * t->acc[1]) / det;
  const float db = -(t->h[0] * t->acc[1] - t->h[1] * t->acc[0]) / det;
  const float ln = sqrtf(t->acc[2] * t->acc[2] + t->acc[3] * t->acc[3]);
  if (!fd_isfinite(da + db) || !(ln > 0.0f)) {
    return false;
  }
  t->a += da;
  t->b += db;
  t->lag[0] = t->acc[2] / ln;
  t->lag[1] = t->acc[3] / ln;
  return true;
}

/* The sweep's result: the bins' scaling divided out (sinc, above). */
FD_COLD static void star_sweep_result(proc_star_t *t, unsigned w) {
  const float d = FRAMES_PI / (float)PROC_STAR_BINS;
  float s1, s2, c;
  fd_sincosf(d, &s1, &c);
  fd_sincosf(2.0f * d, &s2, &c);
  s1 /= d;
  s2 /= 2.0f * d;
  t->sw[w][0] = t->a / s1;
  t->sw[w][1] = t->b / s2;
  t->sw[w][2] = -0.5f * fd_atan2f(t->lag[1], t->lag[0]);
  t->sw[w][3] = sqrtf(t->res2 / (float)PROC_STAR_BINS) / fabsf(t->a);
}

/* The fit phase: pass 0 the start, then the passes, one bin a period;
 * PROC_DONE when the last pass has ended, PROC_FAILED when a step is not
 * finite. */
FD_COLD static int star_fit_step(proc_star_t *t) {
  const unsigned k = t->bin;
  if (k == 0u) {
    for (int x = 0; x < 4; ++x) {
      t->acc[x] = 0.0f;
    }
    t->h[0] = t->h[1] = t->h[2] = 0.0f;
    t->res2 = 0.0f;
  }
  if (t->pass == 0u) {
    star_fit_start(t, k);
  } else {
    star_fit_pass(t, k);
  }
  if (k + 1u < PROC_STAR_BINS) {
    t->bin = (uint8_t)(k + 1u);
    return PROC_RUNNING;
  }
  t->bin = 0u;
  const bool ok = t->pass == 0u ? star_fit_start_end(t) : star_fit_pass_end(t);
  if (!ok || !fd_isfinite(t->a + t->b)) {
    return PROC_FAILED;
  }
  return ++t->pass > PROC_STAR_PASSES ? PROC_DONE : PROC_RUNNING;
}

FD_COLD static int star_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                             proc_out_t *out) {
  proc_star_t *t = &st->star;
  const drive_config_t *c = su->cfg;
  const float i_test = star_current(c);
  const uint32_t n_sweep = star_sweep_periods(c);
  const uint32_t n_align = n_sweep / 2u;
  const uint32_t n_ramp = n_align / 2u; /* the current's ramp: half the alignment */
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  t->n_all++;
  const uint32_t n = t->n++;
  const float i_mag = sqrtf(in->i_ab.alpha * in->i_ab.alpha + in->i_ab.beta * in->i_ab.beta);
  if (!(i_mag <= i_test + PROC_STAR_TRIP * (c->i_max - i_test))) {
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  float amp = i_test;
  float phi = 0.0f;
  /* the position source's speed [rad/s electrical] (the damping, below) */
  const float w = fd_isfinite(in->pos->omega) ? in->pos->omega : 0.0f;
  switch (t->phase) {
  case PH_ALIGN:
    amp = n < n_ramp ? i_test * (float)n / (float)n_ramp : i_test;
    t->swing += w * c->ts;
    if (n + 1u >= n_align) {
      /* the sweep turns back the way the rotor came: it stays within half
       * a turn of where it started */
      t->dir = t->swing > 0.0f ? -1.0f : 1.0f;
      t->phase = PH_SWEEP;
      t->n = 0u;
    }
    break;
  case PH_SWEEP:
  case PH_BACK: {
    const float f = (float)n / (float)n_sweep;
    phi = t->dir * FRAMES_PI * (t->phase == PH_SWEEP ? f : 1.0f - f);
    unsigned k = (unsigned)(f * (float)PROC_STAR_BINS);
    k = t->phase == PH_SWEEP ? k : PROC_STAR_BINS - 1u - k;
    if (k != t->bin) {
      if (!star_bin_close(t)) {
        out->fault = DRIVE_FAULT_POSITION; /* no star-point signals */
        return PROC_FAILED;
      }
      star_bin_reset(t);
      t->bin = (uint8_t)k;
    }
    star_take(t, in->s);
    if (n + 1u >= n_sweep) {
      if (!star_bin_close(t)) {
        out->fault = DRIVE_FAULT_POSITION;
        return PROC_FAILED;
      }
      t->phase = t->phase == PH_SWEEP ? PH_FIT : PH_FIT_BACK;
      t->n = 0u;
      t->bin = 0u;
      t->pass = 0u;
    }
    break;
  }
  case PH_FIT:
  case PH_FIT_BACK:
  default: {
    phi = t->phase == PH_FIT ? t->dir * FRAMES_PI : 0.0f;
    const int r = star_fit_step(t);
    if (r == PROC_FAILED) {
      out->fault = DRIVE_FAULT_POSITION;
      return PROC_FAILED;
    }
    if (r == PROC_DONE) {
      star_sweep_result(t, t->phase == PH_FIT ? 0u : 1u);
      if (!(t->sw[t->phase == PH_FIT ? 0u : 1u][3] <= PROC_STAR_RES_MAX)) {
        out->fault = DRIVE_FAULT_POSITION; /* the signals do not follow (3.6) */
        return PROC_FAILED;
      }
      if (t->phase == PH_FIT_BACK) {
        t->done = true;
      } else {
        t->phase = PH_BACK;
        t->n = 0u;
        t->bin = 0xffu;
        star_bin_reset(t);
      }
    }
    break;
  }
  }
  /* the damping: the vector's angle led by -k_d omega_e (the position
   * source's speed), as the encoder's alignment (proc_align.c) */
  const float wn2 = star_wn2(c);
  const float kd = wn2 > 0.0f ? 2.0f * PROC_STAR_ZETA / sqrtf(wn2) : 0.0f;
  phi -= fd_clampf(kd * w, -0.25f * FRAMES_PI, 0.25f * FRAMES_PI);
  /* the current: the core's current loop in the stator frame (dq at
   * theta = 0), as the alignment's (proc_align.c) */
  const sincos_t sc = frames_sincos(phi);
  const dq_t v = current_ctrl_update(&t->cc, (dq_t){amp * sc.c, amp * sc.s},
                                     (dq_t){in->i_ab.alpha, in->i_ab.beta}, 0.0f, in->v_max);
  out->v_ab = (ab_t){v.d, v.q};
  return t->done ? PROC_DONE : PROC_RUNNING;
}

FD_COLD static void star_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_star_t *t = &st->star;
  tm->phase = t->phase;
  tm->n = t->n_all;
  /* after the first fit: that sweep's; at the end: the mean of both */
  const bool both = t->done;
  const float a = both ? 0.5f * (t->sw[0][0] + t->sw[1][0]) : t->sw[0][0];
  const float b = both ? 0.5f * (t->sw[0][1] + t->sw[1][1]) : t->sw[0][1];
  tm->result[0] = a;
  tm->result[1] = b;
  tm->result[2] = fabsf(a) > 0.0f ? b / a : 0.0f;
  tm->result[3] = t->theta_end;
  tm->result[4] = both ? fd_maxf(t->sw[0][3], t->sw[1][3]) : t->sw[0][3];
  tm->result[5] = both && fabsf(a) > 0.0f ? (t->sw[0][0] - t->sw[1][0]) / fabsf(a) : 0.0f;
  tm->result[6] = both && fabsf(a) > 0.0f ? (t->sw[0][1] - t->sw[1][1]) / fabsf(a) : 0.0f;
  tm->result[7] = t->sw[0][2];
}

const proc_row_t proc_star = {
    .name = "star",
    .id = PROC_STAR,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = star_check,
    .wanted = NULL,
    .init = star_init,
    .step = star_step,
    .abort = NULL,
    .publish = star_publish,
};

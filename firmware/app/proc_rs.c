/*
 * proc_rs.c - the stator resistance R_s and the inverter's voltage error
 * v_err(i), separated, at standstill (issue 25, procedure a;
 * docs/commissioning.md, "rs").
 *
 * At standstill the commanded voltage along the current holds
 *   v(i) = R_s i + v_err(i)                                           (1)
 * with v_err the inverter's mean voltage error (dead time, device drops):
 * odd in i, about linear below a knee (the current ripple crosses zero
 * within a PWM period) and about constant, sign(i) V_0, above it. A single
 * level (ODrive's ResistanceMeasurementControlLaw: R = V / I at one test
 * current) takes V_0 / I into R_s; the slope of (1) between levels above
 * the knee does not (the slope between voltage levels, as moteus'
 * calibration takes it). So: DC current levels along one axis, both signs,
 * each held by the current loop (current_ctrl.h), settled, then the
 * commanded voltage (one period before the sample: the sample reflects it)
 * and the measured current averaged; R_s the least-squares slope of (1)
 * with one intercept per sign over the levels above the knee, v_err(i_k) =
 * v_k - R_s i_k at each level.
 * The devices' resistance is linear in i like R_s: with the switch's and
 * the diode's (or synchronous rectifier's) resistances r_sw, r_d, a leg at
 * duty e carrying i > 0 drops (e r_sw + (1 - e) r_d) i, which at
 * standstill (e ~ 1/2) is r_dev i with r_dev = (r_sw + r_d) / 2 in every
 * phase: the slope is R_s + r_dev, and only a figure from outside the
 * measurement separates them (a different r_sw and r_d would show as a
 * slope that moves with a common-mode duty; a MOSFET bridge has none). The
 * board states r_dev (parameter r_dev, its datasheet); R_s is the slope
 * less r_dev, and v_err then holds the devices' drop.
 *
 * Rotor: free. A DC current aligns a PM rotor's d axis with it (a
 * reluctance rotor its high-inductance axis): the procedure first holds
 * the top level along theta = 0 for id_rs_align (the rotor turns there, at
 * most half an electrical turn), measures the positive levels, turns the
 * current slowly to theta = pi at the top level (the rotor follows: half an
 * electrical turn), waits id_rs_align again and measures the negative
 * levels (phase a's current negative: the other devices). Movement bound:
 * one electrical turn, 2 pi / p mechanical, plus the swing about the axis.
 * The current never exceeds the limit (id_rs_current, clamped to i_max):
 * the top level is PROC_RS_TOP of it, the rest for the loop's overshoot
 * and the ripple; a measured current above PROC_RS_TRIP times the limit
 * fails it (overcurrent). The voltage is the current loop's limit v_max.
 *
 * Phases (proc_telemetry_t.phase) and results: see proc_rs_publish.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"

#define PROC_RS_TOP  0.9f   /* top level: this fraction of the limit */
#define PROC_RS_TRIP 1.2f   /* a measured current above this times the limit fails it */
#define PROC_RS_RAMP 0.005f /* a level change is ramped over this [s] */
#define PROC_RS_TURN 0.2f   /* the turn to theta = pi takes this [s] */
#define PROC_RS_DAMP 0.3f   /* the swing's damping current: at most this fraction of the limit */
/* the longest wait for the swing's turning point (proc_swing.c), a half
 * swing: a swing slower than 2 Hz is averaged over whatever window [s] */
#define PROC_RS_SWING 0.25f
/* the knee: the lowest level from which every level above lies within
 * PROC_RS_KNEE_TOL of its sign's plateau (of |V_0|) */
#define PROC_RS_KNEE_TOL 0.01f

/* The phase numbers (proc_telemetry_t.phase), n = id_rs_levels. */
static inline uint8_t ph_turn(uint8_t n) {
  return (uint8_t)(n + 1u);
}
static inline uint8_t ph_report(uint8_t n) {
  return (uint8_t)(2u * n + 2u);
}
static inline uint8_t ph_done(uint8_t n) {
  return (uint8_t)(4u * n + 2u);
}

/* The limit: id_rs_current (0: half of i_max), clamped to i_max. */
FD_COLD static float rs_limit(const drive_config_t *c) {
  const float i = c->id_rs_current > 0.0f ? c->id_rs_current : 0.5f * c->i_max;
  return fminf(i, c->i_max);
}

/* Level k (0 the top) of n, of either sign [A]. */
FD_COLD static float rs_level(const drive_config_t *c, uint8_t n, uint8_t k) {
  return PROC_RS_TOP * rs_limit(c) * (float)(n - k) / (float)n;
}

FD_COLD static uint32_t rs_periods(float t, float ts) {
  return (uint32_t)(t / ts) + 1u;
}

FD_COLD static const char *rs_check(const proc_setup_t *su, const char **field) {
  const drive_config_t *c = su->cfg;
  if (!(rs_limit(c) > 0.0f)) {
    *field = "id_rs_current";
    return "the test current must be positive";
  }
  if (c->id_rs_levels < 3u || c->id_rs_levels > PROC_RS_LEVELS_MAX) {
    *field = "id_rs_levels";
    return "3 .. 8 levels (PROC_RS_LEVELS_MAX: their storage)";
  }
  return NULL;
}

/* Never in the start: the host runs it (drive_cmd_identify). */
FD_COLD static bool rs_wanted(const proc_setup_t *su) {
  (void)su;
  return false;
}

FD_COLD static void rs_init(proc_state_t *st, const proc_setup_t *su) {
  proc_rs_t *r = &st->rs;
  /* The loop's frame is the current's, not the rotor's: the rotor lies
   * anywhere on it until it has aligned, and on a salient or reluctance
   * rotor either axis may see either inductance. Both axes get the smaller
   * one (of a map: at zero current): the loop never faster than designed
   * (the larger one on the low-inductance axis overshot into the trip on
   * syr_1k1), slower where the rotor puts the larger. */
  /* mut: rs_loop_rotor_gains */
  const machine_ldq_t l0 = machine_inductance(su->machine, (dq_t){0.0f, 0.0f});
  const float l_min = fminf(l0.dd, l0.qq);
  if (machine_init_linear(&r->loop, su->machine->pole_pairs, su->machine->rs, l_min, l_min, 0.0f) !=
      0) {
    r->loop = *su->machine; /* not a valid linear model (the set was checked): the machine's */
  }
  const current_ctrl_cfg_t ccfg = {&r->loop, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&r->cc, &ccfg);
  r->n_levels = (uint8_t)su->cfg->id_rs_levels;
  r->phase = 0u;
  r->n = 0u;
  r->n_all = 0u;
  r->i_ref = 0.0f;
  r->theta = 0.0f;
  r->v_prev = 0.0f;
  r->acc_v = 0.0f;
  r->acc_i = 0.0f;
  r->acc_n = 0u;
  proc_swing_reset(&r->swing);
  r->open = false;
  r->i_peak = 0.0f;
  r->last = -1;
  for (unsigned k = 0; k < 2u * PROC_RS_LEVELS_MAX; ++k) {
    r->lv_i[k] = 0.0f;
    r->lv_v[k] = 0.0f;
  }
  for (unsigned k = 0; k < PROC_RESULTS; ++k) {
    r->res[k] = 0.0f;
  }
}

/* The fit of (1) over the levels at or above level index `top_n` of each
 * sign (the first top_n + 1 of each: levels are stored top first):
 * R = sum_s sum_k (i_k - i_s)(v_k - v_s) / sum_s sum_k (i_k - i_s)^2, one
 * mean (i_s, v_s) per sign, the plateau c_s = v_s - R i_s. Returns R (0
 * when the levels carry no slope). */
FD_COLD static float rs_fit(const proc_rs_t *r, uint8_t used, float c_out[2]) {
  float sxy = 0.0f;
  float sxx = 0.0f;
  float mi[2], mv[2];
  for (unsigned s = 0; s < 2u; ++s) {
    const float *li = &r->lv_i[(size_t)s * r->n_levels];
    const float *lv = &r->lv_v[(size_t)s * r->n_levels];
    float si = 0.0f, sv = 0.0f;
    for (unsigned k = 0; k < used; ++k) {
      si += li[k];
      sv += lv[k];
    }
    mi[s] = si / (float)used;
    mv[s] = sv / (float)used;
    for (unsigned k = 0; k < used; ++k) {
      sxy += (li[k] - mi[s]) * (lv[k] - mv[s]);
      sxx += (li[k] - mi[s]) * (li[k] - mi[s]);
    }
  }
  /* mut: rs_single_level */
  const float rr = sxx > 0.0f ? sxy / sxx : 0.0f;
  c_out[0] = mv[0] - rr * mi[0];
  c_out[1] = mv[1] - rr * mi[1];
  return rr;
}

/* The levels fitted, the knee found, the results written (res[], see
 * proc_rs_publish). Two passes: the upper half of the levels gives a
 * first line; the knee is the lowest level from which every level above
 * lies within PROC_RS_KNEE_TOL |V_0| of its sign's plateau; the fit is
 * repeated over the levels above the knee (at least 2 of each sign). */
FD_COLD static bool rs_finish(proc_rs_t *r, float r_dev) {
  const uint8_t n = r->n_levels;
  float c[2];
  uint8_t used = (uint8_t)((n + 1u) / 2u);
  used = used < 2u ? 2u : used;
  float rr = 0.0f;
  for (unsigned pass = 0; pass < 2u; ++pass) {
    rr = rs_fit(r, used, c);
    const float v0 = 0.5f * (fabsf(c[0]) + fabsf(c[1]));
    const float tol = PROC_RS_KNEE_TOL * v0 + 1e-6f;
    uint8_t k_ok = 0u; /* levels from the top within tol on both signs */
    while (k_ok < n) {
      const float e0 = r->lv_v[k_ok] - rr * r->lv_i[k_ok] - c[0];
      const float e1 = r->lv_v[n + k_ok] - rr * r->lv_i[n + k_ok] - c[1];
      if (fabsf(e0) > tol || fabsf(e1) > tol) {
        break;
      }
      ++k_ok;
    }
    used = k_ok < 2u ? 2u : k_ok;
  }
  /* the residual over the levels used [V rms] */
  float e2 = 0.0f;
  for (unsigned s = 0; s < 2u; ++s) {
    for (unsigned k = 0; k < used; ++k) {
      const float e = r->lv_v[s * n + k] - rr * r->lv_i[s * n + k] - c[s];
      e2 += e * e;
    }
  }
  const float i_top = 0.5f * (r->lv_i[0] - r->lv_i[n]);
  /* the winding's: the slope less the devices' resistance the board states
   * (r_dev); their drop is the inverter's error, with the plateau */
  /* mut: rs_device_resistance_kept */
  const float rw = rr - r_dev;
  const float v_err_top = 0.5f * ((r->lv_v[0] - rw * r->lv_i[0]) - (r->lv_v[n] - rw * r->lv_i[n]));
  const float knee = 0.5f * (fabsf(r->lv_i[used - 1u]) + fabsf(r->lv_i[n + used - 1u]));
  r->res[0] = rw;
  r->res[1] = v_err_top;
  r->res[2] = knee;
  r->res[3] = c[0];
  r->res[4] = c[1];
  r->res[5] = i_top;
  r->res[6] = sqrtf(e2 / (float)(2u * used));
  r->res[7] = (float)used;
  return isfinite(rw) && rw > 0.0f && isfinite(v_err_top);
}

FD_COLD static int rs_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                           proc_out_t *out) {
  proc_rs_t *r = &st->rs;
  const drive_config_t *c = su->cfg;
  const uint8_t n = r->n_levels;
  const float lim = rs_limit(c);
  *out = (proc_out_t){{0.0f, 0.0f}, true, false, 0u};
  ++r->n_all;
  /* mut: rs_overcurrent_bound */
  const float i_abs = sqrtf(in->i_ab.alpha * in->i_ab.alpha + in->i_ab.beta * in->i_ab.beta);
  r->i_peak = fmaxf(r->i_peak, i_abs);
  if (!(i_abs <= PROC_RS_TRIP * lim)) { /* also a non-finite current */
    out->fault = DRIVE_FAULT_OVERCURRENT;
    return PROC_FAILED;
  }
  if (r->phase >= ph_report(n)) { /* the report: one level a slow period, then done */
    out->apply = false;
    if (++r->n >= c->slow_div) {
      r->n = 0u;
      ++r->phase;
    }
    return r->phase >= ph_done(n) ? PROC_DONE : PROC_RUNNING;
  }
  const uint32_t n_align = rs_periods(c->id_rs_align, c->ts);
  const uint32_t n_settle = rs_periods(c->id_rs_settle, c->ts);
  const uint32_t n_avg = rs_periods(c->id_rs_avg, c->ts);
  const uint32_t n_turn = rs_periods(PROC_RS_TURN, c->ts);
  const float top = rs_level(c, n, 0u);
  /* the reference and the axis of this phase */
  float target = top;
  /* the levels' phases (either sign): settled, then averaged */
  uint32_t n_phase = n_settle + n_avg;
  bool measure = true;
  if (r->phase == 0u) {
    /* the alignment: at pi/2 first, then turned to 0 (a rotor that starts
     * where a current along 0 holds it unstably, at pi or, on a reluctance
     * rotor, on its low-inductance axis, would leave it during the levels:
     * proc_ident_align_angle), then held at 0 for id_rs_align */
    /* mut: rs_align_direct */
    r->theta = proc_ident_align_angle(r->n, n_align / 2u, n_turn);
    n_phase = n_align / 2u + n_turn + n_align;
    measure = false;
  } else if (r->phase <= n) { /* positive levels, top first */
    target = rs_level(c, n, (uint8_t)(r->phase - 1u));
  } else if (r->phase == ph_turn(n)) { /* the turn to pi at the top level, then a wait */
    r->theta = FRAMES_PI * fminf((float)r->n / (float)n_turn, 1.0f);
    n_phase = n_turn + n_align;
    measure = false;
  } else { /* negative levels (along theta = pi), top first */
    r->theta = FRAMES_PI;
    target = rs_level(c, n, (uint8_t)(r->phase - ph_turn(n) - 1u));
  }
  /* the reference, slew-limited (no step overshoot) */
  const float slew = top * c->ts / PROC_RS_RAMP;
  r->i_ref += fd_clampf(target - r->i_ref, -slew, slew);
  /* the loop in the frame turned by theta (at standstill: we = 0) */
  const sincos_t sc = frames_sincos(r->theta);
  const float i_x = sc.c * in->i_ab.alpha + sc.s * in->i_ab.beta;
  const float i_y = -sc.s * in->i_ab.alpha + sc.c * in->i_ab.beta;
  /* the swing damped (proc_swing.c) but within a level's window, at most
   * PROC_RS_DAMP of the limit across the current */
  /* mut: rs_swing_undamped */
  const float damp = PROC_RS_DAMP * lim;
  const float iy_ref = proc_swing_damping(&r->swing, r->i_ref, damp, slew, !r->open);
  const dq_t v =
      current_ctrl_update(&r->cc, (dq_t){r->i_ref, iy_ref}, (dq_t){i_x, i_y}, 0.0f, in->v_max);
  out->v_ab = (ab_t){sc.c * v.d - sc.s * v.q, sc.s * v.d + sc.c * v.q};
  /* the swing's turning points (proc_swing.c): along 0 and pi the voltage
   * across the current is the back-EMF of the rotor's swing alone */
  /* mut: rs_swing_window */
  proc_swing_step(&r->swing, v.d, v.q, c->ts);
  const uint32_t n_swing = rs_periods(PROC_RS_SWING, c->ts);
  /* a level's window begins at a turning point after the settling (or
   * when none came within PROC_RS_SWING) ... */
  if (measure && !r->open && r->n >= n_settle && (r->swing.turned || r->n >= n_settle + n_swing)) {
    r->open = true;
  }
  if (r->open) {
    /* the sample reflects the voltage asked the period before */
    r->acc_v += r->v_prev;
    r->acc_i += i_x;
    ++r->acc_n;
  }
  r->v_prev = v.d;
  ++r->n;
  /* ... and ends at one after id_rs_avg (at most PROC_RS_SWING later):
   * the swing's flux along the current is the same at both ends (1).
   * (Windows of whole swings, for the asymmetric swing of a reluctance
   * rotor, and alignments that wait for the swing to calm were tried: no
   * case of the presets and seeds 1-8 came out better, issue 25.) */
  if (measure ? !(r->open && r->acc_n >= n_avg && (r->swing.turned || r->acc_n >= n_avg + n_swing))
              : r->n < n_phase) {
    return PROC_RUNNING;
  }
  r->open = false;
  if (measure) { /* the level's means, stored top first per sign */
    const unsigned s = r->phase <= n ? 0u : 1u;
    const unsigned k = s == 0u ? r->phase - 1u : r->phase - ph_turn(n) - 1u;
    const float na = r->acc_n > 0u ? (float)r->acc_n : 1.0f;
    /* along theta = pi the axis' current and voltage are phase a's negative */
    const float sg = s == 0u ? 1.0f : -1.0f;
    r->lv_i[s * n + k] = sg * r->acc_i / na;
    r->lv_v[s * n + k] = sg * r->acc_v / na;
    r->last = (int8_t)(s * n + k);
    r->acc_v = 0.0f;
    r->acc_i = 0.0f;
    r->acc_n = 0u;
  }
  r->n = 0u;
  ++r->phase;
  if (r->phase == ph_report(n)) {
    if (!rs_finish(r, c->r_dev)) {
      /* no slope (no current, an open phase), or none left for the winding
       * (r_dev above the slope) */
      out->fault = DRIVE_FAULT_CONTROL;
      return PROC_FAILED;
    }
    out->v_ab = (ab_t){0.0f, 0.0f};
  }
  return PROC_RUNNING;
}

/* Phase and results (proc_telemetry_t; docs/commissioning.md, "rs"):
 *  phase 0: alignment; 1..n: positive level k = phase - 1 (top first);
 *  n + 1: the turn to pi; n + 2 .. 2n + 1: negative levels; while they
 *  run the results are the last level measured [i A, v V] (result[0], [1])
 *  and, until done, result[7] the largest measured current [A].
 *  2n + 2 .. 4n + 1: the report, one level a slow period, positive levels
 *  then negative, top first: [i_k A, v_k V, v_err(i_k) = v_k - R_s i_k V,
 *  R_s Ohm]. 4n + 2 (done): the fit:
 *   0 R_s [Ohm] (the slope above the knee less r_dev, the devices'
 *     resistance the board states: no DC measurement separates the two)
 *   1 v_err at the top level [V] (mean of both signs, odd part)
 *   2 the knee current [A] (the lowest level on the plateau)
 *   3, 4 the plateaus V_0 of the positive and negative sign [V]
 *   5 the top level [A]
 *   6 the fit's residual [V rms]
 *   7 the levels of each sign fitted */
FD_COLD static void rs_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_rs_t *r = &st->rs;
  const uint8_t n = r->n_levels;
  tm->phase = r->phase;
  tm->n = r->n_all;
  for (unsigned k = 0; k < PROC_RESULTS; ++k) {
    tm->result[k] = 0.0f;
  }
  if (r->phase >= ph_done(n)) {
    for (unsigned k = 0; k < PROC_RESULTS; ++k) {
      tm->result[k] = r->res[k];
    }
  } else if (r->phase >= ph_report(n)) {
    const unsigned j = r->phase - ph_report(n); /* 0 .. 2n - 1 */
    tm->result[0] = r->lv_i[j];
    tm->result[1] = r->lv_v[j];
    tm->result[2] = r->lv_v[j] - r->res[0] * r->lv_i[j];
    tm->result[3] = r->res[0];
  } else if (r->last >= 0) {
    tm->result[0] = r->lv_i[r->last];
    tm->result[1] = r->lv_v[r->last];
  }
  if (r->phase < ph_done(n)) {
    tm->result[7] = r->i_peak;
  }
}

const proc_row_t proc_rs = {
    .name = "rs",
    .id = PROC_RS,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_IDENT | PROC_CAP_GATES,
    .check = rs_check,
    .wanted = rs_wanted,
    .init = rs_init,
    .step = rs_step,
    .abort = NULL,
    .publish = rs_publish,
};

/*
 * proc_hold.c - the held start (start_mode 1) as a procedure (proc.h): a
 * star-point source starts without letting the rotor turn (issue 23, point
 * 3; docs/dfc.md, "The held start").
 *
 * With zero current the source measures 2 theta_e at standstill (the DFC
 * window works without current); two opposite voltage pulses along the
 * estimate then show the magnet's polarity by the d-axis saturation: the
 * pulse along the north pole adds to the magnet's flux, meets the lower
 * incremental inductance and builds the larger current (Fabbri 2022,
 * 3.1.3: theta is known from 2 theta only up to pi). The pulses carry no
 * torque (d current along the estimate). Then the run starts from
 * standstill on the estimated angle: 2.44 to 3.25 ms with the gates on and
 * no torque, the only time an active load can move the rotor. Bounded: the
 * pulses at the voltage limit v_max no longer than the controller's R-L
 * model takes to reach i_max (pulse_periods), the way back deadbeat within
 * v_max.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"

/* Periods of each phase: the acquisition, then per pulse n_pulse + N_AVG +
 * 1 and n_zero; 39 periods in all, 2.44 ms at 16 kHz, on fabbri2022_t51
 * (n_pulse 3), up to 8 + 2 (8 + 2 + 12) = 52, 3.25 ms */
#define PROC_HOLD_N_ACQ       8u /* zero current: three DFC components, then five updates */
#define PROC_HOLD_N_PULSE_MIN 2u /* voltage pulse, periods (pulse_periods) */
#define PROC_HOLD_N_PULSE_MAX 8u
#define PROC_HOLD_N_AVG       1u   /* samples of its current averaged */
#define PROC_HOLD_N_ZERO      10u  /* at least, the current back to zero (deadbeat) */
#define PROC_HOLD_K_DB        0.8f /* of the deadbeat step: margin for R, L errors */
/* the pulses' currents must differ by this fraction of their mean */
#define PROC_HOLD_EVIDENCE_MIN 0.02f

enum { PH_ACQ = 0, PH_PULSE0, PH_ZERO0, PH_PULSE1, PH_ZERO1 };

/* The pulse's periods: the voltage limit v_max until the controller's
 * linear R-L model reaches i_max, i(t) = v_max / R (1 - exp(-t R / Ld)),
 * but no longer than tau = Ld / R (beyond it the current is set by R, no
 * longer by the inductance that carries the evidence: on fabbri2022_t51
 * tau is 2.9 periods), within PROC_HOLD_N_PULSE_MIN .. _MAX. */
FD_COLD static unsigned pulse_periods(const drive_config_t *c, float v_max) {
  const float tau = c->ld / c->rs;
  const float r = c->i_max * c->rs / v_max;
  const float t = r < 1.0f ? fd_minf(tau, -tau * logf(1.0f - r)) : tau;
  const float n = ceilf(t / c->ts);
  return (unsigned)fd_clampf(n, (float)PROC_HOLD_N_PULSE_MIN, (float)PROC_HOLD_N_PULSE_MAX);
}

/* Wanted with start_mode 1; able only with a source that has an angle at
 * standstill (its hold). */
FD_COLD static bool hold_wanted(const proc_setup_t *su) {
  return su->cfg->start_mode == 1u;
}

FD_COLD static const char *hold_check(const proc_setup_t *su, const char **field) {
  if (su->pos_src->hold == NULL) {
    *field = "start_mode";
    return "the held start (1) needs a star-point position source (an angle at standstill); "
           "the encoder starts by its alignment or its known enc_offset (0)";
  }
  return NULL;
}

FD_COLD static void hold_init(proc_state_t *st, const proc_setup_t *su) {
  (void)su;
  proc_hold_t *h = &st->hold;
  h->phase = PH_ACQ;
  h->n = 0u;
  h->n_all = 0u;
  h->theta = 0.0f;
  h->theta_out = 0.0f;
  h->i0 = 0.0f;
  h->di[0] = 0.0f;
  h->di[1] = 0.0f;
  h->v_prev = (dq_t){0.0f, 0.0f};
  h->plain = false;
  h->n_pulse = PROC_HOLD_N_PULSE_MIN;
  h->n_zero = PROC_HOLD_N_ZERO;
}

/* The current back to zero in the estimate's frame, deadbeat on the
 * controller's R-L model with the one-period delay: the current the last
 * voltage will have built by the next sample (v_prev), then the voltage
 * that takes PROC_HOLD_K_DB of it away over the period after. */
FD_COLD static ab_t zero_current(proc_hold_t *h, const drive_config_t *c, ab_t i_ab, float v_max) {
  const sincos_t sc = frames_sincos(h->theta);
  const dq_t i = frames_park(i_ab, sc);
  const dq_t vp = h->v_prev;
  const dq_t ip = {i.d + (vp.d - c->rs * i.d) * c->ts / c->ld,
                   i.q + (vp.q - c->rs * i.q) * c->ts / c->lq};
  dq_t v = {(c->rs - PROC_HOLD_K_DB * c->ld / c->ts) * ip.d,
            (c->rs - PROC_HOLD_K_DB * c->lq / c->ts) * ip.q};
  const float m = sqrtf(v.d * v.d + v.q * v.q);
  if (m > v_max) {
    v.d *= v_max / m;
    v.q *= v_max / m;
  }
  h->v_prev = v;
  return frames_park_inv(v, sc);
}

/* A pulse of sign sgn along the estimate: n = 0 .. N-1 the voltage, then
 * none for PROC_HOLD_N_AVG periods; the current it built is the mean of the
 * samples n = N + 1 .. N + PROC_HOLD_N_AVG (the voltage written in a period acts
 * over the next; hal.h). The pattern is written without the DFC window
 * meanwhile (plain): a window shifts the valley sample by some 0.1 .. 0.3
 * A, by the leg and the direction, which its correction
 * (drive_window_sample) leaves a few % of, as large as the saturation's
 * evidence (on fabbri2022_t51 it took the decision the wrong way from 3.0
 * rad). The source misses those few components (it coasts). Returns true
 * when the pulse is measured. */
FD_COLD static bool pulse(proc_hold_t *h, ab_t i_ab, float v_max, float sgn, unsigned k,
                          ab_t *v_ab) {
  const sincos_t sc = frames_sincos(h->theta);
  const float i_d = i_ab.alpha * sc.c + i_ab.beta * sc.s;
  const unsigned n = h->n;
  if (n == 0u) {
    h->di[k] = 0.0f;
  } else if (n == 1u) {
    h->i0 = i_d; /* before the pulse acts, the first sample after a plain period */
  }
  const unsigned np = h->n_pulse;
  h->plain = n < np + PROC_HOLD_N_AVG;
  if (n < np) {
    const float v = sgn * v_max;
    *v_ab = (ab_t){v * sc.c, v * sc.s};
    h->v_prev = (dq_t){v, 0.0f};
    return false;
  }
  *v_ab = (ab_t){0.0f, 0.0f};
  h->v_prev = (dq_t){0.0f, 0.0f};
  if (n < np + 1u) {
    return false;
  }
  h->di[k] += sgn * (i_d - h->i0) * (1.0f / (float)PROC_HOLD_N_AVG);
  return n >= np + PROC_HOLD_N_AVG;
}

/* One period: PROC_RUNNING, PROC_DONE (the source takes the north pole's
 * angle: its estimate's branch nearest it), PROC_FAILED (no angle at
 * standstill, or no polarity evidence: the position fault; nothing
 * written). */
FD_COLD static int hold_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                             proc_out_t *out) {
  proc_hold_t *h = &st->hold;
  const float v_max = in->v_max;
  const ab_t i_ab = in->i_ab;
  ab_t v_ab = {0.0f, 0.0f};
  const unsigned ph = h->phase;
  bool next = false;
  int r = PROC_RUNNING;
  h->n_all++;
  if (ph == PH_ACQ) {
    if (h->n >= PROC_HOLD_N_ACQ && in->pos->valid) {
      h->theta = in->pos->theta;
      const unsigned np = pulse_periods(su->cfg, v_max);
      h->n_pulse = (uint8_t)np;
      /* the way back takes as long as the way up at the voltage limit */
      h->n_zero = (uint8_t)(np + 4u > PROC_HOLD_N_ZERO ? np + 4u : PROC_HOLD_N_ZERO);
      next = true;
    } else if (h->n >= 4u * PROC_HOLD_N_ACQ) {
      r = PROC_FAILED; /* no angle at standstill */
    }
  } else if (ph == PH_PULSE0 || ph == PH_PULSE1) {
    const unsigned k = ph == PH_PULSE0 ? 0u : 1u;
    if (pulse(h, i_ab, v_max, k == 0u ? 1.0f : -1.0f, k, &v_ab)) {
      v_ab = zero_current(h, su->cfg, i_ab, v_max);
      next = true;
    }
  } else {
    v_ab = zero_current(h, su->cfg, i_ab, v_max);
    if (h->n + 1u >= h->n_zero) {
      if (ph == PH_ZERO1) {
        /* the pulse along the north pole built the larger current */
        const float d0 = h->di[0], d1 = h->di[1];
        const float mean = 0.5f * (d0 + d1);
        if (!(mean > 0.0f) || !(fabsf(d0 - d1) > PROC_HOLD_EVIDENCE_MIN * mean)) {
          r = PROC_FAILED; /* no saturation to show the pole */
        } else {
          /* mut: held_start_polarity_reversed */
          h->theta_out = d0 > d1 ? h->theta : frames_wrap_pi(h->theta + FRAMES_PI);
          su->pos_src->hold(su->pos_st, h->theta_out);
          r = PROC_DONE;
        }
      }
      next = r == PROC_RUNNING;
    }
  }
  if (r == PROC_FAILED) {
    *out = (proc_out_t){{0.0f, 0.0f}, false, h->plain, DRIVE_FAULT_POSITION};
    return r;
  }
  if (next) {
    h->phase = (uint8_t)(ph + 1u);
    h->n = 0u;
  } else if (r == PROC_RUNNING) {
    h->n++;
  }
  *out = (proc_out_t){v_ab, true, h->plain, 0u};
  return r;
}

FD_COLD static void hold_abort(proc_state_t *st) {
  st->hold.plain = false;
}

FD_COLD static void hold_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_hold_t *h = &st->hold;
  tm->phase = h->phase;
  tm->n = h->n_all;
  tm->result[0] = h->theta;
  tm->result[1] = h->theta_out;
  const float mean = 0.5f * (h->di[0] + h->di[1]);
  tm->result[2] = mean > 0.0f ? (h->di[0] - h->di[1]) / mean : 0.0f;
}

const proc_row_t proc_hold = {
    .name = "hold",
    .id = PROC_HOLD,
    .state = DRIVE_STATE_ALIGN,
    .caps = PROC_CAP_GATES,
    .check = hold_check,
    .wanted = hold_wanted,
    .init = hold_init,
    .step = hold_step,
    .abort = hold_abort,
    .publish = hold_publish,
};

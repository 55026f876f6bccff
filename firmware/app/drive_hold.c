/*
 * drive_hold.c - the held start (drive_hold.h; docs/dfc.md, "The held
 * start"): the angle at standstill, the polarity from two opposite d-axis
 * pulses, no free rotor.
 */
#include "drive_hold.h"

#include <math.h>

#include "math/fd_math.h"
#include "math/frames.h"

enum { PH_ACQ = 0, PH_PULSE0, PH_ZERO0, PH_PULSE1, PH_ZERO1 };

/* The pulse's periods: the voltage limit v_max until the controller's
 * linear R-L model reaches i_max, i(t) = v_max / R (1 - exp(-t R / Ld)),
 * but no longer than tau = Ld / R (beyond it the current is set by R, no
 * longer by the inductance that carries the evidence: on fabbri2022_t51
 * tau is 2.9 periods), within DRIVE_HOLD_N_PULSE_MIN .. _MAX. */
static unsigned pulse_periods(const drive_config_t *c, float v_max) {
  const float tau = c->ld / c->rs;
  const float r = c->i_max * c->rs / v_max;
  const float t = r < 1.0f ? fd_minf(tau, -tau * logf(1.0f - r)) : tau;
  const float n = ceilf(t / c->ts);
  return (unsigned)fd_clampf(n, (float)DRIVE_HOLD_N_PULSE_MIN, (float)DRIVE_HOLD_N_PULSE_MAX);
}

void drive_hold_reset(drive_t *drv) {
  drv->hold.phase = PH_ACQ;
  drv->hold.n = 0u;
  drv->hold.theta = 0.0f;
  drv->hold.i0 = 0.0f;
  drv->hold.di[0] = 0.0f;
  drv->hold.di[1] = 0.0f;
  drv->hold.v_prev = (dq_t){0.0f, 0.0f};
  drv->hold.plain = false;
  drv->hold.n_pulse = DRIVE_HOLD_N_PULSE_MIN;
  drv->hold.n_zero = DRIVE_HOLD_N_ZERO;
}

/* The current back to zero in the estimate's frame, deadbeat on the
 * controller's R-L model with the one-period delay: the current the last
 * voltage will have built by the next sample (v_prev), then the voltage
 * that takes DRIVE_HOLD_K_DB of it away over the period after. */
static ab_t zero_current(drive_t *drv, ab_t i_ab, float v_max) {
  const drive_config_t *c = &drv->cfg;
  const sincos_t sc = frames_sincos(drv->hold.theta);
  const dq_t i = frames_park(i_ab, sc);
  const dq_t vp = drv->hold.v_prev;
  const dq_t ip = {i.d + (vp.d - c->rs * i.d) * c->ts / c->ld,
                   i.q + (vp.q - c->rs * i.q) * c->ts / c->lq};
  dq_t v = {(c->rs - DRIVE_HOLD_K_DB * c->ld / c->ts) * ip.d,
            (c->rs - DRIVE_HOLD_K_DB * c->lq / c->ts) * ip.q};
  const float m = sqrtf(v.d * v.d + v.q * v.q);
  if (m > v_max) {
    v.d *= v_max / m;
    v.q *= v_max / m;
  }
  drv->hold.v_prev = v;
  return frames_park_inv(v, sc);
}

/* A pulse of sign sgn along the estimate: n = 0 .. N-1 the voltage, then
 * none for DRIVE_HOLD_N_AVG periods; the current it built is the mean of
 * the samples n = N + 1 .. N + DRIVE_HOLD_N_AVG (the voltage written in a
 * period acts over the next; hal.h). The pattern is written without the
 * DFC window meanwhile (hold.plain): a window shifts the valley sample by
 * some 0.1 .. 0.3 A, by the leg and the direction, which its correction
 * (drive_window_sample) leaves a few % of, as large as the saturation's
 * evidence (on fabbri2022_t51 it took the decision the wrong way from 3.0
 * rad). The source misses those few components (it coasts). Returns true
 * when the pulse is measured. */
static bool pulse(drive_t *drv, ab_t i_ab, float v_max, float sgn, unsigned k, ab_t *v_ab) {
  const sincos_t sc = frames_sincos(drv->hold.theta);
  const float i_d = i_ab.alpha * sc.c + i_ab.beta * sc.s;
  const unsigned n = drv->hold.n;
  if (n == 0u) {
    drv->hold.di[k] = 0.0f;
  } else if (n == 1u) {
    drv->hold.i0 = i_d; /* before the pulse acts, the first sample after a plain period */
  }
  const unsigned np = drv->hold.n_pulse;
  drv->hold.plain = n < np + DRIVE_HOLD_N_AVG;
  if (n < np) {
    const float v = sgn * v_max;
    *v_ab = (ab_t){v * sc.c, v * sc.s};
    drv->hold.v_prev = (dq_t){v, 0.0f};
    return false;
  }
  *v_ab = (ab_t){0.0f, 0.0f};
  drv->hold.v_prev = (dq_t){0.0f, 0.0f};
  if (n < np + 1u) {
    return false;
  }
  drv->hold.di[k] += sgn * (i_d - drv->hold.i0) * (1.0f / (float)DRIVE_HOLD_N_AVG);
  return n >= np + DRIVE_HOLD_N_AVG;
}

int drive_hold_step(drive_t *drv, ab_t i_ab, float v_max, ab_t *v_ab, float *theta_out) {
  *v_ab = (ab_t){0.0f, 0.0f};
  const unsigned ph = drv->hold.phase;
  bool next = false;
  if (ph == PH_ACQ) {
    if (drv->hold.n >= DRIVE_HOLD_N_ACQ && drv->pos.out.valid) {
      drv->hold.theta = drv->pos.out.theta;
      const unsigned np = pulse_periods(&drv->cfg, v_max);
      drv->hold.n_pulse = (uint8_t)np;
      /* the way back takes as long as the way up at the voltage limit */
      drv->hold.n_zero = (uint8_t)(np + 4u > DRIVE_HOLD_N_ZERO ? np + 4u : DRIVE_HOLD_N_ZERO);
      next = true;
    } else if (drv->hold.n >= 4u * DRIVE_HOLD_N_ACQ) {
      return DRIVE_HOLD_FAIL; /* no angle at standstill */
    }
  } else if (ph == PH_PULSE0 || ph == PH_PULSE1) {
    const unsigned k = ph == PH_PULSE0 ? 0u : 1u;
    if (pulse(drv, i_ab, v_max, k == 0u ? 1.0f : -1.0f, k, v_ab)) {
      *v_ab = zero_current(drv, i_ab, v_max);
      next = true;
    }
  } else {
    *v_ab = zero_current(drv, i_ab, v_max);
    if (drv->hold.n + 1u >= drv->hold.n_zero) {
      if (ph == PH_ZERO1) {
        /* the pulse along the north pole built the larger current */
        const float d0 = drv->hold.di[0], d1 = drv->hold.di[1];
        const float mean = 0.5f * (d0 + d1);
        if (!(mean > 0.0f) || !(fabsf(d0 - d1) > DRIVE_HOLD_EVIDENCE_MIN * mean)) {
          return DRIVE_HOLD_FAIL; /* no saturation to show the pole */
        }
        *theta_out = d0 > d1 ? drv->hold.theta : frames_wrap_pi(drv->hold.theta + FRAMES_PI);
        return DRIVE_HOLD_DONE;
      }
      next = true;
    }
  }
  if (next) {
    drv->hold.phase = (uint8_t)(ph + 1u);
    drv->hold.n = 0u;
  } else {
    drv->hold.n++;
  }
  return DRIVE_HOLD_BUSY;
}

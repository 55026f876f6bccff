/*
 * protect/drive_safe.c - the safe state while the gates do not modulate (idle and
 * fault): all switches off, or the active short circuit (ASC, hal.h
 * hal_pwm_short), issue 13 item 5, docs/faults.md "Safe state".
 *
 * With all switches off a PM machine turning faster than the rectifier
 * speed, where the line-to-line back-EMF peak sqrt(3) psi_pm |w_e| exceeds
 * v_dc, still drives current through the free-wheeling diodes: it brakes
 * and charges the DC link, without limit if the link cannot return the
 * energy (a diode rectifier, a cut supply). With all low sides on the
 * back-EMF drives the short-circuit current in the windings only: at most
 * psi_pm / L in steady state (about twice that in the transient), no
 * energy into the link. So:
 *  - when the gates leave modulation (a trip, a disable), the short is
 *    chosen if sqrt(3) psi_pm |w_e| > asc_speed v_dc, if the link is over
 *    SAFE_V_RATIO v_dc_max, or if the speed is not known (a position fault, a source
 *    without a valid speed); otherwise all off;
 *  - with all off, the short is engaged when the link goes over
 *    SAFE_V_RATIO v_dc_max (ahead of the overvoltage trip),
 *    or when a known speed (a source that runs with the gates off: the
 *    encoder) stays above the entry speed for ENTRY_N periods;
 *  - the short ends, after asc_hold, when the link is within that and
 *    the speed stays below EXIT_RATIO times the entry speed for EXIT_N
 *    periods. The speed is the source's if known, otherwise the rotation
 *    of the short-circuit current vector, which turns at w_e whatever the
 *    position sensor (after its offset decays with L/R: asc_hold);
 *  - never on a machine whose short-circuit current at speed, the current
 *    at zero flux i_sc (psi_pm / L_d on a linear machine), is not below
 *    i_max: the short would hold more than the rated current for as long
 *    as the load turns the rotor (and about twice it in the transient);
 *    such a drive needs a braking chopper or a stiff link instead;
 *  - never when the stator flux the short would trap, bounded from the
 *    current's amplitude, drives a current beyond i_trip in some rotor
 *    position (drive_safe_psi_max: a reluctance machine's flux along its
 *    low inductance);
 *  - never with the hardware break latched or after a fault that makes
 *    the bridge itself suspect (hw_overcurrent: a switch may conduct
 *    across the link, and the timer refuses MOE anyway), nor with
 *    asc_speed = 0 (all off only, the former behaviour).
 * An enable waits while the short is on (the offset calibration needs the
 * gates off and no current). The functions live in flash (FD_COLD): they
 * never run while the law does. The part asks for the switch actions
 * (PROTECT_SAFE_*); drive.c applies them.
 */
#include "protect/drive_safe.h"

#include <math.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"

#define SAFE_SQRT3 1.7320508f
/* the link level that engages the short, ahead of the overvoltage trip */
#define SAFE_V_RATIO 0.95f
/* mut: asc_exit_early */
#define ENTRY_N    16u    /* periods above the entry speed before the short */
#define EXIT_N     16u    /* periods below the exit speed before all off */
#define EXIT_RATIO 0.7f   /* exit speed / entry speed (hysteresis) */
#define W_I_BW     300.0f /* bandwidth of the current-vector speed [rad/s] */
#define I_FLOOR    0.02f  /* current vector too small to turn, times i_max */

/* Faults after which the bridge is not trusted with a short. */
#define SAFE_NO_ASC (DRIVE_FAULT_HW_OVERCURRENT | DRIVE_FAULT_GATE_DRIVER)

static bool asc_allowed(const protect_safe_t *z, const protect_safe_view_t *v) {
  /* mut: asc_never */
  return v->asc_speed > 0.0f && z->i_sc < v->i_max && (v->faults & SAFE_NO_ASC) == 0u &&
         !v->hw_tripped;
}

/* The source's electrical speed when it is known with the gates off (or
 * at the instant they went off), else -1. */
static float known_speed(const protect_safe_view_t *v, bool at_trip) {
  if (!v->pos_valid || (v->faults & DRIVE_FAULT_POSITION) != 0u || (v->pos_gated && !at_trip) ||
      !fd_isfinite(v->pos_omega)) {
    return -1.0f;
  }
  return fabsf(v->pos_omega);
}

/* Largest |f(r e^{j phi})| over RING_N directions: f = machine_current
 * (flux to current) or machine_flux (current to flux). */
#define RING_N 8
FD_COLD static float ring_max(const machine_t *m, float r, bool current) {
  static const float cs[RING_N][2] = {
      {1.0f, 0.0f},  {0.70710678f, 0.70710678f},   {0.0f, 1.0f},  {-0.70710678f, 0.70710678f},
      {-1.0f, 0.0f}, {-0.70710678f, -0.70710678f}, {0.0f, -1.0f}, {0.70710678f, -0.70710678f}};
  float best = 0.0f;
  for (unsigned k = 0; k < RING_N; ++k) {
    const dq_t x = {r * cs[k][0], r * cs[k][1]};
    const dq_t y = current ? machine_current(m, x) : machine_flux(m, x);
    best = fd_maxf(best, sqrtf(y.d * y.d + y.q * y.q));
  }
  return best;
}

/* The short traps the stator flux psi_0 it begins with; in the rotor frame
 * it turns backwards at w_e while it decays (to the flux of i_sc), so the
 * current passes |i(psi)| for |psi| = |psi_0| in every direction. The
 * largest |psi_0| whose ring stays within i_trip (bisection, at
 * configuration): a reluctance machine's trapped flux along its low
 * inductance would otherwise drive a current far beyond the trip. */
FD_COLD void protect_safe_configure(protect_safe_t *z, const machine_t *m, float psi_pm, float i_sc,
                                    float flux_scale, float i_trip) {
  z->psi_pm = psi_pm;
  z->i_sc = i_sc;
  float lo = 0.0f, hi = 4.0f * (psi_pm + flux_scale);
  if (ring_max(m, hi, true) <= i_trip) {
    z->psi_max = hi;
    return;
  }
  for (unsigned k = 0; k < 12u; ++k) {
    const float mid = 0.5f * (lo + hi);
    if (ring_max(m, mid, true) <= i_trip) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  z->psi_max = lo;
}

/* The stator flux a short would trap now: the model's at the last run
 * period's rotor-frame currents when the gates just left modulation with
 * the angle known; else the law's observed flux when it has an observer
 * (the DFVC laws: a voltage model, independent of the position at speed);
 * else bounded from the current's amplitude in any direction. */
FD_COLD static float trapped_flux(const protect_safe_view_t *v, float amp, bool from_run,
                                  bool angle_known) {
  if (from_run && v->ran && angle_known) {
    const dq_t l = machine_flux(v->machine, v->i_dq);
    return sqrtf(l.d * l.d + l.q * l.q);
  }
  const float obs = v->law_flux;
  if (from_run && v->ran && v->law_has_flux && fd_isfinite(obs) && obs > 0.0f) {
    return obs;
  }
  return ring_max(v->machine, amp, false);
}

/* Starts the short unless the flux it would trap exceeds psi_max: then
 * all off. PROTECT_SAFE_SHORT when it starts, else 0. */
FD_COLD static uint32_t start_short(protect_safe_t *z, const protect_safe_view_t *v, bool from_run,
                                    bool angle_known) {
  const float *i = v->i;
  const ab_t a = frames_clarke((abc_t){i[0], i[1], i[2]});
  const float amp = sqrtf(a.alpha * a.alpha + a.beta * a.beta);
  const float psi = trapped_flux(v, amp, from_run, angle_known);
  if (!fd_isfinite(amp) || !(psi <= z->psi_max)) {
    return 0u;
  }
  z->asc = true;
  z->n = 0u;
  z->n_low = 0u;
  z->w_i = 0.0f;
  z->i_prev[0] = a.alpha;
  z->i_prev[1] = a.beta;
  return PROTECT_SAFE_SHORT;
}

FD_COLD static uint32_t end_short(protect_safe_t *z) {
  z->asc = false;
  z->n_high = 0u;
  return PROTECT_SAFE_DISABLE;
}

/* The rotation rate of the current vector, low-pass filtered; 0 while
 * the vector is too small to have a direction. */
FD_COLD static void current_speed(protect_safe_t *z, const protect_safe_view_t *v) {
  const float *i = v->i;
  const ab_t a = frames_clarke((abc_t){i[0], i[1], i[2]});
  const float floor2 = I_FLOOR * I_FLOOR * v->i_max * v->i_max;
  const float m0 = z->i_prev[0] * z->i_prev[0] + z->i_prev[1] * z->i_prev[1];
  const float m1 = a.alpha * a.alpha + a.beta * a.beta;
  float w = 0.0f;
  if (m0 > floor2 && m1 > floor2) {
    const float cr = z->i_prev[0] * a.beta - z->i_prev[1] * a.alpha;
    const float dt = z->i_prev[0] * a.alpha + z->i_prev[1] * a.beta;
    w = fd_atan2f(cr, dt) / v->ts;
  }
  if (fd_isfinite(w)) {
    z->w_i += fd_minf(1.0f, W_I_BW * v->ts) * (w - z->w_i);
  }
  z->i_prev[0] = a.alpha;
  z->i_prev[1] = a.beta;
}

FD_COLD void protect_safe_leave_gates(protect_safe_t *z) {
  z->decide = true;
}

FD_COLD uint32_t protect_safe_step(protect_safe_t *z, const protect_safe_view_t *v) {
  const bool finite_v = fd_isfinite(v->v_dc);
  const bool over_v = finite_v && v->v_dc > SAFE_V_RATIO * v->v_dc_max;
  /* back-EMF peak per rad/s against the link: the speed where the diodes rectify */
  const float k_emf = SAFE_SQRT3 * z->psi_pm;
  const float v_entry = v->asc_speed * (finite_v ? fd_maxf(v->v_dc, 0.0f) : 0.0f);
  if (!asc_allowed(z, v)) {
    z->decide = false;
    if (z->asc || v->state == DRIVE_STATE_FAULT) {
      return end_short(z);
    }
    return 0u;
  }
  uint32_t act = 0u;
  if (z->decide) {
    z->decide = false;
    const float w = known_speed(v, true);
    if (over_v || w < 0.0f || k_emf * w > v_entry) {
      act |= start_short(z, v, true, w >= 0.0f);
    }
  }
  if (!z->asc) {
    if (v->state == DRIVE_STATE_FAULT) {
      act |= PROTECT_SAFE_DISABLE; /* held off, whatever wrote the timer */
    }
    if (v->state == DRIVE_STATE_OFFSET_CAL) {
      return act; /* entered with the short off; the gates stay off */
    }
    const float w = known_speed(v, false);
    z->n_high = (w >= 0.0f && k_emf * w > v_entry) ? z->n_high + 1u : 0u;
    if (over_v || z->n_high >= ENTRY_N) {
      act |= start_short(z, v, false, false);
    }
    return act;
  }
  current_speed(z, v);
  z->n++;
  const float wk = known_speed(v, false);
  const float w = wk >= 0.0f ? wk : fabsf(z->w_i);
  const bool low = finite_v && !over_v && k_emf * w < EXIT_RATIO * v_entry;
  z->n_low = low ? z->n_low + 1u : 0u;
  if ((float)z->n * v->ts >= v->asc_hold && z->n_low >= EXIT_N) {
    return end_short(z); /* (a short started in this step cannot end in it: EXIT_N) */
  }
  return act |
         PROTECT_SAFE_SHORT; /* held, as the gates-off state is (the break may have ended it) */
}

/*
 * proc_swing.c - the free rotor's swing about a DC current vector, seen in
 * the voltage across the current (proc.h; the rs identification, issue 25
 * a; docs/commissioning.md, "The free rotor's swing").
 *
 * A DC current i along a fixed axis x holds a PM rotor's d axis like a
 * spring: it swings about the axis at w_n = p sqrt(1.5 lambda_eff i / J)
 * (electrical; lambda_eff = lambda_m + (L_d - L_q) i), with nothing but
 * friction to damp it (the current loop holds the current). Its back-EMF
 * enters the voltage along the current: with delta the rotor's angle from
 * x, the flux along x is psi_x = L(delta) i + lambda_m cos(delta), and
 *   v_x = R i + v_err + d psi_x / dt                                    (1)
 * a total derivative: its mean over a window is the change of psi_x over
 * the window, which is zero when the window begins and ends at the swing's
 * turning points (delta = +-A, psi_x even in delta; the amplitude A held
 * over the window: friction takes little of it in one swing).
 *
 * The turning points: across the current (y) the loop holds i_y = 0, so
 *   v_y = lambda_eff cos(delta) omega_e                                 (2)
 * (along the phase axes 0 and pi the inverter's error lies along x) and
 * the turning points are the sign changes of v_y (omega_e = 0). v_y is
 * filtered over PROC_SWING_TAU against the current's noise in the loop's
 * voltage. A rotor at rest changes sign on noise alone: any window is
 * then right. No parameter of the machine enters.
 *
 * The swing damped (proc_swing_damping): across the current the loop
 * follows i_y = -v_y / R_app, R_app = v_x / i_x the apparent resistance
 * along the current (>= R_s: it holds the inverter's error), so that the y
 * axis looks like a resistor R_app across the winding: the swing's
 * back-EMF v_y drives a current whose torque always opposes the rotor's
 * motion (the power it takes, -1.5 v_y^2 / R_app, is never positive,
 * whatever the machine's saliency and magnet). With i_y held at 0, as a
 * current loop does, a frictionless rotor swings for ever.
 */
#include <math.h>

#include "math/fd_math.h"
#include "proc.h"

#define PROC_SWING_TAU   2e-3f    /* the filter of v_y [s] */
#define PROC_SWING_TAU_X 6.25e-3f /* the filter of v_x [s] */

FD_COLD void proc_swing_reset(proc_swing_t *w) {
  w->v = 0.0f;
  w->v_x = 0.0f;
  w->i_y = 0.0f;
  w->sign = 0;
  w->turned = false;
}

FD_COLD void proc_swing_step(proc_swing_t *w, float v_x, float v_y, float ts) {
  const float a = ts < PROC_SWING_TAU ? ts / PROC_SWING_TAU : 1.0f;
  w->v += a * (v_y - w->v);
  const float ax = ts < PROC_SWING_TAU_X ? ts / PROC_SWING_TAU_X : 1.0f;
  w->v_x += ax * (v_x - w->v_x);
  if (!fd_isfinite(w->v_x)) {
    w->v_x = 0.0f;
  }
  if (!fd_isfinite(w->v)) { /* a non-finite sample */
    w->v = 0.0f;
  }
  const int8_t s = w->v > 0.0f ? (int8_t)1 : (int8_t)-1;
  w->turned = w->sign != 0 && s != w->sign;
  w->sign = s;
}

/* The damping current across the current for this period (the header's
 * comment), i_x the current along it: -v_y / R_app within +-bound,
 * slew-limited; `on` false: back to 0 at the same rate. */
FD_COLD float proc_swing_damping(proc_swing_t *w, float i_x, float bound, float slew, bool on) {
  const float g = fabsf(i_x) / fmaxf(fabsf(w->v_x), 1e-3f);
  const float target = on ? fd_clampf(-g * w->v, -bound, bound) : 0.0f;
  w->i_y += fd_clampf(target - w->i_y, -slew, slew);
  return w->i_y;
}

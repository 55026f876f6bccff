/*
 * protect/drive_pos_check.c - position plausibility (issue 13 item 2,
 * docs/faults.md): the voltage model of the machine against the voltage
 * the drive applied, in the frame of the position source.
 *
 * In the stator frame the machine needs
 *     v_ab = R i_ab + d Psi_ab / dt,   Psi_ab = e^{j theta_e} psi(i_dq)
 * with psi(i) the drive's own machine model (linear or flux map) and
 * theta_e the source's angle. Over a window of n periods (the periods
 * between two checks) this is, integrated,
 *     Ts sum v_ab = R int i_ab dt + Psi_ab(end) - Psi_ab(start)
 * and the residual is its mean voltage
 *     r = (Ts sum v_ab - (Psi_ab(end) - Psi_ab(start))) / (n Ts)
 *         - R (i_ab(start) + i_ab(end)) / 2
 * (the current's integral by the trapezoid). Both sides cover the same
 * window, so the current loop's transients (L di/dt, a few periods long:
 * a new torque reference every slow period) cancel exactly: the voltage
 * of one period set against the flux's mean change over the window (the
 * check before issue 24 point 8) left them in the residual, and on a
 * reluctance machine near zero torque (the incremental inductance at its
 * unsaturated highest, the MTPA current ~ sqrt(T) swinging with the speed
 * loop's ripple, the flux a law reverses at the end of a speed ramp) they
 * took the residual over its tolerance for 7 checks of the 8 that trip
 * (sil/test_syr_foc, speed_step_and_rated_load).
 *
 * A source's angle wrong by delta turns the model's flux by delta against
 * the machine's: |r| = |e^{j delta} - 1| |Delta Psi_ab| / (n Ts) =
 * 2 sin(delta / 2) w |psi| sinc(phi / 2) (phi = w n Ts, the window's turn;
 * 2 w |psi| sin(delta / 2) of the derivative form times sinc), the
 * back-EMF itself for an encoder frozen on a turning rotor. Healthy, r
 * holds the model's errors (R, L, magnet: tens of per cent of each term)
 * and the inverter's (dead time: a few per cent of v_dc, and the
 * current's noise over the window: L sigma_i sqrt(2) / (n Ts), 1 V on
 * syr_1k1). So the tolerance is each term's own size:
 *     tol = pos_emf_tol (|Delta Psi_pm| + |Delta Psi_i| ) / (n Ts)
 *           + pos_emf_tol R (|i(start)| + |i(end)|) / 2 + POS_V_FLOOR v_dc
 * with Psi_pm the magnet's part (the flux at zero current, turned) and
 * Psi_i the currents' (in flux weakening they cancel, their errors do
 * not). At a constant operating point |Delta Psi_x| / (n Ts) =
 * w |psi_x| sinc(phi / 2): the old w (|psi(0)| + |psi(i) - psi(0)|) at a
 * small turn, so a fault's residual and the tolerance scale alike and the
 * trip ratio 2 sin(delta / 2) / pos_emf_tol is the derivative form's;
 * in a transient |Delta Psi_i| holds the flux the loop built, so a model
 * error on L is tolerated in proportion, not as a fixed voltage.
 *
 * Above a half turn per window (|phi| > POS_TURN_MAX: sinc < 0.64, the
 * window's mean vanishes at a full turn) the check falls back to the
 * derivative form in the source's rotor frame: the last period's voltage
 *     r = v_dq - R i_dq - d psi/dt - w_e J psi(i_dq),  J psi = (-psi_q, psi_d)
 * with d psi / dt the mean since the last check, tolerance
 * pos_emf_tol (w_e (|psi(0)| + |psi(i) - psi(0)|) + R |i|) + POS_V_FLOOR v_dc
 * (there the back-EMF dwarfs the loop's transients).
 *
 * Trips when |r| > tol for POS_TRIP_S worth of checks more than not (a
 * leaky count: transients and single bad samples do not trip), one check
 * every second slow period (its row's divider in the drive's schedule
 * table, drive.c: the ISR cost). Only in run, and only for sources that
 * measure with the gates off (the encoder): the star-point sources are
 * themselves voltage measurements, checked by their own prediction
 * (pos_err_max). The first check of a run starts the window (no test);
 * a window is the `periods` ISRs between two checks (after a live change
 * of slow_div the first one is not: one count at most, of the 8 that
 * trip).
 *
 * The window: protect_pos_integrate sums the applied voltage every ISR
 * (the drive's publication, after the law; this row runs before it, so at
 * a check the sum ends with the last period's voltage); the voltage computed at sample k
 * acts from t_k + t_out - Ts/2 to t_k + t_out + Ts/2 (drive_t_out), so
 * the window's end is t_out - Ts/2 after the last period's sample (the
 * model's flux and current turned there by w_e (t_out - Ts/2)) and the
 * last summed voltage, which acts after it, opens the next window. One
 * sine/cosine and one model evaluation per check (the derivative form:
 * the sine at the last voltage's centre, t_out after its sample); the form
 * is chosen on the window's turn at the check's speed, and a change of
 * form starts a new window (no test).
 */
#include "protect/drive_pos_check.h"

#include <math.h>

#include "drive_enums.h"
#include "math/fast_trig.h"
#include "math/fd_math.h"

#define POS_TRIP_S   0.016f      /* leaky count over the checks: this time's worth trips */
#define POS_V_FLOOR  0.05f       /* voltage floor, times v_dc: inverter errors */
#define POS_TURN_MAX 3.14159265f /* the integral form up to this turn per window [rad] */

static float ab_abs(ab_t x) {
  return sqrtf(x.alpha * x.alpha + x.beta * x.beta);
}

void protect_pos_configure(protect_pos_t *p, const protect_pos_cfg_t *c) {
  p->cfg = *c;
  p->t_win = (float)c->periods * c->ts;
  p->inv_t = p->t_win > 0.0f ? 1.0f / p->t_win : 0.0f;
  p->tau_int = c->t_out - 0.5f * c->ts;
  /* the count n that trips: the least n with n t_win >= POS_TRIP_S */
  p->n_trip = p->t_win > 0.0f ? (int32_t)ceilf(POS_TRIP_S / p->t_win) : 1;
  if (p->n_trip < 1) {
    p->n_trip = 1;
  }
}

uint32_t protect_pos_step(protect_pos_t *p, const protect_pos_view_t *v) {
  if (!v->active) {
    p->n = 0;
    p->psi_ok = false;
    return 0u;
  }
  if (!v->due) {
    return 0u;
  }
  const protect_pos_cfg_t *c = &p->cfg;
  const float w = v->omega_e;
  const float ts = c->ts;
  const dq_t i = v->i_dq;
  /* the form: the integral one up to POS_TURN_MAX per window */
  const bool integral = fabsf(w) * p->t_win <= POS_TURN_MAX;
  /* the angle: the window's end (integral form: the model's flux and
   * current turned there) or the last voltage's centre (derivative form) */
  const float tau = integral ? p->tau_int : c->t_out;
  sincos_t sc;
  /* mut: pos_check_emf_sign */
  fd_sincosf(v->theta_e + w * tau, &sc.s, &sc.c);
  const dq_t psi = machine_flux(c->machine, i);
  const float i_abs = sqrtf(i.d * i.d + i.q * i.q);
  /* the window: the sums before the last voltage (it opens the next), on
   * a start taken in the same form; its changes are read before the end
   * becomes the next window's start */
  const bool window = p->psi_ok && p->ab_ok == integral;
  const float inv_t = p->inv_t;
  const dq_t dpsi_dq = {psi.d - p->psi.d, psi.q - p->psi.q};
  p->psi = psi;
  p->psi_ok = true;
  p->ab_ok = integral;
  float rd, rq, emf, ir;
  if (integral) {
    /* the flux's two parts, the magnet's and the currents', turned */
    const ab_t pm_ab = frames_park_inv(c->psi0, sc);
    const ab_t pi_ab = frames_park_inv((dq_t){psi.d - c->psi0.d, psi.q - c->psi0.q}, sc);
    const ab_t i_ab = frames_park_inv(i, sc);
    const ab_t sum = {p->v_sum.alpha - v->v_ab.alpha, p->v_sum.beta - v->v_ab.beta};
    const ab_t dpm = {pm_ab.alpha - p->psi_pm_ab.alpha, pm_ab.beta - p->psi_pm_ab.beta};
    const ab_t dpi = {pi_ab.alpha - p->psi_i_ab.alpha, pi_ab.beta - p->psi_i_ab.beta};
    const ab_t i2 = {i_ab.alpha + p->i_ab.alpha, i_ab.beta + p->i_ab.beta};
    const float i_abs2 = i_abs + p->i_abs;
    p->v_sum = v->v_ab;
    p->psi_pm_ab = pm_ab;
    p->psi_i_ab = pi_ab;
    p->i_ab = i_ab;
    p->i_abs = i_abs;
    if (!window) {
      return 0u;
    }
    /* stator frame: (rd, rq) = (alpha, beta) */
    rd = (sum.alpha * ts - (dpm.alpha + dpi.alpha)) * inv_t - 0.5f * c->rs * i2.alpha;
    rq = (sum.beta * ts - (dpm.beta + dpi.beta)) * inv_t - 0.5f * c->rs * i2.beta;
    emf = (ab_abs(dpm) + ab_abs(dpi)) * inv_t;
    ir = 0.5f * c->rs * i_abs2;
  } else {
    /* the derivative form, the source's rotor frame: the last voltage
     * around t_out after the sample */
    p->v_sum = v->v_ab;
    if (!window) {
      return 0u;
    }
    const dq_t u = frames_park(v->v_ab, sc);
    const dq_t dpsi = {dpsi_dq.d * inv_t, dpsi_dq.q * inv_t};
    rd = u.d - (c->rs * i.d + dpsi.d - w * psi.q);
    rq = u.q - (c->rs * i.q + dpsi.q + w * psi.d);
    const float pd = psi.d - c->psi0.d, pq = psi.q - c->psi0.q;
    emf = fabsf(w) * (c->psi_pm + sqrtf(pd * pd + pq * pq));
    ir = c->rs * i_abs;
  }
  const float tol = c->emf_tol * (emf + ir) + POS_V_FLOOR * v->v_dc;
  p->res = sqrtf(rd * rd + rq * rq) / fd_maxf(tol, 1e-6f);
  if (!(rd * rd + rq * rq <= tol * tol)) { /* NaN counts as over */
    if (++p->n >= p->n_trip) {
      /* mut: pos_check_never */
      return DRIVE_FAULT_POSITION;
    }
  } else if (p->n > 0) {
    p->n--;
  }
  return 0u;
}

/*
 * protect/drive_pos_check.c - position plausibility (issue 13 item 2,
 * docs/faults.md): the voltage model of the machine against the voltage
 * the drive applied, in the frame of the position source.
 *
 * In the rotor frame the source reports (angle theta_e, speed w_e), the
 * machine needs
 *     v_dq = R i_dq + d psi/dt + w_e J psi(i_dq)   (J psi = (-psi_q, psi_d))
 * with psi(i) the drive's own machine model (linear or flux map). If the
 * source's angle is wrong by delta (a slipped, reversed or frozen encoder,
 * missed counts, too few counts) the machine's real back-EMF, seen in that
 * frame, is turned by -delta and scaled by the real speed: the residual
 *     r = v_dq - R i_dq - w_e J psi(i_dq)
 * is about 2 w psi sin(delta / 2) (twice the back-EMF for a half-turn slip,
 * the back-EMF itself for an encoder frozen on a turning rotor). Healthy,
 * r holds the model's errors (R, L, magnet: tens of per cent of the terms)
 * and the inverter's (dead time: a few per cent of v_dc); d psi / dt is
 * the model flux's change since the previous check, so a step's L di/dt
 * shows for a check or two only.
 *
 * Trips when |r| > pos_emf_tol (w_e (|psi(0)| + |psi(i) - psi(0)|) + R |i|)
 * + POS_V_FLOOR v_dc for POS_TRIP_S worth of checks more than not (a leaky
 * count: transients and single bad samples do not trip), one check every
 * second slow period (its row's divider in the drive's schedule table,
 * drive.c: the ISR cost). Only in run, and only for sources that measure
 * with the gates off (the encoder): the star-point sources are themselves
 * voltage measurements, checked by their own prediction (pos_err_max). The
 * applied voltage (telemetry of the last period) acts over the period after
 * its sample, so it is turned by w_e t_out (drive_t_out) ahead of the
 * sample's angle. One sine/cosine and one model evaluation per check.
 */
#include "protect/drive_pos_check.h"

#include <math.h>

#include "drive_enums.h"
#include "math/fast_trig.h"
#include "math/fd_math.h"

#define POS_TRIP_S  0.016f /* leaky count over the checks: this time's worth trips */
#define POS_V_FLOOR 0.05f  /* voltage floor, times v_dc: inverter errors */

uint32_t protect_pos_step(protect_pos_t *p, const protect_pos_view_t *v) {
  if (!v->active) {
    p->n = 0;
    p->psi_ok = false;
    return 0u;
  }
  if (!v->due) {
    return 0u;
  }
  const float w = v->omega_e;
  const dq_t i = v->i_dq;
  sincos_t sc;
  fd_sincosf(v->theta_e + w * v->t_out, &sc.s, &sc.c);
  const dq_t u = frames_park(v->v_ab, sc);
  const dq_t psi = machine_flux(v->machine, i);
  /* d psi / dt from the previous check: the flux a law builds over a few
   * ms (a reluctance machine at its voltage limit) is not a fault */
  const float inv_dt = 1.0f / ((float)v->periods * v->ts);
  const dq_t dpsi = p->psi_ok ? (dq_t){(psi.d - p->psi.d) * inv_dt, (psi.q - p->psi.q) * inv_dt}
                              : (dq_t){0.0f, 0.0f};
  p->psi = psi;
  p->psi_ok = true;
  const float rd = u.d - (v->rs * i.d + dpsi.d - w * psi.q);
  /* mut: pos_check_emf_sign */
  const float rq = u.q - (v->rs * i.q + dpsi.q + w * psi.d);
  /* the flux's two parts, the magnet's and the currents', each on its own
   * scale (in flux weakening they cancel, their errors do not) */
  const float pd = psi.d - v->psi0.d, pq = psi.q - v->psi0.q;
  const float emf = fabsf(w) * (v->psi_pm + sqrtf(pd * pd + pq * pq));
  const float ir = v->rs * sqrtf(i.d * i.d + i.q * i.q);
  const float tol = v->emf_tol * (emf + ir) + POS_V_FLOOR * v->v_dc;
  p->res = sqrtf(rd * rd + rq * rq) / fd_maxf(tol, 1e-6f);
  if (!(rd * rd + rq * rq <= tol * tol)) { /* NaN counts as over */
    if ((float)++p->n * (float)v->periods * v->ts >= POS_TRIP_S) {
      /* mut: pos_check_never */
      return DRIVE_FAULT_POSITION;
    }
  } else if (p->n > 0) {
    p->n--;
  }
  return 0u;
}

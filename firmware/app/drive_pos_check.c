/*
 * drive_pos_check.c - position plausibility (issue 13 item 2,
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
 * POS_EVERY slow periods. Only in run, and only for sources that measure
 * with the gates off (the encoder): the star-point sources are themselves
 * voltage measurements, checked by their own prediction (pos_err_max). The
 * applied voltage (telemetry of the last period) acts over the period after
 * its sample, so it is turned by w_e t_out (drive_t_out) ahead of the
 * sample's angle. One sine/cosine and one model evaluation per check.
 */
#include "drive_pos_check.h"

#include <math.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"

#define POS_EVERY   2      /* checked every POS_EVERY slow periods (ISR cost) */
#define POS_TRIP_S  0.016f /* leaky count over the checks: this time's worth trips */
#define POS_V_FLOOR 0.05f  /* voltage floor, times v_dc: inverter errors */

uint32_t drive_pos_check(drive_t *drv) {
  const drive_config_t *c = &drv->cfg;
  const drive_telemetry_t *tm = &drv->tm;
  if (c->pos_emf_tol <= 0.0f || drv->state != DRIVE_STATE_RUN || tm->state != DRIVE_STATE_RUN ||
      (drv->pos_src->caps & POS_CAP_GATED) != 0u || !fd_isfinite(tm->v_dc)) {
    drv->pos_chk_n = 0;
    drv->pos_psi_ok = false;
    return 0u;
  }
  if (((drv->isr_count - 1u) / c->slow_div) % POS_EVERY != 0u) {
    return 0u;
  }
  const float w = drv->pos.out.omega;
  const dq_t i = {tm->i_dq[0], tm->i_dq[1]};
  sincos_t sc;
  fd_sincosf(tm->theta_e + w * (1.5f * c->ts - drv->caps->t_i), &sc.s, &sc.c);
  const dq_t v = frames_park((ab_t){tm->v_ab_applied[0], tm->v_ab_applied[1]}, sc);
  const dq_t psi = machine_flux(&drv->machine, i);
  /* d psi / dt from the previous check: the flux a law builds over a few
   * ms (a reluctance machine at its voltage limit) is not a fault */
  const float inv_dt = 1.0f / ((float)(POS_EVERY * c->slow_div) * c->ts);
  const dq_t dpsi =
      drv->pos_psi_ok ? (dq_t){(psi.d - drv->pos_psi.d) * inv_dt, (psi.q - drv->pos_psi.q) * inv_dt}
                      : (dq_t){0.0f, 0.0f};
  drv->pos_psi = psi;
  drv->pos_psi_ok = true;
  const float rd = v.d - (c->rs * i.d + dpsi.d - w * psi.q);
  const float rq = v.q - (c->rs * i.q + dpsi.q + w * psi.d);
  /* the flux's two parts, the magnet's and the currents', each on its own
   * scale (in flux weakening they cancel, their errors do not) */
  const float pd = psi.d - drv->psi0.d, pq = psi.q - drv->psi0.q;
  const float emf = fabsf(w) * (drv->psi_pm + sqrtf(pd * pd + pq * pq));
  const float ir = c->rs * sqrtf(i.d * i.d + i.q * i.q);
  const float tol = c->pos_emf_tol * (emf + ir) + POS_V_FLOOR * tm->v_dc;
  drv->pos_emf_res = sqrtf(rd * rd + rq * rq) / fd_maxf(tol, 1e-6f);
  if (!(rd * rd + rq * rq <= tol * tol)) { /* NaN counts as over */
    if ((float)++drv->pos_chk_n * (float)(POS_EVERY * c->slow_div) * c->ts >= POS_TRIP_S) {
      return DRIVE_FAULT_POSITION;
    }
  } else if (drv->pos_chk_n > 0) {
    drv->pos_chk_n--;
  }
  return 0u;
}

/*
 * current_ctrl.c - dq current regulator (FOC baseline).
 *
 * Per axis: PI with kp = wc*L, ki = wc*Rs, so the PI zero cancels the
 * electrical pole Rs/L and the loop is wc/s (closed loop wc/(s+wc), ignoring
 * the computation and PWM delay). Cross-coupling and back-EMF are fed
 * forward from the measured currents. Voltage limit: circle of radius v_max,
 * d axis first (it sets the flux), q gets what is left; the PI integrators
 * are clamped against these limits (see pi_ctrl.c), so they never wind up.
 *
 * Saturated machine (flux map): the incremental self-inductances fall with
 * the current (to half and less on a SyR machine at rated current), so a
 * constant kp = wc L(0) would give a loop up to twice as fast as designed
 * at load. The proportional gains follow the map's incremental inductance
 * at the reference current, kp = wc l_dd(i*), wc l_qq(i*) (Varatharajan
 * (25)), so the loop stays wc/s at every operating point; ki = wc Rs is
 * kept (the PI zero follows Rs/l). The cross-saturation l_dq is not
 * decoupled (its coupling is a disturbance the integrators remove). The
 * feed-forward uses the map's flux at the measured current.
 */
#include "control/current_ctrl.h"

#include <math.h>

#include "math/fd_math.h"

FD_COLD void current_ctrl_init(current_ctrl_t *cc, const current_ctrl_cfg_t *cfg) {
  cc->cfg = *cfg;
  const float wc = cfg->bandwidth;
  const machine_t *m = cfg->machine;
  /* gains from the incremental inductances at zero current (constant for
   * the linear machine) */
  const machine_ldq_t l = machine_inductance(m, (dq_t){0.0f, 0.0f});
  pi_ctrl_init(&cc->pi_d, wc * l.dd, wc * m->rs, cfg->ts, -INFINITY, INFINITY);
  pi_ctrl_init(&cc->pi_q, wc * l.qq, wc * m->rs, cfg->ts, -INFINITY, INFINITY);
  cc->limited = 0;
}

void current_ctrl_reset(current_ctrl_t *cc) {
  pi_ctrl_reset(&cc->pi_d, 0.0f);
  pi_ctrl_reset(&cc->pi_q, 0.0f);
  cc->limited = 0;
}

dq_t current_ctrl_update(current_ctrl_t *cc, dq_t i_ref, dq_t i, float we, float v_max) {
  return current_ctrl_step(cc, i_ref, i, machine_flux(cc->cfg.machine, i), we, v_max);
}

dq_t current_ctrl_step(current_ctrl_t *cc, dq_t i_ref, dq_t i, dq_t flux_i, float we, float v_max) {
  dq_t v = {0.0f, 0.0f};
  if (!(v_max > 0.0f) || !fd_isfinite(v_max)) {
    cc->limited = 1; /* no voltage available: output zero, keep integrators */
    return v;
  }
  if (!fd_isfinite(we)) {
    we = 0.0f;
  }
  /* the errors and the decoupling feed-forward first (what the map's call
   * below would otherwise keep on the stack): v = Rs i + L di/dt + we J lambda(i) */
  const float e_d = i_ref.d - i.d;
  const float e_q = i_ref.q - i.q;
  const float ff_d = -we * flux_i.q;
  const float ff_q = we * flux_i.d;
  const machine_t *m = cc->cfg.machine;
  /* mut: foc_map_constant_gains */
  if (m->kind == MACHINE_FLUX_MAP) {
    const machine_ldq_t l = machine_inductance(m, i_ref);
    cc->pi_d.kp = cc->cfg.bandwidth * l.dd;
    /* mut: foc_map_q_gain */
    cc->pi_q.kp = cc->cfg.bandwidth * l.qq;
  }

  /* symmetric limits, v_max finite and > 0 (above) and vq_max finite and
   * >= 0 (a NaN room gives 0): the PI's limit checks cannot fire, so the
   * limits are stored and the step runs inline (pi_ctrl_update_sym) */
  v.d = pi_ctrl_update_sym(&cc->pi_d, e_d, ff_d, v_max);
  const float vq_room_sq = v_max * v_max - v.d * v.d;
  const float vq_max = (vq_room_sq > 0.0f) ? sqrtf(vq_room_sq) : 0.0f;
  v.q = pi_ctrl_update_sym(&cc->pi_q, e_q, ff_q, vq_max);

  cc->limited = (fabsf(v.d) >= v_max || fabsf(v.q) >= vq_max) ? 1 : 0;
  return v;
}

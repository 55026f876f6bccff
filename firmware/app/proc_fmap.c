/*
 * proc_fmap.c - flux maps at standstill as a procedure (proc.h, issue 25
 * procedure c): psi_d(i_d, i_q), psi_q(i_d, i_q) of a saturated machine
 * over a grid of currents, cross-saturation included, rotor free.
 *
 * The method (Pescetto and Pellegrino, "Standstill determination of PM
 * synchronous motor magnetic model", IEEE TIA 2018, and Hinkkanen et al.,
 * "Sensorless self-commissioning of synchronous reluctance motors at
 * standstill without rotor locking", IEEE TIA 2017): a DC bias on one axis
 * (i_d) and a bipolar current on the other (i_q = +I, then -I), so that the
 * torque 3/2 p (psi_d i_q - psi_q i_d) changes sign with i_q (psi_d is even
 * in i_q, psi_q odd: the symmetry of every machine of docs/flux-maps.md)
 * and averages to zero: the rotor, free, only rocks. The flux is the
 * integral of the stator voltage equation at standstill,
 *
 *   psi_dq(t) - psi_dq(0) = int_0^t (v_dq - R_s i_dq - j omega psi_dq) dt  (1)
 *
 * (Pescetto 2018 eq. (1)-(2); the omega term, the frame following the
 * rocking rotor, from the position source's turn each period), over each
 * half cycle: from zero
 * current to the point (i_d, s I) (s = +1, -1), dwell there, back to zero,
 * dwell. The flux change over the whole half cycle is zero (the same
 * current at both ends: the loop closes), so what (1) leaves at the end is
 * the integral of the error of the voltage (the inverter's error, R_s's
 * error): taking it along the current's direction, r = e_2 / Q_2 (Q = int
 * i / |i| dt per axis, a smooth sign: a dead time's or a device threshold's
 * error follows the current's sign, not its size), the change to the point
 * is
 *
 *   dpsi = psi(t_1) - r Q(t_1)                                      (2)
 *
 * (the loop-closure correction: Pescetto 2018 sec. III, where the drift of
 * the integrated flux over each cycle is removed; not on an axis the
 * current hardly points along, Q_2 below a tenth of a dwell). The current
 * loop's integrators are cleared as the current goes back to zero, so that
 * no tail of current (and of the inverter's error on it) is left. With psi_q(i_d, 0) = 0 and
 * psi_d(0, 0) = lambda_m (the PM flux: procedure f's result, the parameter lambda_m; 0 for SyR,
 * which standstill cannot see: the flux at zero current),
 *
 *   psi_d(i_d, I) = lambda_m + (dpsi_d(+) + dpsi_d(-)) / 2
 *   psi_q(i_d, I) = (dpsi_q(+) - dpsi_q(-)) / 2                     (3)
 *
 * averaged over FMAP_CYCLES cycles; the flux and the current at the point
 * are averaged over the last quarter of the dwell (FMAP_AVG).
 *
 * The rotor's d axis: the position source's angle (an encoder aligned by
 * the alignment or procedure e; the frame follows the source while the
 * rotor rocks). R_s: the parameter set's (procedure a's result).
 *
 * The grid: i_d = -I_g .. I_g in id_fmap_nd points, i_q = 0 .. I_g in
 * id_fmap_nq points, I_g = id_fmap_current clamped to i_max; points with
 * |i| > I_g are skipped (the current never exceeds I_g). Each point is one
 * phase: phase = 1 + k nd + j (i_q index k, i_d index j), the point in
 * progress; the results are the last point done (written a period before
 * the phase moves on, kept until the next is done: the results the
 * previous phase left, whenever they are read); the host
 * assembles the map (tools/src/fluxdrive/commission_map.py).
 *
 * Bounded: the current by I_g (the current loop's reference; a measured
 * current above FMAP_TRIP I_g + 5 % of i_max fails with the overcurrent
 * fault), the voltage by v_max, the time by the grid (nd nq points of
 * 4 FMAP_CYCLES dwells each). Results (publish): [0] psi_d [Vs], [1] psi_q
 * [Vs], [2] i_d, [3] i_q [A] (the measured point), [4] i_d, [5] i_q the
 * reference [A], [6] the resistance correction r of (2) on q [Ohm], [7]
 * the phase of the point these are (1 + k nd + j; 0: none done yet), so
 * that a reader that samples the telemetry slower than the ISR (the main
 * loop, the host over CAN) pairs them right: each point's results stay
 * for the whole next point.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"

#define FMAP_CYCLES 2u    /* bipolar cycles per point */
#define FMAP_AVG    4u    /* the average over the last 1/FMAP_AVG of a dwell */
#define FMAP_TRIP   1.25f /* the current bound's margin on I_g */
#define FMAP_POINTS 254u  /* at most: the phase is a uint8 (0: none done yet) */
#define FMAP_BAND   0.05f /* the smooth sign's band of the error's weight, x i_max */
#define FMAP_SHOW   64u   /* periods a point's results show before the next phase */

enum { SEG_POINT = 0, SEG_ZERO = 1, SEG_SHOW = 2 };

FD_COLD static float fmap_range(const drive_config_t *c) {
  return fminf(c->id_fmap_current, c->i_max);
}

FD_COLD static uint16_t fmap_dwell(const drive_config_t *c) {
  const float n = c->id_fmap_dwell / c->ts;
  return (uint16_t)fd_clampf(n, 0.0f, 60000.0f);
}

/* the reference of grid point p (k nd + j) */
FD_COLD static dq_t fmap_ref(const drive_config_t *c, uint16_t p) {
  const float ig = fmap_range(c);
  const unsigned nd = c->id_fmap_nd, nq = c->id_fmap_nq;
  const unsigned j = p % nd, k = p / nd;
  return (dq_t){ig * (2.0f * (float)j / (float)(nd - 1u) - 1.0f), ig * (float)k / (float)(nq - 1u)};
}

/* the first grid point from p on within the circle |i| <= I_g; nd nq if none */
FD_COLD static uint16_t fmap_next(const drive_config_t *c, uint16_t p) {
  const float ig = fmap_range(c);
  const unsigned n = (unsigned)c->id_fmap_nd * c->id_fmap_nq;
  /* mut: fmap_circle */
  for (; p < n; ++p) {
    const dq_t r = fmap_ref(c, p);
    if (sqrtf(r.d * r.d + r.q * r.q) <= ig * 1.0001f) {
      break;
    }
  }
  return p;
}

FD_COLD static const char *fmap_check(const proc_setup_t *su, const char **field) {
  const drive_config_t *c = su->cfg;
  if (c->id_fmap_nd < 2u || c->id_fmap_nq < 2u ||
      (unsigned)c->id_fmap_nd * c->id_fmap_nq > FMAP_POINTS) {
    *field = "id_fmap_nd";
    return "the grid needs 2 .. 254 points (id_fmap_nd x id_fmap_nq)";
  }
  if (!(fmap_range(su->cfg) > 0.0f)) {
    *field = "id_fmap_current";
    return "no current to measure the maps with";
  }
  if (fmap_dwell(c) < 4u * FMAP_AVG) {
    *field = "id_fmap_dwell";
    return "a dwell of fewer than 16 periods";
  }
  return NULL;
}

FD_COLD static void fmap_init(proc_state_t *st, const proc_setup_t *su) {
  proc_fmap_t *f = &st->fmap;
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&f->cc, &ccfg);
  f->n = 0u;
  f->point = fmap_next(su->cfg, 0u);
  f->half = 0u;
  f->seg = SEG_POINT;
  f->m = 0u;
  f->theta = 0.0f;
  f->v_prev = f->i_prev = f->phi = f->q = (dq_t){0.0f, 0.0f};
  f->phi1 = f->q1 = f->i1 = f->phi2 = f->q2 = (dq_t){0.0f, 0.0f};
  for (int x = 0; x < 4; ++x) {
    f->acc[x] = 0.0f;
  }
  for (int x = 0; x < PROC_RESULTS; ++x) {
    f->res[x] = 0.0f;
  }
  f->phase = (uint8_t)(f->point + 1u);
}

/* the loop-closure correction (2) on one axis: the change to the point */
FD_COLD static float fmap_closed(float phi1, float q1, float phi2, float q2, float q_min,
                                 float *r) {
  /* an axis the current hardly points along (a zero bias) carries too
   * little of the error to find it: none */
  /* mut: fmap_closure */
  *r = fabsf(q2) > q_min ? phi2 / q2 : 0.0f;
  return phi1 - *r * q1;
}

/* the sign of i_q in half cycle h: + - - + + - - + ... (Gray code), so
 * that the second cycle turns the rotor back by what the first turned it
 * (+ then - leaves it displaced by the speed gained, - then + undoes it) */
FD_COLD static float fmap_sign(uint8_t h) {
  return ((h ^ (h >> 1u)) & 1u) == 0u ? 1.0f : -1.0f;
}

/* one half cycle done: its changes (2) into the point's sums (3) */
FD_COLD static void fmap_half(proc_fmap_t *f, const drive_config_t *c) {
  /* the periods averaged: the step's n_avg, a whole number */
  const unsigned n_avg = (unsigned)fmap_dwell(c) / FMAP_AVG;
  const float k = 1.0f / (float)n_avg;
  const float s = fmap_sign(f->half); /* i_q = s I */
  float r_d, r_q;
  /* the error's weight over a tenth of a dwell at the least */
  const float q_min = 0.1f * (float)fmap_dwell(c) * c->ts;
  const float dd = fmap_closed(f->phi1.d * k, f->q1.d * k, f->phi2.d * k, f->q2.d * k, q_min, &r_d);
  const float dq = fmap_closed(f->phi1.q * k, f->q1.q * k, f->phi2.q * k, f->q2.q * k, q_min, &r_q);
  f->acc[0] += dd;
  /* mut: fmap_q_sign */
  f->acc[1] += s * dq;
  f->acc[2] += f->i1.d * k;
  f->acc[3] += s * f->i1.q * k;
  f->res[6] = r_q;
}

FD_COLD static int fmap_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                             proc_out_t *out) {
  proc_fmap_t *f = &st->fmap;
  const drive_config_t *c = su->cfg;
  const uint16_t n_dw = fmap_dwell(c);
  const uint16_t n_avg = (uint16_t)(n_dw / FMAP_AVG);
  f->n++;
  float dth = 0.0f; /* the frame's turn this period [rad electrical] */
  if (in->pos->valid) {
    /* the d axis; the frame follows the rocking rotor */
    dth = frames_wrap_pi(in->pos->theta - f->theta);
    dth = f->n > 1u ? dth : 0.0f;
    f->theta = in->pos->theta;
  }
  const sincos_t sc = frames_sincos(f->theta);
  const dq_t i = frames_park(in->i_ab, sc);
  const float ig = fmap_range(c);
  if (sqrtf(i.d * i.d + i.q * i.q) > FMAP_TRIP * ig + 0.05f * c->i_max) {
    *out = (proc_out_t){{0.0f, 0.0f}, false, false, DRIVE_FAULT_OVERCURRENT};
    return PROC_FAILED;
  }
  /* (1): the voltage asked last period acted over it; the current's
   * trapezoid */
  const dq_t im = {0.5f * (i.d + f->i_prev.d), 0.5f * (i.q + f->i_prev.q)};
  f->i_prev = i;
  /* the rotor frame turning with the rocking rotor: d psi_dq / dt = v - R i
   * - j omega psi_dq (the dq voltage equation; omega dt = the frame's
   * turn), psi = (lambda_m, 0) + phi over the half */
  const float psd = c->lambda_m + f->phi.d, psq = f->phi.q;
  /* mut: fmap_frame_turn */
  f->phi.d += (f->v_prev.d - c->rs * im.d) * c->ts + dth * psq;
  f->phi.q += (f->v_prev.q - c->rs * im.q) * c->ts - dth * psd;
  /* the weight of the voltage error (2): the current's direction, i / |i|
   * (a smooth sign over FMAP_BAND i_max): a dead time's or a device's
   * threshold error follows the current's sign, not its size */
  const float ia = fmaxf(sqrtf(im.d * im.d + im.q * im.q), FMAP_BAND * c->i_max);
  f->q.d += im.d / ia * c->ts;
  f->q.q += im.q / ia * c->ts;
  if (f->seg == SEG_SHOW) {
    /* the point's results shown for FMAP_SHOW periods (a reader at the
     * main loop's rate sees them under the point's phase; the current held
     * at zero): on to the next */
    if (++f->m >= FMAP_SHOW) {
      f->point = fmap_next(c, (uint16_t)(f->point + 1u));
      if (f->point >= (unsigned)c->id_fmap_nd * c->id_fmap_nq) {
        *out = (proc_out_t){{0.0f, 0.0f}, false, false, 0u};
        return PROC_DONE;
      }
      f->phase = (uint8_t)(f->point + 1u);
      f->seg = SEG_POINT;
      f->m = 0u;
      f->half = 0u;
      f->phi = f->q = (dq_t){0.0f, 0.0f};
    }
  } else if (++f->m > n_dw - n_avg) {
    /* the last quarter of the dwell: the averages */
    if (f->seg == SEG_POINT) {
      f->phi1.d += f->phi.d, f->phi1.q += f->phi.q;
      f->q1.d += f->q.d, f->q1.q += f->q.q;
      f->i1.d += i.d, f->i1.q += i.q;
    } else {
      f->phi2.d += f->phi.d, f->phi2.q += f->phi.q;
      f->q2.d += f->q.d, f->q2.q += f->q.q;
    }
    if (f->m >= n_dw) {
      f->m = 0u;
      if (f->seg == SEG_POINT) {
        /* back to zero with the loop's integrators cleared: what they hold
         * (R i and the inverter's error at the point) would otherwise keep
         * a current's tail for L / R, and the inverter's error on it (a
         * dead time's: its sign, not its size) would spoil (2) */
        current_ctrl_reset(&f->cc);
        f->seg = SEG_ZERO;
      } else {
        fmap_half(f, c);
        f->phi = f->q = (dq_t){0.0f, 0.0f}; /* the next half from zero current */
        f->phi1 = f->q1 = f->i1 = f->phi2 = f->q2 = (dq_t){0.0f, 0.0f};
        f->seg = SEG_POINT;
        if (++f->half >= 2u * FMAP_CYCLES) {
          /* (3) */
          const float kh = 1.0f / (float)(2u * FMAP_CYCLES);
          const dq_t ref = fmap_ref(c, f->point);
          f->res[0] = c->lambda_m + f->acc[0] * kh;
          f->res[1] = f->acc[1] * kh;
          f->res[2] = f->acc[2] * kh;
          f->res[3] = f->acc[3] * kh;
          f->res[4] = ref.d;
          f->res[5] = ref.q;
          f->res[7] = (float)(f->point + 1u); /* whose results: its phase */
          for (int x = 0; x < 4; ++x) {
            f->acc[x] = 0.0f;
          }
          f->seg = SEG_SHOW;
          f->m = 0u;
        }
      }
    }
  }
  dq_t ref = {0.0f, 0.0f};
  if (f->seg == SEG_POINT) {
    ref = fmap_ref(c, f->point);
    ref.q *= fmap_sign(f->half);
  }
  const dq_t v = current_ctrl_update(&f->cc, ref, i, 0.0f, in->v_max);
  f->v_prev = v;
  const ab_t vab = frames_park_inv(v, sc);
  *out = (proc_out_t){vab, true, false, 0u};
  return PROC_RUNNING;
}

FD_COLD static void fmap_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_fmap_t *f = &st->fmap;
  /* the phase: the point in progress; the results: the last point done
   * (the previous phase's, shown until the next is done) */
  tm->phase = f->phase;
  tm->n = f->n;
  for (int x = 0; x < PROC_RESULTS; ++x) {
    tm->result[x] = f->res[x];
  }
}

const proc_row_t proc_fmap = {
    .name = "fmap",
    .id = PROC_FMAP,
    .state = DRIVE_STATE_IDENT,
    .caps = PROC_CAP_GATES | PROC_CAP_IDENT,
    .check = fmap_check,
    .wanted = NULL,
    .init = fmap_init,
    .step = fmap_step,
    .abort = NULL,
    .publish = fmap_publish,
};

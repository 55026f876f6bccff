/*
 * plant_inverter_avg.c - average-value two-level inverter, gates on.
 *
 * Over one PWM period the period-average leg voltage (w.r.t. the negative
 * rail) is d_eff,x * v_dc with
 *   d_eff,x = clamp(d_x - (td/Ts) sgn_s(i_x), 0, 1)   for 0 < d_x < 1,
 *   d_eff,x = d_x                                     for d_x = 0 or 1
 * (no switching, no dead time). The switch turn-on delay td removes td from
 * the high-side pulse when i_x > 0 (the low diode holds the leg at 0 during
 * the dead time) and adds it when i_x < 0; the clamp reproduces a pulse
 * swallowed or stretched to the full period. sgn_s is a saturated linear
 * smooth sign over +-i_band: the real inverter's average voltage error is
 * smoothed by the current ripple, which is much wider than i_band (see
 * plant_inverter.c for its choice), and a hard sign would chatter.
 * Phase-to-neutral voltages remove the common mode (balanced star winding);
 * the voltage vector is constant in the stationary frame over the period
 * and is rotated into dq at every RK4 stage with the stage's rotor angle.
 * The DC-link current is sum d_eff,x i_x, so that v_dc i_dc = sum v_x0 i_x.
 */
#include "plant_internal.h"

#include <math.h>

static inline double eff_duty(double d, double kdt, double i_norm) {
  if (d <= 0.0 || d >= 1.0) {
    return d;
  }
  const double sg = i_norm > 1.0 ? 1.0 : (i_norm < -1.0 ? -1.0 : i_norm);
  const double e = d - kdt * sg;
  return e < 0.0 ? 0.0 : (e > 1.0 ? 1.0 : e);
}

/* Rotor angle reference: the stage angles differ from the reference angle
 * by dth <= w_e h, so cos/sin are obtained by angle addition with a Taylor
 * series of dth (|dth| < 0.3 rad: truncation < 3e-17), and libm is called
 * once per period (the reference is carried from step to step the same
 * way; its rounding error grows by ~1e-16 per substep and restarts each
 * period). */
typedef struct {
  double th, c, s;
} angle_ref_t;

static inline void stage_cos_sin(const angle_ref_t *r, double th, double *c, double *s) {
  const double dt = th - r->th;
  if (dt > 0.3 || dt < -0.3) {
    *c = cos(th);
    *s = sin(th);
    return;
  }
  const double z = dt * dt, z2 = z * z, z4 = z2 * z2;
  /* Taylor coefficients, Estrin evaluation (short dependency chains) */
  const double sd = dt * ((1.0 - z * (1.0 / 6.0)) + z2 * ((1.0 / 120.0) - z * (1.0 / 5040.0)) +
                          z4 * ((1.0 / 362880.0) - z * (1.0 / 39916800.0)));
  const double cd = (1.0 - z * 0.5) + z2 * ((1.0 / 24.0) - z * (1.0 / 720.0)) +
                    z4 * ((1.0 / 40320.0) - z * (1.0 / 3628800.0) + z2 * (1.0 / 479001600.0));
  *c = r->c * cd - r->s * sd;
  *s = r->s * cd + r->c * sd;
}

static inline void avg_deriv(const plant_t *pl, const angle_ref_t *ar, const double *d,
                             const double *x, double m, double *dx) {
  const plant_machine_t *mp = &pl->p.machine;
  const double pp = (double)mp->pole_pairs;
  double c, s;
  stage_cos_sin(ar, pp * x[X_TH], &c, &s);
  const double id = (x[X_LD] - mp->lambda_m) * pl->aux.inv_ld;
  const double iq = x[X_LQ] * pl->aux.inv_lq;
  const double ial = id * c - iq * s, ibe = id * s + iq * c;
  const double ia = ial, ib = -0.5 * ial + PLANT_SQRT3_2 * ibe, ic = -ia - ib;
  const double vdc = plant_dclink_voltage(pl, x);
  const double kdt = pl->aux.kdt, nb = pl->aux.inv_band;
  const double da = eff_duty(d[0], kdt, ia * nb);
  const double db = eff_duty(d[1], kdt, ib * nb);
  const double dc = eff_duty(d[2], kdt, ic * nb);
  const double va0 = da * vdc, vb0 = db * vdc, vc0 = dc * vdc;
  const double vn = (va0 + vb0 + vc0) * (1.0 / 3.0);
  const double van = va0 - vn, vbn = vb0 - vn;
  const double vbe = (vb0 - vc0) * PLANT_INV_SQRT3;
  const double vd = van * c + vbe * s, vq = -van * s + vbe * c;
  const double w = plant_mech_speed(pl, x, m);
  const double we = pp * w;
  dx[X_LD] = vd - mp->rs * id + we * x[X_LQ];
  dx[X_LQ] = vq - mp->rs * iq - we * x[X_LD];
  const double te = 1.5 * pp * (x[X_LD] * iq - x[X_LQ] * id);
  plant_mech_deriv(pl, x, m, te, dx);
  const double idc = da * ia + db * ib + dc * ic;
  dx[X_VC] = plant_dclink_deriv(pl, x, idc);
  dx[X_VA] = van;
  dx[X_VB] = vbn;
  dx[X_VN] = vn - 0.5 * vdc;
  dx[X_IDC] = idc;
}

/* One period with gates on: `substeps` classical RK4 steps. x holds the
 * state at the period start (integrals zeroed) and returns it at the end. */
void plant_inverter_avg_period(plant_t *pl, const double duty[3], double *x) {
  const int n = pl->p.inverter.substeps;
  const double h = pl->p.ts / n, h2 = 0.5 * h, h6 = h / 6.0;
  double t = pl->t;
  double m0 = plant_mech_input(pl, t);
  angle_ref_t ar;
  ar.th = pl->p.machine.pole_pairs * x[X_TH];
  ar.c = cos(ar.th);
  ar.s = sin(ar.th);
  for (int k = 0; k < n; k++) {
    const double m1 = plant_mech_input(pl, t + h2);
    const double m2 = plant_mech_input(pl, t + h);
    double k1[X_N], k2[X_N], k3[X_N], k4[X_N], xs[X_N];
    if (k > 0) { /* carry the reference angle: libm once per period at speed */
      double c, s;
      const double th = pl->p.machine.pole_pairs * x[X_TH];
      stage_cos_sin(&ar, th, &c, &s);
      ar.th = th;
      ar.c = c;
      ar.s = s;
    }
    avg_deriv(pl, &ar, duty, x, m0, k1);
    for (int i = 0; i < X_N; i++) {
      xs[i] = x[i] + h2 * k1[i];
    }
    avg_deriv(pl, &ar, duty, xs, m1, k2);
    for (int i = 0; i < X_N; i++) {
      xs[i] = x[i] + h2 * k2[i];
    }
    avg_deriv(pl, &ar, duty, xs, m1, k3);
    for (int i = 0; i < X_N; i++) {
      xs[i] = x[i] + h * k3[i];
    }
    avg_deriv(pl, &ar, duty, xs, m2, k4);
    for (int i = 0; i < X_N; i++) {
      x[i] += h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
    t += h;
    if (pl->p.mech.mode == PLANT_MECH_IMPOSED) {
      x[X_W] = m2; /* the imposed speed, exactly */
    }
    m0 = m2;
  }
}

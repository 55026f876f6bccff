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
 * Device drops (plant_inverter_t; plant_inverter_sw.c says which device
 * carries the current): over the period the high side conducts for
 * d_eff,x, the low side for 1 - d_eff,x, so the period-average pole
 * voltage loses
 *   i_x > 0:  d_eff,x V_sw(i_x) + (1 - d_eff,x) V_d(i_x)  (high switch, low diode)
 *   i_x < 0:  d_eff,x V_d(i_x)  + (1 - d_eff,x) V_sw(i_x) (high diode, low switch)
 * with V_sw(i) = v_th_sw sgn_s(i) + r_on_sw i, V_d(i) = v_f_diode sgn_s(i) +
 * r_diode i, the same smooth sign (both vanish at i = 0: continuous); the
 * switching model's period average for a current steady over the period
 * (the dead time's diode included in d_eff). The link current keeps
 * sum d_eff,x i_x (the drops are lost in the devices).
 */
#include "plant_internal.h"

#include <math.h>

#if defined(__GNUC__)
#define AVG_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define AVG_ALWAYS_INLINE inline
#endif

/* d_eff for a leg with duty d and kd = td/Ts when 0 < d < 1, else kd = 0
 * (no switching, no dead time: d_eff = d - 0 = d; only a NaN current, i.e.
 * an already diverged state, gives NaN there). Each clamp is written as
 * `bound OP v ? bound : v`, the operand order of SSE's MAXSD/MINSD (the
 * second operand when unordered: NaN passes through, as before), so that
 * the compiler emits the two instructions instead of compares and
 * branches: the same values for every input, signed zeros included. */
static inline double eff_duty(double d, double kd, double i_norm) {
  const double lo = -1.0 > i_norm ? -1.0 : i_norm;
  const double sg = 1.0 < lo ? 1.0 : lo;
  const double e0 = 0.0 > d - kd * sg ? 0.0 : d - kd * sg;
  return 1.0 < e0 ? 1.0 : e0;
}

/* The period-average device drop of a leg with effective duty e at
 * current i (header comment); sg = sgn_s(i). */
static inline double avg_drop(const double dv[4], double e, double i, double sg) {
  /* mut: avg_drop_device_swapped */
  const double vsw = dv[0] * sg + dv[1] * i, vd = dv[2] * sg + dv[3] * i;
  return i > 0.0 ? e * vsw + (1.0 - e) * vd : e * vd + (1.0 - e) * vsw;
}

static inline double sat1(double x) {
  return x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x);
}

/* Rotor angle reference: the stage angles differ from the reference angle
 * by dth <= w_e h, so cos/sin are obtained by angle addition with a Taylor
 * series of dth (plant_cos_sin_near), and libm is called once per period
 * (the reference is carried from step to step the same way; its rounding
 * error grows by ~1e-16 per substep and restarts each period). */
typedef struct {
  double th, c, s;
  const double *i_known; /* currents of the first stage's state, or NULL */
} angle_ref_t;

static inline void stage_cos_sin(const angle_ref_t *r, double th, double *c, double *s) {
  plant_cos_sin_near(r->th, r->c, r->s, th, c, s);
}

/* Constants of one period, in locals (no reloads through pl in the stages). */
typedef struct {
  const plant_mag_t *mag; /* the plant's (read only: no copy) */
  double pp, rs, nb, b, inv_j, vsrc, inv_r, inv_c, g_chop;
  int one_way;        /* rectifier link */
  double d[3], kd[3]; /* duties; td/Ts for a switching leg (0 < d < 1), else 0 */
  int imposed, ideal; /* mech.mode == IMPOSED, dclink.kind == IDEAL */
  int drops;          /* device drops (aux.drops): dv = v_th_sw, r_on_sw, v_f_diode, r_diode */
  double dv[4];
  double cog[3]; /* cogging torque (plant_mech_t): amplitude (0: none), order, phase */
} avg_k_t;

/* Derivative at one stage, c and s being cos and sin of the stage's rotor
 * angle. The same expressions as plant_internal.h's inline mechanics and
 * DC link, with the parameters hoisted. `avgs`: integrate the period
 * averages (v_an, v_bn, i_dc, torque, i_dq: the log's; plant_set_averages)
 * as well; the star point's (X_VN, the sensors') always. `real`: the
 * device drops and the cogging torque (a copy of their own: the usual
 * periods without them run the code they ran before, issue 25). */
static AVG_ALWAYS_INLINE void avg_deriv(const avg_k_t *restrict k, int ideal, int imposed, int avgs,
                                        int real, double c, double s, const double *restrict x,
                                        double m, double *restrict dx, const double *i_known) {
  double id, iq;
  if (i_known != NULL) { /* the state's currents, already computed (the plant's cache) */
    id = i_known[0];
    iq = i_known[1];
  } else {
    plant_mag_current(k->mag, x[X_LD], x[X_LQ], &id, &iq);
  }
  const double ial = id * c - iq * s, ibe = id * s + iq * c;
  const double ia = ial, ib = -0.5 * ial + PLANT_SQRT3_2 * ibe, ic = -ia - ib;
  const double vdc = ideal ? k->vsrc : (x[X_VC] > 0.0 ? x[X_VC] : 0.0);
  const double nb = k->nb;
  const double da = eff_duty(k->d[0], k->kd[0], ia * nb);
  const double db = eff_duty(k->d[1], k->kd[1], ib * nb);
  const double dc = eff_duty(k->d[2], k->kd[2], ic * nb);
  double va0 = da * vdc, vb0 = db * vdc, vc0 = dc * vdc;
  if (real && k->drops) {
    va0 -= avg_drop(k->dv, da, ia, sat1(ia * nb));
    vb0 -= avg_drop(k->dv, db, ib, sat1(ib * nb));
    vc0 -= avg_drop(k->dv, dc, ic, sat1(ic * nb));
  }
  const double vn = (va0 + vb0 + vc0) * (1.0 / 3.0);
  const double van = va0 - vn, vbn = vb0 - vn;
  const double vbe = (vb0 - vc0) * PLANT_INV_SQRT3;
  const double vd = van * c + vbe * s, vq = -van * s + vbe * c;
  const double w = imposed ? m : x[X_W];
  const double we = k->pp * w;
  dx[X_LD] = vd - k->rs * id + we * x[X_LQ];
  dx[X_LQ] = vq - k->rs * iq - we * x[X_LD];
  const double te = 1.5 * k->pp * (x[X_LD] * iq - x[X_LQ] * id);
  if (imposed) {
    dx[X_TH] = m;
    dx[X_W] = 0.0;
  } else {
    dx[X_TH] = x[X_W];
    const double tn = te - k->b * x[X_W] - m;
    dx[X_W] = (real && k->cog[0] != 0.0 ? tn + plant_mech_cogging(k->cog, x[X_TH]) : tn) * k->inv_j;
  }
  dx[X_VN] = vn - 0.5 * vdc;
  const double idc = avgs || !ideal ? da * ia + db * ib + dc * ic : 0.0;
  if (!ideal) { /* ideal: v_C is not integrated (avg_rk4) */
    dx[X_VC] =
        (plant_dclink_source(k->vsrc, x[X_VC], k->inv_r, k->one_way) - x[X_VC] * k->g_chop - idc) *
        k->inv_c;
  }
  if (avgs) {
    dx[X_IDC] = idc;
    dx[X_TE] = te;
    dx[X_ID] = id;
    dx[X_IQ] = iq;
    dx[X_VA] = van;
    dx[X_VB] = vbn;
  }
}

/* The RK4 steps of one period; `ideal`, `imposed`, `avgs` and `real` are constants
 * at each call site (specialised copies). State entries whose derivative is
 * identically zero (v_C on an ideal link, w under imposed speed) are left
 * as they are: x + h * 0 = x, the same result without the work. */
static AVG_ALWAYS_INLINE void avg_rk4(const plant_t *pl, const avg_k_t *restrict kc, int ideal,
                                      int imposed, int avgs, int real, angle_ref_t *restrict ar,
                                      double *restrict x, double *restrict cs_end) {
  /* a stage's state entry; v_C on an ideal link and w under imposed speed
   * are not read by the derivative (nor is their derivative): the entry
   * as it was */
#define AVG_STAGE(i, v) (((ideal && (i) == X_VC) || (imposed && (i) == X_W)) ? x[i] : (v))
  const int n = pl->aux.steps; /* the scenario's, more at speed (plant.h) */
  const double h = pl->p.ts / n, h2 = 0.5 * h, h6 = h / 6.0;
  const avg_k_t *restrict k = kc; /* not copied: a copy of the just-written struct would stall */
  double t = pl->t;
  /* one step inside the mechanical input's constant span (the usual
   * period): t <= t + h/2 <= t + h < m_t1, so plant_mech_input gives the
   * span's value at every stage, without the three look-ups */
  const plant_aux_t *a = &pl->aux;
  const int m_const = n == 1 && t >= a->m_t0 && t + h < a->m_t1;
  const double m_span = a->m_val + a->fric;
  double m0 = m_const ? m_span : plant_mech_input(pl, t);
  for (int j = 0; j < n; j++) {
    const double m1 = m_const ? m_span : plant_mech_input(pl, t + h2);
    const double m2 = m_const ? m_span : plant_mech_input(pl, t + h);
    double k1[X_N], k2[X_N], k3[X_N], k4[X_N], xs[X_N];
    double c, s;
    if (j > 0) { /* carry the reference angle: libm once per period at speed */
      const double th = k->pp * x[X_TH];
      stage_cos_sin(ar, th, &c, &s);
      ar->th = th;
      ar->c = c;
      ar->s = s;
    }
    avg_deriv(k, ideal, imposed, avgs, real, ar->c, ar->s, x, m0, k1, j == 0 ? ar->i_known : NULL);
    for (int i = 0; i < X_VA; i++) { /* the integrals X_VA.. are not read */
      xs[i] = AVG_STAGE(i, x[i] + h2 * k1[i]);
    }
    stage_cos_sin(ar, k->pp * xs[X_TH], &c, &s);
    avg_deriv(k, ideal, imposed, avgs, real, c, s, xs, m1, k2, NULL);
    for (int i = 0; i < X_VA; i++) {
      xs[i] = AVG_STAGE(i, x[i] + h2 * k2[i]);
    }
    stage_cos_sin(ar, k->pp * xs[X_TH], &c, &s);
    avg_deriv(k, ideal, imposed, avgs, real, c, s, xs, m1, k3, NULL);
    for (int i = 0; i < X_VA; i++) {
      xs[i] = AVG_STAGE(i, x[i] + h * k3[i]);
    }
    stage_cos_sin(ar, k->pp * xs[X_TH], &c, &s);
    avg_deriv(k, ideal, imposed, avgs, real, c, s, xs, m2, k4, NULL);
    for (int i = 0; i < X_N; i++) {
      if ((ideal && i == X_VC) || (imposed && i == X_W) || (!avgs && i != X_VN && i >= X_VA)) {
        continue;
      }
      x[i] += h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
    t += h;
    if (imposed) {
      x[X_W] = m2; /* the imposed speed, exactly */
    }
    m0 = m2;
  }
  stage_cos_sin(ar, k->pp * x[X_TH], &cs_end[0], &cs_end[1]);
#undef AVG_STAGE
}

/* One period with gates on: `substeps` classical RK4 steps. x holds the
 * state at the period start (integrals zeroed) and returns it at the end.
 * The first stage of each step is at the reference angle itself (cos and
 * sin known: from the plant's current cache for the first step). cs_end
 * returns cos and sin of pole_pairs * x[X_TH] at the end, carried from the
 * last reference like the stage angles (plant_step decides their use). */
void plant_inverter_avg_period(plant_t *pl, const double duty[3], double *x, double cs_end[2]) {
  const plant_params_t *p = &pl->p;
  avg_k_t k;
  k.pp = (double)p->machine.pole_pairs;
  k.mag = &pl->aux.mag;
  k.rs = p->machine.rs;
  k.nb = pl->aux.inv_band;
  k.b = p->mech.b;
  k.inv_j = pl->aux.inv_j;
  k.vsrc = p->dclink.v_source;
  k.inv_r = pl->aux.inv_r;
  k.inv_c = pl->aux.inv_c;
  k.g_chop = pl->aux.g_chop;
  k.one_way = pl->aux.one_way;
  const double kdt = pl->aux.kdt;
  for (int j = 0; j < 3; j++) {
    k.d[j] = duty[j];
    /* both compares evaluated (`&`, not `&&`): no branch per leg */
    k.kd[j] = ((duty[j] > 0.0) & (duty[j] < 1.0)) ? kdt : 0.0;
  }
  k.imposed = p->mech.mode == PLANT_MECH_IMPOSED;
  k.ideal = p->dclink.kind == PLANT_DC_IDEAL;
  k.drops = pl->aux.drops;
  k.cog[0] = p->mech.cog_amp;
  angle_ref_t ar;
  if (x[X_TH] == pl->theta_m) { /* always, from plant_step */
    const plant_cur_cache_t *cc = plant_machine_cur(pl);
    ar.th = cc->th_e;
    ar.c = cc->c;
    ar.s = cc->s;
    /* the cache is keyed on this very state (flux linkages included): its
     * currents are the first stage's, bit for bit (a map's evaluation is
     * not free) */
    ar.i_known = cc->i_dq;
  } else {
    ar.th = k.pp * x[X_TH];
    ar.c = cos(ar.th);
    ar.s = sin(ar.th);
    ar.i_known = NULL;
  }
  const int avgs = pl->aux.avgs;
  if (k.drops || k.cog[0] != 0.0) { /* device drops, cogging: a copy of their own */
    k.dv[0] = p->inverter.v_th_sw;  /* read by that copy only */
    k.dv[1] = p->inverter.r_on_sw;
    k.dv[2] = p->inverter.v_f_diode;
    k.dv[3] = p->inverter.r_diode;
    k.cog[1] = (double)p->mech.cog_order;
    k.cog[2] = p->mech.cog_phase;
    avg_rk4(pl, &k, k.ideal, k.imposed, avgs, 1, &ar, x, cs_end);
  } else if (k.ideal && !k.imposed) { /* the usual case */
    if (avgs) {
      avg_rk4(pl, &k, 1, 0, 1, 0, &ar, x, cs_end);
    } else {
      avg_rk4(pl, &k, 1, 0, 0, 0, &ar, x, cs_end);
    }
  } else {
    avg_rk4(pl, &k, k.ideal, k.imposed, avgs, 0, &ar, x, cs_end);
  }
}

/*
 * plant_inverter_sw.c - switching-level two-level inverter with dead time,
 * and the diode-only circuit (gates off, both inverter models).
 *
 * Carrier: triangle, valley at 0 and Ts, peak at Ts/2. Commanded high-side
 * state H_x = carrier > 1 - d_x, i.e. on over [(1-d)Ts/2, (1+d)Ts/2] for
 * 0 < d < 1, always for d = 1, never for d = 0. Dead time: the turn-on of
 * each switch is delayed by td after its command edge (turn-off is
 * immediate), so after every edge the leg floats for td. Edges within td of
 * the period end carry over to the next period (per-leg memory).
 * A floating leg follows its free-wheeling diodes:
 *   i_x > 0 -> low diode, leg at 0;   i_x < 0 -> high diode, leg at v_dc;
 *   i_x = 0 -> blocked: the leg floats at the voltage u that keeps
 *              di_x/dt = 0, valid while 0 <= u <= v_dc.
 * With two legs blocked all currents are zero ("all-zero" state): the flux
 * linkages are held at their zero-current value (the PM flux) exactly, the phase voltages are the
 * back-EMF, and conduction resumes when no star-point potential keeps every
 * leg within its allowed range (gap > 0), between the two legs that violate
 * it. This gives extinction without chattering below the rectifier
 * threshold (line-to-line back-EMF peak < v_dc) and uncontrolled
 * rectification above it.
 * Integration: the period is split at every switching event (times exact
 * from the duties and td), each interval is integrated with RK4 steps of at
 * most Ts/substeps; diode events inside an interval (current zero crossing,
 * blocked-leg voltage leaving [0, v_dc], all-zero gap opening) are located
 * with the Illinois method to 1e-8 Ts and the step is split there.
 * Power-stage faults (plant_set_power_faults): a switch stuck open drops
 * out of the commanded leg state (both of a leg: the leg floats on its
 * diodes), a switch stuck closed conducts whatever the gates; a leg with
 * both switches on is a shoot-through, ended at once by the gate driver's
 * desaturation detection (aux.desat: every healthy switch off from then
 * on). An open phase is a leg of its own kind (LEG_OPEN): always blocked,
 * its terminal at whatever potential keeps its current zero, without the
 * [0, v_dc] bound of a diode leg (no EV_U events, unbounded in the
 * all-zero state).
 * Device drops (plant_inverter_t, all 0: none): a conducting leg's pole
 * voltage is its rail's less the drop of the device that carries i_x
 * (i_x > 0 flows out of the leg into the phase):
 *   high side on:  i_x > 0 high switch, i_x < 0 high diode;
 *   low side on:   i_x > 0 low diode,   i_x < 0 low switch;
 *   floating (the dead time, gates off): the diode the current holds on;
 * v_x = rail - (V_0 sgn_s(i_x) + R i_x), (V_0, R) = (v_th_sw, r_on_sw) for a
 * switch, (v_f_diode, r_diode) for a diode: the pole loses the drop for
 * i_x > 0 and gains it for i_x < 0. sgn_s is the average model's smooth
 * sign (plant_inverter.c: a threshold over +-i_band, the knee a real
 * device's exponential characteristic and the ripple round off), so the
 * drop vanishes at i_x = 0: the diode events, the blocked leg's range and
 * the all-zero state keep their rails. The link current is still
 * sum k_x i_x (k_x the rail, units of v_dc): the drops' power is lost in
 * the devices. The gate-driven reverse current goes through the diode
 * (IGBTs; a MOSFET's channel conducting in reverse is not modelled). A
 * floating shorted pair (a fault) is modelled without drops.
 * A lead shorted to earth (the negative rail) ties its leg's output to that
 * rail: a stuck-closed low side that no desaturation turns off. Two leads
 * shorted together (x, y) tie their legs' outputs: legs of opposite
 * commanded states shoot through the short (desaturation, as above); one
 * leg commanded sets both; with both floating the pair is one node on
 * their four diodes carrying -i_z. Only the potential of z relative to the
 * node acts on the machine (v_ab = (2/3)(v_z - v_node) c_z), so the node is
 * taken as the reference (both legs LEG_LO) and leg z floats between rails
 * that are its own range less the node's: [-v_dc, v_dc] with z floating
 * too (i_z > 0: z on its low diode, the node on its high ones), [0, v_dc]
 * with z high, [-v_dc, 0] with z low; the real potentials are restored
 * (offset) for the star point, and the link current is i_z times z's rail
 * in units of v_dc in every case.
 */
#include "plant_internal.h"

#include <math.h>
#include <string.h>

enum { LEG_LO, LEG_HI, LEG_FLOAT, LEG_OPEN };
enum { COND_NONE = -1, COND_LO = 0, COND_HI = 1, COND_BLOCK = 2 };
enum { EV_CUR0 = 0, EV_U_LO = 3, EV_U_HI = 4, EV_GAP = 5, EV_N = 6 };

#define SW_I_EPS      1e-9 /* a current below this is taken as blocked [A] */
#define SW_MAX_EVENTS 24   /* diode events handled per integration step */
#define SW_MAX_EDGES  4

static const double CX[3][2] = {{1.0, 0.0}, {-0.5, PLANT_SQRT3_2}, {-0.5, -PLANT_SQRT3_2}};

typedef struct {
  int type[3];
  int cond[3];
  int all_zero;
  int blocked;  /* the single blocked leg when not all_zero, else -1 */
  double rl[3]; /* a floating leg's rails, in units of v_dc: 0 and 1 but */
  double rh[3]; /* for leg z of a floating shorted pair (header comment) */
  int node;     /* that leg z, else -1 */
  /* the rotor angle pole_pairs theta_m at the period start and its cos,
   * sin: every stage's cos, sin by angle addition from these
   * (plant_cos_sin_near), libm once per period at most */
  double th_ref, c_ref, s_ref;
} sw_cfg_t;

/* cos and sin of the electrical angle of state x (near the reference). */
static inline void sw_cos_sin(const plant_t *pl, const sw_cfg_t *cf, const double *x, double *c,
                              double *s) {
  const double th = pl->p.machine.pole_pairs * x[X_TH];
  plant_cos_sin_near(cf->th_ref, cf->c_ref, cf->s_ref, th, c, s);
}

typedef struct {
  double u;   /* voltage of the blocked leg [V] */
  double gap; /* all-zero: > 0 when a diode path must open [V] */
  double vn0; /* star point w.r.t. the negative rail [V] (isotropic) */
  double vns; /* the same with the (3.3) matrix (plant_star.c) [V] */
  double vdc;
} sw_out_t;

static void phase_currents(const plant_t *pl, const sw_cfg_t *cf, const double *x, double i[3],
                           double *ial, double *ibe) {
  double c, s;
  sw_cos_sin(pl, cf, x, &c, &s);
  double id, iq;
  plant_mag_current(&pl->aux.mag, x[X_LD], x[X_LQ], &id, &iq);
  *ial = id * c - iq * s;
  *ibe = id * s + iq * c;
  i[0] = *ial;
  i[1] = -0.5 * *ial + PLANT_SQRT3_2 * *ibe;
  i[2] = -i[0] - i[1];
}

/* The device drop of leg j of type `type` (diode state cond) at phase
 * current i (header comment); 0 for a blocked or open leg. */
static inline double leg_drop(const plant_t *pl, int type, int cond, double i) {
  const plant_inverter_t *inv = &pl->p.inverter;
  int diode;
  if (type == LEG_HI) {
    diode = i < 0.0;
  } else if (type == LEG_LO) {
    diode = i > 0.0;
  } else if (type == LEG_FLOAT && (cond == COND_LO || cond == COND_HI)) {
    diode = 1;
  } else {
    return 0.0;
  }
  const double in = i * pl->aux.inv_band;
  const double sg = in > 1.0 ? 1.0 : (in < -1.0 ? -1.0 : in);
  /* mut: sw_drop_device_swapped */
  return diode ? inv->v_f_diode * sg + inv->r_diode * i : inv->v_th_sw * sg + inv->r_on_sw * i;
}

/* Allowed potential range of leg j for the all-zero state. */
static void leg_range(const sw_cfg_t *cf, int j, double vdc, double *lo, double *hi) {
  const int type = cf->type[j];
  if (type == LEG_OPEN) {
    *lo = -1e300;
    *hi = 1e300;
    return;
  }
  *lo = type == LEG_HI ? vdc : (type == LEG_LO ? 0.0 : cf->rl[j] * vdc);
  *hi = type == LEG_LO ? 0.0 : (type == LEG_HI ? vdc : cf->rh[j] * vdc);
}

/* The potential of the node of a floating shorted pair (the reference of
 * the pattern, header comment) above the negative rail, w the potential
 * of leg z against it. */
static double node_offset(const sw_cfg_t *cf, double w, double vdc) {
  const int z = cf->node;
  if (cf->rl[z] >= 0.0) {
    return vdc - w; /* z high */
  }
  if (cf->rh[z] <= 0.0) {
    return -w; /* z low */
  }
  return w <= 0.0 ? -w : vdc - w;
}

/* c, s: cos and sin of the electrical angle */
static void backemf(const plant_t *pl, double c, double s, double w, double e[3]) {
  const double pp = (double)pl->p.machine.pole_pairs;
  /* zero current: the flux is lambda(0) turning with the rotor, e = w_e J lambda */
  double l0d, l0q;
  plant_mag_flux0(&pl->aux.mag, &l0d, &l0q);
  const double lal = l0d * c - l0q * s, lbe = l0d * s + l0q * c;
  const double we = pp * w;
  const double eal = -we * lbe, ebe = we * lal;
  e[0] = eal;
  e[1] = -0.5 * eal + PLANT_SQRT3_2 * ebe;
  e[2] = -e[0] - e[1];
}

static void sw_deriv(const plant_t *pl, const sw_cfg_t *cf, const double *x, double m, double *dx,
                     sw_out_t *o) {
  const plant_machine_t *mp = &pl->p.machine;
  const double pp = (double)mp->pole_pairs;
  const double vdc = plant_dclink_voltage(pl, x);
  const double w = plant_mech_speed(pl, x, m);
  const double we = pp * w;
  double te = 0.0, idc = 0.0, vn0, id_now = 0.0, iq_now = 0.0;
  double c, s;
  sw_cos_sin(pl, cf, x, &c, &s);
  if (cf->all_zero) {
    double e[3], lo_max = -1e300, hi_min = 1e300;
    backemf(pl, c, s, w, e);
    for (int j = 0; j < 3; j++) {
      double lo, hi;
      leg_range(cf, j, vdc, &lo, &hi);
      lo_max = fmax(lo_max, lo - e[j]);
      hi_min = fmin(hi_min, hi - e[j]);
    }
    o->gap = lo_max - hi_min;
    vn0 = o->gap > 0.0 ? 0.5 * (lo_max + hi_min) : fmin(fmax(0.5 * vdc, lo_max), hi_min);
    o->vns = vn0;
    o->u = 0.0;
    dx[X_LD] = 0.0;
    dx[X_LQ] = 0.0;
    dx[X_VA] = e[0];
    dx[X_VB] = e[1];
  } else {
    double id, iq;
    plant_mag_current(&pl->aux.mag, x[X_LD], x[X_LQ], &id, &iq);
    const double ial = id * c - iq * s, ibe = id * s + iq * c;
    const double i[3] = {ial, -0.5 * ial + PLANT_SQRT3_2 * ibe, -0.5 * ial - PLANT_SQRT3_2 * ibe};
    double v[3];
    for (int j = 0; j < 3; j++) {
      const int fl = cf->type[j] == LEG_FLOAT;
      const double k = cf->type[j] == LEG_HI            ? 1.0
                       : (fl && cf->cond[j] == COND_HI) ? cf->rh[j]
                       : (fl && cf->cond[j] == COND_LO) ? cf->rl[j]
                                                        : 0.0;
      v[j] = k * vdc;
      /* mut: short_link_current_one_way */
      idc += k * i[j];
    }
    if (pl->aux.drops && cf->node < 0) { /* the device drops (header comment) */
      for (int j = 0; j < 3; j++) {
        /* mut: sw_drop_sign */
        v[j] -= leg_drop(pl, cf->type[j], cf->cond[j], i[j]);
      }
    }
    const double val = (2.0 * v[0] - v[1] - v[2]) * (1.0 / 3.0);
    const double vbe = (v[1] - v[2]) * PLANT_INV_SQRT3;
    double dld = val * c + vbe * s - mp->rs * id + we * x[X_LQ];
    double dlq = -val * s + vbe * c - mp->rs * iq - we * x[X_LD];
    o->u = 0.0;
    if (cf->blocked >= 0) {
      /* leg j blocked: choose its potential u so that di_j/dt = 0;
       * di_j/dt = p.(G dlambda) + w_e c_j.(J i_ab), p = R(-theta) c_j,
       * G = d i / d lambda (plant_magnetics.h), and u enters as
       * dlambda += (2/3) u p. */
      const int j = cf->blocked;
      const double p1 = CX[j][0] * c + CX[j][1] * s, p2 = -CX[j][0] * s + CX[j][1] * c;
      double G[2][2];
      plant_mag_jacobian(&pl->aux.mag, x[X_LD], x[X_LQ], G);
      const double gp1 = G[0][0] * p1 + G[1][0] * p2, gp2 = G[0][1] * p1 + G[1][1] * p2; /* G^T p */
      const double dij = gp1 * dld + gp2 * dlq + we * (-CX[j][0] * ibe + CX[j][1] * ial);
      const double g = (2.0 / 3.0) * (gp1 * p1 + gp2 * p2);
      const double u = -dij / g;
      dld += (2.0 / 3.0) * u * p1;
      dlq += (2.0 / 3.0) * u * p2;
      v[j] = u;
      o->u = u;
    }
    if (cf->node >= 0) {
      const double c0 = node_offset(cf, v[cf->node], vdc);
      for (int j = 0; j < 3; j++) {
        v[j] += c0;
      }
    }
    o->gap = 0.0;
    vn0 = (v[0] + v[1] + v[2]) * (1.0 / 3.0);
    o->vns = vn0;
    if (pl->p.machine.aniso.enabled && pl->aux.star_n > 0) {
      double e[3];
      backemf(pl, c, s, w, e);
      o->vns = plant_star_vn(pl, v, i, c, s, we, iq, e);
    }
    dx[X_LD] = dld;
    dx[X_LQ] = dlq;
    dx[X_VA] = v[0] - vn0;
    dx[X_VB] = v[1] - vn0;
    te = 1.5 * pp * (x[X_LD] * iq - x[X_LQ] * id);
    id_now = id;
    iq_now = iq;
  }
  o->vn0 = vn0;
  o->vdc = vdc;
  plant_mech_deriv(pl, x, m, te, dx);
  dx[X_VC] = plant_dclink_deriv(pl, x, idc);
  dx[X_VN] = vn0 - 0.5 * vdc;
  dx[X_IDC] = idc;
  dx[X_TE] = te;
  dx[X_ID] = id_now;
  dx[X_IQ] = iq_now;
}

static void enter_all_zero(const plant_t *pl, sw_cfg_t *cf, double *x) {
  plant_mag_flux0(&pl->aux.mag, &x[X_LD], &x[X_LQ]);
  cf->all_zero = 1;
  cf->blocked = -1;
  for (int j = 0; j < 3; j++) {
    cf->cond[j] = cf->type[j] == LEG_FLOAT || cf->type[j] == LEG_OPEN ? COND_BLOCK : COND_NONE;
  }
}

/* One RK4 step of size h from (t, x0); keeps the algebraic constraints
 * (blocked current exactly zero, imposed speed exact). */
static void sw_rk4(const plant_t *pl, const sw_cfg_t *cf, double t, const double *x0, double h,
                   double *x1) {
  const double m0 = plant_mech_input(pl, t), m1 = plant_mech_input(pl, t + 0.5 * h),
               m2 = plant_mech_input(pl, t + h);
  double k1[X_N], k2[X_N], k3[X_N], k4[X_N], xs[X_N];
  sw_out_t o;
  sw_deriv(pl, cf, x0, m0, k1, &o);
  for (int i = 0; i < X_N; i++) {
    xs[i] = x0[i] + 0.5 * h * k1[i];
  }
  sw_deriv(pl, cf, xs, m1, k2, &o);
  for (int i = 0; i < X_N; i++) {
    xs[i] = x0[i] + 0.5 * h * k2[i];
  }
  sw_deriv(pl, cf, xs, m1, k3, &o);
  for (int i = 0; i < X_N; i++) {
    xs[i] = x0[i] + h * k3[i];
  }
  sw_deriv(pl, cf, xs, m2, k4, &o);
  for (int i = 0; i < X_N; i++) {
    x1[i] = x0[i] + h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
  }
  plant_mech_end_step(pl, x1, t + h);
  if (!cf->all_zero && cf->blocked >= 0) {
    double c, s;
    sw_cos_sin(pl, cf, x1, &c, &s);
    plant_machine_zero_phase_current_cs(pl, x1, cf->blocked, c, s);
  }
}

/* Event functions at (t, x); z[e] > 0 means event e has happened. */
static void sw_events(const plant_t *pl, const sw_cfg_t *cf, double t, const double *x,
                      double z[EV_N]) {
  for (int e = 0; e < EV_N; e++) {
    z[e] = -1e300;
  }
  if (cf->all_zero) {
    double dx[X_N];
    sw_out_t o;
    sw_deriv(pl, cf, x, plant_mech_input(pl, t), dx, &o);
    z[EV_GAP] = o.gap;
    return;
  }
  double i[3], ial, ibe;
  phase_currents(pl, cf, x, i, &ial, &ibe);
  for (int j = 0; j < 3; j++) {
    if (cf->type[j] == LEG_FLOAT && cf->cond[j] == COND_LO) {
      z[EV_CUR0 + j] = -i[j];
    } else if (cf->type[j] == LEG_FLOAT && cf->cond[j] == COND_HI) {
      z[EV_CUR0 + j] = i[j];
    }
  }
  if (cf->blocked >= 0 && cf->type[cf->blocked] != LEG_OPEN) {
    double dx[X_N];
    sw_out_t o;
    sw_deriv(pl, cf, x, plant_mech_input(pl, t), dx, &o);
    z[EV_U_LO] = cf->rl[cf->blocked] * o.vdc - o.u;
    z[EV_U_HI] = o.u - cf->rh[cf->blocked] * o.vdc;
  }
}

static void exit_all_zero(const plant_t *pl, sw_cfg_t *cf, double t, const double *x) {
  double e[3], lo, hi, best_lo = -1e300, best_hi = 1e300;
  int jx = 0, jy = 1;
  const double vdc = plant_dclink_voltage(pl, x);
  double c, s;
  sw_cos_sin(pl, cf, x, &c, &s);
  backemf(pl, c, s, plant_mech_speed(pl, x, plant_mech_input(pl, t)), e);
  for (int j = 0; j < 3; j++) {
    leg_range(cf, j, vdc, &lo, &hi);
    if (lo - e[j] > best_lo) {
      best_lo = lo - e[j];
      jx = j;
    }
    if (hi - e[j] < best_hi) {
      best_hi = hi - e[j];
      jy = j;
    }
  }
  /* jx sources current into the machine (i > 0: low diode), jy returns it
   * (i < 0: high diode); jx != jy when gap > 0. At the event's located
   * instant the gap may be within rounding of 0 with one leg at both
   * extremes (all three back-EMFs equal, e.g. at standstill): the returning
   * leg is then the most negative of the other two. */
  if (jy == jx) {
    best_hi = 1e300;
    for (int j = 0; j < 3; j++) {
      leg_range(cf, j, vdc, &lo, &hi);
      if (j != jx && hi - e[j] < best_hi) {
        best_hi = hi - e[j];
        jy = j;
      }
    }
  }
  const int jz = 3 - jx - jy;
  cf->all_zero = 0;
  cf->cond[jx] = cf->type[jx] == LEG_FLOAT ? COND_LO : COND_NONE;
  cf->cond[jy] = cf->type[jy] == LEG_FLOAT ? COND_HI : COND_NONE;
  const int jz_free = cf->type[jz] == LEG_FLOAT || cf->type[jz] == LEG_OPEN;
  cf->cond[jz] = jz_free ? COND_BLOCK : COND_NONE;
  cf->blocked = jz_free ? jz : -1;
}

static void sw_transition(const plant_t *pl, sw_cfg_t *cf, double t, double *x, int ev) {
  if (ev == EV_GAP) {
    exit_all_zero(pl, cf, t, x);
  } else if (ev == EV_U_LO || ev == EV_U_HI) {
    cf->cond[cf->blocked] = ev == EV_U_LO ? COND_LO : COND_HI;
    cf->blocked = -1;
  } else {
    const int j = ev - EV_CUR0;
    double c, s;
    sw_cos_sin(pl, cf, x, &c, &s);
    plant_machine_zero_phase_current_cs(pl, x, j, c, s);
    if (cf->blocked >= 0) {
      enter_all_zero(pl, cf, x); /* two phases blocked: all three currents are zero */
      return;
    }
    cf->cond[j] = COND_BLOCK;
    cf->blocked = j;
    double dx[X_N];
    sw_out_t o;
    sw_deriv(pl, cf, x, plant_mech_input(pl, t), dx, &o);
    const double lo = cf->rl[j] * o.vdc, hi = cf->rh[j] * o.vdc;
    if (o.u > hi || o.u < lo) { /* current reverses into the other diode */
      cf->cond[j] = o.u > hi ? COND_HI : COND_LO;
      cf->blocked = -1;
    }
  }
}

/* Locates event ev inside (0, h] (z0 <= 0 < z1) with the Illinois method;
 * returns the time on the event side of the bracket and the state there. */
static double sw_locate(const plant_t *pl, const sw_cfg_t *cf, double t, const double *x, double h,
                        int ev, double z0, double z1, const double *x1, double *xb) {
  double a = 0.0, b = h, za = z0, zb = z1;
  int side = 0;
  memcpy(xb, x1, sizeof(double) * X_N);
  const double tol = 1e-8 * pl->p.ts;
  for (int it = 0; it < 60 && b - a > tol; it++) {
    double tau = a + (b - a) * (-za) / (zb - za);
    if (!(tau > a && tau < b)) {
      tau = 0.5 * (a + b);
    }
    double xt[X_N], z[EV_N];
    sw_rk4(pl, cf, t, x, tau, xt);
    sw_events(pl, cf, t + tau, xt, z);
    if (z[ev] > 0.0) {
      b = tau;
      zb = z[ev];
      memcpy(xb, xt, sizeof xt);
      if (side == 1) {
        za *= 0.5;
      }
      side = 1;
    } else {
      a = tau;
      za = z[ev];
      if (side == -1) {
        zb *= 0.5;
      }
      side = -1;
    }
  }
  return b;
}

/* The star point at (t, x) for the measurement circuit. */
static double sw_star(const plant_t *pl, const sw_cfg_t *cf, double t, const double *x) {
  double dx[X_N];
  sw_out_t o;
  sw_deriv(pl, cf, x, plant_mech_input(pl, t), dx, &o);
  return o.vns;
}

/* Integrates over len with a fixed leg configuration, splitting at diode
 * events. */
static void sw_integrate(plant_t *pl, sw_cfg_t *cf, double *t, double *x, double len) {
  const int star = pl->aux.star_n > 0;
  const double hmax = pl->p.ts / pl->aux.steps; /* more at speed (plant.h) */
  const int nsub = (int)ceil(len / hmax - 1e-9);
  const double h = len / (nsub > 0 ? nsub : 1);
  /* the event functions and the star point at the end of a step without
   * event are those at the start of the next one (same t, x and leg
   * configuration) */
  double z_next[EV_N], vs_next = 0.0;
  int z_known = 0;
  for (int k = 0; k < (nsub > 0 ? nsub : 1); k++) {
    double rem = h;
    for (int guard = 0; rem > 1e-12 * pl->p.ts; guard++) {
      double x1[X_N], z0[EV_N], z1[EV_N];
      double vs0 = 0.0;
      if (z_known) {
        memcpy(z0, z_next, sizeof z0);
        vs0 = vs_next;
      } else {
        sw_events(pl, cf, *t, x, z0);
        vs0 = star ? sw_star(pl, cf, *t, x) : 0.0;
      }
      z_known = 0;
      sw_rk4(pl, cf, *t, x, rem, x1);
      sw_events(pl, cf, *t + rem, x1, z1);
      int best = -1;
      double fbest = 2.0;
      for (int e = 0; e < EV_N && guard < SW_MAX_EVENTS; e++) {
        if (z1[e] > 0.0 || z0[e] > 0.0) {
          const double f = z0[e] >= 0.0 ? 0.0 : z0[e] / (z0[e] - z1[e]);
          if (f < fbest) {
            fbest = f;
            best = e;
          }
        }
      }
      if (best < 0) {
        memcpy(x, x1, sizeof x1);
        memcpy(z_next, z1, sizeof z1);
        z_known = 1;
        *t += rem;
        if (star) {
          vs_next = sw_star(pl, cf, *t, x);
          plant_star_filter(pl, vs0, vs_next, rem);
        }
        break;
      }
      double tau = 0.0;
      if (z0[best] < 0.0) {
        double xb[X_N];
        tau = sw_locate(pl, cf, *t, x, rem, best, z0[best], z1[best], x1, xb);
        memcpy(x, xb, sizeof xb);
      }
      *t += tau;
      if (star && tau > 0.0) {
        plant_star_filter(pl, vs0, sw_star(pl, cf, *t, x), tau);
      }
      rem -= tau;
      sw_transition(pl, cf, *t, x, best);
    }
  }
}

/* The leg states of an interval: types, a floating leg's rails (units of
 * v_dc) and the floating shorted pair's leg z (-1: none). */
typedef struct {
  int type[3];
  double rl[3], rh[3];
  int node;
} sw_legs_t;

/* Sets the leg types for a new interval and the diode state of legs that
 * start to float. */
static void sw_setup(const plant_t *pl, sw_cfg_t *cf, double *x, const sw_legs_t *lg) {
  const int *type = lg->type;
  double i[3], ial, ibe;
  phase_currents(pl, cf, x, i, &ial, &ibe);
  cf->node = lg->node;
  for (int j = 0; j < 3; j++) {
    cf->rl[j] = lg->rl[j];
    cf->rh[j] = lg->rh[j];
    if (type[j] == LEG_FLOAT) {
      if (cf->type[j] != LEG_FLOAT || cf->cond[j] == COND_NONE) {
        cf->cond[j] = fabs(i[j]) <= SW_I_EPS ? COND_BLOCK : (i[j] > 0.0 ? COND_LO : COND_HI);
      }
    } else if (type[j] == LEG_OPEN) {
      cf->cond[j] = COND_BLOCK;
    } else {
      cf->cond[j] = COND_NONE;
    }
    cf->type[j] = type[j];
  }
  if (cf->all_zero) {
    enter_all_zero(pl, cf, x);
    return;
  }
  int nb = 0, jb = -1;
  for (int j = 0; j < 3; j++) {
    if ((cf->type[j] == LEG_FLOAT || cf->type[j] == LEG_OPEN) && cf->cond[j] == COND_BLOCK) {
      nb++;
      jb = j;
    }
  }
  if (nb >= 2) {
    enter_all_zero(pl, cf, x);
  } else if (nb == 1) {
    cf->blocked = jb;
    double c, s;
    sw_cos_sin(pl, cf, x, &c, &s);
    plant_machine_zero_phase_current_cs(pl, x, jb, c, s);
  } else {
    cf->blocked = -1;
  }
}

typedef struct {
  double te[SW_MAX_EDGES];
  int cmd[SW_MAX_EDGES];
  int n;
} edges_t;

static int leg_type_at(const edges_t *e, double tau, double td) {
  int k = 0;
  while (k + 1 < e->n && e->te[k + 1] <= tau) {
    k++;
  }
  if (tau - e->te[k] < td) {
    return LEG_FLOAT;
  }
  return e->cmd[k] ? LEG_HI : LEG_LO;
}

/* The shorted pair x, y and the third phase z of a fault mask (two bits). */
static void short_pair(unsigned sh, int *x, int *y, int *z) {
  *z = (sh & 1u) == 0u ? 0 : ((sh & 2u) == 0u ? 1 : 2);
  *x = (*z + 1) % 3;
  *y = (*z + 2) % 3;
}

/* A floating shorted pair as the reference node, leg z between shifted
 * rails (header comment). */
static void short_node(sw_legs_t *lg, int x, int y, int z) {
  int *type = lg->type;
  const int ix = type[x] == LEG_HI || type[x] == LEG_LO;
  const int iy = type[y] == LEG_HI || type[y] == LEG_LO;
  if (ix || iy) {
    type[ix ? y : x] = type[ix ? x : y]; /* one leg commanded sets both */
    return;
  }
  type[x] = LEG_LO;
  type[y] = LEG_LO;
  if (type[z] != LEG_OPEN) {
    /* mut: short_node_rails_unshifted */
    lg->rl[z] = type[z] == LEG_HI ? 0.0 : -1.0;
    lg->rh[z] = type[z] == LEG_LO ? 0.0 : 1.0;
    type[z] = LEG_FLOAT;
    lg->node = z;
  }
}

/* The leg states the power-stage faults leave of the commanded ones
 * (header comment). */
static void sw_fault_legs(plant_aux_t *a, sw_legs_t *lg) {
  int *type = lg->type;
  int on[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  int x = 0, y = 0, z = 0;
  if (a->pf.shorted != 0u) {
    short_pair(a->pf.shorted, &x, &y, &z);
  }
  for (int pass = 0; pass < 2; pass++) {
    int shoot = 0;
    for (int j = 0; j < 3; j++) {
      const int cmd_lo = !a->desat && type[j] == LEG_LO, cmd_hi = !a->desat && type[j] == LEG_HI;
      on[j][0] = (cmd_lo && (a->pf.open & PLANT_SW_LOW(j)) == 0u) ||
                 (a->pf.closed & PLANT_SW_LOW(j)) != 0u || (a->pf.ground & (1u << j)) != 0u;
      on[j][1] = (cmd_hi && (a->pf.open & PLANT_SW_HIGH(j)) == 0u) ||
                 (a->pf.closed & PLANT_SW_HIGH(j)) != 0u;
      shoot |= on[j][0] && on[j][1];
    }
    if (a->pf.shorted != 0u) { /* through the short */
      shoot |= (on[x][0] && on[y][1]) || (on[x][1] && on[y][0]);
    }
    if (!shoot) {
      break;
    }
    a->desat = 1; /* the second pass: healthy switches off */
  }
  for (int j = 0; j < 3; j++) {
    if ((a->pf.phase_open & (1u << j)) != 0u) {
      type[j] = LEG_OPEN;
    } else {
      type[j] = on[j][1] ? LEG_HI : (on[j][0] ? LEG_LO : LEG_FLOAT);
    }
  }
  if (a->pf.shorted != 0u) {
    short_node(lg, x, y, z);
  }
}

void plant_inverter_sw_period(plant_t *pl, const double on[3], const double off[3], bool gates_on,
                              double *x, double cs_end[2]) {
  plant_aux_t *a = &pl->aux;
  const double ts = pl->p.ts, td = pl->p.inverter.dead_time;
  edges_t ed[3];
  double ev[2 + 3 * 2 * SW_MAX_EDGES + PLANT_STAR_MAX];
  int nev = 0;
  ev[nev++] = 0.0;
  ev[nev++] = ts;
  for (int j = 0; j < 3; j++) {
    edges_t *e = &ed[j];
    e->n = 0;
    e->te[e->n] = a->edge_t[j];
    e->cmd[e->n++] = a->edge_cmd[j];
    if (!gates_on) {
      continue;
    }
    /* high over [on, off): on at the period start when on = 0 (and off
     * = 1: the whole period) */
    const double d = off[j] - on[j];
    const int h0 = d > 0.0 && on[j] <= 0.0;
    if (!a->gates_prev || h0 != a->edge_cmd[j]) {
      e->te[e->n] = 0.0;
      e->cmd[e->n++] = h0;
    }
    if (d > 0.0 && on[j] > 0.0) {
      e->te[e->n] = on[j] * ts;
      e->cmd[e->n++] = 1;
    }
    if (d > 0.0 && off[j] < 1.0) {
      e->te[e->n] = off[j] * ts;
      e->cmd[e->n++] = 0;
    }
    for (int k = 0; k < e->n; k++) {
      if (e->te[k] > 0.0 && e->te[k] < ts) {
        ev[nev++] = e->te[k];
      }
      if (e->te[k] + td > 0.0 && e->te[k] + td < ts) {
        ev[nev++] = e->te[k] + td;
      }
    }
  }
  for (int k = 0; k < a->star_n; k++) {
    ev[nev++] = a->star_t[k]; /* star-point samples end an interval */
  }
  for (int i = 1; i < nev; i++) { /* insertion sort, <= 28 entries */
    const double v = ev[i];
    int k = i - 1;
    while (k >= 0 && ev[k] > v) {
      ev[k + 1] = ev[k];
      k--;
    }
    ev[k + 1] = v;
  }

  sw_cfg_t cf;
  for (int j = 0; j < 3; j++) {
    cf.type[j] = a->cond[j] == COND_NONE ? LEG_LO : LEG_FLOAT;
    cf.cond[j] = a->cond[j];
    cf.rl[j] = 0.0;
    cf.rh[j] = 1.0;
  }
  cf.node = -1;
  cf.all_zero = a->all_zero;
  cf.blocked = -1;
  if (x[X_TH] == pl->theta_m) { /* always, from plant_step: the current cache's angle */
    const plant_cur_cache_t *cc = plant_machine_cur(pl);
    cf.th_ref = cc->th_e;
    cf.c_ref = cc->c;
    cf.s_ref = cc->s;
  } else {
    cf.th_ref = pl->p.machine.pole_pairs * x[X_TH];
    cf.c_ref = cos(cf.th_ref);
    cf.s_ref = sin(cf.th_ref);
  }
  double t = pl->t;
  int ks = 0;      /* next star-point sample */
  int vf_init = 0; /* the circuit's state set (settled in the zero vector) */
  for (int i = 0; i + 1 < nev; i++) {
    const double len = ev[i + 1] - ev[i];
    if (len > 1e-12 * ts) {
      const double mid = 0.5 * (ev[i] + ev[i + 1]);
      sw_legs_t lg = {{LEG_FLOAT, LEG_FLOAT, LEG_FLOAT}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, -1};
      for (int j = 0; j < 3; j++) {
        lg.type[j] = gates_on ? leg_type_at(&ed[j], mid, td) : LEG_FLOAT;
      }
      if (a->pf_any) {
        sw_fault_legs(a, &lg);
      }
      sw_setup(pl, &cf, x, &lg);
      if (!vf_init && a->star_n > 0) {
        a->star_vf = sw_star(pl, &cf, t, x);
        vf_init = 1;
      }
      sw_integrate(pl, &cf, &t, x, len);
    }
    while (ks < a->star_n && a->star_t[ks] <= ev[i + 1]) {
      a->star_v[ks++] = a->star_vf;
    }
  }

  /* memory for the next period */
  for (int j = 0; j < 3; j++) {
    a->cond[j] = cf.type[j] == LEG_FLOAT || cf.type[j] == LEG_OPEN ? cf.cond[j] : COND_NONE;
    if (gates_on) {
      a->edge_t[j] = ed[j].te[ed[j].n - 1] - ts;
      a->edge_cmd[j] = ed[j].cmd[ed[j].n - 1];
    }
  }
  a->all_zero = cf.all_zero;
  a->gates_prev = gates_on;
  /* star point at the valley that ends the period */
  double dx[X_N];
  sw_out_t o;
  sw_deriv(pl, &cf, x, plant_mech_input(pl, pl->t + ts), dx, &o);
  a->v_star = o.vn0 - 0.5 * o.vdc;
  sw_cos_sin(pl, &cf, x, &cs_end[0], &cs_end[1]); /* the end angle's, for the current cache */
}

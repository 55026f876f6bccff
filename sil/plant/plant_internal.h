/*
 * plant_internal.h - shared by the plant_*.c files only: constants, the
 * integration state vector and the small inline pieces (mechanics, DC link)
 * that the inner loops of both inverter models call.
 */
#ifndef FD_PLANT_INTERNAL_H
#define FD_PLANT_INTERNAL_H

#include "plant.h"

#include <math.h>
#include <stddef.h>

#define PLANT_PI        3.14159265358979323846
#define PLANT_TWO_PI    6.28318530717958647692
#define PLANT_SQRT3_2   0.86602540378443864676 /* sqrt(3)/2 */
#define PLANT_INV_SQRT3 0.57735026918962576451 /* 1/sqrt(3) */
/* Periods over which cos/sin of the rotor angle are carried by angle
 * addition from one period to the next (plant_step) before libm
 * recomputes them: each carry adds ~2 ulp, so they stay within ~1e-14 of
 * libm's values. */
#define PLANT_CARRY_MAX 16

/* cos and sin of an angle th near a reference angle th_ref whose cos and
 * sin (c_ref, s_ref) are known: angle addition with the Taylor series of
 * dt = th - th_ref (|dt| <= 0.3 rad: truncation < 3e-17, a few ulp from
 * libm), libm beyond. Both inverter models carry the rotor angle of their
 * stages this way from one reference per period (issue 24: libm sin/cos at
 * every derivative was 31-54 % of a switching run). */
static inline void plant_cos_sin_near(double th_ref, double c_ref, double s_ref, double th,
                                      double *c, double *s) {
  const double dt = th - th_ref;
  if (dt > 0.3 || dt < -0.3) {
    *c = cos(th);
    *s = sin(th);
    return;
  }
  const double z = dt * dt, z2 = z * z, z4 = z2 * z2;
  /* Taylor coefficients, Estrin evaluation (short dependency chains); for
   * |dt| <= 1/16 (a switching period's stages at speed) the terms up to
   * dt^7 and dt^8 suffice (truncation < 5e-17, below half an ulp of 1) */
  double sd, cd;
  if (z <= 1.0 / 256.0) {
    sd = dt * ((1.0 - z * (1.0 / 6.0)) + z2 * ((1.0 / 120.0) - z * (1.0 / 5040.0)));
    cd = (1.0 - z * 0.5) + z2 * ((1.0 / 24.0) - z * (1.0 / 720.0)) + z4 * (1.0 / 40320.0);
  } else {
    sd = dt * ((1.0 - z * (1.0 / 6.0)) + z2 * ((1.0 / 120.0) - z * (1.0 / 5040.0)) +
               z4 * ((1.0 / 362880.0) - z * (1.0 / 39916800.0)));
    cd = (1.0 - z * 0.5) + z2 * ((1.0 / 24.0) - z * (1.0 / 720.0)) +
         z4 * ((1.0 / 40320.0) - z * (1.0 / 3628800.0) + z2 * (1.0 / 479001600.0));
  }
  *c = c_ref * cd - s_ref * sd;
  *s = s_ref * cd + c_ref * sd;
}

/* floor(y), bit for bit, without the libm call (x86-64 without SSE4.1 has no
 * rounding instruction: floor is a call on every period's wraps, ADC codes
 * and encoder count): the truncation, one lower for a negative fraction;
 * libm for |y| >= 2^52 (already an integer) and NaN; -0.0 gives +0.0, which
 * every caller adds to or scales. With SSE4.1 (the release runner's
 * x86-64-v2, sil/CMakeLists.txt) floor is the ROUNDSD instruction. */
static inline double plant_floor(double y) {
#if defined(__SSE4_1__)
  return floor(y); /* ROUNDSD (x86-64-v2 release runner): one instruction */
#else
  if (!(y > -4503599627370496.0 && y < 4503599627370496.0)) {
    return floor(y);
  }
  const double t = (double)(long long)y;
  return t > y ? t - 1.0 : t;
#endif
}

/* Integration state vector. The last four entries are integrals over the
 * period (reset to 0 at its start) from which the period averages are taken. */
enum {
  X_LD,  /* lambda_d [Vs] */
  X_LQ,  /* lambda_q [Vs] */
  X_TH,  /* theta_m [rad] (not wrapped inside a period) */
  X_W,   /* omega_m [rad/s] */
  X_VC,  /* DC-link capacitor voltage [V] (constant v_source for an ideal link) */
  X_VA,  /* integral of v_an [V s] */
  X_VB,  /* integral of v_bn [V s] */
  X_VN,  /* integral of (star point w.r.t. DC midpoint) [V s] */
  X_IDC, /* integral of the DC-link current drawn by the inverter [A s] */
  X_TE,  /* integral of the electromagnetic torque [N m s] */
  X_ID,  /* integrals of the rotor-frame currents [A s] */
  X_IQ,
  X_N
};

/* Mechanical input at time t: the imposed speed [rad/s] (IMPOSED) or the
 * load torque [N m] (FREE), plus the passive load's Coulomb torque of the
 * period (aux.fric, 0 unless injected; FREE only). Bit-identical to evaluating the profile; taken
 * from the span cache (plant_mech_input_refresh) while the profile is
 * constant. */
static inline double plant_mech_input(const plant_t *pl, double t) {
  const plant_aux_t *a = &pl->aux;
  if (t >= a->m_t0 && t < a->m_t1) {
    return a->m_val + a->fric;
  }
  const plant_mech_t *m = &pl->p.mech;
  return profile_eval(m->mode == PLANT_MECH_IMPOSED ? &m->speed : &m->load_torque, t) + a->fric;
}

/* Refreshes the span cache of plant_mech_input when the period starting at
 * the present time is not inside it (once per profile change, or every
 * period while the profile is not constant). */
static inline void plant_mech_input_refresh(plant_t *pl) {
  plant_aux_t *a = &pl->aux;
  const double t = pl->t;
  if (t >= a->m_t0 && t + pl->p.ts < a->m_t1) {
    return;
  }
  const plant_mech_t *m = &pl->p.mech;
  a->m_val =
      profile_eval_span(m->mode == PLANT_MECH_IMPOSED ? &m->speed : &m->load_torque, t, &a->m_t1);
  a->m_t0 = t;
}

/* The cogging torque at mechanical angle theta [rad] (plant_mech.c):
 * cog = {amplitude [N m], order, phase [rad]}. */
static inline double plant_mech_cogging(const double cog[3], double theta) {
  /* mut: cogging_order_dropped */
  return cog[0] * sin(cog[1] * theta + cog[2]);
}

/* Mechanics (plant_mech.c documents the convention):
 * FREE:    J dw/dt = T_e + T_cog(theta) - B w - T_load(t), dtheta/dt = w
 * IMPOSED: w = speed(t) (m), dtheta/dt = speed(t), the state w is set from
 *          the profile at the end of each step. */
static inline void plant_mech_deriv(const plant_t *pl, const double *x, double m, double te,
                                    double *dx) {
  if (pl->p.mech.mode == PLANT_MECH_IMPOSED) {
    dx[X_TH] = m;
    dx[X_W] = 0.0;
  } else {
    dx[X_TH] = x[X_W];
    const plant_mech_t *me = &pl->p.mech;
    const double tn = te - me->b * x[X_W] - m;
    if (me->cog_amp != 0.0) {
      const double cog[3] = {me->cog_amp, (double)me->cog_order, me->cog_phase};
      dx[X_W] = (tn + plant_mech_cogging(cog, x[X_TH])) * pl->aux.inv_j;
    } else {
      dx[X_W] = tn * pl->aux.inv_j;
    }
  }
}

/* Speed in force at a stage. */
static inline double plant_mech_speed(const plant_t *pl, const double *x, double m) {
  return pl->p.mech.mode == PLANT_MECH_IMPOSED ? m : x[X_W];
}

/* DC-link voltage seen by the inverter legs (a capacitor cannot be reverse
 * biased through the free-wheeling diodes: clamp at 0). */
static inline double plant_dclink_voltage(const plant_t *pl, const double *x) {
  if (pl->p.dclink.kind == PLANT_DC_IDEAL) {
    return pl->p.dclink.v_source;
  }
  return x[X_VC] > 0.0 ? x[X_VC] : 0.0;
}

/* The source's current into the link at capacitor voltage v: (Vs - v)/R,
 * not negative through a rectifier's diode. */
static inline double plant_dclink_source(double vs, double v, double inv_r, int one_way) {
  const double i = (vs - v) * inv_r;
  /* mut: rectifier_two_way */
  return one_way && i < 0.0 ? 0.0 : i;
}

/* dv_C/dt for a current i_dc drawn by the inverter:
 * C dv/dt = i_source(v) - v g_chop - i_dc. */
static inline double plant_dclink_deriv(const plant_t *pl, const double *x, double idc) {
  if (pl->p.dclink.kind == PLANT_DC_IDEAL) {
    return 0.0;
  }
  return (plant_dclink_source(pl->p.dclink.v_source, x[X_VC], pl->aux.inv_r, pl->aux.one_way) -
          x[X_VC] * pl->aux.g_chop - idc) *
         pl->aux.inv_c;
}

/* plant_machine.c */
int plant_machine_check(const plant_machine_t *m, const char **field);
/* True currents of the present state, computed into c (keyed on it);
 * _fill with co, si = cos, sin(pole_pairs * theta_m) already known. */
void plant_machine_cur_compute(const plant_t *pl, plant_cur_cache_t *c);
void plant_machine_cur_fill(const plant_t *pl, plant_cur_cache_t *c, double co, double si);
static inline int plant_machine_cur_fresh(const plant_t *pl) {
  const plant_cur_cache_t *c = &pl->aux.cur;
  return c->key[0] == pl->lambda_d && c->key[1] == pl->lambda_q && c->key[2] == pl->theta_m;
}
/* The cached true currents of the present state (computed once per state:
 * the sensors, the metrics and the next period's rotor angle share them). */
static inline const plant_cur_cache_t *plant_machine_cur(plant_t *pl) {
  if (!plant_machine_cur_fresh(pl)) {
    plant_machine_cur_compute(pl, &pl->aux.cur);
  }
  return &pl->aux.cur;
}
/* plant_brief_t of the present state, i_abc its cached true currents. */
static inline void plant_brief_of(const plant_t *pl, const double i_abc[3], plant_brief_t *out) {
  out->i_abc[0] = i_abc[0];
  out->i_abc[1] = i_abc[1];
  out->i_abc[2] = i_abc[2];
  out->omega_m = pl->omega_m;
  out->v_dc = pl->v_dc;
}
/* c, s: cos and sin of pole_pairs * x[X_TH] */
void plant_machine_zero_phase_current_cs(const plant_t *pl, double *x, int leg, double c, double s);

/* plant_inverter.c, plant_inverter_avg.c, plant_inverter_sw.c */
int plant_inverter_check(const plant_inverter_t *inv, double ts, const char **field);
void plant_inverter_init(plant_t *pl);
void plant_inverter_avg_period(plant_t *pl, const double duty[3], double *x, double cs_end[2]);
/* Not inlined into plant_step_pattern (the release runner's link-time
 * inliner would): the average model's usual period then runs without the
 * switching model's stack frame and register saves. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
void plant_inverter_sw_period(plant_t *pl, const double on[3], const double off[3], bool gates_on,
                              double *x, double cs_end[2]);

/* plant_dclink.c */
int plant_dclink_check(const plant_dclink_t *d, const char **field);
/* The braking chopper's state for the period starting now (hysteresis on
 * the capacitor voltage). */
void plant_dclink_chopper(plant_t *pl);

/* plant_mech.c */
int plant_mech_check(const plant_mech_t *m, const char **field);
void plant_mech_end_step(const plant_t *pl, double *x, double t_end);

/* plant_faults.c: checks; the parameters of the period starting now (R_s,
 * PM flux, 1/C, B, the Coulomb torque and its direction); the end of the
 * period (a rotor the friction held or stopped: w = 0, never reversed;
 * cs_end[0] = NAN when the angle was reset). */
int plant_faults_check(const plant_params_t *p, const char **field);
void plant_faults_init(plant_t *pl);
void plant_faults_period_start(plant_t *pl);
void plant_faults_period_end(plant_t *pl, double *x, double cs_end[2]);

/* plant_sensors.c */
int plant_sensors_check(const plant_sensors_t *s, const char **field);
void plant_sensors_init(plant_t *pl);

/* plant_star.c: the star point w.r.t. the negative rail for leg
 * potentials v, phase currents i, electrical angle (its cos and sin) and
 * speed, the q
 * current (load shift) and back-EMF e; the measurement circuit over a step
 * of length h whose input went linearly from v0 to v1. */
double plant_star_vn(const plant_t *pl, const double v[3], const double i[3], double c_e,
                     double s_e, double we, double i_q, const double e[3]);
void plant_star_filter(plant_t *pl, double v0, double v1, double h);
/* plant_sensors.c: one standard normal number from the plant's generator */
double plant_sensors_normal(plant_t *pl);

/* Small helpers. */
static inline int plant_finite_pos(double v) {
  return v > 0.0 && v < 1e300; /* false for NaN and +inf */
}
static inline int plant_finite_nonneg(double v) {
  return v >= 0.0 && v < 1e300;
}

#endif

/*
 * plant.c - parameter check, initialisation and the per-period orchestration
 * of the plant (plant.h). One period: the machine flux linkages, rotor angle
 * and speed and the DC-link capacitor voltage are integrated together,
 *   gates on,  PLANT_INV_AVERAGE:   plant_inverter_avg.c
 *   gates on,  PLANT_INV_SWITCHING: plant_inverter_sw.c
 *   gates off, either model:        plant_inverter_sw.c (diodes only)
 * Star-point voltage (plant_adc_t.v_star, w.r.t. the DC-link midpoint): the
 * star point of the isotropic model sits at the mean of the three leg
 * potentials. Switching model: taken at the valley from the actual switch /
 * diode state (gates on and d < 1: all low sides on -> -v_dc/2). Average
 * model: there is no switching state, it is the period average of the mean
 * leg potential minus v_dc/2.
 */
#include "plant_internal.h"

#include <math.h>
#include <string.h>

/* The smallest incremental inductance of a linear machine: ld lowered by
 * the magnet's saturation (plant_magnetics.h), lq. */
static double linear_l_min(const plant_machine_t *m) {
  const double ld = m->ld / (1.0 + (m->ld_sat > 0.0 ? m->ld_sat : 0.0));
  return ld < m->lq ? ld : m->lq;
}

int plant_substeps_link(const plant_params_t *p) {
  if (p->dclink.kind == PLANT_DC_IDEAL || !plant_finite_pos(p->dclink.r) ||
      !plant_finite_pos(p->dclink.c)) {
    return 1; /* no capacitor, or one plant_check refuses */
  }
  double lo = 1.0, hi = 1.0;
  if (p->faults.c_scale.n > 0) {
    profile_bounds(&p->faults.c_scale, &lo, &hi);
  }
  /* the chopper's resistance (when smaller) sets the faster pole */
  const double r =
      p->dclink.r_chop > 0.0 && p->dclink.r_chop < p->dclink.r ? p->dclink.r_chop : p->dclink.r;
  const double n = ceil(p->ts / (PLANT_HC_MAX * r * p->dclink.c * lo));
  if (!(n < 1e6)) { /* NaN, inf, a scale down to 0: beyond any limit */
    return 1000000;
  }
  return n < 1.0 ? 1 : (int)n;
}

int plant_substeps_mech(const plant_params_t *p) {
  if (p->mech.mode == PLANT_MECH_IMPOSED || !plant_finite_pos(p->mech.j)) {
    return 1; /* no mechanical state, or one plant_check refuses */
  }
  const double lmin =
      p->machine.map != NULL ? plant_fluxmap_l_min(p->machine.map) : linear_l_min(&p->machine);
  double psi = fabs(p->machine.lambda_m);
  if (p->machine.map != NULL) {
    double pd = 0.0, pq = 0.0;
    plant_fluxmap_flux0(p->machine.map, &pd, &pq);
    psi = sqrt(pd * pd + pq * pq);
  }
  double lo = 1.0, hi = 1.0;
  if (p->faults.lambda_m_scale.n > 0) {
    profile_bounds(&p->faults.lambda_m_scale, &lo, &hi);
    psi *= hi > 1.0 ? hi : 1.0;
  }
  double b = p->mech.b;
  if (p->faults.viscous.n > 0) {
    profile_bounds(&p->faults.viscous, &lo, &hi);
    b += hi > 0.0 ? hi : 0.0;
  }
  const double w_em = p->machine.pole_pairs * psi * sqrt(1.5 / (lmin * p->mech.j));
  const double n_em = ceil(p->ts * w_em / PLANT_HW_MAX);
  const double n_b = ceil(p->ts * b / (PLANT_HC_MAX * p->mech.j));
  double n = n_em > n_b ? n_em : n_b;
  if (p->mech.cog_amp != 0.0) { /* the cogging torque's stiffness A N (plant_mech.c) */
    const double w_cog = sqrt(fabs(p->mech.cog_amp) * p->mech.cog_order / p->mech.j);
    const double n_cog = ceil(p->ts * w_cog / PLANT_HW_MAX);
    n = n_cog > n ? n_cog : n;
  }
  if (!(n < 1e6)) { /* NaN, inf: beyond any limit */
    return 1000000;
  }
  return n < 1.0 ? 1 : (int)n;
}

int plant_substeps_needed(const plant_params_t *p) {
  const double lmin =
      p->machine.map != NULL ? plant_fluxmap_l_min(p->machine.map) : linear_l_min(&p->machine);
  double lo = 1.0, hi = 1.0;
  if (p->faults.rs_scale.n > 0) {
    profile_bounds(&p->faults.rs_scale, &lo, &hi);
  }
  /* the device drops' resistance (plant_inverter_t) is in series with R_s */
  const double r_dev = fmax(p->inverter.r_on_sw, p->inverter.r_diode);
  const double n = ceil(p->ts * (p->machine.rs * hi + r_dev) / (PLANT_HR_MAX * lmin));
  if (!(n < 1e6)) { /* NaN, inf: beyond any limit */
    return 1000000;
  }
  const int nl = plant_substeps_link(p), nm = plant_substeps_mech(p);
  const int no = nl > nm ? nl : nm;
  return n < 1.0 ? (no > 1 ? no : 1) : ((int)n > no ? (int)n : no);
}

int plant_steps_last(const plant_t *pl) {
  return pl->aux.steps;
}

double plant_speed_limit_e(const plant_t *pl) {
  return pl->aux.we_max;
}

bool plant_too_fast(const plant_t *pl) {
  return pl->aux.too_fast != 0;
}

/* This period's steps: the scenario's, or more at speed (plant.h). 0: too
 * fast to integrate. */
static int period_steps(const plant_t *pl) {
  double w = fabs(pl->omega_m);
  if (pl->p.mech.mode == PLANT_MECH_IMPOSED) {
    const double w1 = fabs(plant_mech_input(pl, pl->t + pl->p.ts));
    w = w1 > w ? w1 : w;
  } else { /* the speed the load alone reaches by the period's end */
    w += fabs(plant_mech_input(pl, pl->t)) * pl->aux.inv_j * pl->p.ts;
  }
  const double we = (double)pl->p.machine.pole_pairs * w;
  if (!(we <= plant_speed_limit_e(pl))) {
    return 0;
  }
  /* ceil(y) > substeps exactly when y > substeps (an integer): the usual
   * period, within the scenario's steps, needs no ceil (without SSE4.1's
   * rounding instruction, a sequence of ~20 instructions) */
  const double y = we * pl->p.ts / PLANT_HW_MAX;
  const int ns = pl->p.inverter.substeps;
  return y > (double)ns ? (int)ceil(y) : ns;
}

int plant_check(const plant_params_t *p, const char **field) {
  const char *dummy = NULL;
  const char **f = field != NULL ? field : &dummy;
  if (!plant_finite_pos(p->ts)) {
    *f = "ts";
    return -1;
  }
  if (plant_machine_check(&p->machine, f) != 0 ||
      plant_inverter_check(&p->inverter, p->ts, f) != 0 || plant_dclink_check(&p->dclink, f) != 0 ||
      plant_mech_check(&p->mech, f) != 0 || plant_sensors_check(&p->sensors, f) != 0 ||
      plant_faults_check(p, f) != 0) {
    return -1;
  }
  if (p->inverter.substeps < plant_substeps_needed(p)) { /* unstable: NaN within periods */
    *f = "inverter.substeps";
    return -1;
  }
  return 0;
}

static double wrap_2pi(double a) {
  a -= PLANT_TWO_PI * plant_floor(a * (1.0 / PLANT_TWO_PI));
  return a >= PLANT_TWO_PI ? 0.0 : a;
}

int plant_init(plant_t *pl, const plant_params_t *p, const char **field) {
  const int rc = plant_check(p, field);
  if (rc != 0) {
    return rc;
  }
  memset(pl, 0, sizeof *pl);
  pl->p = *p;
  plant_aux_t *a = &pl->aux;
  a->mag = p->machine.map != NULL
               ? plant_mag_map(p->machine.map)
               : plant_mag_linear(p->machine.ld, p->machine.lq, p->machine.lambda_m);
  if (p->machine.map == NULL && p->machine.ld_sat > 0.0) {
    a->mag.sat = p->machine.ld_sat;
    a->mag.i_sat = p->machine.i_sat;
  }
  a->inv_j = 1.0 / p->mech.j;
  a->inv_r = p->dclink.kind != PLANT_DC_IDEAL ? 1.0 / p->dclink.r : 0.0;
  a->inv_c = p->dclink.kind != PLANT_DC_IDEAL ? 1.0 / p->dclink.c : 0.0;
  a->one_way = p->dclink.kind == PLANT_DC_RECTIFIER;
  a->kdt = p->inverter.dead_time / p->ts;
  a->inv_ts = 1.0 / p->ts;
  a->we_max = PLANT_STEPS_SPEED_MAX * PLANT_HW_MAX / p->ts;
  plant_inverter_init(pl);
  for (int j = 0; j < 3; j++) {
    a->edge_t[j] = -1e30; /* no command edge yet */
    a->edge_cmd[j] = 0;
    a->cond[j] = -1;
  }
  a->all_zero = 0;
  a->gates_prev = 0;
  a->v_star = 0.0;
  a->star_n = 0;
  a->l0 = 0.5 * (p->machine.ld + p->machine.lq) + p->machine.aniso.m0;
  a->l2 = (p->machine.ld - p->machine.lq) - 2.0 * p->machine.aniso.m2;
  pl->t = 0.0;
  a->steps = p->inverter.substeps;
  a->too_fast = 0;
  plant_mag_flux0(&a->mag, &pl->lambda_d, &pl->lambda_q); /* zero current */
  pl->theta_m = wrap_2pi(p->mech.theta0);
  pl->omega_m =
      p->mech.mode == PLANT_MECH_IMPOSED ? profile_eval(&p->mech.speed, 0.0) : p->mech.omega0;
  pl->v_dc = p->dclink.v_source;
  a->cur.key[0] = NAN; /* no cached currents */
  a->avgs = 1;
  plant_sensors_init(pl);
  plant_faults_init(pl);
  return 0;
}

static double clamp_duty(double d) {
  if (!(d >= 0.0)) {
    return d < 0.0 ? 0.0 : 0.5; /* NaN: no voltage, like hal_sil */
  }
  return d > 1.0 ? 1.0 : d;
}

void plant_step(plant_t *pl, const double duty[3], bool gates_on) {
  double on[3], off[3];
  for (int j = 0; j < 3; j++) {
    const double d = clamp_duty(duty[j]);
    on[j] = 0.5 * (1.0 - d);
    off[j] = 0.5 * (1.0 + d);
  }
  plant_step_pattern(pl, on, off, gates_on);
}

void plant_step_pattern(plant_t *pl, const double on_in[3], const double off_in[3], bool gates_on) {
  double on[3], off[3], d[3];
  for (int j = 0; j < 3; j++) {
    on[j] = clamp_duty(on_in[j]);
    off[j] = clamp_duty(off_in[j]);
    off[j] = off[j] < on[j] ? on[j] : off[j];
    d[j] = off[j] - on[j];
  }
  const double ts = pl->p.ts;
  if (pl->aux.too_fast) {
    return; /* the run must end (plant_too_fast) */
  }
  plant_mech_input_refresh(pl);
  pl->aux.steps = period_steps(pl);
  if (pl->aux.steps == 0) {
    pl->aux.too_fast = 1;
    return;
  }
  plant_faults_period_start(pl);
  plant_dclink_chopper(pl);
  double x[X_N] = {pl->lambda_d, pl->lambda_q, pl->theta_m, pl->omega_m, pl->v_dc, 0, 0, 0, 0};
  const int avg = pl->p.inverter.model == PLANT_INV_AVERAGE;
  double cs_end[2] = {NAN, NAN}; /* cos, sin of the end angle (both models) */
  if (gates_on && avg && !pl->aux.pf_any) {
    plant_inverter_avg_period(pl, d, x, cs_end);
    for (int j = 0; j < 3; j++) {
      pl->aux.cond[j] = -1; /* all legs driven: no diode state */
    }
    pl->aux.all_zero = 0;
    pl->aux.gates_prev = 1;
  } else {
    plant_inverter_sw_period(pl, on, off, gates_on, x, cs_end);
  }
  plant_faults_period_end(pl, x, cs_end);
  const double inv_ts = pl->aux.inv_ts;
  if (pl->aux.avgs) { /* else NaN (plant_set_averages) */
    pl->v_abc_avg[0] = x[X_VA] * inv_ts;
    pl->v_abc_avg[1] = x[X_VB] * inv_ts;
    pl->v_abc_avg[2] = -(pl->v_abc_avg[0] + pl->v_abc_avg[1]);
    pl->i_dc_avg = x[X_IDC] * inv_ts;
    pl->torque_avg = x[X_TE] * inv_ts;
    pl->i_dq_avg[0] = x[X_ID] * inv_ts;
    pl->i_dq_avg[1] = x[X_IQ] * inv_ts;
  }
  if (avg) {
    pl->aux.v_star = x[X_VN] * inv_ts;
    for (int k = 0; k < pl->aux.star_n; k++) { /* no switching instants */
      pl->aux.star_v[k] = pl->aux.v_star + 0.5 * pl->v_dc;
    }
  }
  pl->lambda_d = x[X_LD];
  pl->lambda_q = x[X_LQ];
  pl->theta_m = wrap_2pi(x[X_TH]);
  pl->omega_m = x[X_W];
  pl->v_dc = pl->p.dclink.kind == PLANT_DC_IDEAL ? pl->p.dclink.v_source : x[X_VC];
  pl->aux.n_steps++;
  pl->t = (double)pl->aux.n_steps * ts;
  if (pl->p.mech.mode == PLANT_MECH_IMPOSED) {
    pl->omega_m = plant_mech_input(pl, pl->t); /* exactly the profile */
  }
  /* The true currents of the new state, for plant_sample, the metrics and
   * the next period. cos/sin of the new rotor angle: carried from the
   * period's reference by the integrator when the angle did not wrap (then
   * pole_pairs * theta_m is exactly the angle they belong to), from libm
   * otherwise and every PLANT_CARRY_MAX periods. */
  if (!isnan(cs_end[0]) && pl->theta_m == x[X_TH] && ++pl->aux.carry_n < PLANT_CARRY_MAX) {
    plant_machine_cur_fill(pl, &pl->aux.cur, cs_end[0], cs_end[1]);
  } else {
    pl->aux.carry_n = 0;
    plant_machine_cur_compute(pl, &pl->aux.cur);
  }
}

static inline double torque_of(const plant_t *pl, const plant_cur_cache_t *c) {
  return 1.5 * pl->p.machine.pole_pairs * (pl->lambda_d * c->i_dq[1] - pl->lambda_q * c->i_dq[0]);
}

void plant_get_brief(plant_t *pl, plant_brief_t *out) {
  plant_brief_of(pl, plant_machine_cur(pl)->i_abc, out);
}

double plant_get_torque(plant_t *pl) {
  return torque_of(pl, plant_machine_cur(pl));
}

void plant_get_state(const plant_t *pl, plant_state_t *out) {
  plant_cur_cache_t fresh;
  const plant_cur_cache_t *c = &pl->aux.cur;
  if (!plant_machine_cur_fresh(pl)) {
    plant_machine_cur_compute(pl, &fresh);
    c = &fresh;
  }
  out->t = pl->t;
  out->i_dq[0] = c->i_dq[0];
  out->i_dq[1] = c->i_dq[1];
  for (int k = 0; k < 3; k++) {
    out->i_abc[k] = c->i_abc[k];
  }
  out->lambda_dq[0] = pl->lambda_d;
  out->lambda_dq[1] = pl->lambda_q;
  for (int k = 0; k < 3; k++) {
    out->v_abc[k] = pl->v_abc_avg[k];
  }
  out->theta_m = pl->theta_m;
  out->theta_e = wrap_2pi(c->th_e);
  out->omega_m = pl->omega_m;
  out->torque = torque_of(pl, c);
  out->load_torque = pl->p.mech.mode == PLANT_MECH_FREE ? plant_mech_input(pl, pl->t) : 0.0;
  out->v_dc = pl->v_dc;
  out->i_dc = pl->i_dc_avg;
  out->torque_avg = pl->torque_avg;
  out->i_dq_avg[0] = pl->i_dq_avg[0];
  out->i_dq_avg[1] = pl->i_dq_avg[1];
}

int plant_set_power_faults(plant_t *pl, const plant_power_fault_t *f) {
  for (int j = 0; j < 3; j++) {
    const unsigned both = PLANT_SW_LOW(j) | PLANT_SW_HIGH(j);
    if ((f->closed & both) == both) {
      return -1;
    }
  }
  const unsigned sh = f->shorted & 0x7u;
  if ((sh != 0u && sh != 0x3u && sh != 0x5u && sh != 0x6u) || (sh & f->phase_open) != 0u) {
    return -1; /* one pair; an open lead cannot be shorted to its partner */
  }
  pl->aux.pf.open = f->open & 0x3Fu;
  pl->aux.pf.closed = f->closed & 0x3Fu;
  pl->aux.pf.phase_open = f->phase_open & 0x7u;
  pl->aux.pf.ground = f->ground & 0x7u;
  pl->aux.pf.shorted = sh;
  pl->aux.pf_any = (pl->aux.pf.open | pl->aux.pf.closed | pl->aux.pf.phase_open |
                    pl->aux.pf.ground | pl->aux.pf.shorted) != 0u;
  return 0;
}

void plant_set_averages(plant_t *pl, bool on) {
  pl->aux.avgs = on ? 1 : 0;
  if (!on) {
    pl->v_abc_avg[0] = pl->v_abc_avg[1] = pl->v_abc_avg[2] = NAN;
    pl->i_dc_avg = pl->torque_avg = pl->i_dq_avg[0] = pl->i_dq_avg[1] = NAN;
  }
}

bool plant_take_desat(plant_t *pl) {
  const bool d = pl->aux.desat != 0;
  pl->aux.desat = 0;
  return d;
}

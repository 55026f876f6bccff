/*
 * test_check.c - plant_check rejects each bad parameter and names it;
 * plant_init refuses too; profile evaluation and profile_add limits.
 */
#include "plant_test_util.h"

typedef struct {
  const char *field;
  void (*spoil)(plant_params_t *p);
} bad_case_t;

#define SPOIL(name, stmt)                                                                          \
  static void name(plant_params_t *p) {                                                            \
    stmt;                                                                                          \
  }
SPOIL(s_ts, p->ts = 0.0)
SPOIL(s_ts_nan, p->ts = NAN)
SPOIL(s_pp, p->machine.pole_pairs = 0)
SPOIL(s_rs, p->machine.rs = -0.1)
SPOIL(s_rs_inf, p->machine.rs = INFINITY)
SPOIL(s_ld, p->machine.ld = 0.0)
SPOIL(s_lq, p->machine.lq = NAN)
SPOIL(s_lm, p->machine.lambda_m = -0.01)
SPOIL(s_model, p->inverter.model = (plant_inverter_model_t)7)
SPOIL(s_td_neg, p->inverter.dead_time = -1e-9)
SPOIL(s_td_big, p->inverter.dead_time = 0.25 * p->ts)
SPOIL(s_sub0, p->inverter.substeps = 0)
SPOIL(s_sub65, p->inverter.substeps = 65)
SPOIL(s_dckind, p->dclink.kind = (plant_dc_kind_t)3)
SPOIL(s_vs, p->dclink.v_source = 0.0)
SPOIL(s_r, p->dclink.kind = PLANT_DC_RC; p->dclink.r = 0.0)
SPOIL(s_c, p->dclink.kind = PLANT_DC_RC; p->dclink.c = -1e-3)
SPOIL(s_mode, p->mech.mode = (plant_mech_mode_t)5)
SPOIL(s_j, p->mech.j = 0.0)
SPOIL(s_b, p->mech.b = -1e-3)
SPOIL(s_th0, p->mech.theta0 = NAN)
SPOIL(s_w0, p->mech.omega0 = INFINITY)
SPOIL(s_ln, p->mech.load_torque.n = PROFILE_MAX_TERMS + 1)
SPOIL(s_lkind, p->mech.load_torque.n = 1; p->mech.load_torque.term[0].kind = (profile_kind_t)9)
SPOIL(s_lval, p->mech.load_torque.n = 1; p->mech.load_torque.term[0].value = NAN)
SPOIL(s_sramp, p->mech.speed.n = 1; p->mech.speed.term[0].kind = PROFILE_RAMP;
      p->mech.speed.term[0].t0 = 1.0; p->mech.speed.term[0].t1 = 1.0)
SPOIL(s_sfreq, p->mech.speed.n = 1; p->mech.speed.term[0].kind = PROFILE_SINE;
      p->mech.speed.term[0].freq = -1.0)
SPOIL(s_sn, p->mech.speed.n = -1)
SPOIL(s_bits7, p->sensors.adc_bits = 7)
SPOIL(s_bits25, p->sensors.adc_bits = 25)
SPOIL(s_ifs, p->sensors.i_full_scale = 0.0)
SPOIL(s_vfs, p->sensors.v_full_scale = -60.0)
SPOIL(s_gain, p->sensors.gain_error[2] = 0.6)
SPOIL(s_off, p->sensors.offset_error[1] = NAN)
SPOIL(s_inoise, p->sensors.i_noise = -0.01)
SPOIL(s_vnoise, p->sensors.v_noise = NAN)
SPOIL(s_cpr, p->sensors.encoder_cpr = -1)

static const bad_case_t cases[] = {
    {"ts", s_ts},
    {"ts", s_ts_nan},
    {"machine.pole_pairs", s_pp},
    {"machine.rs", s_rs},
    {"machine.rs", s_rs_inf},
    {"machine.ld", s_ld},
    {"machine.lq", s_lq},
    {"machine.lambda_m", s_lm},
    {"inverter.model", s_model},
    {"inverter.dead_time", s_td_neg},
    {"inverter.dead_time", s_td_big},
    {"inverter.substeps", s_sub0},
    {"inverter.substeps", s_sub65},
    {"dclink.kind", s_dckind},
    {"dclink.v_source", s_vs},
    {"dclink.r", s_r},
    {"dclink.c", s_c},
    {"mech.mode", s_mode},
    {"mech.j", s_j},
    {"mech.b", s_b},
    {"mech.theta0", s_th0},
    {"mech.omega0", s_w0},
    {"mech.load_torque.n", s_ln},
    {"mech.load_torque.term.kind", s_lkind},
    {"mech.load_torque.term.value", s_lval},
    {"mech.speed.term.t1", s_sramp},
    {"mech.speed.term.freq", s_sfreq},
    {"mech.speed.n", s_sn},
    {"sensors.adc_bits", s_bits7},
    {"sensors.adc_bits", s_bits25},
    {"sensors.i_full_scale", s_ifs},
    {"sensors.v_full_scale", s_vfs},
    {"sensors.gain_error", s_gain},
    {"sensors.offset_error", s_off},
    {"sensors.i_noise", s_inoise},
    {"sensors.v_noise", s_vnoise},
    {"sensors.encoder_cpr", s_cpr},
};

static void test_rejects(void **state) {
  (void)state;
  const plant_params_t good = test_params();
  const char *f = "untouched";
  assert_int_equal(plant_check(&good, &f), 0);
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
    plant_params_t p = good;
    cases[k].spoil(&p);
    f = NULL;
    const int rc = plant_check(&p, &f);
    if (rc >= 0 || f == NULL || strcmp(f, cases[k].field) != 0) {
      print_error("case %zu: expected %s, got rc %d field %s\n", k, cases[k].field, rc,
                  f ? f : "(null)");
    }
    assert_true(rc < 0);
    assert_non_null(f);
    assert_string_equal(f, cases[k].field);
    plant_t pl;
    f = NULL;
    assert_true(plant_init(&pl, &p, &f) < 0);
    assert_string_equal(f, cases[k].field);
  }
  /* boundary values that are valid */
  plant_params_t p = good;
  p.inverter.dead_time = 0.2499 * p.ts;
  p.inverter.substeps = 64;
  p.sensors.adc_bits = 24;
  p.machine.lambda_m = 0.0;
  assert_int_equal(plant_check(&p, &f), 0);
}

static void test_profile(void **state) {
  (void)state;
  profile_t p;
  memset(&p, 0, sizeof p);
  assert_true(profile_eval(&p, 1.0) == 0.0);
  const profile_term_t c = {PROFILE_CONST, 1.5, 0, 0, 0, 0};
  const profile_term_t st = {PROFILE_STEP, 2.0, 0.1, 0, 0, 0};
  const profile_term_t r = {PROFILE_RAMP, 4.0, 0.2, 0.6, 0, 0};
  const profile_term_t sn = {PROFILE_SINE, 3.0, 0.5, 1.0, 2.0, 0.25};
  assert_int_equal(profile_add(&p, c), 0);
  assert_int_equal(profile_add(&p, st), 0);
  assert_int_equal(profile_add(&p, r), 0);
  assert_int_equal(profile_add(&p, sn), 0);
  assert_true(fabs(profile_eval(&p, 0.05) - 1.5) < 1e-15);
  assert_true(fabs(profile_eval(&p, 0.1) - 3.5) < 1e-15);
  assert_true(fabs(profile_eval(&p, 0.4) - (3.5 + 2.0)) < 1e-15);
  const double t = 0.7;
  assert_true(fabs(profile_eval(&p, t) - (7.5 + 3.0 * sin(T_TWO_PI * 2.0 * (t - 0.5) + 0.25))) <
              1e-14);
  assert_true(fabs(profile_eval(&p, 1.2) - 7.5) < 1e-15); /* sine ended at t1 */
  for (int k = 4; k < PROFILE_MAX_TERMS; k++) {
    assert_int_equal(profile_add(&p, c), 0);
  }
  assert_int_equal(profile_add(&p, c), -1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rejects),
      cmocka_unit_test(test_profile),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/*
 * test_sensors.c - ADC, noise and encoder models (plant_sensors.c):
 * quantisation step and rounding, gain/offset errors, saturation, noise
 * rms within 5 % over many samples, determinism with the seed, DC-link ADC,
 * encoder quantisation, star-point voltage at the valley.
 */
#include "plant_test_util.h"

/* Forces phase current i_a = i (i_b = i_c = -i/2) on the locked rotor at theta = 0. */
static void set_current(plant_t *pl, double i) {
  pl->lambda_d = pl->p.machine.lambda_m + pl->p.machine.ld * i;
  pl->lambda_q = 0.0;
}

static void test_quantisation(void **state) {
  (void)state;
  plant_params_t p = test_params();
  plant_t pl;
  test_init(&pl, &p);
  const double lsb = 2.0 * 20.0 / 4096.0;
  for (int k = -2000; k <= 2000; k++) {
    const double i = k * 0.00731; /* irrational-ish sweep of +-14.6 A */
    set_current(&pl, i);
    plant_adc_t a;
    plant_sample(&pl, &a);
    const double q = a.i_abc[0] / lsb;
    assert_true(fabs(q - nearbyint(q)) < 1e-9);             /* on the code grid */
    assert_true(fabs(a.i_abc[0] - i) <= 0.5 * lsb + 1e-12); /* rounding */
    assert_true(fabs(a.i_abc[1] + 0.5 * i) <= 0.5 * lsb + 1e-12);
  }
  /* saturation: codes 0 and 4095 -> -FS and FS - LSB */
  plant_adc_t a;
  set_current(&pl, 100.0);
  plant_sample(&pl, &a);
  assert_true(a.i_abc[0] == 20.0 - lsb && a.i_abc[1] == -20.0);
  set_current(&pl, -100.0);
  plant_sample(&pl, &a);
  assert_true(a.i_abc[0] == -20.0 && a.i_abc[1] == 20.0 - lsb);
}

static void test_gain_offset(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.sensors.adc_bits = 16;
  p.sensors.gain_error[0] = 0.02;
  p.sensors.gain_error[1] = -0.01;
  p.sensors.offset_error[0] = 0.15;
  p.sensors.offset_error[2] = -0.2;
  plant_t pl;
  test_init(&pl, &p);
  const double lsb = 40.0 / 65536.0;
  for (int k = -10; k <= 10; k++) {
    const double i = k * 1.1;
    set_current(&pl, i);
    plant_adc_t a;
    plant_sample(&pl, &a);
    assert_true(fabs(a.i_abc[0] - (1.02 * i + 0.15)) <= 0.5 * lsb + 1e-12);
    assert_true(fabs(a.i_abc[1] - (0.99 * -0.5 * i)) <= 0.5 * lsb + 1e-12);
    assert_true(fabs(a.i_abc[2] - (-0.5 * i - 0.2)) <= 0.5 * lsb + 1e-12);
  }
}

static void noise_stats(uint32_t seed, double out[4], double first[3]) {
  plant_params_t p = test_params();
  p.sensors.i_noise = 0.05; /* 5 LSB: quantisation adds LSB^2/12, 0.3 % of the variance */
  p.sensors.v_noise = 0.2;  /* 14 LSB of the 60 V / 4096 ADC */
  p.sensors.seed = seed;
  plant_t pl;
  test_init(&pl, &p);
  set_current(&pl, 3.0);
  const int n = 40000;
  double s[4] = {0}, s2[4] = {0};
  for (int k = 0; k < n; k++) {
    plant_adc_t a;
    plant_sample(&pl, &a);
    if (k == 0) {
      first[0] = a.i_abc[0];
      first[1] = a.i_abc[1];
      first[2] = a.v_dc;
    }
    const double x[4] = {a.i_abc[0] - 3.0, a.i_abc[1] + 1.5, a.i_abc[2] + 1.5, a.v_dc - 24.0};
    for (int c = 0; c < 4; c++) {
      s[c] += x[c];
      s2[c] += x[c] * x[c];
    }
  }
  for (int c = 0; c < 4; c++) {
    out[c] = sqrt(s2[c] / n - (s[c] / n) * (s[c] / n));
  }
}

/* 40000 samples: the standard error of an rms estimate is 1/sqrt(2n) =
 * 0.35 %, so 5 % is > 10 sigma; a missing or doubled noise fails. */
static void test_noise_and_seed(void **state) {
  (void)state;
  double r[4], r2[4], f1[3], f2[3], f3[3];
  noise_stats(7, r, f1);
  print_message("noise rms: %.5f %.5f %.5f A (set 0.05), %.5f V (set 0.2)\n", r[0], r[1], r[2],
                r[3]);
  for (int c = 0; c < 3; c++) {
    assert_true(fabs(r[c] / 0.05 - 1.0) < 0.05);
  }
  assert_true(fabs(r[3] / 0.2 - 1.0) < 0.05);
  noise_stats(7, r2, f2);
  for (int c = 0; c < 4; c++) {
    assert_true(r[c] == r2[c]); /* same seed, same sequence */
  }
  assert_true(f1[0] == f2[0] && f1[1] == f2[1] && f1[2] == f2[2]);
  noise_stats(8, r2, f3);
  assert_true(r[0] != r2[0]);
}

static void test_vdc_encoder_vstar(void **state) {
  (void)state;
  plant_params_t p = test_params();
  p.sensors.encoder_cpr = 1000;
  p.dclink.v_source = 24.01;
  p.inverter.model = PLANT_INV_SWITCHING;
  const double w = 3.0;
  test_const_speed(&p, w);
  plant_t pl;
  test_init(&pl, &p);
  const double vlsb = 60.0 / 4096.0, step = T_TWO_PI / 1000.0;
  const double d[3] = {0.5, 0.6, 0.3};
  for (int k = 0; k < 3000; k++) {
    plant_step(&pl, d, true);
    plant_adc_t a;
    plant_sample(&pl, &a);
    assert_true(a.v_dc == nearbyint(24.01 / vlsb) * vlsb);
    const double cnt = a.enc_angle / step;
    assert_true(fabs(cnt - nearbyint(cnt)) < 1e-9);
    assert_true(pl.theta_m - a.enc_angle >= -1e-12 && pl.theta_m - a.enc_angle < step);
    /* valley, gates on, 0 < d < 1: all low sides on -> star at -vdc/2 */
    assert_true(fabs(a.v_star + 0.5 * 24.01) < 1e-12);
  }
  /* DC-link ADC saturates at v_full_scale - LSB */
  p.dclink.v_source = 80.0;
  test_init(&pl, &p);
  plant_adc_t a;
  plant_sample(&pl, &a);
  assert_true(a.v_dc == 60.0 - vlsb);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_quantisation),
      cmocka_unit_test(test_gain_offset),
      cmocka_unit_test(test_noise_and_seed),
      cmocka_unit_test(test_vdc_encoder_vstar),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

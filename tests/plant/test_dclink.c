/*
 * test_dclink.c - DC link.
 *  - RC link, machine driven as a generator (dynamometer) with a braking
 *    current: the capacitor charges above v_source; the capacitor energy
 *    obeys d(C v^2/2)/dt = v (Vs - v)/R - v i_dc (summed per period, exact up
 *    to the in-period variation), and the inverter DC power matches the
 *    machine: -v i_dc = -T_e w - 1.5 Rs |i|^2 (+ magnetic energy change).
 *  - ideal link: v_dc is v_source, constant, under the same regeneration.
 */
#include "plant_test_util.h"

static void run_regen(plant_dc_kind_t kind, double *v_end, double *bal_c, double *bal_m) {
  plant_params_t p = test_params();
  p.dclink.kind = kind;
  p.dclink.r = 2.0;
  p.dclink.c = 4.7e-3; /* RC = 9.4 ms: the capacitor energy is a large term */
  p.inverter.substeps = 2;
  const double w = 200.0;
  test_const_speed(&p, w);
  plant_t pl;
  test_init(&pl, &p);
  double e_src = 0.0, e_inv = 0.0, e_mech = 0.0, e_cu = 0.0;
  plant_state_t s, s0;
  plant_get_state(&pl, &s0);
  const double v0 = s0.v_dc;
  for (int k = 0; k < 3200; k++) {
    double d[3];
    /* steady state i_d = 0, i_q = -5 A at w_e = 800 rad/s: braking */
    test_duties_dq(&pl, 6.4, 5.5, d);
    plant_step(&pl, d, true);
    plant_get_state(&pl, &s);
    const double vm = 0.5 * (s.v_dc + s0.v_dc);
    e_src += vm * (p.dclink.v_source - vm) / p.dclink.r * p.ts;
    e_inv += -vm * s.i_dc * p.ts;
    e_mech += -0.5 * (s.torque + s0.torque) * w * p.ts;
    e_cu += 0.75 * p.machine.rs *
            (s.i_dq[0] * s.i_dq[0] + s.i_dq[1] * s.i_dq[1] + s0.i_dq[0] * s0.i_dq[0] +
             s0.i_dq[1] * s0.i_dq[1]) *
            p.ts;
    if (kind == PLANT_DC_IDEAL) {
      assert_true(s.v_dc == p.dclink.v_source);
    }
    s0 = s;
  }
  *v_end = s.v_dc;
  /* steady state (20 RC): mean((Vs - v)/R) = mean(i_dc) */
  const double v_ss = p.dclink.v_source - p.dclink.r * s.i_dc;
  print_message("v_dc %.6f V, Vs - R i_dc %.6f V\n", s.v_dc, v_ss);
  if (kind == PLANT_DC_RC) {
    assert_true(fabs(s.v_dc - v_ss) < 1e-3); /* i_dc sample vs its period mean: ~1e-4 V */
  }
  const double de_c = 0.5 * p.dclink.c * (s.v_dc * s.v_dc - v0 * v0);
  *bal_c = kind == PLANT_DC_RC ? (de_c - (e_src + e_inv)) / de_c : 0.0;
  /* magnetic energy left at the end (started at zero current) */
  const double e_mag =
      0.75 * (p.machine.ld * s.i_dq[0] * s.i_dq[0] + p.machine.lq * s.i_dq[1] * s.i_dq[1]);
  *bal_m = (e_inv - (e_mech - e_cu - e_mag)) / e_inv;
  print_message("kind %d: v_dc %.4f V, E_inv %.4f J, dE_C %.4f J, E_src %.4f J, cap balance %.2e, "
                "machine balance %.2e\n",
                (int)kind, s.v_dc, e_inv, de_c, e_src, *bal_c, *bal_m);
}

static void test_regeneration(void **state) {
  (void)state;
  double v, bc, bm;
  run_regen(PLANT_DC_RC, &v, &bc, &bm);
  assert_true(v > 24.0 + 0.5); /* charged by the generator */
  /* trapezoidal sums over 16 kHz periods of quantities varying with
   * RC = 150 periods: the capacitor balance (relative to its energy
   * change) to 1 %, the machine balance (relative to the inverter energy)
   * to 0.1 % */
  assert_true(fabs(bc) < 1e-2);
  assert_true(fabs(bm) < 1e-3);
  run_regen(PLANT_DC_IDEAL, &v, &bc, &bm);
  assert_true(v == 24.0);
  assert_true(fabs(bm) < 1e-3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_regeneration),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

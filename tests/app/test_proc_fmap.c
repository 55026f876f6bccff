/*
 * The flux maps at standstill (proc_fmap.c) on a small saturated model
 * without the SIL: a machine with saturation and cross-saturation given by
 * its magnetic energy W(psi) (i = grad W: reciprocal, one-to-one), the
 * voltage asked acting a period later, a resistance 2 % off the parameter
 * set's and a dead-time-like voltage error on each phase. The procedure
 * visits every grid point within the circle, each once as a phase, keeps
 * the current within its bound and finds psi_d, psi_q at the measured
 * current within 1 % rms / 2 % worst of the largest flux (the 3 %
 * / 6 % with room for the SIL's noise); its grid is refused when too large;
 * a current above its bound fails with the overcurrent fault.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "proc.h"

/* the model (tests only): W = psi_d'^2 / (2 L_d) + c1 psi_d'^4 / 4 +
 * psi_q^2 / (2 L_q) + c2 psi_q^4 / 4 + k psi_d'^2 psi_q^2 / 2, psi_d' =
 * psi_d - lambda_m */
typedef struct {
  float ld, lq, lm, c1, c2, k;
} model_t;

static dq_t model_current(const model_t *m, dq_t psi) {
  const float x = psi.d - m->lm, y = psi.q;
  return (dq_t){x / m->ld + m->c1 * x * x * x + m->k * x * y * y,
                y / m->lq + m->c2 * y * y * y + m->k * x * x * y};
}

/* psi at current i (Newton on grad W = i) */
static dq_t model_flux(const model_t *m, dq_t i) {
  dq_t psi = {m->lm + m->ld * i.d, m->lq * i.q};
  for (int it = 0; it < 50; ++it) {
    const float x = psi.d - m->lm, y = psi.q;
    const dq_t f = model_current(m, psi);
    const float a = 1.0f / m->ld + 3.0f * m->c1 * x * x + m->k * y * y;
    const float b = 2.0f * m->k * x * y;
    const float c = 1.0f / m->lq + 3.0f * m->c2 * y * y + m->k * x * x;
    const float det = a * c - b * b;
    const float ed = f.d - i.d, eq = f.q - i.q;
    psi.d -= (c * ed - b * eq) / det;
    psi.q -= (a * eq - b * ed) / det;
  }
  return psi;
}

static float sgn(float x) {
  return x > 0.0f ? 1.0f : (x < 0.0f ? -1.0f : 0.0f);
}

typedef struct {
  int points;             /* phases seen */
  float err_rms, err_max; /* flux error / the largest flux */
  float i_peak;           /* largest current amplitude [A] */
  float range;            /* the grid's range [A] */
  int status;
  uint32_t fault;
} run_t;

/* one run of the procedure on the model; r_plant: the model's resistance
 * over the parameter's; v_err: the dead-time-like error per phase [V] */
static run_t run(float r_plant, float v_err, float i_trip_at) {
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.rs = 1.0f;
  cfg.id_fmap_nd = 7u;
  cfg.id_fmap_nq = 4u;
  machine_t mach;
  assert_int_equal(machine_init_linear(&mach, cfg.pole_pairs, cfg.rs, cfg.ld, cfg.lq, cfg.lambda_m),
                   0);
  const model_t mdl = {cfg.ld, cfg.lq, cfg.lambda_m, 187.0f, 16.0f, 12.0f};
  const proc_row_t *row = proc_row(PROC_FMAP);
  proc_setup_t su = {&cfg, &mach, NULL, NULL, NULL, NULL, false};
  const char *field = NULL;
  assert_null(row->check(&su, &field));
  static proc_state_t st;
  row->init(&st, &su);
  hal_sample_t s;
  memset(&s, 0, sizeof s);
  s.valid = true;
  pos_estimate_t pos;
  memset(&pos, 0, sizeof pos);
  pos.valid = true; /* the d axis at theta = 0, the rotor held by symmetry */
  dq_t psi = {cfg.lambda_m, 0.0f};
  ab_t v_asked = {0.0f, 0.0f};
  run_t r = {0, 0.0f, 0.0f, 0.0f, fminf(cfg.id_fmap_current, cfg.i_max), PROC_RUNNING, 0u};
  proc_telemetry_t tm;
  memset(&tm, 0, sizeof tm);
  uint8_t phase = 0u;
  float psi_max = 0.0f, e2 = 0.0f;
  float pts[256][4];
  for (long n = 0; n < 2000000L && r.status == PROC_RUNNING; ++n) {
    dq_t i = model_current(&mdl, psi);
    if (n == i_trip_at) {
      i.d += 3.0f * r.range;
    }
    r.i_peak = fmaxf(r.i_peak, sqrtf(i.d * i.d + i.q * i.q));
    const proc_in_t in = {&s, {i.d, i.q}, 200.0f, &pos};
    proc_out_t out;
    r.status = row->step(&st, &su, &in, &out);
    r.fault = out.fault;
    row->publish(&st, &tm);
    if (tm.phase != phase && phase != 0u) {
      /* the previous phase's point */
      memcpy(pts[r.points], tm.result, 4 * sizeof(float));
      r.points++;
    }
    phase = tm.phase;
    /* the period: the voltage asked last period (the one-period delay),
     * less the error on each phase */
    const abc_t iabc = frames_clarke_inv((ab_t){i.d, i.q});
    const ab_t ve =
        frames_clarke((abc_t){-v_err * sgn(iabc.a), -v_err * sgn(iabc.b), -v_err * sgn(iabc.c)});
    const float rp = r_plant * cfg.rs;
    psi.d += (v_asked.alpha + ve.alpha - rp * i.d) * cfg.ts;
    psi.q += (v_asked.beta + ve.beta - rp * i.q) * cfg.ts;
    v_asked = out.apply ? out.v_ab : (ab_t){0.0f, 0.0f};
  }
  if (r.status == PROC_DONE) {
    row->publish(&st, &tm);
    memcpy(pts[r.points], tm.result, 4 * sizeof(float));
    r.points++;
  }
  for (int p = 0; p < r.points; ++p) {
    const dq_t t = model_flux(&mdl, (dq_t){pts[p][2], pts[p][3]});
    psi_max = fmaxf(psi_max, sqrtf(t.d * t.d + t.q * t.q));
  }
  for (int p = 0; p < r.points; ++p) {
    const dq_t t = model_flux(&mdl, (dq_t){pts[p][2], pts[p][3]});
    const float e = fmaxf(fabsf(pts[p][0] - t.d), fabsf(pts[p][1] - t.q)) / psi_max;
    print_message("%d %f %f: %f %f | %f %f\n", p, (double)pts[p][2], (double)pts[p][3],
                  (double)pts[p][0], (double)t.d, (double)pts[p][1], (double)t.q);
    e2 += e * e;
    r.err_max = fmaxf(r.err_max, e);
  }
  r.err_rms = r.points > 0 ? sqrtf(e2 / (float)r.points) : 1.0f;
  return r;
}

static int points_in_circle(void) {
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < 7; ++j) {
      const float d = 2.0f * (float)j / 6.0f - 1.0f, q = (float)k / 3.0f;
      n += sqrtf(d * d + q * q) <= 1.0001f ? 1 : 0;
    }
  }
  return n;
}

static void maps_found_within_bounds(void **state) {
  (void)state;
  const run_t r = run(1.02f, 1.5f, -1);
  print_message("fmap on the model: %d points, flux error rms %.4f worst %.4f, i_peak %.3f A "
                "(range %.3f A)\n",
                r.points, (double)r.err_rms, (double)r.err_max, (double)r.i_peak, (double)r.range);
  assert_int_equal(r.status, PROC_DONE);
  assert_int_equal(r.points, points_in_circle());
  assert_true(r.err_rms < 0.01f);
  assert_true(r.err_max < 0.02f);
  assert_true(r.i_peak <= 1.25f * r.range + 0.05f * 3.5355339f);
}

static void overcurrent_fails(void **state) {
  (void)state;
  const run_t r = run(1.0f, 0.0f, 500);
  assert_int_equal(r.status, PROC_FAILED);
  assert_int_equal(r.fault, DRIVE_FAULT_OVERCURRENT);
}

static void grid_too_large_refused(void **state) {
  (void)state;
  drive_config_t cfg;
  drive_config_default(&cfg);
  cfg.id_fmap_nd = 20u;
  cfg.id_fmap_nq = 20u;
  proc_setup_t su = {&cfg, NULL, NULL, NULL, NULL, NULL, false};
  const char *field = NULL;
  assert_non_null(proc_row(PROC_FMAP)->check(&su, &field));
  assert_string_equal(field, "id_fmap_nd");
  assert_non_null(proc_ident_refusal(PROC_FMAP, &su, &field));
  cfg.id_fmap_nd = 9u;
  cfg.id_fmap_nq = 5u;
  assert_null(proc_ident_refusal(PROC_FMAP, &su, &field));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(maps_found_within_bounds),
      cmocka_unit_test(overcurrent_fails),
      cmocka_unit_test(grid_too_large_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/*
 * The encoder identifications (issue 25 d-g: proc_poles.c, proc_enc.c,
 * proc_flux.c, proc_mech.c) on a small model without the SIL: a PM
 * machine (R, L_d, L_q, lambda_m, p) in the rotor frame, the inverter's
 * voltage error along -sgn(i) per phase (dead time), the voltage asked at
 * period k acting over period k + 1 (drive.c, t_out), a rotor with inertia,
 * Coulomb and viscous friction (held while the torque is below T_c), and a
 * quantised encoder with an offset and a direction. Each procedure against
 * the model's truth with the limits: pole pairs exact, the offset
 * within 1 deg electrical (also under a holding friction), lambda_m 2 %, J
 * 5 %, friction 10 %; the current within its bound; refusals without an
 * encoder.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "estimation/ident_mech.h"
#include "hal_sil.h"
#include "proc.h"
#include "proc_fixture.h"

#define PI_F 3.14159265f

typedef struct {
  /* truth */
  float p, rs, ld, lq, lam, j, tc, b;
  float e_dt;    /* the inverter's voltage error per phase [V] (sgn(i)) */
  float off_m;   /* the encoder's zero against the rotor's d axis [rad mechanical] */
  float enc_dir; /* +1, -1 */
  float i_noise; /* [A] rms-ish */
  /* state */
  float id, iq, th, w; /* th: mechanical angle of the d axis; w mechanical */
  ab_t v_next;         /* asked last period: acts over this one */
  float i_peak;
  uint32_t rng;
} model_t;

typedef struct {
  PROC_FIXTURE_FIELDS
  pos_io_t io;
  model_t md;
} fixture_t;

static fixture_t fx;

static float noise(model_t *m) {
  /* sum of two uniforms, [-1, 1] */
  m->rng = m->rng * 1664525u + 1013904223u;
  const float u1 = (float)(m->rng >> 8) / 16777216.0f;
  m->rng = m->rng * 1664525u + 1013904223u;
  const float u2 = (float)(m->rng >> 8) / 16777216.0f;
  return u1 + u2 - 1.0f;
}

static float sgnf(float x) {
  return x > 0.0f ? 1.0f : (x < 0.0f ? -1.0f : 0.0f);
}

/* one period of the model with the voltage v (alpha-beta) */
static void model_period(model_t *m, ab_t v, float ts) {
  const unsigned sub = 8u;
  const float h = ts / (float)sub;
  for (unsigned k = 0; k < sub; ++k) {
    const sincos_t sc = frames_sincos(frames_wrap_pi(m->p * m->th));
    /* the inverter's error: -e sgn(i_x) per phase, in alpha-beta */
    const ab_t i_ab = frames_park_inv((dq_t){m->id, m->iq}, sc);
    const abc_t i3 = frames_clarke_inv(i_ab);
    const ab_t e =
        frames_clarke((abc_t){-m->e_dt * sgnf(i3.a), -m->e_dt * sgnf(i3.b), -m->e_dt * sgnf(i3.c)});
    const dq_t vd = frames_park((ab_t){v.alpha + e.alpha, v.beta + e.beta}, sc);
    const float we = m->p * m->w;
    const float did = (vd.d - m->rs * m->id + we * m->lq * m->iq) / m->ld;
    const float diq = (vd.q - m->rs * m->iq - we * (m->ld * m->id + m->lam)) / m->lq;
    m->id += h * did;
    m->iq += h * diq;
    const float t = 1.5f * m->p * (m->lam + (m->ld - m->lq) * m->id) * m->iq;
    if (m->w == 0.0f && fabsf(t) <= m->tc) {
      /* held by the Coulomb friction */
    } else {
      const float s = m->w != 0.0f ? sgnf(m->w) : sgnf(t);
      const float w1 = m->w + h * (t - m->tc * s - m->b * m->w) / m->j;
      m->w = (w1 * m->w < 0.0f && fabsf(t) <= m->tc) ? 0.0f : w1;
    }
    m->th += h * m->w;
    const float ia = sqrtf(m->id * m->id + m->iq * m->iq);
    m->i_peak = ia > m->i_peak ? ia : m->i_peak;
  }
}

static void fixture(void) {
  memset(&fx, 0, sizeof fx);
  drive_config_default(&fx.cfg);
  fx.cfg.pos_source = POS_SOURCE_ENCODER;
  model_t *m = &fx.md;
  const drive_config_t *c = &fx.cfg;
  *m = (model_t){c->pole_pairs, c->rs, c->ld,        c->lq, c->lambda_m, c->inertia, 0.0f,
                 0.0f,          2.0f,  0.0f,         1.0f,  0.01f,       0.0f,       0.0f,
                 0.0f,          0.0f,  {0.0f, 0.0f}, 0.0f,  12345u};
}

/* the parameter set as identified so far (the model's truth, or not) */
static void setup(void) {
  proc_fixture_bind(&fx);
}

/* the sample of the model now */
static void sample(void) {
  model_t *m = &fx.md;
  const drive_config_t *c = &fx.cfg;
  const sincos_t sc = frames_sincos(frames_wrap_pi(m->p * m->th));
  const ab_t i = frames_park_inv((dq_t){m->id, m->iq}, sc);
  fx.s.valid = true;
  fx.s.enc_valid = true;
  fx.s.v_dc = 310.0f;
  const float step = 2.0f * PI_F / (float)c->enc_cpr;
  float e = m->enc_dir * m->th + m->off_m;
  e = e - 2.0f * PI_F * floorf(e / (2.0f * PI_F));
  fx.s.enc_angle = floorf(e / step) * step;
  fx.s.t_enc = 0.0f;
  const float a = i.alpha + m->i_noise * noise(m), b = i.beta + m->i_noise * noise(m);
  fx.s.i_abc[0] = a;
  fx.s.i_abc[1] = -0.5f * a + 0.8660254f * b;
  fx.s.i_abc[2] = -0.5f * a - 0.8660254f * b;
}

/* run the procedure to its end (at most t_max), its telemetry in *tm */
static int run(proc_id_t id, float t_max, proc_telemetry_t *tm) {
  const proc_row_t *r = proc_row(id);
  assert_non_null(r);
  const char *field = NULL;
  assert_null(proc_ident_refusal(id, &fx.su, &field));
  r->init(&fx.st, &fx.su);
  const drive_config_t *c = &fx.cfg;
  const float v_max = c->v_margin * 310.0f / 1.7320508f;
  memset(tm, 0, sizeof *tm);
  const uint32_t n_max = (uint32_t)(t_max / c->ts);
  int res = PROC_RUNNING;
  for (uint32_t k = 0; k < n_max && res == PROC_RUNNING; ++k) {
    sample();
    fx.su.pos_src->update(&fx.pos_st, c, &fx.s, &fx.io);
    const ab_t i = frames_clarke((abc_t){fx.s.i_abc[0], fx.s.i_abc[1], fx.s.i_abc[2]});
    const proc_in_t in = {&fx.s, i, v_max, &fx.io.out};
    proc_out_t out;
    res = r->step(&fx.st, &fx.su, &in, &out);
    r->publish(&fx.st, tm);
    const float va = hypotf(out.v_ab.alpha, out.v_ab.beta);
    assert_true(va <= v_max * 1.0001f);
    model_period(&fx.md, fx.md.v_next, c->ts);
    fx.md.v_next = out.apply ? out.v_ab : (ab_t){0.0f, 0.0f};
    if (!out.apply) {
      fx.md.id = fx.md.iq = 0.0f; /* gates off: the currents decay (a diode's few periods) */
    }
    if (res == PROC_FAILED) {
      tm->fault = out.fault;
    }
  }
  return res;
}

/* ----------------------------------------------------------- poles */

static void poles_exact(void **state) {
  (void)state;
  static const float pp[] = {21.0f, 7.0f, 4.0f, 2.0f, 1.0f};
  for (unsigned k = 0; k < sizeof pp / sizeof pp[0]; ++k) {
    for (int d = -1; d <= 1; d += 2) {
      fixture();
      fx.md.p = pp[k];
      fx.md.enc_dir = (float)d;
      fx.md.off_m = 1.234f;
      fx.md.tc = 0.05f * 1.5f * pp[k] * fx.md.lam * 1.06f; /* 5 % of the vector's torque */
      fx.cfg.pole_pairs = 3.0f;                            /* not known yet */
      setup();
      proc_telemetry_t tm;
      const int res = run(PROC_POLES, 12.0f, &tm);
      print_message("poles: p %.0f dir %d: %.0f %.0f (%.3f, residue %.3f) fault %u\n",
                    (double)pp[k], d, (double)tm.result[0], (double)tm.result[1],
                    (double)tm.result[2], (double)tm.result[3], (unsigned)tm.fault);
      assert_int_equal(res, PROC_DONE);
      assert_float_equal(tm.result[0], pp[k], 0.0f);
      assert_float_equal(tm.result[1], (float)d, 0.0f);
      assert_true(fabsf(tm.result[3]) < 0.25f);
      assert_true(fx.md.i_peak <= 1.3f * 0.3f * fx.cfg.i_max + 0.05f * fx.cfg.i_max);
    }
  }
}

/* ------------------------------------------------------------- enc */

static float enc_true_offset(void) {
  /* theta_e = p (theta_enc + half) - offset with theta_enc = theta_m + off_m:
   * offset = p off_m (the half count: on average half a count) */
  return frames_wrap_pi(fx.md.p * fx.md.off_m);
}

static void enc_offset_within_a_degree(void **state) {
  (void)state;
  static const float offs[] = {0.3f, 2.0f, 4.5f};
  static const float tcs[] = {0.0f, 0.15f}; /* free; a holding friction (x the vector's torque) */
  for (unsigned k = 0; k < 3u; ++k) {
    for (unsigned f = 0; f < 2u; ++f) {
      fixture();
      fx.md.off_m = offs[k];
      fx.md.tc = tcs[f] * 1.5f * fx.md.p * fx.md.lam * 0.3f * fx.cfg.i_max;
      setup();
      proc_telemetry_t tm;
      assert_int_equal(run(PROC_ENC, 20.0f, &tm), PROC_DONE);
      const float err = frames_wrap_pi(tm.result[0] - enc_true_offset());
      print_message("enc: offset %.4f true %.4f err %.3f deg, bias %.3f deg\n",
                    (double)tm.result[0], (double)enc_true_offset(), (double)(err * 57.29578f),
                    (double)(tm.result[4] * 57.29578f));
      assert_true(fabsf(err) < 1.0f * PI_F / 180.0f);
      assert_float_equal(tm.result[1], 1.0f, 0.0f);
      assert_true(fx.md.i_peak <= 1.3f * 0.3f * fx.cfg.i_max + 0.05f * fx.cfg.i_max);
    }
  }
  /* the direction reversed */
  fixture();
  fx.md.enc_dir = -1.0f;
  setup();
  proc_telemetry_t tm;
  assert_int_equal(run(PROC_ENC, 20.0f, &tm), PROC_DONE);
  assert_float_equal(tm.result[1], -1.0f, 0.0f);
}

/* ------------------------------------------------------------ flux */

static void flux_within_two_percent(void **state) {
  (void)state;
  static const float lam[] = {0.19f, 0.12f};
  static const float ldq[][2] = {{0.057f, 0.057f}, {0.04f, 0.07f}};
  for (unsigned k = 0; k < 2u; ++k) {
    fixture();
    fx.md.lam = lam[k];
    fx.md.ld = ldq[k][0];
    fx.md.lq = ldq[k][1];
    fx.md.e_dt = 4.0f;
    fx.md.tc = 0.05f;
    fx.md.b = 0.002f;
    fx.cfg.ld = fx.md.ld;
    fx.cfg.lq = fx.md.lq;
    fx.cfg.lambda_m = 0.5f * lam[k]; /* not known yet */
    fx.cfg.rs = 1.5f * fx.md.rs;     /* R_s off: cancelled */
    setup();
    proc_telemetry_t tm;
    const int res = run(PROC_FLUX, 30.0f, &tm);
    print_message("flux: %.5f (%.5f %.5f) true %.5f, w %.1f %.1f, limited %.0f fault %u\n",
                  (double)tm.result[0], (double)tm.result[1], (double)tm.result[2], (double)lam[k],
                  (double)tm.result[3], (double)tm.result[4], (double)tm.result[6],
                  (unsigned)tm.fault);
    assert_int_equal(res, PROC_DONE);
    assert_true(fabsf(tm.result[0] / lam[k] - 1.0f) < 0.02f);
  }
}

/* ------------------------------------------------------------ mech */

static void mech_within_limits(void **state) {
  (void)state;
  static const float js[] = {0.021f, 0.005f, 0.08f};
  for (unsigned k = 0; k < 3u; ++k) {
    fixture();
    fx.md.j = js[k];
    const float ta = 1.5f * fx.md.p * fx.md.lam * 0.3f * fx.cfg.i_max;
    const float w_hi = 0.8f * 0.3f * fx.cfg.speed_max;
    fx.md.tc = 0.03f * ta;
    fx.md.b = 0.03f * ta / w_hi;
    fx.cfg.inertia = 0.3f * js[k]; /* not known yet */
    setup();
    proc_telemetry_t tm;
    const int res = run(PROC_MECH, 30.0f, &tm);
    print_message("mech: J %.5f (%.5f) Tc %.4f (%.4f) B %.6f (%.6f) rms %.3f fault %u\n",
                  (double)tm.result[0], (double)js[k], (double)tm.result[1], (double)fx.md.tc,
                  (double)tm.result[2], (double)fx.md.b, (double)tm.result[3], (unsigned)tm.fault);
    assert_int_equal(res, PROC_DONE);
    assert_true(fabsf(tm.result[0] / js[k] - 1.0f) < 0.05f);
    assert_true(fabsf(tm.result[1] / fx.md.tc - 1.0f) < 0.10f);
    assert_true(fabsf(tm.result[2] / fx.md.b - 1.0f) < 0.10f);
    assert_true(fx.md.i_peak <= 1.3f * 0.3f * fx.cfg.i_max + 0.05f * fx.cfg.i_max);
  }
}

/* -------------------------------------------------------- refusals */

static void refused_without_an_encoder(void **state) {
  (void)state;
  fixture();
  setup();
  fx.cfg.pos_source = POS_SOURCE_IVD;
  static const proc_id_t ids[] = {PROC_POLES, PROC_ENC, PROC_FLUX, PROC_MECH};
  for (unsigned k = 0; k < 4u; ++k) {
    const char *field = NULL;
    assert_non_null(proc_ident_refusal(ids[k], &fx.su, &field));
    assert_string_equal(field, "pos_source");
    const proc_row_t *r = proc_row(ids[k]);
    assert_int_equal(r->state, DRIVE_STATE_IDENT);
    assert_int_equal(r->caps, PROC_CAP_IDENT | PROC_CAP_GATES);
  }
  assert_true(sizeof(proc_poles_t) <= 400u && sizeof(proc_enc_t) <= 400u);
  assert_true(sizeof(proc_flux_t) <= 400u && sizeof(proc_mech_t) <= 400u);
}

/* the least squares alone: an exact system is solved */
static void mech_least_squares_exact(void **state) {
  (void)state;
  float ls[IDENT_MECH_LS];
  ident_mech_reset(ls);
  const float x0[3] = {0.7f, -0.2f, 0.4f};
  for (unsigned k = 0; k < 20u; ++k) {
    const float a[3] = {sinf((float)k), cosf(0.3f * (float)k), 0.1f * (float)k - 1.0f};
    ident_mech_add(ls, a, a[0] * x0[0] + a[1] * x0[1] + a[2] * x0[2]);
  }
  float x[3], rms;
  assert_int_equal(ident_mech_solve(ls, 20u, x, &rms), 0);
  for (unsigned k = 0; k < 3u; ++k) {
    assert_float_equal(x[k], x0[k], 1e-3f);
  }
  assert_true(rms < 1e-2f);
  ident_mech_reset(ls);
  assert_int_equal(ident_mech_solve(ls, 0u, x, &rms), -1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(refused_without_an_encoder),
      cmocka_unit_test(mech_least_squares_exact),
      cmocka_unit_test(poles_exact),
      cmocka_unit_test(enc_offset_within_a_degree),
      cmocka_unit_test(flux_within_two_percent),
      cmocka_unit_test(mech_within_limits),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

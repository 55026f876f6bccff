/*
 * plant_sensors.c - what the board measures at the carrier valley.
 * Phase currents: bipolar ADC of adc_bits over +-i_full_scale, mid-scale
 *   code = 0 A, LSB = 2 i_full_scale / 2^bits; input
 *   (1 + gain_error) i + offset_error + noise, rounded to the nearest code,
 *   saturated to codes [0, 2^bits - 1] (i.e. [-FS, FS - LSB]) and converted
 *   back with the nominal gain, as the firmware would.
 * DC-link voltage: unipolar ADC 0..v_full_scale, LSB = v_full_scale/2^bits,
 *   same rounding and saturation, white noise v_noise.
 * Noise: xorshift64* seeded through splitmix64 from `seed`, Marsaglia
 *   polar normals, drawn one sample ahead (draw_noise); deterministic for a
 *   given seed and call sequence; no random number is drawn for a zero
 *   noise setting.
 * Encoder: mechanical angle floored to 2 pi / encoder_cpr (0 = ideal).
 * Star point: returned exactly (no ADC model), see plant.c.
 */
#include "plant_internal.h"

#include <math.h>

int plant_sensors_check(const plant_sensors_t *s, const char **field) {
  const char *bad = NULL;
  if (s->adc_bits < 8 || s->adc_bits > 24) {
    bad = "sensors.adc_bits";
  } else if (!plant_finite_pos(s->i_full_scale)) {
    bad = "sensors.i_full_scale";
  } else if (!plant_finite_pos(s->v_full_scale)) {
    bad = "sensors.v_full_scale";
  } else if (!plant_finite_nonneg(s->i_noise)) {
    bad = "sensors.i_noise";
  } else if (!plant_finite_nonneg(s->v_noise)) {
    bad = "sensors.v_noise";
  } else if (s->encoder_cpr < 0 || s->encoder_cpr > (1 << 30)) {
    bad = "sensors.encoder_cpr";
  }
  for (int k = 0; bad == NULL && k < 3; k++) {
    if (!(fabs(s->gain_error[k]) < 0.5)) {
      bad = "sensors.gain_error";
    } else if (!(fabs(s->offset_error[k]) < 1e300)) {
      bad = "sensors.offset_error";
    }
  }
  if (bad != NULL) {
    *field = bad;
    return -1;
  }
  return 0;
}

static uint64_t splitmix64(uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}


/* uniform in (0, 1] */
static double rng_uniform(uint64_t *s) {
  uint64_t x = *s;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  *s = x;
  return (double)(((x * 0x2545F4914F6CDD1Dull) >> 11) + 1u) * 0x1.0p-53;
}

/* Two independent standard normals, Marsaglia's polar method (no trig).
 * A pair is accepted with probability pi/4; after 32 rejections (chance
 * 1e-21) it returns zeros, so the loop is bounded. */
static void rng_normal2(uint64_t *s, double *z0, double *z1) {
  for (int attempt = 0; attempt < 32; ++attempt) {
    const double u = 2.0 * rng_uniform(s) - 1.0;
    const double v = 2.0 * rng_uniform(s) - 1.0;
    const double q = u * u + v * v;
    if (q > 0.0 && q < 1.0) {
      const double f = sqrt(-2.0 * log(q) / q);
      *z0 = u * f;
      *z1 = v * f;
      return;
    }
  }
  *z0 = 0.0;
  *z1 = 0.0;
}

/* The standard normals of the next sample (n[0..2] currents, n[3] DC-link
 * voltage), drawn one sample ahead: the sequence is the same as drawing
 * them in plant_sample, but the draw (log, sqrt, division) is off the path
 * from the plant state to the ISR and overlaps with it. */
static void draw_noise(plant_t *pl) {
  const plant_sensors_t *s = &pl->p.sensors;
  double *n = pl->aux.noise;
  n[0] = n[1] = n[2] = n[3] = 0.0;
  if (s->i_noise > 0.0) {
    rng_normal2(&pl->rng, &n[0], &n[1]);
    rng_normal2(&pl->rng, &n[2], &n[3]);
  } else if (s->v_noise > 0.0) {
    double unused;
    rng_normal2(&pl->rng, &n[3], &unused);
  }
}

void plant_sensors_init(plant_t *pl) {
  const plant_sensors_t *s = &pl->p.sensors;
  plant_aux_t *a = &pl->aux;
  a->adc_levels = ldexp(1.0, s->adc_bits);
  a->adc_ilsb = 2.0 * s->i_full_scale / a->adc_levels;
  a->adc_vlsb = s->v_full_scale / a->adc_levels;
  a->enc_step = s->encoder_cpr > 0 ? PLANT_TWO_PI / s->encoder_cpr : 0.0;
  pl->rng = splitmix64(pl->p.sensors.seed);
  if (pl->rng == 0) {
    pl->rng = 0x9E3779B97F4A7C15ull;
  }
  draw_noise(pl);
}

static double adc_round(double x, double lsb, double code_min, double code_max, double code_off) {
  double code = floor(x / lsb + 0.5) + code_off;
  code = code < code_min ? code_min : (code > code_max ? code_max : code);
  return (code - code_off) * lsb;
}

void plant_sample(plant_t *pl, plant_adc_t *out) {
  const plant_sensors_t *s = &pl->p.sensors;
  const plant_aux_t *a = &pl->aux;
  const double levels = a->adc_levels;
  const double *n = a->noise;
  const double *i_abc = plant_machine_cur(pl)->i_abc;
  const double ilsb = a->adc_ilsb;
  for (int k = 0; k < 3; k++) {
    const double raw = (1.0 + s->gain_error[k]) * i_abc[k] + s->offset_error[k] + s->i_noise * n[k];
    out->i_abc[k] = adc_round(raw, ilsb, 0.0, levels - 1.0, 0.5 * levels);
  }
  const double vlsb = a->adc_vlsb;
  out->v_dc = adc_round(pl->v_dc + s->v_noise * n[3], vlsb, 0.0, levels - 1.0, 0.0);
  out->v_star = pl->aux.v_star;
  if (s->encoder_cpr > 0) {
    const double step = a->enc_step;
    double cnt = floor(pl->theta_m / step);
    cnt = cnt >= s->encoder_cpr ? 0.0 : (cnt < 0.0 ? 0.0 : cnt);
    out->enc_angle = cnt * step;
  } else {
    out->enc_angle = pl->theta_m;
  }
  draw_noise(pl); /* for the next sample */
}

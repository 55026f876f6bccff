/*
 * plant_sensors.c - what the board measures at the carrier valley.
 * Phase currents: bipolar ADC of adc_bits over +-i_full_scale, mid-scale
 *   code = 0 A, LSB = 2 i_full_scale / 2^bits; input
 *   (1 + gain_error) i + offset_error + noise, rounded to the nearest code,
 *   saturated to codes [0, 2^bits - 1] (i.e. [-FS, FS - LSB]) and converted
 *   back with the nominal gain, as the firmware would.
 * DC-link voltage: unipolar ADC 0..v_full_scale, LSB = v_full_scale/2^bits,
 *   same rounding and saturation, white noise v_noise.
 * Noise: xorshift64* seeded through splitmix64 from `seed`, ziggurat
 *   normals (rng_normal); deterministic for a given seed and call sequence;
 *   no random number is drawn for a zero noise setting.
 * Encoder: mechanical angle floored to 2 pi / encoder_cpr (0 = ideal).
 * Star point at the valley (plant_adc_t.v_star): returned exactly (see
 *   plant.c); the star-point samples of the DFC window go through their own
 *   channel (plant_star.c: circuit, gain, offset, noise, adc_bits over
 *   +-star_full_scale).
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
  } else if (!plant_finite_nonneg(s->star_full_scale)) {
    bad = "sensors.star_full_scale";
  } else if (!(fabs(s->star_gain_error) < 0.5)) {
    bad = "sensors.star_gain_error";
  } else if (!(fabs(s->star_offset) < 1e6)) {
    bad = "sensors.star_offset";
  } else if (!plant_finite_nonneg(s->star_noise)) {
    bad = "sensors.star_noise";
  } else if (!(s->star_tau >= 0.0 && s->star_tau < 1e-3)) {
    bad = "sensors.star_tau";
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

/* xorshift64*: the next 64 random bits */
static inline uint64_t rng_next(uint64_t *s) {
  uint64_t x = *s;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  *s = x;
  return x * 0x2545F4914F6CDD1Dull;
}

/* uniform in (0, 1] */
static double rng_uniform(uint64_t *s) {
  return (double)((rng_next(s) >> 11) + 1u) * 0x1.0p-53;
}

/* Standard normals: the ziggurat of Marsaglia and Tsang (J. Stat. Softw. 5,
 * 2000; 128 layers, RNOR), with the layer index and the 32-bit abscissa
 * taken from separate bits of one 64-bit draw. 98.8 % of the draws cost one
 * random number, a multiplication and a well-predicted comparison (the
 * polar method it replaces needed log, sqrt and a division, and rejected
 * 21 % of its pairs); the wedges and the tail are sampled exactly. The
 * tables are built by plant_sensors_init in the plant's aux data. Bounded
 * loops: after 32 rejections (chance far below 1e-40) they return 0. */
#define ZIG_R 3.442619855899      /* start of the tail */
#define ZIG_V 9.91256303526217e-3 /* area of each layer */
#define ZIG_M 2147483648.0        /* 2^31 */

static void zig_init(plant_aux_t *a) {
  double dn = ZIG_R, tn = ZIG_R;
  const double q = ZIG_V / exp(-0.5 * dn * dn);
  a->zig_k[0] = (uint32_t)((dn / q) * ZIG_M);
  a->zig_k[1] = 0;
  a->zig_w[0] = q / ZIG_M;
  a->zig_w[PLANT_ZIG_N - 1] = dn / ZIG_M;
  a->zig_f[0] = 1.0;
  a->zig_f[PLANT_ZIG_N - 1] = exp(-0.5 * dn * dn);
  for (int i = PLANT_ZIG_N - 2; i >= 1; i--) {
    dn = sqrt(-2.0 * log(ZIG_V / dn + exp(-0.5 * dn * dn)));
    a->zig_k[i + 1] = (uint32_t)((dn / tn) * ZIG_M);
    tn = dn;
    a->zig_f[i] = exp(-0.5 * dn * dn);
    a->zig_w[i] = dn / ZIG_M;
  }
}

/* The rare part of rng_normal (1.2 %): the draw (hz, iz, x) fell outside
 * its layer's rectangle. Kept out of line so that the fast path stays a
 * handful of instructions. */
static double rng_normal_slow(const plant_aux_t *a, uint64_t *s, int32_t hz, unsigned iz,
                              double x) {
  for (int attempt = 0; attempt < 32; ++attempt) {
    if (iz == 0) { /* the tail beyond ZIG_R */
      for (int k = 0; k < 32; ++k) {
        const double xt = -log(rng_uniform(s)) * (1.0 / ZIG_R);
        const double y = -log(rng_uniform(s));
        if (y + y >= xt * xt) {
          return hz > 0 ? ZIG_R + xt : -ZIG_R - xt;
        }
      }
      return 0.0;
    }
    if (a->zig_f[iz] + rng_uniform(s) * (a->zig_f[iz - 1] - a->zig_f[iz]) < exp(-0.5 * x * x)) {
      return x; /* in the wedge under the density */
    }
    const uint64_t r = rng_next(s);
    hz = (int32_t)(uint32_t)(r >> 32);
    iz = (unsigned)(r >> 25) & (PLANT_ZIG_N - 1);
    const uint32_t ahz = hz < 0 ? (uint32_t)(-(int64_t)hz) : (uint32_t)hz;
    x = hz * a->zig_w[iz];
    if (ahz < a->zig_k[iz]) {
      return x;
    }
  }
  return 0.0;
}

static inline double rng_normal(const plant_aux_t *a, uint64_t *s) {
  const uint64_t r = rng_next(s);
  const int32_t hz = (int32_t)(uint32_t)(r >> 32);
  const unsigned iz = (unsigned)(r >> 25) & (PLANT_ZIG_N - 1);
  const uint32_t ahz = hz < 0 ? (uint32_t)(-(int64_t)hz) : (uint32_t)hz;
  const double x = hz * a->zig_w[iz];
  if (ahz < a->zig_k[iz]) {
    return x; /* inside the layer's rectangle */
  }
  return rng_normal_slow(a, s, hz, iz, x);
}

double plant_sensors_normal(plant_t *pl) {
  return rng_normal(&pl->aux, &pl->rng);
}

void plant_sensors_init(plant_t *pl) {
  const plant_sensors_t *s = &pl->p.sensors;
  plant_aux_t *a = &pl->aux;
  a->adc_levels = ldexp(1.0, s->adc_bits);
  a->adc_ilsb = 2.0 * s->i_full_scale / a->adc_levels;
  a->adc_vlsb = s->v_full_scale / a->adc_levels;
  for (int k = 0; k < 3; k++) {
    a->adc_gain[k] = 1.0 + s->gain_error[k];
  }
  a->adc_code_max = a->adc_levels - 1.0;
  a->adc_i_off = 0.5 * a->adc_levels;
  a->enc_step = s->encoder_cpr > 0 ? PLANT_TWO_PI / s->encoder_cpr : 0.0;
  pl->rng = splitmix64(pl->p.sensors.seed);
  if (pl->rng == 0) {
    pl->rng = 0x9E3779B97F4A7C15ull;
  }
  zig_init(a);
}

static double adc_round(double x, double lsb, double code_min, double code_max, double code_off) {
  double code = plant_floor(x / lsb + 0.5) + code_off;
  code = code_min > code ? code_min : code; /* MAXSD, MINSD (NaN passes) */
  code = code_max < code ? code_max : code;
  return (code - code_off) * lsb;
}

/* The sensors, and the true values of the same state (br, when not NULL)
 * from the same current cache: one freshness check for both. */
static inline __attribute__((always_inline)) void sample_of(plant_t *pl, plant_adc_t *out,
                                                            plant_brief_t *br) {
  const plant_sensors_t *s = &pl->p.sensors;
  const plant_aux_t *a = &pl->aux;
  const double code_max = a->adc_code_max;
  double n[4] = {0.0, 0.0, 0.0, 0.0};
  if (s->i_noise > 0.0) {
    for (int k = 0; k < 3; k++) {
      n[k] = rng_normal(a, &pl->rng);
    }
  }
  if (s->v_noise > 0.0) {
    n[3] = rng_normal(a, &pl->rng);
  }
  const double *i_abc = plant_machine_cur(pl)->i_abc;
  if (br != NULL) {
    plant_brief_of(pl, i_abc, br);
  }
  const double ilsb = a->adc_ilsb;
  for (int k = 0; k < 3; k++) {
    const double raw = a->adc_gain[k] * i_abc[k] + s->offset_error[k] + s->i_noise * n[k];
    out->i_abc[k] = adc_round(raw, ilsb, 0.0, code_max, a->adc_i_off);
  }
  const double vlsb = a->adc_vlsb;
  out->v_dc = adc_round(pl->v_dc + s->v_noise * n[3], vlsb, 0.0, code_max, 0.0);
  out->v_star = pl->aux.v_star;
  if (s->encoder_cpr > 0) {
    const double step = a->enc_step;
    double cnt = plant_floor(pl->theta_m / step);
    const double c0 = 0.0 > cnt ? 0.0 : cnt; /* MAXSD (NaN passes) */
    cnt = cnt >= s->encoder_cpr ? 0.0 : c0;
    out->enc_angle = cnt * step;
  } else {
    out->enc_angle = pl->theta_m;
  }
}
void plant_sample(plant_t *pl, plant_adc_t *out) {
  sample_of(pl, out, NULL);
}
void plant_sample_brief(plant_t *pl, plant_adc_t *out, plant_brief_t *br) {
  sample_of(pl, out, br);
}

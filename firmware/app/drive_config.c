/*
 * drive_config.c - defaults and validation of the drive parameter set.
 */
#include "drive_config.h"

#include <math.h>

#define PI_F        3.14159265f
#define RPM_TO_RADS (2.0f * PI_F / 60.0f)

void drive_config_default(drive_config_t *cfg) {
  /* Machine: Rubino 2020, Table I (SPM, 20 N m, 1200 rpm, 2.5 A rms). */
  cfg->pole_pairs = 21.0f;
  cfg->rs = 7.1f;
  cfg->ld = 0.057f;
  cfg->lq = 0.057f;
  cfg->lambda_m = 0.19f;
  cfg->inertia = 0.021f;

  cfg->ts = 1.0f / 16000.0f;
  cfg->slow_div = 16; /* 1 kHz slow loop */
  cfg->dead_time = 1.0e-6f;

  cfg->i_max = 2.5f * 1.41421356f; /* rated 2.5 A rms, peak */
  cfg->i_trip = 2.0f * cfg->i_max;
  cfg->v_dc_max = 400.0f;
  cfg->v_dc_min = 150.0f;
  cfg->speed_max = 1200.0f * RPM_TO_RADS;
  cfg->speed_trip = 1.25f * cfg->speed_max;
  cfg->offset_max = 0.5f;
  cfg->offset_samples = 256;
  cfg->torque_max = 20.0f;
  cfg->v_margin = 0.95f;

  cfg->law = DRIVE_LAW_FOC;
  cfg->mode = DRIVE_MODE_TORQUE;
  cfg->current_bw = 2000.0f; /* ~ 320 Hz; wc*Ts = 0.125 */
  cfg->speed_bw = 60.0f;
  cfg->accel_max = 1200.0f * RPM_TO_RADS; /* 1200 rpm/s */
  cfg->pll_bw = 400.0f;
  cfg->enc_offset = 0.0f;

  cfg->flux_obs_wc = 125.0f;                 /* Rubino 2020, section III.B */
  cfg->delta_max = 80.0f * PI_F / 180.0f;    /* Rubino 2020, Table I */
  cfg->vsd_max = 60.0f;                      /* Rubino 2020, section III.D */
  cfg->flux_min = 0.2f * cfg->lambda_m;      /* below the flux at top speed */
  cfg->dfvc_flux_bw = 2.0f * PI_F * 1000.0f; /* Rubino 2020, IV.7: 1 kHz */
  cfg->dfvc_iqs_bw = 2.0f * PI_F * 1000.0f;
}

/* A parameter that must be finite and inside [lo, hi]. */
static int in_range(float x, float lo, float hi) {
  return isfinite(x) && x >= lo && x <= hi;
}

#define CHECK(cond, name)                                                                          \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      *field = (name);                                                                             \
      return -1;                                                                                   \
    }                                                                                              \
  } while (0)

int drive_config_check(const drive_config_t *cfg, const char **field) {
  CHECK(in_range(cfg->pole_pairs, 1.0f, 100.0f) &&
            fabsf(cfg->pole_pairs - roundf(cfg->pole_pairs)) < 1e-6f,
        "pole_pairs");
  CHECK(in_range(cfg->rs, 1e-5f, 1e3f), "rs");
  CHECK(in_range(cfg->ld, 1e-7f, 10.0f), "ld");
  CHECK(in_range(cfg->lq, 1e-7f, 10.0f), "lq");
  CHECK(in_range(cfg->lambda_m, 0.0f, 10.0f), "lambda_m");
  CHECK(in_range(cfg->inertia, 1e-9f, 1e3f), "inertia");
  CHECK(in_range(cfg->ts, 1e-6f, 1e-2f), "ts");
  CHECK(cfg->slow_div >= 1 && cfg->slow_div <= 1000, "slow_div");
  CHECK(in_range(cfg->dead_time, 0.0f, 0.25f * cfg->ts), "dead_time");
  CHECK(in_range(cfg->i_max, 1e-3f, 1e4f), "i_max");
  CHECK(in_range(cfg->i_trip, cfg->i_max, 1e4f), "i_trip");
  CHECK(in_range(cfg->v_dc_max, 1.0f, 1e4f), "v_dc_max");
  CHECK(in_range(cfg->v_dc_min, 0.0f, cfg->v_dc_max), "v_dc_min");
  CHECK(in_range(cfg->speed_max, 0.0f, 1e5f), "speed_max");
  CHECK(in_range(cfg->speed_trip, cfg->speed_max, 1e5f) && cfg->speed_trip > 0.0f, "speed_trip");
  CHECK(in_range(cfg->offset_max, 0.0f, 1e3f), "offset_max");
  CHECK(cfg->offset_samples >= 1 && cfg->offset_samples <= 60000, "offset_samples");
  CHECK(in_range(cfg->torque_max, 0.0f, 1e5f), "torque_max");
  CHECK(in_range(cfg->v_margin, 0.1f, 1.0f), "v_margin");
  CHECK((unsigned)cfg->law < (unsigned)DRIVE_LAW_COUNT, "law");
  CHECK((unsigned)cfg->mode < (unsigned)DRIVE_MODE_COUNT, "mode");
  CHECK(cfg->mode != DRIVE_MODE_CURRENT || cfg->law == DRIVE_LAW_FOC, "mode");
  /* Discrete PI current loop: wc*Ts beyond ~0.5 is not a sane design. */
  CHECK(in_range(cfg->current_bw, 1.0f, 0.5f / cfg->ts), "current_bw");
  CHECK(in_range(cfg->speed_bw, 0.1f, 0.25f * cfg->current_bw), "speed_bw");
  CHECK(in_range(cfg->accel_max, 1e-3f, 1e7f), "accel_max");
  CHECK(in_range(cfg->pll_bw, 1.0f, 0.5f / cfg->ts), "pll_bw");
  CHECK(in_range(cfg->enc_offset, -7.0f, 7.0f), "enc_offset");
  CHECK(in_range(cfg->flux_obs_wc, 0.0f, 0.25f / cfg->ts), "flux_obs_wc");
  CHECK(in_range(cfg->delta_max, 0.1f, 1.5f), "delta_max");
  CHECK(in_range(cfg->vsd_max, 0.0f, 1e4f), "vsd_max");
  CHECK(in_range(cfg->flux_min, 0.0f, 10.0f), "flux_min");
  CHECK(in_range(cfg->dfvc_flux_bw, 1.0f, 0.5f / cfg->ts), "dfvc_flux_bw");
  CHECK(in_range(cfg->dfvc_iqs_bw, 1.0f, 0.5f / cfg->ts), "dfvc_iqs_bw");
  *field = "";
  return 0;
}

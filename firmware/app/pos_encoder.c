/*
 * pos_encoder.c - the encoder as a position source: quantised mechanical
 * angle -> electrical angle, half-count corrected, and a type-2 PLL for the
 * speed and the plausibility check.
 *
 * Quantisation: an incremental encoder (and the SIL's, sil/plant) reports
 * floor(theta / step) counts, so the reading lies between 0 and one count
 * below the true angle: on average half a count low. Adding half a count
 * (pi / cpr mechanical) removes that bias; without it the DFVC torque sat
 * 0.7 % above its reference at 100 rpm with 4096 counts (the field is
 * oriented half a count late). enc_cpr = 0: an unquantised angle.
 * The angle is used as measured (Park at the sample); the PLL (pll_bw)
 * gives the speed, and its prediction for this sample the plausibility
 * measure (health).
 */
#include <stddef.h>

#include "math/fd_math.h"
#include "math/frames.h"
#include "pos_encoder.h"

FD_COLD void pos_encoder_init(pos_state_t *s, const drive_config_t *cfg) {
  angle_pll_init(&s->enc.pll, cfg->pll_bw, cfg->ts);
  s->enc.offset = cfg->enc_offset;
  /* mut: encoder_half_count_removed */
  s->enc.half = cfg->enc_cpr > 0u ? FRAMES_PI / (float)cfg->enc_cpr : 0.0f;
  s->enc.started = false;
}

void pos_encoder_reset(pos_state_t *s) {
  s->enc.started = false;
}

static float enc_electrical(const pos_state_t *s, const drive_config_t *cfg,
                            const hal_sample_t *smp) {
  return frames_wrap_pi(cfg->pole_pairs * (smp->enc_angle + s->enc.half) - s->enc.offset);
}

void pos_encoder_update(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                        pos_io_t *io) {
  const pos_input_t *in = &io->in;
  pos_estimate_t *out = &io->out;
  (void)in;
  angle_pll_t *pll = &s->enc.pll;
  out->t = smp->t_enc; /* out->load: 0 from the source's start (drive.c) */
  out->valid = smp->enc_valid && fd_isfinite(smp->enc_angle);
  if (!out->valid) {
    /* no measurement: the PLL coasts; the estimate is not usable */
    angle_pll_update(pll, NAN);
    out->theta = pll->theta;
    out->omega = pll->omega;
    out->rate = pll->omega_rate;
    out->health = 0.0f;
    return;
  }
  const float th = enc_electrical(s, cfg, smp);
  if (!s->enc.started) {
    angle_pll_reset(pll, th, 0.0f);
    s->enc.started = true;
  }
  /* th is finite (frames_wrap_pi): angle_pll_update's error, taken once */
  const float e = frames_wrap_pi(th - pll->theta);
  out->health = fabsf(e); /* measured - predicted */
  angle_pll_update_err(pll, e);
  out->theta = th;
  out->omega = pll->omega;
  out->rate = pll->omega_rate;
}

/* Held at electrical angle theta: offset = measured - theta. */
void pos_encoder_align(pos_state_t *s, const drive_config_t *cfg, const hal_sample_t *smp,
                       float theta) {
  s->enc.offset = frames_wrap_pi(s->enc.offset + enc_electrical(s, cfg, smp) - theta);
  s->enc.started = false;
}

/* Counts enough to commutate: 8 per electrical revolution (45 degrees
 * electrical per count; the PLL interpolates between them at speed). An
 * encoder of 16 counts on Rubino's 21 pole pairs has less than one count
 * per electrical revolution: the drive cannot even tell the sector. */
#define ENC_MIN_COUNTS_PER_E_REV 8.0f
FD_COLD const char *pos_encoder_check(const drive_config_t *cfg, const char **field) {
  if (cfg->enc_cpr > 0u && (float)cfg->enc_cpr < ENC_MIN_COUNTS_PER_E_REV * cfg->pole_pairs) {
    *field = "enc_cpr";
    return "too few encoder counts to commutate: at least 8 per electrical revolution "
           "(enc_cpr >= 8 pole_pairs; 0: an unquantised angle)";
  }
  return NULL;
}

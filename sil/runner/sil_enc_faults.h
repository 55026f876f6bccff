/*
 * sil_enc_faults.h - encoder faults injected in the SIL (scenario
 * `inject.encoder`, docs/scenarios.md), applied to the mechanical angle the
 * board reads, after the plant's quantisation and `inject.encoder_error`:
 *   missing  each count edge is lost with this probability (an incremental
 *            encoder's counter then lags the shaft for good: the error
 *            grows with every lost edge);
 *   jitter   the sample instant jitters by this rms time [s]: the reading
 *            is off by w_m dt;
 *   reversed while > 0.5 the encoder counts the other way (A and B
 *            swapped), from the angle it read when the fault began;
 *   frozen   while > 0.5 the reading holds (a stopped counter, a broken
 *            cable with a latched interface).
 * Loss of signal is `inject.encoder_invalid` (the interface flags it).
 */
#ifndef FD_SIL_ENC_FAULTS_H
#define FD_SIL_ENC_FAULTS_H

#include <stdbool.h>
#include <stdint.h>

#include "profile.h"

typedef struct {
  profile_t frozen, reversed; /* on while > 0.5 */
  double jitter;              /* rms sample-time jitter [s] */
  double missing;             /* probability that a count edge is lost */
  uint32_t seed;
} sil_enc_faults_t;

typedef struct {
  bool init;
  double prev;     /* the plant's (quantised) angle at the last sample [rad] */
  double lost;     /* angle of the lost edges [rad] (counts x step) */
  bool frozen;     /* holding */
  double hold;     /* the reading held */
  bool reversed;   /* counting backwards */
  double rev_base; /* reversed reading = 2 rev_base - angle */
  uint64_t rng;    /* xorshift64* state */
} sil_enc_state_t;

void sil_enc_faults_reset(sil_enc_state_t *st, const sil_enc_faults_t *f);
/* The reading at t for the plant's angle `angle` (after quantisation and
 * encoder_error, [0, 2 pi) not required), the true speed w_m [rad/s] and
 * the encoder's step (2 pi / counts, 0: ideal); returns it in [0, 2 pi). */
double sil_enc_faults_apply(const sil_enc_faults_t *f, sil_enc_state_t *st, double t, double angle,
                            double w_m, double step);

#endif

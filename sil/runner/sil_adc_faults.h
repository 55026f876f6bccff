/*
 * sil_adc_faults.h - current-ADC channel faults injected in the SIL
 * (scenario `inject.current`, docs/scenarios.md): applied to the board's
 * sample set after the plant's ADC, per channel, while the fault's
 * `active` profile is > 0.5 (no profile: always).
 */
#ifndef FD_SIL_ADC_FAULTS_H
#define FD_SIL_ADC_FAULTS_H

#include <stdbool.h>

#include "hal.h"
#include "profile.h"

typedef enum {
  SIL_ADC_STUCK,   /* reads `value` [A] (a rail: +-sensors.i_full_scale) */
  SIL_ADC_FROZEN,  /* holds the reading it had when the fault began */
  SIL_ADC_NAN,     /* reads NaN (a broken conversion result) */
  SIL_ADC_INVALID, /* not converted: the sample set is flagged invalid
                      (hal_sample_t.valid) and the channel holds its last
                      reading (stale) */
  SIL_ADC_OFFSET,  /* `value` [A] added (offset drift after calibration) */
  SIL_ADC_GAIN,    /* reading times 1 + `value` (gain drift) */
  SIL_ADC_KIND_COUNT
} sil_adc_kind_t;

#define SIL_ADC_FAULTS_MAX 6

typedef struct {
  int channel; /* 0, 1, 2: a, b, c */
  sil_adc_kind_t kind;
  profile_t active; /* > 0.5: active; no terms: always */
  profile_t value;  /* stuck, offset, gain */
} sil_adc_fault_t;

typedef struct {
  int n;
  sil_adc_fault_t f[SIL_ADC_FAULTS_MAX];
} sil_adc_faults_t;

/* What the faults remember between samples. */
typedef struct {
  bool held[SIL_ADC_FAULTS_MAX]; /* frozen: holding */
  float hold[SIL_ADC_FAULTS_MAX];
  float last[3]; /* the readings the drive got last */
} sil_adc_state_t;

/* The kind's name in the scenario ("stuck", ...), NULL beyond the list. */
const char *sil_adc_kind_name(int kind);
/* Whether the kind takes a `value` profile. */
bool sil_adc_kind_has_value(sil_adc_kind_t kind);
void sil_adc_faults_reset(sil_adc_state_t *st);
/* Applies the faults active at t to the sample set s (readings clamped to
 * the ADC range +-full_scale, as a converter would). */
void sil_adc_faults_apply(const sil_adc_faults_t *fs, sil_adc_state_t *st, double t,
                          double full_scale, hal_sample_t *s);

#endif

/*
 * sil_adc_faults.c - current-ADC channel faults (sil_adc_faults.h).
 */
#include "sil_adc_faults.h"

#include <math.h>
#include <stddef.h>

static const char *const kind_names[SIL_ADC_KIND_COUNT] = {"stuck",   "frozen", "nan",
                                                           "invalid", "offset", "gain"};

const char *sil_adc_kind_name(int kind) {
  return kind >= 0 && kind < (int)SIL_ADC_KIND_COUNT ? kind_names[kind] : NULL;
}

bool sil_adc_kind_has_value(sil_adc_kind_t kind) {
  return kind == SIL_ADC_STUCK || kind == SIL_ADC_OFFSET || kind == SIL_ADC_GAIN;
}

void sil_adc_faults_reset(sil_adc_state_t *st) {
  for (int k = 0; k < SIL_ADC_FAULTS_MAX; ++k) {
    st->held[k] = false;
    st->hold[k] = 0.0f;
  }
  for (int j = 0; j < 3; ++j) {
    st->last[j] = 0.0f;
  }
}

static float clamp_fs(double v, double fs) {
  return (float)(v > fs ? fs : (v < -fs ? -fs : v));
}

void sil_adc_faults_apply(const sil_adc_faults_t *fs, sil_adc_state_t *st, double t,
                          double full_scale, hal_sample_t *s) {
  for (int k = 0; k < fs->n && k < SIL_ADC_FAULTS_MAX; ++k) {
    const sil_adc_fault_t *f = &fs->f[k];
    const int j = f->channel;
    if (f->active.n > 0 && !(profile_eval(&f->active, t) > 0.5)) {
      st->held[k] = false;
      continue;
    }
    const double v = sil_adc_kind_has_value(f->kind) ? profile_eval(&f->value, t) : 0.0;
    switch (f->kind) {
    case SIL_ADC_STUCK:
      s->i_abc[j] = clamp_fs(v, full_scale);
      break;
    case SIL_ADC_FROZEN:
      if (!st->held[k]) {
        st->held[k] = true;
        st->hold[k] = s->i_abc[j];
      }
      s->i_abc[j] = st->hold[k];
      break;
    case SIL_ADC_NAN:
      s->i_abc[j] = NAN;
      break;
    case SIL_ADC_INVALID:
      s->i_abc[j] = st->last[j];
      s->valid = false;
      break;
    case SIL_ADC_OFFSET:
      s->i_abc[j] = clamp_fs((double)s->i_abc[j] + v, full_scale);
      break;
    case SIL_ADC_GAIN:
      s->i_abc[j] = clamp_fs((double)s->i_abc[j] * (1.0 + v), full_scale);
      break;
    default:
      break;
    }
  }
  for (int j = 0; j < 3; ++j) {
    st->last[j] = s->i_abc[j];
  }
}

/*
 * sil_can_faults.c - CAN link faults of the scenario at a given time.
 */
#include "sil_can_faults.h"

void sil_can_dir_at(const sil_can_dir_t *d, double t, can_link_fault_t *out) {
  out->loss = d->loss.n > 0 ? profile_eval(&d->loss, t) : 0.0;
  out->delay = d->delay.n > 0 ? profile_eval(&d->delay, t) : 0.0;
  out->jitter = d->jitter.n > 0 ? profile_eval(&d->jitter, t) : 0.0;
  out->every = d->every;
}

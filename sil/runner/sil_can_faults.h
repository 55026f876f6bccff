/*
 * sil_can_faults.h - CAN frame loss and delay injected in the SIL's
 * socketcand transport (scenario `inject.can`, docs/scenarios.md): per
 * direction, profiles in simulated time evaluated at each poll of the
 * transport and handed to its links (hal/sil/can_link.h).
 */
#ifndef FD_SIL_CAN_FAULTS_H
#define FD_SIL_CAN_FAULTS_H

#include <stdbool.h>
#include <stdint.h>

#include "can_link.h"
#include "profile.h"

typedef struct {
  profile_t loss;   /* probability a frame is lost, in [0, 1] */
  profile_t delay;  /* latency [s], in [0, SIL_CAN_DELAY_MAX] */
  profile_t jitter; /* extra latency, uniform in [0, jitter] [s], likewise */
  uint32_t every;   /* every n-th frame is lost (0: none) */
} sil_can_dir_t;

#define SIL_CAN_DELAY_MAX 1.0 /* [s]: the links hold CAN_LINK_QUEUE frames */

typedef struct {
  bool on;          /* inject.can given */
  uint32_t seed;    /* loss and jitter draws */
  sil_can_dir_t rx; /* host -> drive */
  sil_can_dir_t tx; /* drive -> host */
} sil_can_faults_t;

/* The fault in force at time t [s]. */
void sil_can_dir_at(const sil_can_dir_t *d, double t, can_link_fault_t *out);

#endif

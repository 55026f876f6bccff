/*
 * can_link.h - an injected CAN link fault in one direction of a SIL CAN
 * transport (hal/sil/can_socketcand.c): frame loss (a probability, and/or
 * every n-th frame) and delay (a fixed latency plus a uniform jitter).
 *
 * Times are the simulated time the transport is polled with, so a delay
 * is quantised to its polls (the main-loop period, 1 ms). Frames keep their
 * order (one bus: a frame never overtakes an earlier one, so with jitter a
 * frame leaves at max(its own instant, the previous frame's)). The loss
 * draws come from a seeded generator: runs are repeatable given the same
 * frames at the same instants.
 */
#ifndef FLUXDRIVE_CAN_LINK_H
#define FLUXDRIVE_CAN_LINK_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"

#define CAN_LINK_QUEUE 2048 /* frames in flight (delayed) */

/* The fault in force; the caller may change it before each offer. */
typedef struct {
  double loss;    /* probability that a frame is lost, [0, 1] */
  uint32_t every; /* every n-th frame offered is lost (0: none) */
  double delay;   /* latency [s], >= 0 */
  double jitter;  /* extra latency uniform in [0, jitter] [s], >= 0 */
} can_link_fault_t;

typedef struct {
  can_link_fault_t fault;
  uint64_t rng;     /* xorshift64* state */
  uint32_t offered; /* frames offered */
  uint32_t lost;    /* of them lost */
  uint32_t delayed; /* passed with a latency > 0 */
  double last_out;  /* release instant of the last frame queued [s] */
  uint32_t head, tail;
  hal_can_frame_t frame[CAN_LINK_QUEUE];
  double out_t[CAN_LINK_QUEUE];
} can_link_t;

/* No fault, the generator seeded (any seed, 0 included). */
void can_link_init(can_link_t *l, uint64_t seed);
/* Whether a frame can be offered now. */
bool can_link_room(const can_link_t *l);
/* A frame enters the link at time t: lost, or queued for its release.
 * false when the link is full (nothing done: offer it again later). */
bool can_link_offer(can_link_t *l, const hal_can_frame_t *f, double t);
/* The next frame whose release instant is at or before t (in order);
 * false when none is due. *t_out receives that instant. */
bool can_link_take(can_link_t *l, double t, hal_can_frame_t *f, double *t_out);

#endif

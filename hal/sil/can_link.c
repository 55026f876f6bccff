/*
 * can_link.c - injected CAN frame loss and delay (see can_link.h).
 */
#include "can_link.h"

#include <string.h>

void can_link_init(can_link_t *l, uint64_t seed) {
  memset(l, 0, sizeof *l);
  /* splitmix64 of the seed: any seed gives a non-zero xorshift state */
  uint64_t z = seed + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  l->rng = z != 0u ? z : 1u;
  l->last_out = -1e300;
}

/* Uniform in [0, 1). */
static double uniform(can_link_t *l) {
  uint64_t x = l->rng;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  l->rng = x;
  return (double)((x * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

bool can_link_room(const can_link_t *l) {
  return l->head - l->tail < CAN_LINK_QUEUE;
}

bool can_link_offer(can_link_t *l, const hal_can_frame_t *f, double t) {
  if (!can_link_room(l)) {
    return false;
  }
  const can_link_fault_t *q = &l->fault;
  l->offered++;
  /* both draws every frame: the pattern does not depend on which fault is on */
  const double u_loss = uniform(l);
  const double u_jit = uniform(l);
  if ((q->every > 0u && l->offered % q->every == 0u) || u_loss < q->loss) {
    l->lost++;
    return true;
  }
  const double lat = q->delay + u_jit * q->jitter;
  double out = t + lat;
  if (out < l->last_out) {
    out = l->last_out; /* no overtaking */
  }
  if (lat > 0.0) {
    l->delayed++;
  }
  l->last_out = out;
  const uint32_t i = l->head % CAN_LINK_QUEUE;
  l->frame[i] = *f;
  l->out_t[i] = out;
  l->head++;
  return true;
}

bool can_link_take(can_link_t *l, double t, hal_can_frame_t *f, double *t_out) {
  if (l->head == l->tail) {
    return false;
  }
  const uint32_t i = l->tail % CAN_LINK_QUEUE;
  if (l->out_t[i] > t) {
    return false;
  }
  *f = l->frame[i];
  if (t_out != NULL) {
    *t_out = l->out_t[i];
  }
  l->tail++;
  return true;
}

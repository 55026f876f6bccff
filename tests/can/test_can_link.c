/*
 * The SIL's injected CAN link fault (hal/sil/can_link.h, scenario
 * inject.can): every n-th frame lost exactly, a loss probability within the
 * binomial's bounds, a latency never shortened, jitter without overtaking,
 * the same pattern from the same seed, a full link refusing (not losing).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>

#include "can_link.h"

static can_link_t link; /* large: off the stack */

static hal_can_frame_t frame(uint32_t n) {
  hal_can_frame_t f;
  memset(&f, 0, sizeof f);
  f.id = 0x123u;
  f.dlc = 4u;
  memcpy(f.data, &n, sizeof n);
  return f;
}

static uint32_t number(const hal_can_frame_t *f) {
  uint32_t n;
  memcpy(&n, f->data, sizeof n);
  return n;
}

static void every_nth_frame_is_lost(void **state) {
  (void)state;
  can_link_init(&link, 1u);
  link.fault.every = 4u;
  uint32_t got = 0u;
  for (uint32_t n = 1u; n <= 100u; ++n) {
    const hal_can_frame_t f = frame(n);
    assert_true(can_link_offer(&link, &f, 1e-3 * n));
    hal_can_frame_t g;
    if (can_link_take(&link, 1e-3 * n, &g, NULL)) {
      assert_int_equal(number(&g), n); /* no latency: out at once */
      assert_true(n % 4u != 0u);
      got++;
    } else {
      assert_int_equal(n % 4u, 0u);
    }
  }
  printf("every 4th: %u of 100 passed, %u lost\n", (unsigned)got, (unsigned)link.lost);
  assert_int_equal(got, 75u);
  assert_int_equal(link.lost, 25u);
}

static uint32_t lost_with_seed(uint64_t seed, double p, uint32_t n) {
  can_link_init(&link, seed);
  link.fault.loss = p;
  hal_can_frame_t g;
  for (uint32_t k = 0u; k < n; ++k) {
    const hal_can_frame_t f = frame(k);
    assert_true(can_link_offer(&link, &f, 0.0));
    (void)can_link_take(&link, 0.0, &g, NULL);
  }
  return link.lost;
}

static void loss_probability_and_seed(void **state) {
  (void)state;
  const uint32_t n = 20000u;
  const double p = 0.3, sd = sqrt(n * p * (1.0 - p));
  const uint32_t a = lost_with_seed(5u, p, n), b = lost_with_seed(5u, p, n);
  const uint32_t c = lost_with_seed(6u, p, n);
  printf("loss 0.3 of %u frames: %u lost (limits %.0f .. %.0f); same seed %u, other seed %u\n",
         (unsigned)n, (unsigned)a, n * p - 5.0 * sd, n * p + 5.0 * sd, (unsigned)b, (unsigned)c);
  assert_true(fabs(a - n * p) <= 5.0 * sd);
  assert_int_equal(a, b);
  assert_true(a != c); /* another pattern (equal counts would be a 1 % coincidence) */
  assert_int_equal(lost_with_seed(7u, 0.0, 1000u), 0u);
  assert_int_equal(lost_with_seed(7u, 1.0, 1000u), 1000u);
}

/* Frames offered every 1 ms with 20 ms + up to 15 ms latency, taken at
 * 1 ms polls: each leaves at or after its own instant plus the latency,
 * at most the latency and jitter plus one poll later, in order. */
static void latency_and_jitter_keep_order(void **state) {
  (void)state;
  can_link_init(&link, 3u);
  link.fault.delay = 0.020;
  link.fault.jitter = 0.015;
  double lo = 1.0, hi = 0.0;
  uint32_t next = 0u, n_out = 0u;
  for (uint32_t k = 0u; k < 2000u; ++k) {
    const double t = 1e-3 * k;
    if (k < 1000u) {
      const hal_can_frame_t f = frame(k);
      assert_true(can_link_offer(&link, &f, t));
    }
    hal_can_frame_t g;
    double t_out;
    while (can_link_take(&link, t, &g, &t_out)) {
      const uint32_t m = number(&g);
      assert_int_equal(m, next++);
      const double lat = t - 1e-3 * m;
      lo = fmin(lo, lat);
      hi = fmax(hi, lat);
      assert_true(t_out <= t);
      n_out++;
    }
  }
  printf("latency 20 ms + jitter 15 ms: %u frames in order, seen %.1f .. %.1f ms after sending "
         "(limits 20.0 .. 36.0)\n",
         (unsigned)n_out, 1e3 * lo, 1e3 * hi);
  assert_int_equal(n_out, 1000u);
  assert_true(lo >= 0.020 - 1e-12);
  assert_true(hi <= 0.020 + 0.015 + 1e-3 + 1e-12);
  assert_true(hi > 0.030); /* the jitter acts */
  assert_int_equal(link.delayed, 1000u);
}

static void a_full_link_refuses(void **state) {
  (void)state;
  can_link_init(&link, 1u);
  link.fault.delay = 1.0;
  const hal_can_frame_t f = frame(0u);
  for (int k = 0; k < CAN_LINK_QUEUE; ++k) {
    assert_true(can_link_offer(&link, &f, 0.0));
  }
  assert_false(can_link_room(&link));
  assert_false(can_link_offer(&link, &f, 0.0));
  assert_int_equal(link.offered, CAN_LINK_QUEUE);
  assert_int_equal(link.lost, 0u);
  hal_can_frame_t g;
  assert_false(can_link_take(&link, 0.999, &g, NULL));
  assert_true(can_link_take(&link, 1.0, &g, NULL));
  assert_true(can_link_room(&link));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(every_nth_frame_is_lost), cmocka_unit_test(loss_probability_and_seed),
      cmocka_unit_test(latency_and_jitter_keep_order), cmocka_unit_test(a_full_link_refuses)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}

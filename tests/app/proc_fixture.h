/*
 * proc_fixture.h - the procedures' unit-test frame (test_proc*.c): the
 * parameter set, the machine and the position source built from it, and
 * the setup, state and sample a procedure sees. A test's fixture_t holds
 * PROC_FIXTURE_FIELDS and whatever else it needs; proc_fixture_bind builds
 * the machine, the source and the setup from the parameter set as the test
 * left it (the drive does the same: drive_proc_setup).
 */
#ifndef FD_TEST_PROC_FIXTURE_H
#define FD_TEST_PROC_FIXTURE_H

#include <cmocka.h>

#include "drive.h"
#include "proc.h"

#define PROC_FIXTURE_FIELDS                                                                        \
  drive_config_t cfg;                                                                              \
  machine_t m;                                                                                     \
  pos_state_t pos_st;                                                                              \
  float offset[3];                                                                                 \
  float i_sum_noise;                                                                               \
  proc_setup_t su;                                                                                 \
  proc_state_t st;                                                                                 \
  hal_sample_t s;

static inline void proc_fixture_bind_parts(drive_config_t *c, machine_t *m, pos_state_t *pos_st,
                                           float *offset, float *i_sum_noise, proc_setup_t *su) {
  assert_int_equal(machine_init_linear(m, c->pole_pairs, c->rs, c->ld, c->lq, c->lambda_m), 0);
  const pos_source_row_t *ps = pos_source(c->pos_source);
  ps->init(pos_st, c);
  ps->reset(pos_st);
  *su = (proc_setup_t){c, m, ps, pos_st, offset, i_sum_noise, (ps->caps & POS_CAP_GATED) != 0u};
}

/* fx: a fixture with PROC_FIXTURE_FIELDS */
#define proc_fixture_bind(fx)                                                                      \
  proc_fixture_bind_parts(&(fx)->cfg, &(fx)->m, &(fx)->pos_st, (fx)->offset, &(fx)->i_sum_noise,   \
                          &(fx)->su)

#endif

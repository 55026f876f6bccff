/*
 * The table of position sources as data (firmware/app/pos_sources.c,
 * pos_star.h), without the SIL: every entry of POS_SOURCE_LIST has its
 * row; a star-point row names the columns its name says (method, tracker,
 * identification) and each column has the functions its decoding calls;
 * the source's init takes the row's columns into the state; each tracker's
 * angle and speed indices read what its start wrote; the configuration
 * check is the tracker's and the identification's, on their rows only.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive_config.h"
#include "drive_enums.h"
#include "pos_star.h"

/* What each row's name says: method, tracker, identification */
typedef struct {
  const char *name;
  const pos_method_t *method;
  const pos_tracker_t *tracker;
  const pos_ident_t *ident;
} want_t;

static const want_t want[] = {
    {"dfc", &pos_method_dfc, &pos_tracker_pll, NULL},
    {"dfc_inv", &pos_method_dfc_inv, &pos_tracker_pll, NULL},
    {"ivd", &pos_method_ivd, &pos_tracker_pll, NULL},
    {"dfc+kf", &pos_method_dfc, &pos_tracker_kf, NULL},
    {"ivd+kf", &pos_method_ivd, &pos_tracker_kf, NULL},
    {"ekf", &pos_method_dfc, &pos_tracker_ekf, NULL},
    {"ivd+kf+rls", &pos_method_ivd, &pos_tracker_kf, &pos_ident_rls},
};

static void every_source_has_its_row(void **state) {
  (void)state;
  unsigned star = 0u;
  for (unsigned i = 0u; i < (unsigned)POS_SOURCE_COUNT; ++i) {
    const pos_source_row_t *r = pos_source((pos_source_t)i);
    assert_non_null(r);
    assert_non_null(r->init);
    assert_non_null(r->reset);
    assert_non_null(r->update);
    assert_non_null(r->check);
    if ((r->caps & POS_CAP_ALIGN) != 0u) {
      assert_non_null(r->align);
    }
    if ((r->caps & POS_CAP_GATED) == 0u) { /* the encoder: its own functions, no columns */
      assert_null(r->method);
      assert_null(r->tracker);
      assert_null(r->ident);
      continue;
    }
    star++;
    const char *name = drive_pos_source_name(i);
    const want_t *w = NULL;
    for (size_t k = 0u; k < sizeof want / sizeof want[0]; ++k) {
      if (strcmp(want[k].name, name) == 0) {
        w = &want[k];
      }
    }
    assert_non_null(w); /* a new row: add what its name says above */
    assert_ptr_equal(r->method, w->method);
    assert_ptr_equal(r->tracker, w->tracker);
    assert_ptr_equal(r->ident, w->ident);
    assert_non_null(r->hold);
  }
  assert_int_equal(star, sizeof want / sizeof want[0]);
  assert_null(pos_source(POS_SOURCE_COUNT));
}

static void columns_have_their_functions(void **state) {
  (void)state;
  const pos_tracker_t *t[] = {&pos_tracker_pll, &pos_tracker_kf, &pos_tracker_ekf};
  for (size_t k = 0u; k < sizeof t / sizeof t[0]; ++k) {
    assert_non_null(t[k]->measure);
    assert_non_null(t[k]->coast);
    assert_non_null(t[k]->start);
    assert_non_null(t[k]->branch);
    assert_non_null(t[k]->init);
    /* a state predicted to the edge is one that predicts */
    assert_true(t[k]->at_edge == (t[k]->predict != NULL));
  }
  assert_non_null(pos_ident_rls.init);
  assert_non_null(pos_ident_rls.step);
  assert_non_null(pos_ident_rls.aligned);
  assert_non_null(pos_ident_rls.check);
}

static drive_config_t star_cfg(pos_source_t src) {
  drive_config_t c;
  drive_config_default(&c);
  c.pos_source = src;
  c.align_time = 0.05f;
  c.inertia = 1e-4f;
  return c;
}

/* init takes the row's columns; each tracker's indices read what its
 * start wrote */
static void init_decodes_the_row(void **state) {
  (void)state;
  for (unsigned i = 0u; i < (unsigned)POS_SOURCE_COUNT; ++i) {
    const pos_source_row_t *r = pos_source((pos_source_t)i);
    if (r->tracker == NULL) {
      continue;
    }
    const drive_config_t c = star_cfg((pos_source_t)i);
    const char *field = NULL;
    assert_null(r->check(&c, &field));
    pos_state_t s;
    memset(&s, 0xa5, sizeof s);
    r->init(&s, &c);
    assert_ptr_equal(s.star.method, r->method);
    assert_ptr_equal(s.star.tracker, r->tracker);
    assert_ptr_equal(s.star.ident, r->ident);
    assert_false(s.star.trk.started);
    assert_false(s.star.pol.aligned);
    r->reset(&s);
    s.star.tracker->start(&s, 0.3f, 12.0f);
    assert_float_equal(pos_track_theta(&s), 0.3f, 0.0f);
    assert_float_equal(pos_track_omega(&s), 12.0f, 0.0f);
    /* the alignment's branch: pi on, the speed kept */
    s.star.tracker->branch(&s, -2.0f);
    assert_float_equal(pos_track_theta(&s), -2.0f, 0.0f);
    assert_float_equal(pos_track_omega(&s), 12.0f, 0.0f);
  }
}

/* The column's checks, on their rows only: the EKF's |p| limit, the RLS's
 * covariance limits. */
static void checks_are_the_columns(void **state) {
  (void)state;
  for (unsigned i = 0u; i < (unsigned)POS_SOURCE_COUNT; ++i) {
    const pos_source_row_t *r = pos_source((pos_source_t)i);
    if (r->tracker == NULL) {
      continue;
    }
    drive_config_t c = star_cfg((pos_source_t)i);
    c.dfc_b = 0.4f * c.dfc_a; /* the IVD converges (< 1/2), the EKF is refused (> 0.35) */
    const char *field = NULL;
    const char *why = r->check(&c, &field);
    if (r->tracker == &pos_tracker_ekf) {
      assert_non_null(why);
      assert_string_equal(field, "dfc_b");
    } else {
      assert_null(why);
    }
    c = star_cfg((pos_source_t)i);
    c.rls_p_min = 2.0f * c.rls_p_max;
    field = NULL;
    why = r->check(&c, &field);
    if (r->ident != NULL) {
      assert_non_null(why);
      assert_string_equal(field, "rls_p_min");
    } else {
      assert_null(why);
    }
    c = star_cfg((pos_source_t)i);
    c.inertia = 0.0f;
    field = NULL;
    why = r->check(&c, &field);
    if (r->tracker->at_edge) { /* the Kalman filters' model */
      assert_non_null(why);
      assert_string_equal(field, "inertia");
    } else {
      assert_null(why);
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(every_source_has_its_row), cmocka_unit_test(columns_have_their_functions),
      cmocka_unit_test(init_decodes_the_row), cmocka_unit_test(checks_are_the_columns)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}

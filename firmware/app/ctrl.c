/*
 * ctrl.c - the law table and what every law shares: selection with the
 * gates off, the availability check, the applied-voltage memory and the
 * predictive dead-time compensation's setup (Rubino 2020, Fig. 8; its
 * per-period delta is inline in ctrl.h).
 */
#include "ctrl.h"

#include <stddef.h>

#include "ctrl_laws.h"
#include "math/fd_math.h"

/* One row per DRIVE_LAW_LIST entry, in its order. */
#define CTRL_LAW_ROW(E, n, d) &ctrl_law_##n,
static const ctrl_law_t *const laws[DRIVE_LAW_COUNT] = {DRIVE_LAW_LIST(CTRL_LAW_ROW)};
#undef CTRL_LAW_ROW

/* Current band over which the dead-time correction fades through zero. */
#define DEADTIME_BAND_FRACTION 0.02f

const ctrl_law_t *ctrl_law(drive_law_t law) {
  return (unsigned)law < (unsigned)DRIVE_LAW_COUNT ? laws[law] : NULL;
}

const char *ctrl_unavailable(const ctrl_t *c, drive_law_t law) {
  const ctrl_law_t *row = ctrl_law(law);
  if (row == NULL) {
    return "no such law";
  }
  return (c->available & (1u << (unsigned)law)) != 0u ? NULL : row->check(&c->su);
}

FD_COLD const char *ctrl_law_refusal(drive_law_t law, const ctrl_setup_t *su) {
  const ctrl_law_t *row = ctrl_law(law);
  if (row == NULL) {
    return "no such law";
  }
  const char *why = row->check(su);
  if (why != NULL) {
    return why;
  }
  ctrl_state_t scratch; /* what the law's init refuses, without touching a drive */
  return row->init(&scratch, su) == 0 ? NULL : "the law's initialisation refused the parameter set";
}

FD_COLD int ctrl_select(ctrl_t *c, drive_law_t law) {
  const ctrl_law_t *row = ctrl_law(law);
  if (row == NULL || ctrl_unavailable(c, law) != NULL) {
    return -1;
  }
  /* into a scratch state first: a refused init leaves the law in force,
   * its state and its row exactly as they were (issue 22, point 2) */
  ctrl_state_t st;
  /* mut: law_init_over_running_state */
  if (row->init(&st, &c->su) != 0) {
    return -1;
  }
  c->st = st;
  c->law = law;
  c->impl = row;
  return 0;
}

FD_COLD int ctrl_init(ctrl_t *c, const drive_config_t *cfg, const machine_t *machine, float t_out,
                      drive_law_t law, const char **reason) {
  *c = (ctrl_t){0};
  c->su = (ctrl_setup_t){cfg, machine, t_out};
  for (unsigned k = 0; k < (unsigned)DRIVE_LAW_COUNT; ++k) {
    c->available |= laws[k]->check(&c->su) == NULL ? (1u << k) : 0u;
  }
  const deadtime_comp_cfg_t tcfg = {cfg->dead_time, cfg->ts, DEADTIME_BAND_FRACTION * cfg->i_max};
  if (deadtime_comp_init(&c->dtc, &tcfg) != 0) {
    *reason = "dead-time compensation refused dead_time or ts";
    return -1;
  }
  const char *why = ctrl_unavailable(c, law);
  if (why != NULL) {
    *reason = why;
    return -1;
  }
  if (ctrl_select(c, law) != 0) {
    *reason = "the law refused the parameter set";
    return -1;
  }
  *reason = "";
  return 0;
}

void ctrl_reset(ctrl_t *c) {
  c->impl->reset(&c->st);
}

/*
 * presets.h - built-in machines: the plant parameters and a matching
 * controller parameter set (limits and protections scaled to the rating).
 */
#ifndef FD_SIL_PRESETS_H
#define FD_SIL_PRESETS_H

#include "drive_config.h"
#include "plant.h"

typedef struct {
  const char *name;
  const char *source; /* where the numbers come from */
  plant_machine_t machine;
  double inertia;      /* [kg m^2] */
  double friction;     /* viscous [N m s/rad] */
  double v_dc;         /* nominal DC link [V] */
  double i_rated;      /* rated current [A rms] */
  double torque_rated; /* [N m] */
  double speed_max;    /* mechanical [rad/s] */
  const char *map;     /* flux-map file (repository-relative) of a saturated machine, or NULL */
} machine_preset_t;

/* NULL when unknown. */
const machine_preset_t *preset_find(const char *name);
/* Comma-separated list of names, for error messages. */
const char *preset_names(void);
/* Plant machine/mechanics/DC link and the drive's machine estimates,
 * limits and protections from a preset (a map preset's map is loaded by the
 * scenario parser: scenario.c, map_load.h). */
void preset_apply(const machine_preset_t *p, plant_params_t *plant, drive_config_t *drive);

#endif

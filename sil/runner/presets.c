/*
 * presets.c - built-in machines (see presets.h).
 */
#include "presets.h"

#include <string.h>

#define RPM (3.14159265358979 / 30.0)

static const machine_preset_t presets[] = {
    {
        .name = "rubino2020_spm",
        .source = "Rubino et al. 2020, Table I",
        .machine = {.pole_pairs = 21, .rs = 7.1, .ld = 0.057, .lq = 0.057, .lambda_m = 0.19},
        .inertia = 0.021,
        .friction = 1e-3,
        .v_dc = 310.0,
        .i_rated = 2.5,
        .torque_rated = 20.0,
        .speed_max = 1200.0 * RPM,
    },
    {
        .name = "fabbri2022_t51",
        .source = "Fabbri 2022, Table 5.1 (118.6 mVs line to line per mechanical rad/s; inertia "
                  "and rating assumed, docs/dfc.md)",
        .machine = {.pole_pairs = 8,
                    .rs = 2.2,
                    .ld = 394e-6,
                    .lq = 475e-6,
                    .lambda_m = 0.1186 / (8.0 * 1.7320508075688772),
                    /* star point (3.3): a = 0.05, p = -0.0932 (docs/dfc.md) */
                    .aniso = {.enabled = 1, .m0 = 20e-6, .m2 = -48.54e-6, .phi_self = 0.0}},
        .inertia = 2e-4,
        .friction = 1e-5,
        .v_dc = 24.0,
        .i_rated = 2.0,
        .torque_rated = 0.3,
        .speed_max = 1500.0 * RPM,
    },
    {
        .name = "fabbri2022_fig33",
        .source = "Fabbri 2022, Fig. 3.3: L0 442.2, M0 20.7, L2 103.3 uH, M2 for p = 0.15 "
                  "(machine.star_p sets another); the rest of Table 5.1",
        .machine = {.pole_pairs = 8,
                    .rs = 2.2,
                    .ld = 421.5e-6 * 1.15,
                    .lq = 421.5e-6 * 0.85,
                    .lambda_m = 0.1186 / (8.0 * 1.7320508075688772),
                    .aniso = {.enabled = 1,
                              .m0 = 20.7e-6,
                              .m2 = 0.15 * 421.5e-6 - 0.5 * 103.3e-6,
                              .phi_self = 0.0,
                              .amp_iq = 0.0}},
        .inertia = 2e-4,
        .friction = 1e-5,
        .v_dc = 24.0,
        .i_rated = 2.0,
        .torque_rated = 0.3,
        .speed_max = 1500.0 * RPM,
    },
    {
        .name = "fabbri2022_ebike",
        .source = "Fabbri 2022, Table 5.4 (inertia and rating assumed, docs/scenarios.md)",
        .machine = {.pole_pairs = 23,
                    .rs = 0.069,
                    .ld = 103e-6,
                    .lq = 149e-6,
                    .lambda_m = 0.0236,
                    /* star point (3.3): a = 0.05, p = -0.1825 (docs/dfc.md) */
                    .aniso = {.enabled = 1, .m0 = 6e-6, .m2 = -21.42e-6, .phi_self = 0.0}},
        .inertia = 0.05,
        .friction = 1e-3,
        .v_dc = 24.0,
        .i_rated = 15.0,
        .torque_rated = 15.0,
        .speed_max = 200.0 * RPM,
    },
    {
        .name = "syr_1k1",
        .source = "Varatharajan et al. 2022, Table I; analytic saturation (docs/flux-maps.md)",
        .machine = {.pole_pairs = 2, .rs = 6.8, .ld = 0.1, .lq = 0.1, .lambda_m = 0.0},
        .inertia = 0.04,
        .friction = 2e-3,
        .v_dc = 340.0,
        .i_rated = 2.3,
        .torque_rated = 7.1,
        .speed_max = 1800.0 * RPM,
        .map = "maps/syr_1k1.fdmap",
    },
    {
        .name = "ipm_sat",
        .source = "interior PM with saturation, analytic (docs/flux-maps.md)",
        .machine = {.pole_pairs = 4, .rs = 0.1, .ld = 1e-3, .lq = 1e-3, .lambda_m = 0.0},
        .inertia = 5e-3,
        .friction = 1e-3,
        .v_dc = 300.0,
        .i_rated = 10.0,
        .torque_rated = 7.9,
        .speed_max = 3000.0 * RPM,
        .map = "maps/ipm_sat.fdmap",
    },
    {
        .name = "pmasyr_file",
        .source = "PM-assisted SyR, map file in the SyR convention (maps/pmasyr_file.npz)",
        .machine = {.pole_pairs = 2, .rs = 1.0, .ld = 0.1, .lq = 0.1, .lambda_m = 0.0},
        .inertia = 0.01,
        .friction = 1e-3,
        .v_dc = 540.0,
        .i_rated = 5.0,
        .torque_rated = 12.9,
        .speed_max = 3000.0 * RPM,
        .map = "maps/pmasyr_file.npz",
    },
};

const machine_preset_t *preset_find(const char *name) {
  for (size_t i = 0; i < sizeof presets / sizeof presets[0]; ++i) {
    if (strcmp(presets[i].name, name) == 0) {
      return &presets[i];
    }
  }
  return NULL;
}

const char *preset_names(void) {
  return "rubino2020_spm, fabbri2022_t51, fabbri2022_fig33, fabbri2022_ebike, syr_1k1, ipm_sat, "
         "pmasyr_file";
}

void preset_apply(const machine_preset_t *p, plant_params_t *plant, drive_config_t *drive) {
  plant->machine = p->machine;
  plant->mech.j = p->inertia;
  plant->mech.b = p->friction;
  plant->dclink.v_source = p->v_dc;

  drive->pole_pairs = (float)p->machine.pole_pairs;
  drive->rs = (float)p->machine.rs;
  drive->ld = (float)p->machine.ld;
  drive->lq = (float)p->machine.lq;
  drive->lambda_m = (float)p->machine.lambda_m;
  drive->inertia = (float)p->inertia;
  drive->friction = (float)p->friction;
  drive->i_max = (float)(p->i_rated * 1.41421356237);
  drive->i_trip = 2.0f * drive->i_max;
  drive->torque_max = (float)p->torque_rated;
  drive->speed_max = (float)p->speed_max;
  drive->speed_trip = 1.25f * drive->speed_max;
  drive->v_dc_max = (float)(1.3 * p->v_dc);
  drive->v_dc_min = (float)(0.5 * p->v_dc);
  drive->accel_max = drive->speed_max; /* 0 -> max speed in 1 s */
  drive->flux_min = 0.2f * drive->lambda_m;
  drive->machine_map = NULL; /* a map preset's: set by the scenario parser */
  plant->machine.map = NULL;
  if (p->machine.aniso.enabled) { /* the DFC model of the star point (3.7) */
    double a, b;
    plant_aniso_ab(&p->machine, &a, &b);
    drive->dfc_a = (float)a;
    drive->dfc_b = (float)b;
  }
  plant->sensors.i_full_scale = 2.5 * drive->i_trip;
  plant->sensors.v_full_scale = 2.0 * p->v_dc;
}

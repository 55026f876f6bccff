/*
 * machine.h - the one machine model of the core. Every block that needs
 * the machine (flux observer, current predictor, references, control laws)
 * holds a const pointer to one machine_t, owned by the drive, instead of a
 * copy of its constants; derived constants a block needs (discretisation,
 * gains) are computed by that block's init from the pointer.
 *
 * Rotor frame: d on the PM flux. A machine without magnet (synchronous
 * reluctance, lambda_m = 0) uses the same convention with d on the
 * minimum-inductance axis, so that Lq > Ld as for an interior-PM machine;
 * the SyR literature's convention (d on the maximum inductance, PM on -q)
 * is converted once, at the edge where such data enters (docs/scenarios.md).
 *
 * Kinds: MACHINE_LINEAR (constant Ld, Lq, lambda_m) and MACHINE_FLUX_MAP
 * (saturation and cross-saturation: flux_map.h, docs/flux-maps.md) behind
 * the same functions: flux from current, current from flux, incremental
 * inductance, torque, MTPA.
 */
#ifndef FD_MODEL_MACHINE_H
#define FD_MODEL_MACHINE_H

#include "math/frames.h"
#include "model/flux_map.h"

typedef enum { MACHINE_LINEAR = 0, MACHINE_FLUX_MAP, MACHINE_KIND_COUNT } machine_kind_t;

/* Incremental inductance matrix d lambda_dq / d i_dq [H]: the map's type
 * (flux_map.h), so that a map's lookup fills the caller's matrix in place. */
typedef flux_map_ldq_t machine_ldq_t;

typedef struct {
  machine_kind_t kind;
  float pole_pairs;
  float rs; /* stator phase resistance [Ohm] */
  /* MACHINE_LINEAR: lambda_dq = (Ld i_d + lambda_m, Lq i_q).
   * MACHINE_FLUX_MAP: the incremental inductances at zero current (the
   * unsaturated machine) and the map's flux at zero current, for the
   * blocks that need one constant (gains); the model itself is `map`. */
  float ld, lq;          /* [H] */
  float lambda_m;        /* PM flux linkage, peak per phase [Vs] */
  const flux_map_t *map; /* MACHINE_FLUX_MAP: the map (outlives the machine) */
} machine_t;

/* A linear machine; 0, or -1 when a constant is not finite or out of its
 * physical range (pole_pairs >= 1, rs > 0, ld, lq > 0, lambda_m >= 0). */
int machine_init_linear(machine_t *m, float pole_pairs, float rs, float ld, float lq,
                        float lambda_m);

/* A flux-map machine (map parsed by flux_map_parse); 0, or -1 when rs is
 * not finite and positive or map is NULL. The pole pairs are the map's. */
int machine_init_map(machine_t *m, float rs, const flux_map_t *map);

/* lambda_dq(i_dq) [Vs] */
dq_t machine_flux(const machine_t *m, dq_t i);
/* i_dq(lambda_dq) [A], the inverse of machine_flux */
dq_t machine_current(const machine_t *m, dq_t lambda);
/* d lambda / d i at i [H] */
machine_ldq_t machine_inductance(const machine_t *m, dq_t i);
/* machine_flux(m, i) and, in *l, machine_inductance(m, i) in one call
 * (a map: flux_map_flux_inductance, one cell and its neighbours) */
dq_t machine_flux_inductance(const machine_t *m, dq_t i, machine_ldq_t *l);
/* T = 3/2 p (lambda_d i_q - lambda_q i_d) [N m] */
float machine_torque(const machine_t *m, dq_t i);
/* PM flux: lambda_d at zero current [Vs] (0 for SyR) */
float machine_pm_flux(const machine_t *m);
/* 1 when Ld and Lq agree within rel_tol of Ld (surface PM); 0 for a map. */
int machine_is_isotropic(const machine_t *m, float rel_tol);
/* The stator inductance L_s of an isotropic (SPM) machine: the d-axis
 * value. The SPM blocks of Rubino 2020 (flux observer, current predictor,
 * DFVC references and laws) use it; the drive enables them only on
 * machines that machine_is_isotropic() accepts (firmware/app). */
static inline float machine_ls(const machine_t *m) {
  return m->ld;
}
/* Current on the MTPA trajectory giving torque t (maximum torque per
 * ampere); (0, 0) when the machine cannot produce torque (no magnet and no
 * saliency) or t is not finite. */
dq_t machine_mtpa_current(const machine_t *m, float t);
/* Torque on the MTPA trajectory at current amplitude i_amp >= 0. */
float machine_mtpa_torque(const machine_t *m, float i_amp);
/* Steady-state voltage (di/dt = 0) at electrical speed we [rad/s]:
 * v_d = Rs i_d - we lambda_q, v_q = Rs i_q + we lambda_d. */
dq_t machine_voltage_ss(const machine_t *m, dq_t i, float we);

#endif

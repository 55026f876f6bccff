/*
 * flux_map.h - the saturated machine of the core: flux linkages
 * lambda_d(i_d, i_q), lambda_q(i_d, i_q) on a regular current grid, held in
 * a const table (a .fdmap blob, docs/flux-maps.md), with the tables the
 * tools derive from it (MTPA and MTPV, Varatharajan et al. 2022 (29),
 * (31)). Frame: fluxdrive's (d on the PM flux, d on the minimum inductance
 * of a reluctance machine); the SyR convention is converted by the tool.
 *
 * Single precision, no allocation: flux_map_t points into the blob, whose
 * storage (a const array the board build links, a buffer the SIL fills
 * from the file) must outlive it. The blob is read as 32-bit words through
 * memcpy (no type punning). flux_map_parse() validates the blob
 * (flux_map_blob.c); the functions below assume a parsed map.
 *
 * Interpolation: bilinear on the grid cell holding i, the cell clamped at
 * the edge so that outside the grid the edge cell's plane continues
 * (linear extrapolation, continuous).
 */
#ifndef FD_MODEL_FLUX_MAP_H
#define FD_MODEL_FLUX_MAP_H

#include <stdint.h>

#include "math/frames.h"

#define FLUX_MAP_MAGIC    0x50414D46u /* "FMAP" little-endian */
#define FLUX_MAP_VERSION  1u
#define FLUX_MAP_GRID_MAX 64u
#define FLUX_MAP_LUT_MAX  128u
#define FLUX_MAP_FLAG_PM  1u
/* Bounds of a blob the parser accepts (found by tests/fuzz fuzz_fluxmap:
 * finite but huge pole pairs, currents or flux values overflow the
 * lookups): the pole_pairs parameter's range, grid currents within ten
 * times the largest i_max, flux values [Vs]. */
#define FLUX_MAP_POLES_MAX 100.0f
#define FLUX_MAP_I_MAX     1e5f
#define FLUX_MAP_PSI_MAX   1e3f
/* the torque bound of the tables: 1.5 p psi i at the bounds above [N m] */
#define FLUX_MAP_T_MAX (1.5f * FLUX_MAP_POLES_MAX * FLUX_MAP_PSI_MAX * FLUX_MAP_I_MAX)
/* Newton steps of flux_map_current (bounded loop). */
#define FLUX_MAP_NEWTON 6

typedef struct {
  uint32_t nd, nq, n_lut, flags, crc;
  float pole_pairs;
  float id0, did, iq0, diq;   /* current grid [A] */
  float inv_did, inv_diq;     /* 1/did, 1/diq */
  const uint32_t *psi_d;      /* [nq][nd] f32 words [Vs] */
  const uint32_t *psi_q;      /* [nq][nd] */
  float mtpa_t_max, mtpa_inv; /* range [N m], (n_lut - 1) / range */
  const uint32_t *mtpa_id, *mtpa_iq, *mtpa_flux;
  float mtpv_flux_max, mtpv_inv; /* range [Vs], (n_lut - 1) / range */
  const uint32_t *mtpv_torque;
} flux_map_t;

/* Incremental inductance matrix d lambda_dq / d i_dq [H]. */
typedef struct {
  float dd, dq, qd, qq;
} flux_map_ldq_t;

/* lambda_dq(i_dq) [Vs], bilinear. */
dq_t flux_map_flux(const flux_map_t *m, dq_t i);
/* The incremental inductance matrix at i by finite differences of the map,
 * Varatharajan 2022 eq. (25), taken centred over one grid step
 * (l_d = (Lambda_d(i_d + h, i_q) - Lambda_d(i_d - h, i_q)) / 2h, h = did/2,
 * and alike for the other three): on a bilinear map this is continuous in
 * i, where the one-sided (25) with a 10 mA step jumps at every cell edge. */
flux_map_ldq_t flux_map_inductance(const flux_map_t *m, dq_t i);
/* lambda_dq(i_dq) and, in *l, flux_map_inductance(m, i) (the same centred
 * (25), equal up to rounding) from one cell and the rows and columns next
 * to it: the centred difference over one step on a bilinear map is the
 * slopes of the two cells the window covers, weighted by its share in
 * each. 16 table words instead of the 40 of five lookups (the ISR of the
 * decoupled DFVC, control/dfvc_decoupled.h). */
dq_t flux_map_flux_inductance(const flux_map_t *m, dq_t i, flux_map_ldq_t *l);
/* i_dq(lambda_dq) [A]: Newton on the bilinear map (FLUX_MAP_NEWTON steps
 * from the zero-current linearisation, each with the interpolant's own
 * Jacobian); the residual is checked by tests/core/test_flux_map.c. */
dq_t flux_map_current(const flux_map_t *m, dq_t lambda);
/* T = 3/2 p (lambda_d i_q - lambda_q i_d), Varatharajan (4) [N m]. */
float flux_map_torque(const flux_map_t *m, float pole_pairs, dq_t i);
/* MTPA current for torque t from the map's table (i_q has the sign of t);
 * |t| beyond the table's range gives its last point. */
dq_t flux_map_mtpa_current(const flux_map_t *m, float t);
/* Stator flux amplitude on MTPA for torque |t|, (29). */
float flux_map_mtpa_flux(const flux_map_t *m, float t);
/* Torque on MTPA at current amplitude i_amp (the table inverted by a
 * bounded search; the table's last torque beyond its range). */
float flux_map_mtpa_torque(const flux_map_t *m, float i_amp);
/* Largest torque at stator flux amplitude flux, f_T of (31) (no margin). */
float flux_map_mtpv_torque(const flux_map_t *m, float flux);

/* Why a blob was refused, and where (grid cell j, k or table index j). */
typedef enum {
  FLUX_MAP_OK = 0,
  FLUX_MAP_E_NULL,
  FLUX_MAP_E_MAGIC,
  FLUX_MAP_E_VERSION,
  FLUX_MAP_E_SIZE,
  FLUX_MAP_E_GRID,
  FLUX_MAP_E_LUT,
  FLUX_MAP_E_FLAGS,
  FLUX_MAP_E_CRC,
  FLUX_MAP_E_AXES,
  FLUX_MAP_E_IQ_SIGNS,
  FLUX_MAP_E_FINITE,
  FLUX_MAP_E_SELF_L,
  FLUX_MAP_E_NOT_PD,
  FLUX_MAP_E_TABLES,
  FLUX_MAP_E_COUNT
} flux_map_err_t;

typedef struct {
  flux_map_err_t code;
  int j, k; /* cell or table index, -1 when the error has no place */
} flux_map_status_t;

/* Parses and validates a blob of size bytes (a multiple of 4) held in
 * words: 0 and *m filled, or -1 with *st naming the check and place. */
int flux_map_parse(flux_map_t *m, const uint32_t *words, uint32_t size, flux_map_status_t *st);
/* A short text for an error code (static string). */
const char *flux_map_err_str(flux_map_err_t e);
/* CRC-32 (IEEE 802.3, reflected, as zlib.crc32) of n bytes of words. */
uint32_t flux_map_crc32(const uint32_t *words, uint32_t n_bytes);

#endif

/*
 * log_npy.c - .npy structured-array log (see log_npy.h).
 */
#include "log_npy.h"

#include <math.h>
#include <string.h>

/* Signal names, in column order. Units in docs/log-format.md. */
static const char *const signals[] = {"t",
                                      "speed",
                                      "speed_est",
                                      "speed_ref",
                                      "torque",
                                      "torque_ref",
                                      "torque_est",
                                      "load_torque",
                                      "i_a",
                                      "i_b",
                                      "i_c",
                                      "i_a_meas",
                                      "i_b_meas",
                                      "i_c_meas",
                                      "i_d",
                                      "i_q",
                                      "i_ds",
                                      "i_qs",
                                      "i_qs_ref",
                                      "flux",
                                      "flux_ref",
                                      "flux_est",
                                      "delta",
                                      "delta_est",
                                      "v_dc",
                                      "duty_a",
                                      "duty_b",
                                      "duty_c",
                                      "gates",
                                      "state",
                                      "faults",
                                      "theta_e",
                                      "theta_e_est",
                                      "lc_cause",
                                      "torque_max",
                                      "flux_mtpa",
                                      "torque_mtpv",
                                      "gain_a",
                                      "gain_b",
                                      "mtpa_angle",
                                      "mtpv_angle",
                                      "theta_e_enc",
                                      "dfc_t",
                                      "dfc_ga",
                                      "dfc_gb",
                                      "dfc_gc",
                                      "dfc_k0",
                                      "dfc_k1",
                                      "dfc_k2",
                                      "dfc_k3",
                                      "dfc_k4",
                                      "dfc_k5",
                                      "dfc_k6",
                                      "dfc_k7",
                                      "dfc_k8",
                                      "torque_avg",
                                      "i_d_avg",
                                      "i_q_avg",
                                      "load_torque_est",
                                      "rls_a",
                                      "rls_b",
                                      "kf_r",
                                      "pos_emf_res",
                                      "rls_ok"};
enum { NSIG = sizeof signals / sizeof signals[0], HEADER_LEN = 4096 };

static void fill_row(const sil_step_t *st, double *r) {
  const plant_state_t *p = st->plant;
  const drive_telemetry_t *tm = &st->drive->tm; /* lock-step: the ISR's own telemetry */
  /* the decoupled DFVC's own telemetry, in its state (lock-step: the ISR
   * has returned) */
  const dfvc_sat_tm_t sat = st->drive->ctrl.law == DRIVE_LAW_DFVC_DECOUPLED
                                ? st->drive->ctrl.st.dfvc_sat.tm
                                : (dfvc_sat_tm_t){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  /* the star-point source's last estimate (pos_dfc.c; zeros otherwise):
   * 2 theta after IVD step k, from its unit vector */
  const bool dfc = (st->drive->pos_src->caps & POS_CAP_GATED) != 0u;
  const float *tr = st->drive->pos_st.star.meas.trace;
  double k2[DFC_ITER_MAX + 1u];
  for (unsigned k = 0u; k <= DFC_ITER_MAX; ++k) {
    k2[k] = dfc ? atan2((double)tr[(size_t)2 * k + 1u], (double)tr[(size_t)2 * k]) : 0.0;
  }
  const float *g = st->drive->pos_st.star.meas.sig.g;
  /* the a, b the IVD used (identified: ivd+kf+rls) */
  const bool rls = dfc && st->drive->pos_st.star.ident != NULL;
  double ld = p->lambda_dq[0], lq = p->lambda_dq[1];
  double flux = hypot(ld, lq);
  /* True stator-flux frame currents: projection of i on lambda_s and its
   * quadrature (Rubino 2020, the (ds, qs) frame). */
  double i_ds = flux > 0.0 ? (ld * p->i_dq[0] + lq * p->i_dq[1]) / flux : 0.0;
  double i_qs = flux > 0.0 ? (ld * p->i_dq[1] - lq * p->i_dq[0]) / flux : 0.0;
  double v[NSIG] = {st->t,
                    p->omega_m,
                    tm->omega_m,
                    tm->speed_ref,
                    p->torque,
                    tm->torque_ref,
                    tm->torque_est,
                    p->load_torque,
                    p->i_abc[0],
                    p->i_abc[1],
                    p->i_abc[2],
                    tm->i_abc[0],
                    tm->i_abc[1],
                    tm->i_abc[2],
                    p->i_dq[0],
                    p->i_dq[1],
                    i_ds,
                    i_qs,
                    tm->law_tm.i_qs_ref,
                    flux,
                    tm->law_tm.flux_ref,
                    tm->law_tm.flux,
                    atan2(lq, ld),
                    ctrl_tm_delta(&tm->law_tm),
                    p->v_dc,
                    tm->duty[0],
                    tm->duty[1],
                    tm->duty[2],
                    st->gates_on ? 1.0 : (st->asc ? 2.0 : 0.0),
                    (double)tm->state,
                    (double)tm->faults,
                    p->theta_e,
                    tm->theta_e,
                    (double)tm->lc_cause,
                    st->drive->torque_max_avail,
                    sat.flux_mtpa,
                    sat.torque_mtpv,
                    sat.gain_a,
                    sat.gain_b,
                    sat.mtpa_angle,
                    sat.mtpv_angle,
                    st->scenario->plant.machine.pole_pairs * (double)st->adc->enc_angle,
                    dfc ? (double)st->drive->pos_st.star.meas.t : 0.0,
                    dfc ? (double)g[0] : 0.0,
                    dfc ? (double)g[1] : 0.0,
                    dfc ? (double)g[2] : 0.0,
                    k2[0],
                    k2[1],
                    k2[2],
                    k2[3],
                    k2[4],
                    k2[5],
                    k2[6],
                    k2[7],
                    k2[8],
                    p->torque_avg,
                    p->i_dq_avg[0],
                    p->i_dq_avg[1],
                    tm->load_est,
                    rls ? (double)st->drive->pos_st.star.meas.dc.a : 0.0,
                    rls ? (double)st->drive->pos_st.star.meas.dc.b : 0.0,
                    dfc ? (double)st->drive->pos_st.star.trk.r : 0.0,
                    st->drive->pos_emf_res,
                    tm->rls_ok ? 1.0 : 0.0};
  memcpy(r, v, sizeof v);
}

static int write_header(log_npy_t *lg) {
  char dict[HEADER_LEN];
  int n = snprintf(dict, sizeof dict, "{'descr': [");
  for (int i = 0; i < NSIG; ++i) {
    n += snprintf(dict + n, sizeof dict - (size_t)n, "('%s', '<f8'), ", signals[i]);
  }
  n += snprintf(dict + n, sizeof dict - (size_t)n,
                "], 'fortran_order': False, 'shape': (%20llu,), }", (unsigned long long)lg->rows);
  /* magic(6) + version(2) + len(2) + dict, padded with spaces, ends in \n,
   * total a multiple of 64 (format 1.0). */
  size_t total = 10 + (size_t)n + 1;
  size_t padded = (total + 63) / 64 * 64;
  memset(dict + n, ' ', padded - total);
  dict[padded - 10 - 1] = '\n';
  unsigned short hlen = (unsigned short)(padded - 10);
  unsigned char pre[10] = {0x93,
                           'N',
                           'U',
                           'M',
                           'P',
                           'Y',
                           1,
                           0,
                           (unsigned char)(hlen & 0xff),
                           (unsigned char)(hlen >> 8)};
  if (fseek(lg->f, 0, SEEK_SET) != 0 || fwrite(pre, 1, 10, lg->f) != 10 ||
      fwrite(dict, 1, hlen, lg->f) != hlen) {
    return -1;
  }
  return 0;
}

int log_npy_open(log_npy_t *lg, const char *path, int decimation) {
  memset(lg, 0, sizeof *lg);
  lg->decimation = decimation < 1 ? 1 : decimation;
  lg->f = fopen(path, "wb");
  if (lg->f == NULL) {
    return -1;
  }
  return write_header(lg);
}

void log_npy_observer(void *user, const sil_step_t *st) {
  log_npy_t *lg = user;
  if (lg->failed || st->k % (uint64_t)lg->decimation != 0) {
    return;
  }
  double row[NSIG];
  fill_row(st, row);
  /* x86-64 and Cortex hosts are little-endian, as '<f8' says. */
  if (fwrite(row, sizeof row, 1, lg->f) != 1) {
    lg->failed = 1;
    return;
  }
  lg->rows++;
}

int log_npy_close(log_npy_t *lg) {
  int r = lg->failed ? -1 : write_header(lg);
  if (fclose(lg->f) != 0) {
    r = -1;
  }
  lg->f = NULL;
  return r;
}

/*
 * isr_stream.h - the ISR input/output stream shared by the SIL recorder
 * (sil/runner/isr_record.c, `fluxdrive-sil --record-isr PATH`) and the PIL
 * image (pil/, Cortex-M4F on QEMU mps2-an386). Format in docs/pil.md.
 *
 * File: header, then the drive_config_t as ISR_STREAM_CONFIG_WORDS words (one
 * per field, in the order of ISR_STREAM_CONFIG_FIELDS), then `count` records
 * of isr_stream_in_t followed by isr_stream_out_t (the host's outputs). All
 * fields are 32-bit little-endian (uint32_t or IEEE-754 binary32), so the
 * layout is the same on x86-64 and on ARMv7E-M. drive_config_t itself is
 * not copied as bytes: arm-none-eabi uses short enums (its layout differs).
 * The PIL writes `count` isr_stream_out_t records (no header).
 */
#ifndef FD_ISR_STREAM_H
#define FD_ISR_STREAM_H

#include <stdint.h>
#include <string.h>

#include "drive_config.h"

#define ISR_STREAM_MAGIC   0x52534946u /* "FISR" */
#define ISR_STREAM_VERSION 1u

/* isr_stream_header_t.flags: the replay sets the law's applied-voltage
 * memory (drive_t.ctrl.v_applied) to the host's before each ISR, see
 * docs/pil.md ("Why the applied voltage is forced"). */
#define ISR_STREAM_FORCE_APPLIED (1u << 0)

/* isr_stream_in_t.flags */
#define ISR_IN_SLOW       (1u << 0) /* drive_slow_loop() before this ISR, with cmd_* */
#define ISR_IN_CMD_ENABLE (1u << 1) /* cmd.enable */
#define ISR_IN_CMD_CLEAR  (1u << 2) /* cmd.clear_fault */
#define ISR_IN_ENC_VALID  (1u << 3) /* hal_adc_sample_t.enc_valid */
#define ISR_IN_HW_TRIPPED (1u << 4) /* hal_fault_hw_tripped() during this ISR */

/* isr_stream_out_t.flags */
#define ISR_OUT_GATES_ON (1u << 0)

typedef struct {
  uint32_t magic;       /* ISR_STREAM_MAGIC */
  uint32_t version;     /* ISR_STREAM_VERSION */
  uint32_t header_size; /* sizeof(isr_stream_header_t) */
  uint32_t config_size; /* 4 * ISR_STREAM_CONFIG_WORDS */
  uint32_t in_size;     /* sizeof(isr_stream_in_t) */
  uint32_t out_size;    /* sizeof(isr_stream_out_t) */
  uint32_t count;       /* records */
  uint32_t flags;       /* ISR_STREAM_FORCE_APPLIED (set by the PIL runner) */
} isr_stream_header_t;

/* Everything the drive sees before and during one ISR. */
typedef struct {
  uint32_t flags;
  uint32_t time_us; /* hal_time_us() */
  float i_abc[3];   /* hal_adc_sample_t */
  float v_dc;
  float v_star;
  float enc_angle;
  uint32_t cmd_law; /* staged commands (drive_t.cmd) for ISR_IN_SLOW */
  uint32_t cmd_mode;
  float cmd_torque;
  float cmd_speed;
  float cmd_id;
  float cmd_iq;
  float cmd_flux;
  uint32_t raise_fault; /* drive_raise_fault() bits raised before this ISR */
  float v_applied[2];   /* host drive_t.ctrl.v_applied before this ISR (alpha, beta) */
} isr_stream_in_t;

/* What one ISR produced. */
typedef struct {
  float duty[3];   /* duties as the HAL holds them (clamped to [0, 1]) */
  uint32_t flags;  /* ISR_OUT_GATES_ON */
  uint32_t faults; /* drive_t.faults after the ISR */
  uint32_t state;  /* drive_state_t after the ISR */
} isr_stream_out_t;

_Static_assert(sizeof(isr_stream_header_t) == 32, "isr_stream_header_t layout");
_Static_assert(sizeof(isr_stream_in_t) == 72, "isr_stream_in_t layout");
_Static_assert(sizeof(isr_stream_out_t) == 24, "isr_stream_out_t layout");

/* Every drive_config_t field, in file order: FLT(name) for float fields,
 * INT(name, type) for integer and enum fields. A field missing here is
 * caught by the recorder (isr_record_open). */
/* clang-format off */
#define ISR_STREAM_CONFIG_FIELDS(FLT, INT) \
  FLT(pole_pairs) \
  FLT(rs) \
  FLT(ld) \
  FLT(lq) \
  FLT(lambda_m) \
  FLT(inertia) \
  FLT(ts) \
  INT(slow_div, uint16_t) \
  FLT(dead_time) \
  FLT(i_trip) \
  FLT(v_dc_max) \
  FLT(v_dc_min) \
  FLT(speed_trip) \
  FLT(offset_max) \
  INT(offset_samples, uint16_t) \
  FLT(i_max) \
  FLT(torque_max) \
  FLT(speed_max) \
  FLT(v_margin) \
  INT(law, drive_law_t) \
  INT(mode, drive_mode_t) \
  FLT(current_bw) \
  FLT(speed_bw) \
  FLT(accel_max) \
  FLT(pll_bw) \
  FLT(enc_offset) \
  FLT(flux_obs_wc) \
  FLT(delta_max) \
  FLT(vsd_max) \
  FLT(flux_min) \
  FLT(dfvc_flux_bw) \
  FLT(dfvc_iqs_bw)
/* clang-format on */

/* Each field adds one to a sum written as "0 +1 +1 ...": the bare "+1" is
 * the point of these X-macro arms. */
#define ISR_STREAM_COUNT_FLT(n)    +1 // NOLINT(bugprone-macro-parentheses)
#define ISR_STREAM_COUNT_INT(n, t) +1 // NOLINT(bugprone-macro-parentheses)
enum {
  ISR_STREAM_CONFIG_WORDS = 0 ISR_STREAM_CONFIG_FIELDS(ISR_STREAM_COUNT_FLT, ISR_STREAM_COUNT_INT)
};

static inline void isr_stream_config_put(const drive_config_t *c,
                                         uint32_t w[ISR_STREAM_CONFIG_WORDS]) {
  unsigned i = 0;
#define ISR_STREAM_PUT_FLT(n)    memcpy(&w[i++], &c->n, sizeof(float));
#define ISR_STREAM_PUT_INT(n, t) w[i++] = (uint32_t)c->n;
  ISR_STREAM_CONFIG_FIELDS(ISR_STREAM_PUT_FLT, ISR_STREAM_PUT_INT)
#undef ISR_STREAM_PUT_FLT
#undef ISR_STREAM_PUT_INT
}

static inline void isr_stream_config_get(drive_config_t *c,
                                         const uint32_t w[ISR_STREAM_CONFIG_WORDS]) {
  unsigned i = 0;
#define ISR_STREAM_GET_FLT(n)    memcpy(&c->n, &w[i++], sizeof(float));
#define ISR_STREAM_GET_INT(n, t) c->n = (t)w[i++];
  ISR_STREAM_CONFIG_FIELDS(ISR_STREAM_GET_FLT, ISR_STREAM_GET_INT)
#undef ISR_STREAM_GET_FLT
#undef ISR_STREAM_GET_INT
}

#endif

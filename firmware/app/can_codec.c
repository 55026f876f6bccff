/*
 * can_codec.c - message and signal tables of can/fluxdrive.dbc and a
 * little-endian bit codec over them (see can_codec.h).
 */
#include "can_codec.h"

#include <math.h>
#include <string.h>

#define F32_MAX 3.4e38f

/* clang-format off */
static const can_sig_desc_t sigs[CAN_SIG_COUNT] = {
  /* name             start len signed float scale    offset min        max */
  {"enable",            0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"clear_fault",       8,  8, false, false, 1.0f,    0.0f, 0.0f,      1.0f, 0, 1},
  {"mode",             16,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"law",              24,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"cmd_torque",        0, 32, true,  false, 1e-4f,   0.0f, -10000.0f, 10000.0f, -100000000, 100000000},
  {"cmd_speed_rpm",     0, 32, true,  false, 0.01f,   0.0f, -200000.0f, 200000.0f, -20000000, 20000000},
  {"cmd_id",            0, 32, true,  false, 1e-4f,   0.0f, -10000.0f, 10000.0f, -100000000, 100000000},
  {"cmd_iq",           32, 32, true,  false, 1e-4f,   0.0f, -10000.0f, 10000.0f, -100000000, 100000000},
  {"cmd_flux",          0, 32, true,  false, 1e-6f,   0.0f, 0.0f,      10.0f, 0, 10000000},
  {"param_op",          0,  8, false, false, 1.0f,    0.0f, 0.0f,      1.0f, 0, 1},
  {"param_id",          8,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"param_value",      32, 32, true,  true,  1.0f,    0.0f, -F32_MAX,  F32_MAX, 0, 0},
  {"host_hb_count",     0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"cmd_proc",          0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"reply_req",         0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"reply_result",      8,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"reply_signal",     16,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"reply_param",      24,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"reply_value",      32, 32, true,  true,  1.0f,    0.0f, -F32_MAX,  F32_MAX, 0, 0},
  {"state",             0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"ctrl_mode",         8,  4, false, false, 1.0f,    0.0f, 0.0f,      15.0f, 0, 15},
  {"ctrl_law",         12,  4, false, false, 1.0f,    0.0f, 0.0f,      15.0f, 0, 15},
  {"faults",           16, 16, false, false, 1.0f,    0.0f, 0.0f,      65535.0f, 0, 65535},
  {"v_dc",             32, 16, false, false, 0.1f,    0.0f, 0.0f,      6553.5f, 0, 65535},
  {"timeout_ramp",     48,  1, false, false, 1.0f,    0.0f, 0.0f,      1.0f, 0, 1},
  {"cmd_enabled",      49,  1, false, false, 1.0f,    0.0f, 0.0f,      1.0f, 0, 1},
  {"err_count",        56,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"speed_rpm",         0, 32, true,  false, 0.01f,   0.0f, -21474836.48f, 21474836.47f, -2147483648, 2147483647},
  {"speed_ref_rpm",    32, 32, true,  false, 0.01f,   0.0f, -21474836.48f, 21474836.47f, -2147483648, 2147483647},
  {"torque_est",        0, 32, true,  false, 1e-4f,   0.0f, -214748.3648f, 214748.3647f, -2147483648, 2147483647},
  {"torque_ref",       32, 32, true,  false, 1e-4f,   0.0f, -214748.3648f, 214748.3647f, -2147483648, 2147483647},
  {"i_a",               0, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_b",              16, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_c",              32, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_d",               0, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_q",              16, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_ds",             32, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"i_qs",             48, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"flux",              0, 16, false, false, 1e-4f,   0.0f, 0.0f,      6.5535f, 0, 65535},
  {"flux_ref",         16, 16, false, false, 1e-4f,   0.0f, 0.0f,      6.5535f, 0, 65535},
  {"delta",            32, 16, true,  false, 1e-4f,   0.0f, -3.2768f,  3.2767f, -32768, 32767},
  {"i_qs_ref",         48, 16, true,  false, 0.01f,   0.0f, -327.68f,  327.67f, -32768, 32767},
  {"isr_cycles_mean",   0, 16, false, false, 1.0f,    0.0f, 0.0f,      65535.0f, 0, 65535},
  {"isr_cycles_max",   16, 16, false, false, 1.0f,    0.0f, 0.0f,      65535.0f, 0, 65535},
  {"isr_load",         32, 16, false, false, 0.01f,   0.0f, 0.0f,      655.35f, 0, 65535},
  {"isr_overruns",     48, 16, false, false, 1.0f,    0.0f, 0.0f,      65535.0f, 0, 65535},
  {"load_torque_est",   0, 32, true,  false, 1e-4f,   0.0f, -214748.3648f, 214748.3647f, -2147483648, 2147483647},
  {"pos_err",          32, 16, false, false, 1e-4f,   0.0f, 0.0f,      6.5535f, 0, 65535},
  {"rls_ok",           48,  1, false, false, 1.0f,    0.0f, 0.0f,      1.0f, 0, 1},
  {"proc_id",           0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"proc_status",       8,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"proc_phase",       16,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"proc_index",       24,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"proc_result",      32, 32, true,  true,  1.0f,    0.0f, -F32_MAX,  F32_MAX, 0, 0},
  {"hb_count",          0,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
  {"hb_state",          8,  8, false, false, 1.0f,    0.0f, 0.0f,      255.0f, 0, 255},
};

static const can_msg_desc_t msgs[CAN_MSG_COUNT] = {
  /* name          base  dlc to_drive first signal            n */
  {"CMD_STATE",   0x100, 4, true,  CAN_SIG_ENABLE,        4},
  {"CMD_TORQUE",  0x110, 4, true,  CAN_SIG_CMD_TORQUE,    1},
  {"CMD_SPEED",   0x120, 4, true,  CAN_SIG_CMD_SPEED_RPM, 1},
  {"CMD_CURRENT", 0x130, 8, true,  CAN_SIG_CMD_ID,        2},
  {"CMD_FLUX",    0x140, 4, true,  CAN_SIG_CMD_FLUX,      1},
  {"PARAM_REQ",   0x150, 8, true,  CAN_SIG_PARAM_OP,      3},
  {"HOST_HB",     0x160, 1, true,  CAN_SIG_HOST_HB_COUNT, 1},
  {"CMD_PROC",    0x170, 1, true,  CAN_SIG_CMD_PROC,      1},
  {"REPLY",       0x180, 8, false, CAN_SIG_REPLY_REQ,     5},
  {"STATUS",      0x200, 8, false, CAN_SIG_STATE,         8},
  {"TM_SPEED",    0x300, 8, false, CAN_SIG_SPEED_RPM,     2},
  {"TM_TORQUE",   0x310, 8, false, CAN_SIG_TORQUE_EST,    2},
  {"TM_PHASE",    0x320, 6, false, CAN_SIG_I_A,           3},
  {"TM_DQ",       0x330, 8, false, CAN_SIG_I_D,           4},
  {"TM_FLUX",     0x340, 8, false, CAN_SIG_FLUX,          4},
  {"TM_CPU",      0x350, 8, false, CAN_SIG_ISR_CYCLES_MEAN, 4},
  {"TM_POSITION", 0x360, 7, false, CAN_SIG_LOAD_TORQUE_EST, 3},
  {"TM_PROC",     0x370, 8, false, CAN_SIG_PROC_ID,       5},
  {"HEARTBEAT",   0x700, 2, false, CAN_SIG_HB_COUNT,      2},
};
/* clang-format on */

static const char *const result_names[] = {
    "ok",           "out_of_range", "bad_dlc",    "unknown_param", "read_only", "not_while_running",
    "inconsistent", "timed_out",    "unavailable"};

const can_msg_desc_t *can_codec_msg(can_msg_t m) {
  return (unsigned)m < (unsigned)CAN_MSG_COUNT ? &msgs[m] : 0;
}

const can_sig_desc_t *can_codec_sig(can_sig_t s) {
  return (unsigned)s < (unsigned)CAN_SIG_COUNT ? &sigs[s] : 0;
}

const char *can_codec_result_name(unsigned r) {
  return r < sizeof result_names / sizeof result_names[0] ? result_names[r] : "?";
}

uint32_t can_codec_id(can_msg_t m, uint8_t node) {
  return (uint32_t)msgs[m].base_id + (uint32_t)node;
}

can_msg_t can_codec_lookup(uint32_t id, bool extended, uint8_t node) {
  if (extended || id > 0x7FFu || id < (uint32_t)node) {
    return CAN_MSG_COUNT;
  }
  for (unsigned m = 0; m < (unsigned)CAN_MSG_COUNT; ++m) {
    if (id == (uint32_t)msgs[m].base_id + (uint32_t)node) {
      return (can_msg_t)m;
    }
  }
  return CAN_MSG_COUNT;
}

uint32_t can_codec_get_raw(can_sig_t s, const uint8_t data[8]) {
  const can_sig_desc_t *d = &sigs[s];
  uint64_t all = 0;
  for (unsigned b = 0; b < 8u; ++b) {
    all |= (uint64_t)data[b] << (8u * b);
  }
  uint64_t mask = (d->length >= 32u) ? 0xFFFFFFFFull : ((1ull << d->length) - 1ull);
  return (uint32_t)((all >> d->start) & mask);
}

void can_codec_set_raw(can_sig_t s, uint8_t data[8], uint32_t raw) {
  const can_sig_desc_t *d = &sigs[s];
  uint64_t all = 0;
  for (unsigned b = 0; b < 8u; ++b) {
    all |= (uint64_t)data[b] << (8u * b);
  }
  uint64_t mask = (d->length >= 32u) ? 0xFFFFFFFFull : ((1ull << d->length) - 1ull);
  all &= ~(mask << d->start);
  all |= ((uint64_t)raw & mask) << d->start;
  for (unsigned b = 0; b < 8u; ++b) {
    data[b] = (uint8_t)(all >> (8u * b));
  }
}

/* Sign-extended raw value as a 64-bit integer. */
static int64_t raw_value(const can_sig_desc_t *d, uint32_t raw) {
  if (d->is_signed && d->length < 32u && (raw & (1u << (d->length - 1u))) != 0u) {
    return (int64_t)raw - (int64_t)(1ll << d->length);
  }
  if (d->is_signed && d->length == 32u) {
    return (int64_t)(int32_t)raw;
  }
  return (int64_t)raw;
}

float can_codec_get(can_sig_t s, const uint8_t data[8]) {
  const can_sig_desc_t *d = &sigs[s];
  uint32_t raw = can_codec_get_raw(s, data);
  if (d->is_float) {
    float f;
    memcpy(&f, &raw, sizeof f);
    return f;
  }
  return (float)raw_value(d, raw) * d->scale + d->offset;
}

void can_codec_set(can_sig_t s, uint8_t data[8], float v) {
  const can_sig_desc_t *d = &sigs[s];
  if (d->is_float) {
    uint32_t raw;
    memcpy(&raw, &v, sizeof raw);
    can_codec_set_raw(s, data, raw);
    return;
  }
  int64_t lo = d->is_signed ? -(int64_t)(1ll << (d->length - 1u)) : 0;
  int64_t hi =
      d->is_signed ? (int64_t)(1ll << (d->length - 1u)) - 1 : (int64_t)(1ll << d->length) - 1;
  int64_t r = 0;
  if (!isnan(v)) {
    float x = roundf((v - d->offset) / d->scale);
    /* compare in float first: the conversion of an out-of-range float is UB */
    if (x <= (float)lo) {
      r = lo;
    } else if (x >= (float)hi) {
      r = hi;
    } else {
      r = (int64_t)x;
    }
  }
  can_codec_set_raw(s, data, (uint32_t)r);
}

bool can_codec_in_range(can_sig_t s, const uint8_t data[8]) {
  const can_sig_desc_t *d = &sigs[s];
  if (d->is_float) {
    return isfinite(can_codec_get(s, data));
  }
  int64_t r = raw_value(d, can_codec_get_raw(s, data));
  return r >= d->raw_min && r <= d->raw_max;
}

/*
 * drive_signals.c - the rows of drive_signal_table.h: one getter each
 * (FD_COLD: main loop only, left in flash on the boards).
 */
#include "drive_signals.h"

#include <stddef.h>

#include "drive_signal_table.h"
#include "math/fd_math.h"

#define DRIVE_SIG_GETTER(name, type, unit, value, can, scale, can_unit, doc)                       \
  FD_COLD static double sig_##name(const void *owner) {                                            \
    const drive_signal_src_t *s = owner;                                                           \
    return (double)(value);                                                                        \
  }
DRIVE_SIGNAL_TABLE(DRIVE_SIG_GETTER)
#undef DRIVE_SIG_GETTER

#define DRIVE_SIG_ROW(name, type, unit, value, can, scale, can_unit, doc)                          \
  {{#name, SIGNAL_##type, unit, doc, sig_##name}, CAN_SIG_##can, scale, can_unit},
static const drive_signal_t table[] = {DRIVE_SIGNAL_TABLE(DRIVE_SIG_ROW)};
#undef DRIVE_SIG_ROW

enum { N_ROWS = sizeof table / sizeof table[0] };

FD_COLD const drive_signal_t *drive_signals(unsigned *n) {
  *n = (unsigned)N_ROWS;
  return table;
}

FD_COLD const drive_signal_t *drive_signal_of_can(can_sig_t c) {
  for (unsigned i = 0u; i < (unsigned)N_ROWS; ++i) {
    if (table[i].can == c && c != CAN_SIG_NONE) {
      return &table[i];
    }
  }
  return NULL;
}

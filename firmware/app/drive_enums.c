/*
 * drive_enums.c - names of the drive's enumerations (drive_enums.h).
 */
#include "drive_enums.h"

#include <string.h>

#define NAME(E, n, d) #n,

static const char *const law_names[] = {DRIVE_LAW_LIST(NAME)};
static const char *const mode_names[] = {DRIVE_MODE_LIST(NAME)};
static const char *const state_names[] = {DRIVE_STATE_LIST(NAME)};
static const char *const fault_names[] = {DRIVE_FAULT_LIST(NAME)};
#define POS_NAME(E, n, s, d) s,
static const char *const pos_names[] = {POS_SOURCE_LIST(POS_NAME)};

static const char *pick(const char *const *names, unsigned n, unsigned i) {
  return i < n ? names[i] : "?";
}

static int find(const char *const *names, unsigned n, const char *name) {
  for (unsigned i = 0; name != NULL && i < n; ++i) {
    if (strcmp(names[i], name) == 0) {
      return (int)i;
    }
  }
  return -1;
}

const char *drive_law_name(unsigned law) {
  return pick(law_names, DRIVE_LAW_COUNT, law);
}

const char *drive_mode_name(unsigned mode) {
  return pick(mode_names, DRIVE_MODE_COUNT, mode);
}

const char *drive_state_name(unsigned state) {
  return pick(state_names, DRIVE_STATE_COUNT, state);
}

const char *drive_pos_source_name(unsigned src) {
  return pick(pos_names, POS_SOURCE_COUNT, src);
}

const char *drive_fault_name(unsigned fault_bits) {
  if (fault_bits == 0u) {
    return "none";
  }
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    if ((fault_bits & (1u << b)) != 0u) {
      return fault_names[b];
    }
  }
  return "unknown";
}

int drive_law_index(const char *name) {
  return find(law_names, DRIVE_LAW_COUNT, name);
}

int drive_mode_index(const char *name) {
  return find(mode_names, DRIVE_MODE_COUNT, name);
}

int drive_pos_source_index(const char *name) {
  return find(pos_names, POS_SOURCE_COUNT, name);
}

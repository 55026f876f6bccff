/*
 * pos_sources.c - the table of position sources, one row per entry of
 * POS_SOURCE_LIST (drive_enums.h), in its order.
 */
#include <stddef.h>

#include "pos_source.h"

#define POS_ROW_DECLARE(E, n, s, d) extern const pos_source_row_t pos_source_##n;
POS_SOURCE_LIST(POS_ROW_DECLARE)
#undef POS_ROW_DECLARE

#define POS_ROW(E, n, s, d) &pos_source_##n,
static const pos_source_row_t *const sources[POS_SOURCE_COUNT] = {POS_SOURCE_LIST(POS_ROW)};
#undef POS_ROW

const pos_source_row_t *pos_source(pos_source_t src) {
  return (unsigned)src < (unsigned)POS_SOURCE_COUNT ? sources[src] : NULL;
}

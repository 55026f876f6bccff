/*
 * ctrl_laws.h - the rows of the law table, one per module (law_*.c), named
 * ctrl_law_<name> after DRIVE_LAW_LIST (drive_enums.h).
 */
#ifndef FLUXDRIVE_CTRL_LAWS_H
#define FLUXDRIVE_CTRL_LAWS_H

#include "ctrl.h"

#define CTRL_LAW_DECLARE(E, n, d) extern const ctrl_law_t ctrl_law_##n;
DRIVE_LAW_LIST(CTRL_LAW_DECLARE)
#undef CTRL_LAW_DECLARE

#endif

/*
 * proc.c - the procedure table and the start sequence (proc.h).
 */
#include "proc.h"

#include <stddef.h>

#include "math/fd_math.h"

/* One row per PROC_LIST entry, in its order. */
#define PROC_ROW(E, n, d) &proc_##n,
static const proc_row_t *const rows[PROC_COUNT] = {PROC_LIST(PROC_ROW)};
#undef PROC_ROW

/* The start: the offsets with the gates off, then the held start or the
 * alignment (whichever the parameter set and the source want), then the
 * law (drive.c). */
static const proc_id_t start_seq[] = {PROC_OFFSET, PROC_HOLD, PROC_ALIGN};

FD_COLD const proc_row_t *proc_row(proc_id_t id) {
  return (unsigned)id < (unsigned)PROC_COUNT ? rows[id] : NULL;
}

FD_COLD const proc_id_t *proc_start_sequence(unsigned *n) {
  *n = (unsigned)(sizeof start_seq / sizeof start_seq[0]);
  return start_seq;
}

FD_COLD bool proc_applies(proc_id_t id, const proc_setup_t *su) {
  const proc_row_t *r = proc_row(id);
  const char *field = NULL;
  return r != NULL && (r->wanted == NULL || r->wanted(su)) &&
         (r->check == NULL || r->check(su, &field) == NULL);
}

FD_COLD const char *proc_start_refusal(const proc_setup_t *su, const char **field) {
  unsigned n;
  const proc_id_t *seq = proc_start_sequence(&n);
  for (unsigned k = 0; k < n; ++k) {
    const proc_row_t *r = proc_row(seq[k]);
    const char *why =
        (r->check != NULL && (r->wanted == NULL || r->wanted(su))) ? r->check(su, field) : NULL;
    if (why != NULL) {
      return why;
    }
  }
  return NULL;
}

FD_COLD void proc_ident_sequence(proc_id_t id, proc_id_t seq[2], unsigned *n) {
  seq[0] = PROC_OFFSET;
  seq[1] = id;
  *n = id == PROC_OFFSET ? 1u : 2u;
}

FD_COLD const char *proc_ident_refusal(proc_id_t id, const proc_setup_t *su, const char **field) {
  const proc_row_t *r = proc_row(id);
  *field = "proc";
  if (r == NULL || (r->caps & PROC_CAP_IDENT) == 0u) {
    return "not an identification procedure";
  }
  *field = NULL;
  return r->check != NULL ? r->check(su, field) : NULL;
}

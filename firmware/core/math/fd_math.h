/*
 * fd_math.h - small float helpers for the ISR path, inlined: no libm call
 * for a classification, a minimum or a clamp.
 *
 * newlib's isfinite() expands to a call of __fpclassifyf and fminf/fmaxf
 * are library functions; these compile to a few instructions (VCMP, VSEL
 * or a branch). NaN handling is explicit and documented per helper.
 */
#ifndef FD_MATH_FD_MATH_H
#define FD_MATH_FD_MATH_H

/* A function kept out of line so that the PIL trace counts it per call
 * (docs/benchmarks.md); a call costs a few instructions. */
#if defined(__GNUC__)
#define FD_NOINLINE __attribute__((noinline))
#else
#define FD_NOINLINE
#endif

/* Initialisation and configuration code (runs at start-up or when a
 * parameter set is taken, never in a normal period): on the Cortex-M builds
 * in section .fd_cold, which the STM32G474 link leaves in flash so that the
 * CCM SRAM holds the periodic ISR path (hal/stm32g4/stm32g474re.ld);
 * nothing on the host. */
#if defined(__GNUC__) && defined(__arm__)
#define FD_COLD __attribute__((section(".fd_cold")))
#else
#define FD_COLD
#endif

/* 1 if x is neither infinite nor NaN. */
static inline int fd_isfinite(float x) {
  return __builtin_isfinite(x);
}

/* 0 for a finite x, NaN for an infinite or NaN x (0 * x). A sum of these
 * is finite only if every term's x is: one classification for many values. */
static inline float fd_zero_if_finite(float x) {
  return 0.0f * x;
}

/* The smaller of a and b; b when a is NaN (as fminf). b must not be NaN. */
static inline float fd_minf(float a, float b) {
  return (a < b) ? a : b;
}

/* The larger of a and b; b when a is NaN (as fmaxf). b must not be NaN. */
static inline float fd_maxf(float a, float b) {
  return (a > b) ? a : b;
}

/* fd_minf(fd_maxf(x, lo), hi), i.e. fminf(fmaxf(x, lo), hi): lo for a NaN x,
 * hi when lo > hi. lo and hi must not be NaN. */
static inline float fd_clampf(float x, float lo, float hi) {
  return fd_minf(fd_maxf(x, lo), hi);
}

#endif

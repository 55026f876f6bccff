/*
 * frames.h - vector types and the Clarke / Park transforms.
 * Amplitude-invariant Clarke (a 3-phase set of peak I gives |i_ab| = I).
 * Park rotates by the electrical angle theta: x_dq = e^{-j theta} x_ab.
 */
#ifndef FD_MATH_FRAMES_H
#define FD_MATH_FRAMES_H

typedef struct {
  float a, b, c;
} abc_t;

typedef struct {
  float alpha, beta;
} ab_t;

typedef struct {
  float d, q;
} dq_t;

/* sin and cos of one angle, computed once and shared by Park and inverse. */
typedef struct {
  float s, c;
} sincos_t;

sincos_t frames_sincos(float theta);
ab_t frames_clarke(abc_t x);
/* Clarke from two phases, assuming a + b + c = 0 (two-shunt boards). */
ab_t frames_clarke2(float a, float b);
abc_t frames_clarke_inv(ab_t x);
dq_t frames_park(ab_t x, sincos_t sc);
ab_t frames_park_inv(dq_t x, sincos_t sc);
/* Wrap an angle to [-pi, pi). */
float frames_wrap_pi(float theta);
/* Wrap an angle to [0, 2 pi). */
float frames_wrap_2pi(float theta);

#endif

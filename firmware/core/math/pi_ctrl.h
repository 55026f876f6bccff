/*
 * pi_ctrl.h - discrete PI regulator (forward-Euler integral) with output
 * limits and anti-windup by conditional integration plus back-calculation:
 * the integral never grows while the output is saturated in the direction
 * of the error, and it is re-aligned so that integ + ff stays within the
 * limits, and kp*e + integ + ff too whenever kp*e points away from the
 * limit (so the output leaves saturation as soon as the error reverses).
 * Details in pi_ctrl.c.
 */
#ifndef FD_MATH_PI_CTRL_H
#define FD_MATH_PI_CTRL_H

typedef struct {
  float kp;      /* proportional gain */
  float ki;      /* integral gain [1/s] */
  float ts;      /* sampling period [s] */
  float out_min; /* output limits, out_min < out_max */
  float out_max;
  float integ; /* integral state (same unit as the output) */
} pi_ctrl_t;

void pi_ctrl_init(pi_ctrl_t *pi, float kp, float ki, float ts, float out_min, float out_max);
void pi_ctrl_reset(pi_ctrl_t *pi, float integ);
void pi_ctrl_set_limits(pi_ctrl_t *pi, float out_min, float out_max);
/* One step: err is ref - meas, ff a feed-forward added before the limit.
 * Returns the limited output. */
float pi_ctrl_update(pi_ctrl_t *pi, float err, float ff);

#endif

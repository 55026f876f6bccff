/*
 * hal_regs_test.c - the STM32G4 HAL's break, idle-state and comparator-trip
 * set-up (hal/stm32g4/pwm_tim1.c, break_comp.c) run on the host against
 * fake register blocks: the peripheral macros of stm32g4_regs.h are pointed
 * at static structs before the two HAL files are included. Built once per
 * board (tests/target/extra.cmake defines FD_BOARD_*). The expected values
 * come from RM0440 and the board's physics (shunt, gains, dead time), not
 * from the code under test.
 */
#include <setjmp.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "stm32g4_regs.h"

static rcc_regs_t s_rcc;
static tim_regs_t s_tim1;
static dbgmcu_regs_t s_dbgmcu;
static comp_regs_t s_comp;
static dac_regs_t s_dac3;

#undef RCC
#undef TIM1
#undef DBGMCU
#undef COMP
#undef DAC3
#define RCC    (&s_rcc)
#define TIM1   (&s_tim1)
#define DBGMCU (&s_dbgmcu)
#define COMP   (&s_comp)
#define DAC3   (&s_dac3)

#include "break_comp.c" /* NOLINT(bugprone-suspicious-include) */
#include "pwm_tim1.c"   /* NOLINT(bugprone-suspicious-include) */

/* ---- stubs of the HAL files not under test ---- */
static hal_pin_t s_af_pins[8];
static uint32_t s_af_pull[8];
static unsigned s_af_n;

void hal_gpio_af(hal_pin_t p, uint32_t pull) {
  if (s_af_n < 8u) {
    s_af_pins[s_af_n] = p;
    s_af_pull[s_af_n] = pull;
    s_af_n++;
  }
}

void hal_delay_cycles(uint32_t n) {
  (void)n;
}

static int reset_regs(void **state) {
  (void)state;
  memset((void *)&s_rcc, 0, sizeof s_rcc);
  memset((void *)&s_tim1, 0, sizeof s_tim1);
  memset((void *)&s_dbgmcu, 0, sizeof s_dbgmcu);
  memset((void *)&s_comp, 0, sizeof s_comp);
  memset((void *)&s_dac3, 0, sizeof s_dac3);
  s_tim1.AF1 = TIM1_AF1_BKINE; /* reset value (RM0440 TIMx_AF1) */
  s_af_n = 0u;
  return 0;
}

static uint32_t field(uint32_t reg, uint32_t pos, uint32_t width) {
  return (reg >> pos) & ((1u << width) - 1u);
}

/* Break and idle set-up common to both boards (RM0440 28.6.20, 28.6.2):
 * the complementary outputs of an active-high gate driver. */
static void check_bdtr_common(void) {
  const uint32_t bdtr = s_tim1.BDTR;
  /* dead time 500 ns at 170 MHz: 85 ticks of t_DTS, DTG[7] = 0 */
  const double ticks = 500e-9 * 170e6;
  printf("BDTR 0x%08x: DTG %u (500 ns x 170 MHz = %.1f), LOCK %u, BKF 0x%x\n", (unsigned)bdtr,
         (unsigned)(bdtr & 0xFFu), ticks, (unsigned)field(bdtr, 8, 2),
         (unsigned)field(bdtr, 16, 4));
  assert_int_equal(bdtr & 0xFFu, (uint32_t)(ticks + 0.5));
  /* LOCK level 1: dead time, break, OISx frozen; level 2 would freeze
   * OSSI/OSSR, level 3 OCxM (the short's force-inactive mode) */
  assert_int_equal(field(bdtr, 8, 2), 1u);
  assert_true((bdtr & TIM_BDTR_OSSI) != 0u); /* MOE = 0: outputs driven to OISx, not released */
  assert_true((bdtr & TIM_BDTR_OSSR) != 0u); /* MOE = 1, channel off: driven inactive */
  assert_true((bdtr & TIM_BDTR_BKE) != 0u);
  assert_true((bdtr & TIM_BDTR_AOE) == 0u);    /* no restart at the next update */
  assert_true((bdtr & TIM_BDTR_MOE) == 0u);    /* gates off after init */
  assert_true((bdtr & TIM_BDTR_BKBID) == 0u);  /* the break is an input only */
  assert_true((bdtr & TIM_BDTR_BKDSRM) == 0u); /* break not disarmed */
  /* idle levels: OIS1..OIS3N (CR2 bits 8..13) = 0, the off level of an
   * active-high driver input; CCxP = CCxNP = 0 */
  assert_int_equal(field(s_tim1.CR2, 8, 6), 0u);
  assert_int_equal(s_tim1.CCER & 0x0AAAu, 0u);
  assert_int_equal(s_tim1.CCER & 0x0555u, 0x0555u); /* CC1E, CC1NE .. CC3E, CC3NE */
}

/* The short (ASC) under LOCK level 1: OCxM = 0100 (force inactive) on the
 * three channels and MOE = 1; enable restores PWM mode 2 (0111). */
static void short_and_enable(void **state) {
  (void)state;
  hal_tim1_init();
  hal_pwm_short();
  assert_int_equal(field(s_tim1.CCMR1, 4, 3), 4u);
  assert_int_equal(field(s_tim1.CCMR1, 12, 3), 4u);
  assert_int_equal(field(s_tim1.CCMR2, 4, 3), 4u);
  assert_true((s_tim1.BDTR & TIM_BDTR_MOE) != 0u);
  assert_true(field(s_tim1.BDTR, 8, 2) < 3u); /* OCxM writable */
  assert_true(hal_pwm_is_shorted());
  assert_false(hal_pwm_is_enabled());
  hal_pwm_enable();
  assert_int_equal(field(s_tim1.CCMR1, 4, 3), 7u);
  assert_int_equal(field(s_tim1.CCMR1, 12, 3), 7u);
  assert_int_equal(field(s_tim1.CCMR2, 4, 3), 7u);
  assert_true(hal_pwm_is_enabled());
  hal_pwm_disable();
  assert_true((s_tim1.BDTR & TIM_BDTR_MOE) == 0u);
  /* the break flag is the hardware trip; cleared by writing 0 (rc_w0) */
  s_tim1.SR = TIM_SR_BIF;
  assert_true(hal_fault_hw_tripped());
}

#if defined(FD_BOARD_B_G431B_ESC1)

/* B-G431B-ESC1 (UM2516): 3 mOhm shunts, 9.14 V/V to the ADC pin of which
 * the op-amp's PGA gives x16, 1.65 V at zero current, VDDA = VREF+ = 3.3 V;
 * the trip at 40 A taken out of the machine (the signal rises). */
#define ESC1_SHUNT      0.003
#define ESC1_GAIN       9.14
#define ESC1_PGA        16.0
#define ESC1_MID        1.65
#define ESC1_VREF       3.3
#define ESC1_TRIP_A     40.0
#define ESC1_DRIVE_TRIP 30.0 /* BOARD_I_TRIP: the drive's sampled trip */

static double esc1_current_of_code(uint32_t code) {
  const double v_cmp = (double)code * ESC1_VREF / 4095.0;
  return (v_cmp * ESC1_PGA - ESC1_MID) / (ESC1_SHUNT * ESC1_GAIN);
}

static void esc1_comparators_and_dac3(void **state) {
  (void)state;
  s_dac3.SR = DAC_SR_DAC1RDY | DAC_SR_DAC2RDY;
  assert_true(hal_break_comp_init());
  /* clocks: SYSCFG (COMP registers), DAC3 (RCC_AHB2ENR bit 18) */
  assert_true((s_rcc.APB2ENR & 1u) != 0u);
  assert_true((s_rcc.AHB2ENR & (1u << 18)) != 0u);
  /* DAC3: MODE1 = MODE2 = 011 (internal, unbuffered), HFSEL = 10, both on */
  assert_int_equal(field(s_dac3.MCR, 0, 3), 3u);
  assert_int_equal(field(s_dac3.MCR, 16, 3), 3u);
  assert_int_equal(field(s_dac3.MCR, 14, 2), 2u);
  assert_int_equal(s_dac3.CR & ((1u << 0) | (1u << 16)), (1u << 0) | (1u << 16));
  assert_int_equal(s_dac3.CR & ~((1u << 0) | (1u << 16)), 0u); /* no trigger, wave, DMA */
  /* COMP1 (U, PA1), COMP2 (V, PA7), COMP4 (W, PB0): INP IO1 (INPSEL 0),
   * INM DAC3 (INMSEL 100), not inverted, no hysteresis, no blanking, no
   * scaler, enabled and locked; COMP3 untouched */
  const unsigned idx[3] = {0u, 1u, 3u};
  for (unsigned k = 0; k < 3u; k++) {
    const uint32_t csr = s_comp.CSR[idx[k]];
    printf("COMP%u_CSR 0x%08x\n", idx[k] + 1u, (unsigned)csr);
    assert_int_equal(field(csr, 4, 3), 4u);  /* INMSEL */
    assert_int_equal(field(csr, 8, 1), 0u);  /* INPSEL */
    assert_int_equal(field(csr, 15, 1), 0u); /* POLARITY */
    assert_int_equal(field(csr, 16, 3), 0u); /* HYST */
    assert_int_equal(field(csr, 19, 3), 0u); /* BLANKSEL */
    assert_int_equal(field(csr, 22, 2), 0u); /* BRGEN, SCALEN */
    assert_int_equal(csr & (COMP_CSR_EN | COMP_CSR_LOCK), COMP_CSR_EN | COMP_CSR_LOCK);
  }
  assert_int_equal(s_comp.CSR[2], 0u);
  /* the threshold: both channels, the code of 40 A from the physics */
  const double v_trip = (ESC1_MID + ESC1_TRIP_A * ESC1_SHUNT * ESC1_GAIN) / ESC1_PGA;
  const double code_exact = v_trip / ESC1_VREF * 4095.0;
  const double i_code = esc1_current_of_code(s_dac3.DHR12R1);
  const double lsb_a = ESC1_VREF / 4095.0 * ESC1_PGA / (ESC1_SHUNT * ESC1_GAIN);
  printf("DAC3 DHR12R1 %u DHR12R2 %u (exact %.2f: %.4f V at the comparator); trips at %.2f A "
         "(1 LSB = %.3f A); zero current at %.4f V = code %.1f; ADC pin %.2f mV/A\n",
         (unsigned)s_dac3.DHR12R1, (unsigned)s_dac3.DHR12R2, code_exact, v_trip, i_code, lsb_a,
         ESC1_MID / ESC1_PGA, ESC1_MID / ESC1_PGA / ESC1_VREF * 4095.0,
         1e3 * ESC1_SHUNT * ESC1_GAIN);
  assert_int_equal(s_dac3.DHR12R1, s_dac3.DHR12R2);
  assert_true(i_code > ESC1_TRIP_A - 0.5 * lsb_a && i_code < ESC1_TRIP_A + 0.5 * lsb_a);
  assert_true(i_code > ESC1_DRIVE_TRIP); /* the drive trips first */
  /* the inverse the docs quote */
  const float i_back = hal_break_comp_trip_current(s_dac3.DHR12R1);
  assert_true(fabs((double)i_back - i_code) < 0.01);
}

static void esc1_dac3_not_ready_is_an_error(void **state) {
  (void)state;
  s_dac3.SR = DAC_SR_DAC1RDY; /* channel 2 never ready */
  assert_false(hal_break_comp_init());
}

static void esc1_tim1_break_from_the_comparators(void **state) {
  (void)state;
  hal_tim1_init();
  const uint32_t af1 = s_tim1.AF1;
  printf("TIM1_AF1 0x%08x\n", (unsigned)af1);
  /* BKCMP1E (bit 1), BKCMP2E (bit 2), BKCMP4E (bit 4); BKINE = 0 (no pin);
   * BKINP and BKCMP1P..4P (bits 9..13) = 0 */
  assert_int_equal(af1, (1u << 1) | (1u << 2) | (1u << 4));
  /* BKP = 1: with BKCMPxP = 0 the comparator's high output is the break */
  assert_true((s_tim1.BDTR & TIM_BDTR_BKP) != 0u);
  /* BKF = 0111: f_DTS / 4, N = 8 -> 8 x 4 / 170 MHz */
  assert_int_equal(field(s_tim1.BDTR, 16, 4), 7u);
  printf("break filter %.0f ns\n", 8.0 * 4.0 / 170e6 * 1e9);
  check_bdtr_common();
  assert_int_equal(s_af_n, 6u); /* the six PWM pins, no BKIN pin */
  /* no gate-driver fault output on the kit: break 2 off */
  assert_int_equal(s_tim1.AF2, 0u);
  assert_true((s_tim1.BDTR & TIM_BDTR_BK2E) == 0u);
}

#else /* the NUCLEO-G474 header: external comparator on BKIN (PA6, AF6), active low */

static void g474_tim1_break_from_bkin(void **state) {
  (void)state;
  hal_tim1_init();
  printf("TIM1_AF1 0x%08x\n", (unsigned)s_tim1.AF1);
  assert_int_equal(s_tim1.AF1, 1u);                /* BKINE only, BKINP = 0 */
  assert_true((s_tim1.BDTR & TIM_BDTR_BKP) == 0u); /* active low */
  assert_int_equal(field(s_tim1.BDTR, 16, 4), 3u);
  check_bdtr_common();
  assert_int_equal(s_af_n, 8u);
  assert_int_equal(s_af_pins[6].port, PORT_A);
  assert_int_equal(s_af_pins[6].pin, 6u);
  assert_int_equal(s_af_pins[6].af, 6u);
  assert_int_equal(s_af_pull[6], 1u); /* pulled up: the inactive level */
  /* break 2: the gate driver's nFAULT (open drain, active low) on BKIN2 */
  printf("TIM1_AF2 0x%08x, BK2E %u, BK2P %u, BK2F 0x%x\n", (unsigned)s_tim1.AF2,
         (unsigned)((s_tim1.BDTR & TIM_BDTR_BK2E) != 0u),
         (unsigned)((s_tim1.BDTR & TIM_BDTR_BK2P) != 0u), (unsigned)field(s_tim1.BDTR, 20, 4));
  assert_int_equal(s_tim1.AF2, TIM1_AF2_BK2INE);
  assert_true((s_tim1.BDTR & TIM_BDTR_BK2E) != 0u);
  assert_true((s_tim1.BDTR & TIM_BDTR_BK2P) == 0u); /* active low */
  assert_int_equal(field(s_tim1.BDTR, 20, 4), 3u);
  assert_int_equal(s_af_pins[7].port, PORT_C);
  assert_int_equal(s_af_pins[7].pin, 3u);
  assert_int_equal(s_af_pins[7].af, 6u);
  assert_int_equal(s_af_pull[7], 1u);
}

static void g474_no_comparators(void **state) {
  (void)state;
  assert_true(hal_break_comp_init());
  assert_int_equal(hal_break_comp_af1(), 0u);
  for (unsigned k = 0; k < 7u; k++) {
    assert_int_equal(s_comp.CSR[k], 0u);
  }
  assert_int_equal(s_dac3.CR, 0u);
}

#endif

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test_setup(short_and_enable, reset_regs),
#if defined(FD_BOARD_B_G431B_ESC1)
    cmocka_unit_test_setup(esc1_comparators_and_dac3, reset_regs),
    cmocka_unit_test_setup(esc1_dac3_not_ready_is_an_error, reset_regs),
    cmocka_unit_test_setup(esc1_tim1_break_from_the_comparators, reset_regs),
#else
    cmocka_unit_test_setup(g474_tim1_break_from_bkin, reset_regs),
    cmocka_unit_test_setup(g474_no_comparators, reset_regs),
#endif
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/*
 * hal_adc_test.c - the STM32G4 HAL's PWM-period interrupt (hal/stm32g4/adc.c)
 * run on the host against fake register blocks, as hal_regs_test.c does for
 * the break set-up: the peripheral macros of stm32g4_regs.h are pointed at
 * static structs before adc.c is included. Built once per board
 * (tests/target/extra.cmake defines FD_BOARD_*).
 *
 * What is proven (RM0440 section 21: the injected group, ADC_ISR's rc_w1
 * flags, ADC_IER; the two ADCs share the ADC1_2 line, vector 18 of the
 * vector table, section 16.3): hal_adc_start arms
 * the injected end-of-sequence interrupt (JEOSIE) and the conversions
 * (JADSTART) of every ADC with an injected sequence and enables IRQ 18 at
 * the highest priority; ADC1_2_IRQHandler runs the registered period body
 * once per period, at the last of the ends, whichever ADC ends first, and
 * never waits: an entry that does not complete the period returns at once.
 * The fake ISR registers do not clear on a write of 1 (the hardware's
 * rc_w1); the tests clear a flag by hand where the hardware would, and
 * check which bits the handler wrote.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "stm32g4_regs.h"

static adc_regs_t s_adc1;
static adc_regs_t s_adc2;
static adc_common_regs_t s_adc12;
static rcc_regs_t s_rcc;
static opamp_regs_t s_opamp;
static nvic_regs_t s_nvic;
static dwt_regs_t s_dwt;

#undef ADC1
#undef ADC2
#undef ADC12_COMMON
#undef RCC
#undef OPAMP
#undef NVIC
#undef DWT
#define ADC1         (&s_adc1)
#define ADC2         (&s_adc2)
#define ADC12_COMMON (&s_adc12)
#define RCC          (&s_rcc)
#define OPAMP        (&s_opamp)
#define NVIC         (&s_nvic)
#define DWT          (&s_dwt)
/* PRIMASK is a Cortex-M register: no masking on the host */
#define hal_irq_save()     0u
#define hal_irq_restore(p) ((void)(p))

#include "adc.c" /* NOLINT(bugprone-suspicious-include) */

/* ---- stubs of the HAL files not under test ---- */
static unsigned s_calls;        /* a call log: one digit per call */
static unsigned s_period_runs;  /* calls of the registered period body */
static bool s_update_pending;   /* TIM1's update flag at the overrun check */
static uint32_t s_adc1_isr_out; /* what the handler wrote to ADCx_ISR */
static uint32_t s_adc2_isr_out;

void hal_gpio_analog(uint8_t port, uint8_t pin) {
  (void)port;
  (void)pin;
}

void hal_delay_cycles(uint32_t n) {
  (void)n;
}

void hal_tim1_clear_update(void) {
  s_calls = s_calls * 10u + 1u;
}

bool hal_tim1_update_pending(void) {
  return s_update_pending;
}

static void period_body(void) {
  s_calls = s_calls * 10u + 2u;
  s_period_runs++;
}

static int reset_regs(void **state) {
  (void)state;
  memset((void *)&s_adc1, 0, sizeof s_adc1);
  memset((void *)&s_adc2, 0, sizeof s_adc2);
  memset((void *)&s_adc12, 0, sizeof s_adc12);
  memset((void *)&s_rcc, 0, sizeof s_rcc);
  memset((void *)&s_opamp, 0, sizeof s_opamp);
  memset((void *)&s_nvic, 0, sizeof s_nvic);
  memset((void *)&s_dwt, 0, sizeof s_dwt);
  memset(&s_isr, 0, sizeof s_isr);
  s_nvic.IPR[IRQN_ADC1_2] = 0xF0u;
  s_calls = 0u;
  s_period_runs = 0u;
  s_update_pending = false;
  return 0;
}

/* The injected sequences as hal_adc_init leaves them: JEXTEN = 01 (rising
 * edge of TIM1_TRGO) on each ADC in use. */
static void sequences(bool adc1, bool adc2) {
  s_adc1.JSQR = adc1 ? (1u << ADC_JSQR_JEXTEN_Pos) : 0u;
  s_adc2.JSQR = adc2 ? (1u << ADC_JSQR_JEXTEN_Pos) : 0u;
}

/* hal_adc_start, then its flag clears (rc_w1) applied as the hardware would. */
static bool start(hal_control_fn body) {
  const bool ok = hal_adc_start(body);
  if (ok) {
    /* stale ends and queue overflows of before the start cleared */
    assert_int_equal(s_adc1.ISR, ADC_ISR_JEOC | ADC_ISR_JEOS | ADC_ISR_JQOVF);
    assert_int_equal(s_adc2.ISR, ADC_ISR_JEOC | ADC_ISR_JEOS | ADC_ISR_JQOVF);
  }
  s_adc1.ISR = 0u;
  s_adc2.ISR = 0u;
  return ok;
}

/* One entry of ADC1_2_IRQHandler with these JEOS flags; the flags the
 * handler wrote (rc_w1) are then cleared as the hardware would. */
static void enter(bool end1, bool end2) {
  if (end1) {
    s_adc1.ISR |= ADC_ISR_JEOS | ADC_ISR_JEOC;
  }
  if (end2) {
    s_adc2.ISR |= ADC_ISR_JEOS | ADC_ISR_JEOC;
  }
  const uint32_t before1 = s_adc1.ISR;
  const uint32_t before2 = s_adc2.ISR;
  ADC1_2_IRQHandler();
  s_adc1_isr_out = s_adc1.ISR;
  s_adc2_isr_out = s_adc2.ISR;
  s_adc1.ISR = before1 & ~(s_adc1_isr_out & ADC_ISR_JEOS);
  s_adc2.ISR = before2 & ~(s_adc2_isr_out & ADC_ISR_JEOS);
}

static void start_arms_every_adc_in_use(void **state) {
  (void)state;
  sequences(true, true);
  assert_true(start(period_body));
  /* JEOSIE on both (the line is shared, either may end last), nothing else */
  assert_int_equal(s_adc1.IER, ADC_IER_JEOSIE);
  assert_int_equal(s_adc2.IER, ADC_IER_JEOSIE);
  assert_int_equal(s_adc1.CR & ADC_CR_JADSTART, ADC_CR_JADSTART);
  assert_int_equal(s_adc2.CR & ADC_CR_JADSTART, ADC_CR_JADSTART);
  /* IRQ 18 enabled at priority 0 (above SysTick's 8) */
  assert_int_equal(s_nvic.ISER[0], 1u << 18);
  assert_int_equal(s_nvic.ICPR[0], 1u << 18);
  assert_int_equal(s_nvic.IPR[18], 0u);
}

static void start_leaves_an_unused_adc_alone(void **state) {
  (void)state;
  sequences(true, false);
  assert_true(start(period_body));
  assert_int_equal(s_adc1.IER, ADC_IER_JEOSIE);
  assert_int_equal(s_adc2.IER, 0u);
  assert_int_equal(s_adc2.CR & ADC_CR_JADSTART, 0u);
}

static void start_refuses_no_body_or_no_sequence(void **state) {
  (void)state;
  sequences(true, true);
  assert_false(start(0));
  assert_int_equal(s_nvic.ISER[0], 0u); /* not armed */
  assert_int_equal(s_adc1.IER, 0u);
  sequences(false, false);
  assert_false(start(period_body));
  assert_int_equal(s_nvic.ISER[0], 0u);
}

/* ADC2's shorter sequence ends first (the g474 and ESC1 tables): that entry
 * clears ADC2's end and returns; ADC1's end runs the period. */
static void period_at_the_second_end(void **state) {
  (void)state;
  sequences(true, true);
  assert_true(start(period_body));
  enter(false, true);
  assert_int_equal(s_period_runs, 0u);
  assert_int_equal(s_calls, 0u);                  /* no TIM1 access either */
  assert_int_equal(s_adc2_isr_out, ADC_ISR_JEOS); /* only the end it saw */
  assert_int_equal(s_adc1_isr_out, 0u);           /* ADC1's flags untouched */
  assert_int_equal(s_adc2.IER, ADC_IER_JEOSIE);   /* interrupts stay armed */
  enter(true, false);
  assert_int_equal(s_period_runs, 1u);
  assert_int_equal(s_calls, 12u); /* TIM1's update flag cleared, then the body */
  assert_int_equal(s_adc1_isr_out, ADC_ISR_JEOS);
  assert_int_equal(s_isr.isr_count, 1u);
  /* the next period, ends in the other order */
  enter(true, false);
  assert_int_equal(s_period_runs, 1u);
  enter(false, true);
  assert_int_equal(s_period_runs, 2u);
}

static void both_ends_in_one_entry(void **state) {
  (void)state;
  sequences(true, true);
  assert_true(start(period_body));
  enter(true, true);
  assert_int_equal(s_period_runs, 1u);
  assert_int_equal(s_adc1_isr_out, ADC_ISR_JEOS);
  assert_int_equal(s_adc2_isr_out, ADC_ISR_JEOS);
  /* a spurious re-entry (the clear not yet seen by the NVIC): nothing */
  enter(false, false);
  assert_int_equal(s_period_runs, 1u);
  assert_int_equal(s_adc1_isr_out, 0u);
  assert_int_equal(s_adc2_isr_out, 0u);
}

static void one_adc_in_use(void **state) {
  (void)state;
  sequences(true, false);
  assert_true(start(period_body));
  enter(true, false);
  assert_int_equal(s_period_runs, 1u);
  enter(true, false);
  assert_int_equal(s_period_runs, 2u);
}

/* An ADC whose end does not come stops the periods (and, in the drive,
 * the watchdog refresh); the first end of both runs one period. */
static void a_missing_end_stops_the_periods(void **state) {
  (void)state;
  sequences(true, true);
  assert_true(start(period_body));
  for (int k = 0; k < 5; k++) {
    enter(true, false);
  }
  assert_int_equal(s_period_runs, 0u);
  enter(false, true);
  assert_int_equal(s_period_runs, 1u);
}

static void overrun_counted_after_the_body(void **state) {
  (void)state;
  sequences(true, true);
  assert_true(start(period_body));
  s_update_pending = true; /* the next valley came before the period ended */
  enter(true, true);
  assert_int_equal(s_isr.overruns, 1u);
  assert_int_equal(hal_isr_overruns(), 1u);
  s_update_pending = false;
  enter(true, true);
  assert_int_equal(hal_isr_overruns(), 1u);
  assert_int_equal(s_isr.isr_count, 2u);
}

/* The sample is always this period's: the body runs only after every end. */
static void sample_valid(void **state) {
  (void)state;
  uint32_t jdr1[4] = {2048u, 2048u, 2048u, 0u};
  for (uint32_t s = 0; s < SIG_COUNT; s++) {
    s_jdr[s] = (k_sig[s].adc != 0u) ? &jdr1[s % 3u] : 0;
  }
  hal_sample_t smp;
  memset(&smp, 0, sizeof smp);
  hal_adc_read(&smp);
  assert_true(smp.valid);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(start_arms_every_adc_in_use, reset_regs),
      cmocka_unit_test_setup(start_leaves_an_unused_adc_alone, reset_regs),
      cmocka_unit_test_setup(start_refuses_no_body_or_no_sequence, reset_regs),
      cmocka_unit_test_setup(period_at_the_second_end, reset_regs),
      cmocka_unit_test_setup(both_ends_in_one_entry, reset_regs),
      cmocka_unit_test_setup(one_adc_in_use, reset_regs),
      cmocka_unit_test_setup(a_missing_end_stops_the_periods, reset_regs),
      cmocka_unit_test_setup(overrun_counted_after_the_body, reset_regs),
      cmocka_unit_test_setup(sample_valid, reset_regs),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

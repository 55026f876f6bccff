/*
 * adc.c - phase currents, DC-link and star-point voltage sampled by ADC1 and
 * ADC2 injected sequences at the TIM1 update (carrier valley).
 *
 * RM0440 section 21.4: clock (21.4.3: CKMODE = 11, adc_hclk/4 = 42.5 MHz,
 * synchronous, so the trigger-to-sample delay is fixed), deep power-down exit
 * and regulator start-up (21.4.6), calibration (21.4.8: ADCAL with ADEN = 0,
 * single-ended), enable (21.4.9: ADRDY), injected group (21.4.21: JSQR with
 * JEXTSEL = TIM1_TRGO, JEXTEN = rising edge; JQDIS = 1, queue disabled).
 * The PWM-period interrupt is the end of the later of the two injected
 * sequences: ADC1 and ADC2 share one interrupt line (ADC1_2, vector 18,
 * RM0440 section 16.3) and each raises it with its own JEOS (JEOSIE on
 * every ADC in use); the entry of the first end notes it and returns, the
 * entry of the second runs the period. No wait, whichever sequence is
 * longer.
 * OPAMP PGA (RM0440 section 25.3.5) for boards that amplify the shunt
 * signal inside the MCU.
 */
#include "adc.h"

#include "board.h"
#include "clock.h"
#include "hal.h"
#include "hal_stm32g4.h"
#include "pwm_tim1.h"
#include "star_window.h"

#define HOT __attribute__((section(".ccmram.text.hal")))

enum { SIG_IA = 0, SIG_IB, SIG_IC, SIG_VDC, SIG_VSTAR, SIG_COUNT };

typedef struct {
  uint8_t adc;     /* 1, 2; 0 = not measured */
  uint8_t channel; /* ADCx_INn */
  uint8_t smp;     /* ADC_SMP_* */
} adc_signal_t;

static const adc_signal_t k_sig[SIG_COUNT] = {BOARD_ADC_IA, BOARD_ADC_IB, BOARD_ADC_IC,
                                              BOARD_ADC_VDC, BOARD_ADC_VSTAR};
static const hal_pin_t k_adc_pins[BOARD_ADC_NPINS] = BOARD_ADC_PINS;

/* Data register of each signal, set by hal_adc_init. */
static reg32_t *s_jdr[SIG_COUNT];

/* The ends a period needs and has seen: bit 0 ADC1's JEOS, bit 1 ADC2's. */
enum { END_ADC1 = 1u, END_ADC2 = 2u };
_Static_assert(ADC_ISR_JEOS >> 6 == END_ADC1 && ADC_ISR_JEOS >> 5 == END_ADC2,
               "ADC1_2_IRQHandler shifts JEOS (RM0440 ADC_ISR bit 6) onto END_*");

static struct {
  hal_control_fn control; /* the application's period body (hal_stm32g4_start) */
  uint32_t ends;          /* END_* seen since the last period ran */
  uint32_t ends_needed;   /* END_* of the ADCs with an injected sequence */
  uint32_t isr_count;
  uint32_t overruns;
  uint32_t cycles_last;
  uint32_t cycles_max;
  uint32_t cycles_acc; /* 256 x the exponential mean (time constant 256 periods) */
} s_isr;

/* Sampling cycles of the ADC_SMP_* codes (RM0440 21.4.12), x2 (half cycles). */
static const uint16_t k_smp_half_cycles[8] = {5u, 13u, 25u, 49u, 95u, 185u, 495u, 1281u};

/* The instant the phase currents are sampled after the valley: the
 * trigger (TIM1 TRGO at the update) plus ~2 ADC clock cycles of latency,
 * then the middle of the first conversion's sampling window (42.5 MHz ADC
 * clock, synchronous: the delay is fixed). */
static float adc_sample_instant(void) {
  const float f_adc = (float)BOARD_SYSCLK_HZ / 4.0f;
  const float half = (float)k_smp_half_cycles[k_sig[SIG_IA].smp & 7u];
  return (2.0f + 0.25f * half) / f_adc;
}

/* adc_sample_instant(), set by hal_adc_init (the ISR reads it, no call). */
static float s_t_i;
/* the star point's injected sample: its instant after the valley */
static float s_t_star;

/* The middle of signal sig's sampling window after the trigger: the ranks
 * before it on its ADC (sampling + 12.5 cycles of conversion each). */
static float adc_signal_instant(uint32_t sig) {
  const float f_adc = (float)BOARD_SYSCLK_HZ / 4.0f;
  float half_cycles = 4.0f; /* trigger latency, ~2 ADC clocks */
  for (uint32_t s = 0; s < sig; s++) {
    if (k_sig[s].adc == k_sig[sig].adc) {
      half_cycles += (float)k_smp_half_cycles[k_sig[s].smp & 7u] + 25.0f;
    }
  }
  half_cycles += 0.5f * (float)k_smp_half_cycles[k_sig[sig].smp & 7u];
  return 0.5f * half_cycles / f_adc;
}

static adc_regs_t *adc_of(uint32_t n) {
  return (n == 1u) ? ADC1 : ADC2;
}

static bool wait_flag(const reg32_t *reg, uint32_t mask, bool set) {
  for (uint32_t t = 0; t < 1000000u; t++) {
    if (((*reg & mask) != 0u) == set) {
      return true;
    }
  }
  return false;
}

static void opamp_init(void) {
#if BOARD_USE_OPAMP_PGA
  /* OPAMP1..3: VINP0 input, PGA mode (VM_SEL = 10), board gain code,
   * high-speed mode, output to the pin (OPAINTOEN = 0) which is also the
   * ADC input; configure first, then enable (RM0440 25.3). */
  RCC->APB2ENR |= RCC_APB2ENR_SYSCFGEN; /* OPAMP registers sit on the SYSCFG clock */
  (void)RCC->APB2ENR;
  const uint32_t csr = /* VP_SEL = 00 */ (2u << OPAMP_CSR_VM_SEL_Pos) |
                       ((uint32_t)BOARD_OPAMP_PGA_GAIN_CODE << OPAMP_CSR_PGA_GAIN_Pos) |
                       OPAMP_CSR_OPAHSM;
  for (uint32_t i = 0; i < 3u; i++) {
    OPAMP->CSR[i] = csr;
    OPAMP->CSR[i] |= OPAMP_CSR_OPAEN;
  }
#endif
}

static bool adc_power_up(adc_regs_t *adc) {
  adc->CR = 0u;                             /* DEEPPWD = 0 */
  adc->CR = ADC_CR_ADVREGEN;                /* regulator on */
  hal_delay_cycles(170u * 25u);             /* t_ADCVREG_STUP = 20 us */
  adc->DIFSEL = 0u;                         /* all single ended */
  adc->CR = ADC_CR_ADVREGEN | ADC_CR_ADCAL; /* ADCALDIF = 0 */
  if (!wait_flag(&adc->CR, ADC_CR_ADCAL, false)) {
    return false;
  }
  hal_delay_cycles(64u); /* >= 4 ADC clocks between ADCAL = 0 and ADEN */
  adc->ISR = ADC_ISR_ADRDY;
  adc->CR = ADC_CR_ADVREGEN | ADC_CR_ADEN;
  return wait_flag(&adc->ISR, ADC_ISR_ADRDY, true);
}

bool hal_adc_init(void) {
  s_t_i = adc_sample_instant();
  s_t_star = adc_signal_instant(SIG_VSTAR);
  opamp_init();
  for (uint32_t i = 0; i < BOARD_ADC_NPINS; i++) {
    hal_gpio_analog(k_adc_pins[i].port, k_adc_pins[i].pin);
  }

  RCC->CCIPR = (RCC->CCIPR & ~RCC_CCIPR_ADC12SEL_Msk) |
               (RCC_CCIPR_ADC12SEL_SYSCLK << RCC_CCIPR_ADC12SEL_Pos);
  RCC->AHB2ENR |= RCC_AHB2ENR_ADC12EN;
  (void)RCC->AHB2ENR;
  ADC12_COMMON->CCR = 3u << ADC_CCR_CKMODE_Pos; /* independent mode, HCLK/4 */

  if (!adc_power_up(ADC1) || !adc_power_up(ADC2)) {
    return false;
  }

  uint32_t jsqr[2] = {0u, 0u};
  uint32_t len[2] = {0u, 0u};
  for (uint32_t s = 0; s < SIG_COUNT; s++) {
    const adc_signal_t *sig = &k_sig[s];
    if (sig->adc == 0u) {
      s_jdr[s] = 0;
      continue;
    }
    const uint32_t a = sig->adc - 1u;
    adc_regs_t *adc = adc_of(sig->adc);
    const uint32_t rank = len[a]++;
    jsqr[a] |= (uint32_t)sig->channel << ADC_JSQR_JSQ_Pos(rank);
    if (sig->channel < 10u) {
      const uint32_t sh = 3u * sig->channel;
      adc->SMPR1 = (adc->SMPR1 & ~(7u << sh)) | ((uint32_t)sig->smp << sh);
    } else {
      const uint32_t sh = 3u * (sig->channel - 10u);
      adc->SMPR2 = (adc->SMPR2 & ~(7u << sh)) | ((uint32_t)sig->smp << sh);
    }
    s_jdr[s] = &adc->JDR[rank];
  }
  for (uint32_t a = 0; a < 2u; a++) {
    adc_regs_t *adc = adc_of(a + 1u);
    adc->CFGR = ADC_CFGR_JQDIS; /* 12 bit, right aligned, injected queue off */
    if (len[a] == 0u) {
      continue;
    }
    /* JEXTSEL = 0 (left at 0): TIM1_TRGO; JEXTEN = 01: rising edge; JL = length - 1 */
    adc->JSQR = jsqr[a] | (1u << ADC_JSQR_JEXTEN_Pos) | ((len[a] - 1u) << ADC_JSQR_JL_Pos);
  }
#if BOARD_HAS_STAR_WINDOW
  star_window_adc_init(); /* the after-sample: the star channel on TRGO2 */
#endif
  return len[0] + len[1] != 0u; /* the period interrupt needs a sequence */
}

bool hal_adc_start(hal_control_fn control) {
  if (control == 0) {
    return false;
  }
  s_isr.control = control;
  s_isr.ends = 0u;
  s_isr.ends_needed = 0u;
  ADC1->ISR = ADC_ISR_JEOC | ADC_ISR_JEOS | ADC_ISR_JQOVF;
  ADC2->ISR = ADC_ISR_JEOC | ADC_ISR_JEOS | ADC_ISR_JQOVF;
  ADC1->IER = 0u;
  ADC2->IER = 0u;
  /* every ADC with an injected sequence (JEXTEN set by hal_adc_init) ends
   * the period with its JEOS interrupt; the period runs at the last end */
  for (uint32_t a = 0; a < 2u; a++) {
    adc_regs_t *adc = adc_of(a + 1u);
    if ((adc->JSQR & (3u << ADC_JSQR_JEXTEN_Pos)) != 0u) {
      s_isr.ends_needed |= 1u << a;
      adc->IER = ADC_IER_JEOSIE;
      adc->CR |= ADC_CR_JADSTART;
    }
  }
  if (s_isr.ends_needed == 0u) {
    return false;
  }
#if BOARD_HAS_STAR_WINDOW
  star_window_adc_start();
#endif
  NVIC->IPR[IRQN_ADC1_2] = (uint8_t)(0u << (8u - NVIC_PRIO_BITS)); /* highest */
  NVIC->ICPR[IRQN_ADC1_2 / 32u] = 1u << (IRQN_ADC1_2 % 32u);
  NVIC->ISER[IRQN_ADC1_2 / 32u] = 1u << (IRQN_ADC1_2 % 32u);
  return true;
}

/* ---- hal.h ---- */

HOT static float raw_volts(const reg32_t *jdr) {
  return (float)(*jdr & 0xFFFFu) * (BOARD_VDDA / 4095.0f);
}

HOT void hal_adc_read(hal_sample_t *s) {
  float i[3];
  int missing = -1;
  float sum = 0.0f;
  for (int k = 0; k < 3; k++) {
    if (s_jdr[k] != 0) {
      i[k] = (raw_volts(s_jdr[k]) - BOARD_I_MID_V) * BOARD_I_A_PER_V;
      sum += i[k];
    } else {
      i[k] = 0.0f;
      missing = k;
    }
  }
  if (missing >= 0) {
    i[missing] = -sum; /* two-shunt boards: Kirchhoff */
  }
  s->i_abc[0] = i[0];
  s->i_abc[1] = i[1];
  s->i_abc[2] = i[2];
  s->v_dc = (s_jdr[SIG_VDC] != 0) ? raw_volts(s_jdr[SIG_VDC]) * BOARD_VDC_RATIO : 0.0f;
  s->t_i = s_t_i;
  /* star point measured to ground; hal.h wants it w.r.t. the DC midpoint */
  const float v_star = (s_jdr[SIG_VSTAR] != 0)
                           ? raw_volts(s_jdr[SIG_VSTAR]) * BOARD_VSTAR_RATIO - 0.5f * s->v_dc
                           : 0.0f;
#if BOARD_HAS_STAR_WINDOW
  /* the window of the last period: its before- and after-samples */
  star_window_read(s, v_star, s_t_star);
#else
  /* sampled with the currents */
  s->n_star = (s_jdr[SIG_VSTAR] != 0) ? 1u : 0u;
  s->v_star[0] = v_star;
  s->t_star[0] = s_t_star;
  s->v_star[1] = 0.0f;
  s->t_star[1] = 0.0f;
  s->test_vector = 0u;
#endif
  s->enc_angle = 0.0f; /* no encoder interface on these boards yet */
  s->t_enc = 0.0f;
  s->enc_valid = false;
  /* the period runs only once every injected sequence has ended
   * (ADC1_2_IRQHandler): every data register holds this period's sample */
  s->valid = true;
}

/* The PWM-period interrupt: the end of an injected sequence (JEOS) of
 * ADC1 or ADC2, which share this line. Each entry takes the JEOS flags it
 * sees (write 1 to clear only those: an end after the read stays pending
 * and re-enters) and notes them; the period runs when every ADC in use has
 * ended since the last one, i.e. on the second entry of a normal period
 * (or the first, when both ended before it). The first entry costs the
 * exception and a few register accesses: no wait for the other ADC. An
 * ADC that never ends (faulty or misconfigured) stops the periods, and
 * with them the watchdog refresh (drive_background: only when the ISR
 * advanced): the IWDG resets the MCU with the gates off. */
void ADC1_2_IRQHandler(void);
HOT void ADC1_2_IRQHandler(void) {
  const uint32_t t0 = DWT->CYCCNT;
  const uint32_t f1 = ADC1->ISR & ADC_ISR_JEOS;
  const uint32_t f2 = ADC2->ISR & ADC_ISR_JEOS;
  ADC1->ISR = f1;
  ADC2->ISR = f2;
  const uint32_t ends = s_isr.ends | (f1 >> 6) | (f2 >> 5); /* JEOS is bit 6: END_ADC1, END_ADC2 */
  if ((ends & s_isr.ends_needed) != s_isr.ends_needed) {
    s_isr.ends = ends; /* the first end of this period: the other one comes */
    return;
  }
  s_isr.ends = 0u;
  hal_tim1_clear_update(); /* set at this period's valley */

  s_isr.control();

  /* Overrun: the next valley (update) came before the ISR finished. */
  if (hal_tim1_update_pending()) {
    s_isr.overruns++;
  }
  s_isr.isr_count++;
  const uint32_t dt = DWT->CYCCNT - t0;
  s_isr.cycles_last = dt;
  if (dt > s_isr.cycles_max) {
    s_isr.cycles_max = dt;
  }
  s_isr.cycles_acc += dt - (s_isr.cycles_acc >> 8);
}

void hal_isr_stats(hal_isr_stats_t *st) {
  const uint32_t pm = hal_irq_save();
  st->cycles_last = s_isr.cycles_last;
  st->cycles_max = s_isr.cycles_max;
  st->cycles_mean = s_isr.cycles_acc >> 8;
  st->overruns = s_isr.overruns;
  hal_irq_restore(pm);
}

/* One aligned word: read whole, also from the ISR (which adds to it only
 * after the drive's code returned). */
uint32_t hal_isr_overruns(void) {
  return s_isr.overruns;
}

/* What the board can do (hal.h), fixed by its header and the ADC set-up. */
const hal_caps_t *hal_caps(void) {
  static hal_caps_t caps;
  static bool done;
  if (!done) {
    const float ts = (float)(2u * BOARD_PWM_ARR) / (float)BOARD_SYSCLK_HZ;
    caps.ts = ts;
    caps.t_count = ts / (float)BOARD_PWM_ARR;
    caps.dead_time = (float)BOARD_DEAD_TIME_NS * 1e-9f;
    caps.duty_min = 0.0f;
    caps.duty_max = BOARD_DUTY_MAX;
    caps.t_i = adc_sample_instant();
    caps.t_i_clear = (1.0f - BOARD_DUTY_MAX) * ts; /* low sides on around the valley */
    caps.t_enc = 0.0f;
    caps.cpu_hz = (float)BOARD_SYSCLK_HZ;
    /* the ADC's ranges through the board's amplifiers: the current either
     * side of the mid-point, the link from 0 */
    const float i_span =
        BOARD_I_MID_V < BOARD_VDDA - BOARD_I_MID_V ? BOARD_I_MID_V : BOARD_VDDA - BOARD_I_MID_V;
    caps.i_full_scale = i_span * (BOARD_I_A_PER_V < 0.0f ? -BOARD_I_A_PER_V : BOARD_I_A_PER_V);
    caps.v_full_scale = BOARD_VDDA * BOARD_VDC_RATIO;
    /* one 12-bit step of VDDA through the amplifier (the full scale above is
     * the shorter side of the mid-point, not half the span) */
    caps.i_lsb =
        BOARD_VDDA / 4096.0f * (BOARD_I_A_PER_V < 0.0f ? -BOARD_I_A_PER_V : BOARD_I_A_PER_V);
#if BOARD_HAS_STAR_WINDOW
    /* the DFC window: independent edges, two star-point samples */
    caps.features = HAL_CAP_DWT_CYCLES | HAL_CAP_ASYM_EDGES | HAL_CAP_STAR_POINT;
#else
    caps.features = HAL_CAP_DWT_CYCLES; /* centred pulses, no encoder, star point at the valley */
#endif
    if (k_sig[SIG_IA].adc != 0u && k_sig[SIG_IB].adc != 0u && k_sig[SIG_IC].adc != 0u) {
      caps.features |= HAL_CAP_I_ABC; /* three shunts: none reconstructed */
    }
    done = true;
  }
  return &caps;
}

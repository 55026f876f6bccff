/*
 * stm32g4_regs.h - the STM32G4 registers fluxdrive uses, written from the
 * reference manual RM0440 (Rev 8) and, for the Cortex-M4 core peripherals,
 * the programming manual PM0214. Only what the HAL touches; names follow the
 * manuals. Every struct's layout is checked against the manual's offsets by
 * the _Static_asserts at the end of the file.
 */
#ifndef FLUXDRIVE_STM32G4_REGS_H
#define FLUXDRIVE_STM32G4_REGS_H

#include <stddef.h>
#include <stdint.h>

typedef volatile uint32_t reg32_t;

/* ---- RCC: RM0440 section 7.4 (reset and clock control registers) ---- */
typedef struct {
  reg32_t CR;        /* 0x00 */
  reg32_t ICSCR;     /* 0x04 */
  reg32_t CFGR;      /* 0x08 */
  reg32_t PLLCFGR;   /* 0x0C */
  reg32_t RES0[2];   /* 0x10 */
  reg32_t CIER;      /* 0x18 */
  reg32_t CIFR;      /* 0x1C */
  reg32_t CICR;      /* 0x20 */
  reg32_t RES1;      /* 0x24 */
  reg32_t AHB1RSTR;  /* 0x28 */
  reg32_t AHB2RSTR;  /* 0x2C */
  reg32_t AHB3RSTR;  /* 0x30 */
  reg32_t RES2;      /* 0x34 */
  reg32_t APB1RSTR1; /* 0x38 */
  reg32_t APB1RSTR2; /* 0x3C */
  reg32_t APB2RSTR;  /* 0x40 */
  reg32_t RES3;      /* 0x44 */
  reg32_t AHB1ENR;   /* 0x48 */
  reg32_t AHB2ENR;   /* 0x4C */
  reg32_t AHB3ENR;   /* 0x50 */
  reg32_t RES4;      /* 0x54 */
  reg32_t APB1ENR1;  /* 0x58 */
  reg32_t APB1ENR2;  /* 0x5C */
  reg32_t APB2ENR;   /* 0x60 */
  reg32_t RES5[9];   /* 0x64 .. 0x84: sleep-mode enables, unused */
  reg32_t CCIPR;     /* 0x88 */
  reg32_t RES6;      /* 0x8C */
  reg32_t BDCR;      /* 0x90 */
  reg32_t CSR;       /* 0x94 */
} rcc_regs_t;
#define RCC ((rcc_regs_t *)0x40021000u)

#define RCC_CR_HSION              (1u << 8)
#define RCC_CR_HSIRDY             (1u << 10)
#define RCC_CR_HSEON              (1u << 16)
#define RCC_CR_HSERDY             (1u << 17)
#define RCC_CR_PLLON              (1u << 24)
#define RCC_CR_PLLRDY             (1u << 25)
#define RCC_CFGR_SW_Pos           0u
#define RCC_CFGR_SW_Msk           (3u << 0)
#define RCC_CFGR_SW_PLL           3u
#define RCC_CFGR_SWS_Pos          2u
#define RCC_CFGR_SWS_Msk          (3u << 2)
#define RCC_CFGR_HPRE_Pos         4u
#define RCC_CFGR_HPRE_Msk         (0xFu << 4)
#define RCC_CFGR_HPRE_DIV1        0u
#define RCC_CFGR_HPRE_DIV2        8u
#define RCC_CFGR_PPRE1_Msk        (7u << 8)
#define RCC_CFGR_PPRE2_Msk        (7u << 11)
#define RCC_PLLCFGR_SRC_HSI       2u
#define RCC_PLLCFGR_SRC_HSE       3u
#define RCC_PLLCFGR_M_Pos         4u /* M = PLLM + 1 */
#define RCC_PLLCFGR_N_Pos         8u /* N = PLLN, 8..127 */
#define RCC_PLLCFGR_PLLREN        (1u << 24)
#define RCC_PLLCFGR_R_Pos         25u /* 00: /2 */
#define RCC_AHB1ENR_CORDICEN      (1u << 3)
#define RCC_AHB2ENR_GPIOAEN       (1u << 0) /* GPIOx = bit x */
#define RCC_AHB2ENR_ADC12EN       (1u << 13)
#define RCC_APB1ENR1_TIM2EN       (1u << 0)
#define RCC_APB1ENR1_FDCANEN      (1u << 25)
#define RCC_APB1ENR1_PWREN        (1u << 28)
#define RCC_APB2ENR_SYSCFGEN      (1u << 0)
#define RCC_APB2ENR_TIM1EN        (1u << 11)
#define RCC_CCIPR_FDCANSEL_Pos    24u /* 00 HSE, 01 PLLQ, 10 PCLK1 */
#define RCC_CCIPR_FDCANSEL_Msk    (3u << 24)
#define RCC_CCIPR_FDCANSEL_PCLK1  2u
#define RCC_CCIPR_ADC12SEL_Pos    28u /* 00 none, 01 PLLP, 10 SYSCLK */
#define RCC_CCIPR_ADC12SEL_Msk    (3u << 28)
#define RCC_CCIPR_ADC12SEL_SYSCLK 2u

/* ---- FLASH: RM0440 section 3.7.1 (FLASH_ACR) ---- */
typedef struct {
  reg32_t ACR; /* 0x00 */
} flash_regs_t;
#define FLASH                 ((flash_regs_t *)0x40022000u)
#define FLASH_ACR_LATENCY_Msk 0xFu
#define FLASH_ACR_PRFTEN      (1u << 8)
#define FLASH_ACR_ICEN        (1u << 9)
#define FLASH_ACR_DCEN        (1u << 10)

/* ---- PWR: RM0440 section 6.4 (PWR_CR1 VOS, PWR_CR5 R1MODE) ---- */
typedef struct {
  reg32_t CR1;      /* 0x00 */
  reg32_t CR2;      /* 0x04 */
  reg32_t CR3;      /* 0x08 */
  reg32_t CR4;      /* 0x0C */
  reg32_t SR1;      /* 0x10 */
  reg32_t SR2;      /* 0x14 */
  reg32_t RES0[26]; /* 0x18 .. 0x7C */
  reg32_t CR5;      /* 0x80 */
} pwr_regs_t;
#define PWR            ((pwr_regs_t *)0x40007000u)
#define PWR_CR5_R1MODE (1u << 8) /* 0: range 1 boost mode */
#define PWR_SR2_VOSF   (1u << 10)

/* ---- GPIO: RM0440 section 9.4 ---- */
typedef struct {
  reg32_t MODER;   /* 0x00 */
  reg32_t OTYPER;  /* 0x04 */
  reg32_t OSPEEDR; /* 0x08 */
  reg32_t PUPDR;   /* 0x0C */
  reg32_t IDR;     /* 0x10 */
  reg32_t ODR;     /* 0x14 */
  reg32_t BSRR;    /* 0x18 */
  reg32_t LCKR;    /* 0x1C */
  reg32_t AFR[2];  /* 0x20, 0x24 */
  reg32_t BRR;     /* 0x28 */
} gpio_regs_t;
#define GPIO_BASE(port)  ((gpio_regs_t *)(0x48000000u + 0x400u * (uint32_t)(port)))
#define GPIO_MODE_INPUT  0u
#define GPIO_MODE_OUTPUT 1u
#define GPIO_MODE_AF     2u
#define GPIO_MODE_ANALOG 3u

/* ---- TIM1 (advanced control) RM0440 section 28.6; TIM2 (general
 * purpose, same offsets up to ARR) RM0440 section 29.5 ---- */
typedef struct {
  reg32_t CR1;   /* 0x00 */
  reg32_t CR2;   /* 0x04 */
  reg32_t SMCR;  /* 0x08 */
  reg32_t DIER;  /* 0x0C */
  reg32_t SR;    /* 0x10 */
  reg32_t EGR;   /* 0x14 */
  reg32_t CCMR1; /* 0x18 */
  reg32_t CCMR2; /* 0x1C */
  reg32_t CCER;  /* 0x20 */
  reg32_t CNT;   /* 0x24 */
  reg32_t PSC;   /* 0x28 */
  reg32_t ARR;   /* 0x2C */
  reg32_t RCR;   /* 0x30 (TIM1 only) */
  reg32_t CCR1;  /* 0x34 */
  reg32_t CCR2;  /* 0x38 */
  reg32_t CCR3;  /* 0x3C */
  reg32_t CCR4;  /* 0x40 */
  reg32_t BDTR;  /* 0x44 (TIM1 only) */
  reg32_t CCR5;  /* 0x48 */
  reg32_t CCR6;  /* 0x4C */
  reg32_t CCMR3; /* 0x50 */
  reg32_t DTR2;  /* 0x54 */
  reg32_t ECR;   /* 0x58 */
  reg32_t TISEL; /* 0x5C */
  reg32_t AF1;   /* 0x60 */
  reg32_t AF2;   /* 0x64 */
  reg32_t RES_DMA[221];
  reg32_t DCR;  /* 0x3DC */
  reg32_t DMAR; /* 0x3E0 */
} tim_regs_t;
#define TIM1 ((tim_regs_t *)0x40012C00u)
#define TIM2 ((tim_regs_t *)0x40000000u)

#define TIM_CR1_CEN         (1u << 0)
#define TIM_CR1_DIR         (1u << 4)
#define TIM_CR1_CMS_Pos     5u
#define TIM_CR1_ARPE        (1u << 7)
#define TIM_CR2_MMS_Pos     4u
#define TIM_CR2_MMS_UPDATE  2u
#define TIM_SR_UIF          (1u << 0)
#define TIM_SR_BIF          (1u << 7)
#define TIM_SR_B2IF         (1u << 8)
#define TIM_SR_SBIF         (1u << 13)
#define TIM_EGR_UG          (1u << 0)
#define TIM_SR_CC4IF        (1u << 4)
#define TIM_DIER_UDE        (1u << 8)
#define TIM_CR2_MMS_OC4REF  7u  /* TRGO = OC4REF */
#define TIM_CR2_MMS2_Pos    20u /* 1000: TRGO2 = OC5REF */
#define TIM_CR2_MMS2_OC5REF 8u
#define TIM_CCMR_OC4PE      (1u << 11) /* in CCMR2 */
#define TIM_CCMR_OC4M_Pos   12u
#define TIM_CCMR3_OC5PE     (1u << 3)
#define TIM_CCMR3_OC5M_Pos  4u
#define TIM_DCR_DBA_Pos     0u /* DMA base: register index from CR1 */
#define TIM_DCR_DBL_Pos     8u /* burst length - 1 */
#define TIM_CCMR_OC1PE      (1u << 3)
#define TIM_CCMR_OC1M_Pos   4u /* OC1M[2:0]; OC1M[3] is bit 16 */
#define TIM_CCMR_OC2PE      (1u << 11)
#define TIM_CCMR_OC2M_Pos   12u /* OC2M[2:0]; OC2M[3] is bit 24 */
#define TIM_OCM_PWM2        7u
#define TIM_OCM_FORCE_LOW   4u /* OCxREF forced low (inactive) */
#define TIM_CCER_CC1E       (1u << 0)
#define TIM_CCER_CC1P       (1u << 1)
#define TIM_CCER_CC1NE      (1u << 2)
#define TIM_CCER_CC1NP      (1u << 3) /* channel n: shift by 4*(n-1) */
#define TIM_BDTR_DTG_Msk    0xFFu
#define TIM_BDTR_LOCK_Pos   8u
#define TIM_BDTR_OSSI       (1u << 10)
#define TIM_BDTR_OSSR       (1u << 11)
#define TIM_BDTR_BKE        (1u << 12)
#define TIM_BDTR_BKP        (1u << 13)
#define TIM_BDTR_AOE        (1u << 14)
#define TIM_BDTR_MOE        (1u << 15)
#define TIM_BDTR_BKF_Pos    16u
#define TIM_BDTR_BKF_Msk    (0xFu << 16)
#define TIM_BDTR_BKDSRM     (1u << 26)
#define TIM_BDTR_BKBID      (1u << 28)
#define TIM1_AF1_BKINE      (1u << 0)             /* BKIN pin enable (reset value 1) */
#define TIM1_AF1_BKCMP1E    (1u << 1)             /* COMPx output to break: bit x */
#define TIM1_AF1_BKCMPE(x)  (1u << (uint32_t)(x)) /* x = 1..7 */
#define TIM_BDTR_BK2F_Pos   20u
#define TIM_BDTR_BK2E       (1u << 24)
#define TIM_BDTR_BK2P       (1u << 25)
#define TIM1_AF2_BK2INE     (1u << 0) /* BKIN2 pin enable (reset value 1) */
#define TIM1_AF1_BKINE      (1u << 0) /* BKIN pin enable (reset value 1) */
#define TIM1_AF1_BKCMP1E    (1u << 1) /* COMPx output to break: bit x */
#define TIM1_AF1_BKINP      (1u << 9)
#define TIM1_AF1_BKCMPP(x)  (1u << (9u + (uint32_t)(x))) /* x = 1..4: polarity */

/* ---- ADC: RM0440 section 21.7 (ADC1/ADC2 registers) and 21.8 (common
 * registers of ADC1/ADC2 at ADC12 base + 0x300) ---- */
typedef struct {
  reg32_t ISR;     /* 0x00 */
  reg32_t IER;     /* 0x04 */
  reg32_t CR;      /* 0x08 */
  reg32_t CFGR;    /* 0x0C */
  reg32_t CFGR2;   /* 0x10 */
  reg32_t SMPR1;   /* 0x14 */
  reg32_t SMPR2;   /* 0x18 */
  reg32_t RES0;    /* 0x1C */
  reg32_t TR1;     /* 0x20 */
  reg32_t TR2;     /* 0x24 */
  reg32_t TR3;     /* 0x28 */
  reg32_t RES1;    /* 0x2C */
  reg32_t SQR1;    /* 0x30 */
  reg32_t SQR2;    /* 0x34 */
  reg32_t SQR3;    /* 0x38 */
  reg32_t SQR4;    /* 0x3C */
  reg32_t DR;      /* 0x40 */
  reg32_t RES2[2]; /* 0x44 */
  reg32_t JSQR;    /* 0x4C */
  reg32_t RES3[4]; /* 0x50 */
  reg32_t OFR[4];  /* 0x60 */
  reg32_t RES4[4]; /* 0x70 */
  reg32_t JDR[4];  /* 0x80 */
  reg32_t RES5[4]; /* 0x90 */
  reg32_t AWD2CR;  /* 0xA0 */
  reg32_t AWD3CR;  /* 0xA4 */
  reg32_t RES6[2]; /* 0xA8 */
  reg32_t DIFSEL;  /* 0xB0 */
  reg32_t CALFACT; /* 0xB4 */
} adc_regs_t;
typedef struct {
  reg32_t CSR; /* 0x00 */
  reg32_t RES0;
  reg32_t CCR; /* 0x08 */
  reg32_t CDR; /* 0x0C */
} adc_common_regs_t;
#define ADC1         ((adc_regs_t *)0x50000000u)
#define ADC2         ((adc_regs_t *)0x50000100u)
#define ADC12_COMMON ((adc_common_regs_t *)0x50000300u)

#define ADC_ISR_ADRDY       (1u << 0)
#define ADC_ISR_JEOC        (1u << 5)
#define ADC_ISR_JEOS        (1u << 6)
#define ADC_ISR_JQOVF       (1u << 10)
#define ADC_IER_JEOSIE      (1u << 6)
#define ADC_CR_ADEN         (1u << 0)
#define ADC_CR_ADDIS        (1u << 1)
#define ADC_CR_JADSTART     (1u << 3)
#define ADC_CR_ADVREGEN     (1u << 28)
#define ADC_CR_DEEPPWD      (1u << 29)
#define ADC_CR_ADCALDIF     (1u << 30)
#define ADC_CR_ADCAL        (1u << 31)
#define ADC_CFGR_JQDIS      (1u << 31)
#define ADC_CFGR_EXTSEL_Pos 5u  /* ADC12 regular: 10 = TIM1_TRGO2 (RM0440 21.4.18) */
#define ADC_CFGR_EXTEN_Pos  10u /* 01: rising edge */
#define ADC_CFGR_OVRMOD     (1u << 12)
#define ADC_CR_ADSTART      (1u << 2)
#define ADC_SQR1_SQ1_Pos    6u
#define ADC_JSQR_JL_Pos     0u
#define ADC_JSQR_JEXTSEL_Pos                                                                       \
  2u /* ADC12 JEXT0 = TIM1_TRGO (RM0440 21.4.x, ADC1/2 injected trigger table) */
#define ADC_JSQR_JEXTEN_Pos    7u                           /* 01: rising edge */
#define ADC_JSQR_JSQ_Pos(rank) (9u + 6u * (uint32_t)(rank)) /* rank 0..3 */
#define ADC_CCR_CKMODE_Pos     16u                          /* 11: adc_hclk / 4, synchronous */
#define ADC_SMP_2_5            0u
#define ADC_SMP_6_5            1u
#define ADC_SMP_12_5           2u
#define ADC_SMP_24_5           3u
#define ADC_SMP_47_5           4u
#define ADC_SMP_92_5           5u
#define ADC_SMP_247_5          6u
#define ADC_SMP_640_5          7u

/* ---- DMA1 (RM0440 section 12) and DMAMUX (section 13): DMA1 channel 1
 * is DMAMUX1 channel 0 ---- */
typedef struct {
  reg32_t CCR;   /* 0x08 + 0x14 (x - 1) */
  reg32_t CNDTR; /* 0x0C */
  reg32_t CPAR;  /* 0x10 */
  reg32_t CMAR;  /* 0x14 */
  reg32_t RES;
} dma_channel_regs_t;
typedef struct {
  reg32_t ISR;  /* 0x00 */
  reg32_t IFCR; /* 0x04 */
  dma_channel_regs_t CH[8];
} dma_regs_t;
#define DMA1                  ((dma_regs_t *)0x40020000u)
#define DMAMUX1_C0CR          (*(reg32_t *)0x40020800u)
#define DMA_CCR_EN            (1u << 0)
#define DMA_CCR_DIR           (1u << 4) /* read from memory */
#define DMA_CCR_CIRC          (1u << 5)
#define DMA_CCR_MINC          (1u << 7)
#define DMA_CCR_PSIZE_32      (2u << 8)
#define DMA_CCR_MSIZE_32      (2u << 10)
#define DMA_CCR_PL_VHIGH      (3u << 12)
#define DMAMUX_REQ_TIM1_UP    46u /* RM0440 table 91 */
#define RCC_AHB1ENR_DMA1EN    (1u << 0)
#define RCC_AHB1ENR_DMAMUX1EN (1u << 2)

/* ---- OPAMP: RM0440 section 25.5 (OPAMPx_CSR) ---- */
typedef struct {
  reg32_t CSR[6]; /* 0x00 OPAMP1 .. 0x14 OPAMP6 */
} opamp_regs_t;
#define OPAMP                  ((opamp_regs_t *)0x40010300u)
#define OPAMP_CSR_OPAEN        (1u << 0)
#define OPAMP_CSR_VP_SEL_Pos   2u
#define OPAMP_CSR_VM_SEL_Pos   5u /* 10: PGA mode */
#define OPAMP_CSR_OPAHSM       (1u << 7)
#define OPAMP_CSR_OPAINTOEN    (1u << 8)
#define OPAMP_CSR_PGA_GAIN_Pos 14u

/* ---- COMP: RM0440 section 24.6 (COMPx_CSR, one word per comparator) ---- */
typedef struct {
  reg32_t CSR[7]; /* 0x00 COMP1 .. 0x18 COMP7 (COMP1..4 on the STM32G431) */
} comp_regs_t;
#define COMP                ((comp_regs_t *)0x40010200u)
#define COMP_CSR_EN         (1u << 0)
#define COMP_CSR_INMSEL_Pos 4u /* 100: DAC3_CH1 (COMP1, 3), DAC3_CH2 (COMP2, 4) */
#define COMP_INMSEL_DAC3    4u
#define COMP_CSR_INPSEL     (1u << 8) /* 0: INP IO1 (PA1, PA7, PA0, PB0 for COMP1..4) */
#define COMP_CSR_POLARITY   (1u << 15)
#define COMP_CSR_HYST_Pos   16u /* 000: none .. 111: 70 mV, 10 mV steps */
#define COMP_CSR_BLANK_Pos  19u /* 000: no blanking */
#define COMP_CSR_BRGEN      (1u << 22)
#define COMP_CSR_SCALEN     (1u << 23)
#define COMP_CSR_VALUE      (1u << 30)
#define COMP_CSR_LOCK       (1u << 31)

/* ---- DAC3 (internal channels only): RM0440 section 22.7 ---- */
typedef struct {
  reg32_t CR;      /* 0x00 */
  reg32_t SWTRIGR; /* 0x04 */
  reg32_t DHR12R1; /* 0x08 */
  reg32_t DHR12L1; /* 0x0C */
  reg32_t DHR8R1;  /* 0x10 */
  reg32_t DHR12R2; /* 0x14 */
  reg32_t DHR12L2; /* 0x18 */
  reg32_t DHR8R2;  /* 0x1C */
  reg32_t DHR12RD; /* 0x20 */
  reg32_t DHR12LD; /* 0x24 */
  reg32_t DHR8RD;  /* 0x28 */
  reg32_t DOR1;    /* 0x2C */
  reg32_t DOR2;    /* 0x30 */
  reg32_t SR;      /* 0x34 */
  reg32_t CCR;     /* 0x38 */
  reg32_t MCR;     /* 0x3C */
} dac_regs_t;
#define DAC3               ((dac_regs_t *)0x50001000u)
#define DAC_CR_EN1         (1u << 0)
#define DAC_CR_EN2         (1u << 16)
#define DAC_SR_DAC1RDY     (1u << 11)
#define DAC_SR_DAC2RDY     (1u << 27)
#define DAC_MCR_MODE2_Pos  16u /* MODE1 at bit 0 */
#define DAC_MODE_INTERNAL  3u  /* 011: normal mode, on-chip peripherals only, no buffer */
#define DAC_MCR_HFSEL_Pos  14u
#define DAC_HFSEL_160MHZ   2u /* 10: AHB clock above 160 MHz */
#define RCC_AHB2ENR_DAC3EN (1u << 18)

/* ---- FDCAN1: RM0440 section 44.4 (registers), 44.3.3 (message RAM) ---- */
typedef struct {
  reg32_t CREL;    /* 0x00 */
  reg32_t ENDN;    /* 0x04 */
  reg32_t RES0;    /* 0x08 */
  reg32_t DBTP;    /* 0x0C */
  reg32_t TEST;    /* 0x10 */
  reg32_t RWD;     /* 0x14 */
  reg32_t CCCR;    /* 0x18 */
  reg32_t NBTP;    /* 0x1C */
  reg32_t TSCC;    /* 0x20 */
  reg32_t TSCV;    /* 0x24 */
  reg32_t TOCC;    /* 0x28 */
  reg32_t TOCV;    /* 0x2C */
  reg32_t RES1[4]; /* 0x30 */
  reg32_t ECR;     /* 0x40 */
  reg32_t PSR;     /* 0x44 */
  reg32_t TDCR;    /* 0x48 */
  reg32_t RES2;    /* 0x4C */
  reg32_t IR;      /* 0x50 */
  reg32_t IE;      /* 0x54 */
  reg32_t ILS;     /* 0x58 */
  reg32_t ILE;     /* 0x5C */
  reg32_t RES3[8]; /* 0x60 */
  reg32_t RXGFC;   /* 0x80 */
  reg32_t XIDAM;   /* 0x84 */
  reg32_t HPMS;    /* 0x88 */
  reg32_t RES4;    /* 0x8C */
  reg32_t RXF0S;   /* 0x90 */
  reg32_t RXF0A;   /* 0x94 */
  reg32_t RXF1S;   /* 0x98 */
  reg32_t RXF1A;   /* 0x9C */
  reg32_t RES5[8]; /* 0xA0 */
  reg32_t TXBC;    /* 0xC0 */
  reg32_t TXFQS;   /* 0xC4 */
  reg32_t TXBRP;   /* 0xC8 */
  reg32_t TXBAR;   /* 0xCC */
  reg32_t TXBCR;   /* 0xD0 */
  reg32_t TXBTO;   /* 0xD4 */
  reg32_t TXBCF;   /* 0xD8 */
  reg32_t TXBTIE;  /* 0xDC */
  reg32_t TXBCIE;  /* 0xE0 */
  reg32_t TXEFS;   /* 0xE4 */
  reg32_t TXEFA;   /* 0xE8 */
} fdcan_regs_t;
#define FDCAN1 ((fdcan_regs_t *)0x40006400u)
/* Message RAM (SRAMCAN), fixed layout per instance, RM0440 44.3.3 */
#define SRAMCAN_BASE          0x4000A400u
#define SRAMCAN_FLSSA         0x000u /* 28 standard filters x 1 word */
#define SRAMCAN_FLESA         0x070u /* 8 extended filters x 2 words */
#define SRAMCAN_RF0SA         0x0B0u /* Rx FIFO 0: 3 x 18 words */
#define SRAMCAN_RF1SA         0x188u /* Rx FIFO 1: 3 x 18 words */
#define SRAMCAN_TEFSA         0x260u /* Tx event FIFO: 3 x 2 words */
#define SRAMCAN_TFQSA         0x278u /* Tx FIFO/queue: 3 x 18 words */
#define SRAMCAN_SIZE          0x350u
#define SRAMCAN_ELEM_SIZE     72u /* 18 words */
#define FDCAN_CCCR_INIT       (1u << 0)
#define FDCAN_CCCR_CCE        (1u << 1)
#define FDCAN_CCCR_DAR        (1u << 6)
#define FDCAN_CCCR_FDOE       (1u << 8)
#define FDCAN_CCCR_BRSE       (1u << 9)
#define FDCAN_RXGFC_RRFE      (1u << 0)
#define FDCAN_RXGFC_RRFS      (1u << 1)
#define FDCAN_RXGFC_ANFE_Pos  2u /* 10: reject */
#define FDCAN_RXGFC_ANFS_Pos  4u
#define FDCAN_RXGFC_LSS_Pos   16u
#define FDCAN_RXGFC_LSE_Pos   24u
#define FDCAN_TXBC_TFQM       (1u << 24)
#define FDCAN_TXFQS_TFQPI_Pos 16u
#define FDCAN_TXFQS_TFQF      (1u << 21)
#define FDCAN_RXF0S_F0FL_Msk  0xFu
#define FDCAN_RXF0S_F0GI_Pos  8u
#define FDCAN_PSR_BO          (1u << 7)

/* ---- CORDIC: RM0440 section 17.4 ---- */
typedef struct {
  reg32_t CSR;   /* 0x00 */
  reg32_t WDATA; /* 0x04 */
  reg32_t RDATA; /* 0x08 */
} cordic_regs_t;
#define CORDIC                   ((cordic_regs_t *)0x40020C00u)
#define CORDIC_CSR_FUNC_Pos      0u
#define CORDIC_FUNC_COSINE       0u
#define CORDIC_FUNC_PHASE        2u
#define CORDIC_CSR_PRECISION_Pos 4u
#define CORDIC_CSR_SCALE_Pos     8u
#define CORDIC_CSR_NRES          (1u << 19) /* 1: two results */
#define CORDIC_CSR_NARGS         (1u << 20) /* 1: two arguments */
#define CORDIC_CSR_RESSIZE       (1u << 21) /* 0: q1.31 */
#define CORDIC_CSR_ARGSIZE       (1u << 22) /* 0: q1.31 */
#define CORDIC_CSR_RRDY          (1u << 31)

/* ---- IWDG: RM0440 section 41.4 ---- */
typedef struct {
  reg32_t KR;   /* 0x00 */
  reg32_t PR;   /* 0x04 */
  reg32_t RLR;  /* 0x08 */
  reg32_t SR;   /* 0x0C */
  reg32_t WINR; /* 0x10 */
} iwdg_regs_t;
#define IWDG            ((iwdg_regs_t *)0x40003000u)
#define IWDG_KEY_ENABLE 0xCCCCu
#define IWDG_KEY_RELOAD 0xAAAAu
#define IWDG_KEY_ACCESS 0x5555u

/* ---- DBGMCU: RM0440 section 47.15 ---- */
typedef struct {
  reg32_t IDCODE;   /* 0x00 */
  reg32_t CR;       /* 0x04 */
  reg32_t APB1FZR1; /* 0x08 */
  reg32_t APB1FZR2; /* 0x0C */
  reg32_t APB2FZR;  /* 0x10 */
} dbgmcu_regs_t;
#define DBGMCU                    ((dbgmcu_regs_t *)0xE0042000u)
#define DBGMCU_APB1FZR1_IWDG_STOP (1u << 12)
#define DBGMCU_APB1FZR1_TIM2_STOP (1u << 0)
#define DBGMCU_APB2FZR_TIM1_STOP  (1u << 11)

/* ---- Cortex-M4 core: PM0214 section 4 (SCB 4.4, SysTick 4.5, NVIC 4.3,
 * FPU CPACR 4.6.1) and DWT (ARMv7-M ARM C1.8) ---- */
typedef struct {
  reg32_t CPUID;             /* 0x00 */
  reg32_t ICSR;              /* 0x04 */
  reg32_t VTOR;              /* 0x08 */
  reg32_t AIRCR;             /* 0x0C */
  reg32_t SCR;               /* 0x10 */
  reg32_t CCR;               /* 0x14 */
  volatile uint8_t SHPR[12]; /* 0x18: system handler priorities 4..15 */
  reg32_t SHCSR;             /* 0x24 */
  reg32_t CFSR;              /* 0x28 */
  reg32_t HFSR;              /* 0x2C */
  reg32_t RES0[22];
  reg32_t CPACR; /* 0x88 */
} scb_regs_t;
#define SCB                      ((scb_regs_t *)0xE000ED00u)
#define SCB_CPACR_CP10_CP11_FULL (0xFu << 20)

typedef struct {
  reg32_t CTRL; /* 0x00 */
  reg32_t LOAD; /* 0x04 */
  reg32_t VAL;  /* 0x08 */
  reg32_t CALIB;
} systick_regs_t;
#define SYSTICK                ((systick_regs_t *)0xE000E010u)
#define SYSTICK_CTRL_ENABLE    (1u << 0)
#define SYSTICK_CTRL_TICKINT   (1u << 1)
#define SYSTICK_CTRL_CLKSOURCE (1u << 2)

typedef struct {
  reg32_t ISER[8]; /* 0x000 */
  reg32_t RES0[24];
  reg32_t ICER[8]; /* 0x080 */
  reg32_t RES1[24];
  reg32_t ISPR[8]; /* 0x100 */
  reg32_t RES2[24];
  reg32_t ICPR[8]; /* 0x180 */
  reg32_t RES3[24];
  reg32_t IABR[8]; /* 0x200 */
  reg32_t RES4[56];
  volatile uint8_t IPR[240]; /* 0x300 */
} nvic_regs_t;
#define NVIC           ((nvic_regs_t *)0xE000E100u)
#define NVIC_PRIO_BITS 4u /* STM32G4: 16 priority levels */

typedef struct {
  reg32_t CTRL;   /* 0x00 */
  reg32_t CYCCNT; /* 0x04 */
} dwt_regs_t;
#define DWT                ((dwt_regs_t *)0xE0001000u)
#define DWT_CTRL_CYCCNTENA (1u << 0)
#define DEMCR              (*(reg32_t *)0xE000EDFCu)
#define DEMCR_TRCENA       (1u << 24)

/* STM32G4 interrupt numbers used here: RM0440 section 16.3 (vector table) */
#define IRQN_ADC1_2         18u
#define IRQN_FDCAN1_IT0     21u
#define IRQN_TIM1_BRK_TIM15 24u
#define STM32G4_IRQ_COUNT   102u

/* Layout checks against the manuals' offset tables. */
_Static_assert(offsetof(rcc_regs_t, PLLCFGR) == 0x0Cu, "RCC_PLLCFGR");
_Static_assert(offsetof(rcc_regs_t, AHB1ENR) == 0x48u, "RCC_AHB1ENR");
_Static_assert(offsetof(tim_regs_t, DCR) == 0x3DCu, "TIM_DCR");
_Static_assert(offsetof(tim_regs_t, DMAR) == 0x3E0u, "TIM_DMAR");
_Static_assert(offsetof(dma_regs_t, CH[1]) == 0x1Cu, "DMA_CCR2");
_Static_assert(offsetof(rcc_regs_t, APB1ENR1) == 0x58u, "RCC_APB1ENR1");
_Static_assert(offsetof(rcc_regs_t, APB2ENR) == 0x60u, "RCC_APB2ENR");
_Static_assert(offsetof(rcc_regs_t, CCIPR) == 0x88u, "RCC_CCIPR");
_Static_assert(offsetof(rcc_regs_t, CSR) == 0x94u, "RCC_CSR");
_Static_assert(offsetof(pwr_regs_t, CR5) == 0x80u, "PWR_CR5");
_Static_assert(offsetof(gpio_regs_t, BRR) == 0x28u, "GPIO_BRR");
_Static_assert(offsetof(tim_regs_t, RCR) == 0x30u, "TIM_RCR");
_Static_assert(offsetof(tim_regs_t, BDTR) == 0x44u, "TIM_BDTR");
_Static_assert(offsetof(tim_regs_t, AF1) == 0x60u, "TIM_AF1");
_Static_assert(offsetof(dac_regs_t, DHR12R2) == 0x14u, "DAC_DHR12R2");
_Static_assert(offsetof(dac_regs_t, SR) == 0x34u, "DAC_SR");
_Static_assert(offsetof(dac_regs_t, MCR) == 0x3Cu, "DAC_MCR");
_Static_assert(offsetof(comp_regs_t, CSR[3]) == 0x0Cu, "COMP4_CSR");
_Static_assert(offsetof(adc_regs_t, JSQR) == 0x4Cu, "ADC_JSQR");
_Static_assert(offsetof(adc_regs_t, JDR) == 0x80u, "ADC_JDR1");
_Static_assert(offsetof(adc_regs_t, DIFSEL) == 0xB0u, "ADC_DIFSEL");
_Static_assert(offsetof(fdcan_regs_t, CCCR) == 0x18u, "FDCAN_CCCR");
_Static_assert(offsetof(fdcan_regs_t, IR) == 0x50u, "FDCAN_IR");
_Static_assert(offsetof(fdcan_regs_t, RXGFC) == 0x80u, "FDCAN_RXGFC");
_Static_assert(offsetof(fdcan_regs_t, RXF0S) == 0x90u, "FDCAN_RXF0S");
_Static_assert(offsetof(fdcan_regs_t, TXBC) == 0xC0u, "FDCAN_TXBC");
_Static_assert(offsetof(fdcan_regs_t, TXEFA) == 0xE8u, "FDCAN_TXEFA");
_Static_assert(offsetof(scb_regs_t, SHPR) == 0x18u, "SCB_SHPR1");
_Static_assert(offsetof(scb_regs_t, CPACR) == 0x88u, "SCB_CPACR");
_Static_assert(offsetof(nvic_regs_t, ICER) == 0x80u, "NVIC_ICER");
_Static_assert(offsetof(nvic_regs_t, IPR) == 0x300u, "NVIC_IPR");
_Static_assert(SRAMCAN_TFQSA + 3u * SRAMCAN_ELEM_SIZE == SRAMCAN_SIZE, "SRAMCAN layout");

/* Interrupt masking (PRIMASK), PM0214 section 3.2.3. */
static inline uint32_t hal_irq_save(void) {
  uint32_t primask;
  __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
  return primask;
}
static inline void hal_irq_restore(uint32_t primask) {
  __asm__ volatile("msr primask, %0" ::"r"(primask) : "memory");
}

#endif /* FLUXDRIVE_STM32G4_REGS_H */

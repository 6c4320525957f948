/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver for MicroBlaze standalone: see stepramp.h. C99, no malloc, no stdio.
 */
#include "stepramp_bus_priv.h" /* first: STEPRAMP_CONFIG_HEADER, STEPRAMP_READ32 / _WRITE32 / _WRITE8 / _IDLE */

#include "stepramp.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* Byte address offset, within a register, of its bits 7:0 (see stepramp.h). */
#ifndef STEPRAMP_CMD_BYTE_LANE
#if defined(__BYTE_ORDER__) && defined(__ORDER_BIG_ENDIAN__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#define STEPRAMP_CMD_BYTE_LANE 3u
#else
#define STEPRAMP_CMD_BYTE_LANE 0u
#endif
#endif

#define REG(dev, off) ((dev)->base + (uintptr_t)(off))

/* 2 * math.pi, the double plan_jog divides by */
#define TWO_PI 6.283185307179586

static void write_reg(const stepramp_t *dev, uint32_t off, uint32_t value)
{
    STEPRAMP_WRITE32(REG(dev, off), value);
}

static uint32_t read_reg(const stepramp_t *dev, uint32_t off)
{
    return (uint32_t)STEPRAMP_READ32(REG(dev, off));
}

/* A wide value as its _LO (bits 31:0) and _HI (the bits above) words. */
static void write_wide(const stepramp_t *dev, uint32_t off_lo, uint32_t off_hi, uint64_t value)
{
    write_reg(dev, off_lo, (uint32_t)(value & UINT32_C(0xFFFFFFFF)));
    write_reg(dev, off_hi, (uint32_t)(value >> 32));
}

/* Byte address of CTRL bits 8k+7 .. 8k (byte lane k of the word) on this bus's byte order. */
#define CTRL_BYTE(dev, k) REG(dev, STEPRAMP_REG_CTRL + (STEPRAMP_CMD_BYTE_LANE == 0u ? (k) : 3u - (k)))

/* A CTRL command (START / SOFT_STOP / HARD_STOP, all in bits 7:0): byte 0 of CTRL only, the enables are kept. */
static void command(const stepramp_t *dev, uint32_t mask)
{
    STEPRAMP_WRITE8(CTRL_BYTE(dev, 0u), (uint8_t)mask);
}

int stepramp_init(stepramp_t *dev, uintptr_t base, double fclk, double spr, uint32_t prescale)
{
    return stepramp_init_ramp(dev, base, fclk, spr, prescale, STEPRAMP_RAMP_AVR446);
}

int stepramp_init_ramp(stepramp_t *dev, uintptr_t base, double fclk, double spr, uint32_t prescale, uint32_t ramp)
{
    uint32_t id;

    if (dev == NULL) {
        return STEPRAMP_ENULL;
    }
    if (ramp != STEPRAMP_RAMP_AVR446 && ramp != STEPRAMP_RAMP_EXACT) {
        return STEPRAMP_ERAMP; /* StepRamp's check_ramp: nothing set up */
    }
    dev->base = base;
    dev->fclk = fclk;
    dev->spr = spr;
    dev->prescale = prescale;
    dev->ramp = ramp;
    dev->segment_dirty = 1u; /* SEGMENT .. HEAD_PROD_HI unknown: the first program writes them */
    dev->min_gap = STEPRAMP_MIN_GAP_RESET;
    dev->input_filter = 0u; /* the reset values */
    dev->input_cfg = STEPRAMP_INPUT_CFG_RESET;
    id = read_reg(dev, STEPRAMP_REG_ID);
    dev->version = id & 0x3FFFu;
    dev->windings = ((id >> STEPRAMP_ID_WINDINGS_BIT) & 1u) ^ 1u; /* StepRamp.check_id: ID bit 14 is NO_WINDINGS */
    /* StepRamp.check_id: a stepramp core, built for the ramp this driver plans for (ID bit 15 is its G_RAMP) */
    return ((id >> 16) == STEPRAMP_ID_MAGIC && ((id >> STEPRAMP_ID_RAMP_BIT) & 1u) == ramp) ? STEPRAMP_OK
                                                                                             : STEPRAMP_EID;
}

int stepramp_plan(const stepramp_t *dev, stepramp_plan_t *plan, int64_t steps, double accel, double decel, double speed)
{
    stepramp_plan_t out;
    stepramp_info_t info;
    int rc;

    if (dev == NULL || plan == NULL) {
        return STEPRAMP_ENULL;
    }
    rc = (int)stepramp_plan_move_info_ramp(&out, &info, steps, accel, decel, speed, dev->spr, dev->fclk, dev->prescale,
                                           dev->ramp);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    /* StepRamp.plan: the STEP width + space must fit the move's shortest interval, floor(min_interval) * prescale */
    if (out.steps > 1u && (double)dev->min_gap > floor(info.min_interval) * (double)dev->prescale) {
        return STEPRAMP_EGAP;
    }
    *plan = out;
    return STEPRAMP_OK;
}

int stepramp_program(stepramp_t *dev, const stepramp_plan_t *plan)
{
    return stepramp_program_segment(dev, plan, NULL);
}

int stepramp_program_segment(stepramp_t *dev, const stepramp_plan_t *plan, const stepramp_segment_regs_t *segment)
{
    static const stepramp_segment_regs_t no_segment = {0u, 0u, 0u, 0u, 0u}; /* driver.NO_SEGMENT */
    const stepramp_segment_regs_t *seg = (segment != NULL) ? segment : &no_segment;

    if (dev == NULL || plan == NULL) {
        return STEPRAMP_ENULL;
    }
    /* in address order, like driver.plan_writes (the order does not matter to the core) */
    write_reg(dev, STEPRAMP_REG_STEPS, plan->direction ? 0u - plan->steps : plan->steps);
    write_reg(dev, STEPRAMP_REG_PRESCALE, plan->prescale);
    write_wide(dev, STEPRAMP_REG_C_FIRST_LO, STEPRAMP_REG_C_FIRST_HI, plan->c_first);
    write_wide(dev, STEPRAMP_REG_C_LAST_LO, STEPRAMP_REG_C_LAST_HI, plan->c_last);
    write_reg(dev, STEPRAMP_REG_SA, plan->sa);
    write_wide(dev, STEPRAMP_REG_C_SA_LO, STEPRAMP_REG_C_SA_HI, plan->c_sa);
    write_reg(dev, STEPRAMP_REG_SD, plan->sd);
    write_wide(dev, STEPRAMP_REG_C_SD_LO, STEPRAMP_REG_C_SD_HI, plan->c_sd);
    write_wide(dev, STEPRAMP_REG_ACCEL_SEED_LO, STEPRAMP_REG_ACCEL_SEED_HI, plan->accel_seed);
    write_wide(dev, STEPRAMP_REG_DECEL_SEED_LO, STEPRAMP_REG_DECEL_SEED_HI, plan->decel_seed);
    write_wide(dev, STEPRAMP_REG_CRUISE_LO, STEPRAMP_REG_CRUISE_HI, plan->cruise);
    write_reg(dev, STEPRAMP_REG_STOP_RATIO, plan->stop_ratio);
    if (segment != NULL || dev->segment_dirty) { /* driver.segment_writes, in address order */
        write_reg(dev, STEPRAMP_REG_SEGMENT,
                  (seg->head_down << STEPRAMP_SEGMENT_HEAD_DOWN_SHIFT) |
                      (seg->endless << STEPRAMP_SEGMENT_ENDLESS_SHIFT));
        write_reg(dev, STEPRAMP_REG_HEAD_INDEX, seg->head_index);
        write_reg(dev, STEPRAMP_REG_RUN_STOP, seg->run_stop);
        write_wide(dev, STEPRAMP_REG_HEAD_PROD_LO, STEPRAMP_REG_HEAD_PROD_HI, seg->head_prod);
        dev->segment_dirty = (seg->head_down | seg->endless | seg->head_index | seg->run_stop) != 0u ||
                             seg->head_prod != 0u;
    }
    return STEPRAMP_OK;
}

void stepramp_start(const stepramp_t *dev)
{
    command(dev, STEPRAMP_CTRL_START_MASK);
}

int stepramp_move(stepramp_t *dev, int64_t steps, double accel, double decel, double speed)
{
    stepramp_plan_t plan;
    int rc = stepramp_plan(dev, &plan, steps, accel, decel, speed);

    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    (void)stepramp_program(dev, &plan);
    stepramp_start(dev);
    return STEPRAMP_OK;
}

int stepramp_plan_jog(const stepramp_t *dev, stepramp_plan_t *plan, stepramp_segment_regs_t *regs, double speed,
                      double accel, double decel)
{
    stepramp_change_t ch;
    double shortest;
    int rc;

    if (dev == NULL || plan == NULL || regs == NULL) {
        return STEPRAMP_ENULL;
    }
    if (!(isfinite(speed) && speed != 0.0)) {
        return STEPRAMP_EJOG_SPEED;
    }
    rc = stepramp_plan_change_ramp(&ch, 0.0, STEPRAMP_ENDLESS, accel, decel, fabs(speed), dev->spr, dev->fclk,
                                   dev->prescale, dev->ramp);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    /* int(fclk / prescale / (|speed| spr / 2 pi)) * prescale, as plan_jog has it; a product that rounds does so
     * monotonically, and an infinite quotient leaves any gap room: the same outcome as Python's integers */
    shortest = floor(dev->fclk / (double)dev->prescale / (fabs(speed) * dev->spr / TWO_PI));
    if ((double)dev->min_gap > shortest * (double)dev->prescale) {
        return STEPRAMP_EGAP;
    }
    return stepramp_segment_registers(&ch.segment, (speed < 0.0) ? 1u : 0u, plan, regs);
}

int stepramp_jog(stepramp_t *dev, double speed, double accel, double decel)
{
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;
    int rc = stepramp_plan_jog(dev, &plan, &regs, speed, accel, decel);

    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    (void)stepramp_program_segment(dev, &plan, &regs);
    stepramp_start(dev);
    return STEPRAMP_OK;
}

int stepramp_change(stepramp_t *dev, const stepramp_segment_t *seg, uint32_t direction, uint32_t pulse)
{
    stepramp_plan_t plan;
    stepramp_segment_regs_t regs;
    int rc;

    if (dev == NULL || seg == NULL) {
        return STEPRAMP_ENULL;
    }
    if (pulse == 0u || pulse > STEPRAMP_MAX_PULSE) {
        return STEPRAMP_EPULSE;
    }
    rc = stepramp_segment_registers(seg, direction, &plan, &regs);
    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    (void)stepramp_program_segment(dev, &plan, &regs); /* the staging registers, in address order */
    write_reg(dev, STEPRAMP_REG_CHANGE_AT, pulse);
    command(dev, STEPRAMP_CTRL_CHANGE_MASK);
    return STEPRAMP_OK;
}

int stepramp_change_to(stepramp_t *dev, uint32_t pulse, double u, int64_t remaining, double accel, double decel,
                       double speed)
{
    stepramp_change_t ch;
    stepramp_change_info_t info;
    stepramp_status_t st;
    double f_tick;
    double shortest;
    int rc;

    if (dev == NULL) {
        return STEPRAMP_ENULL;
    }
    if (pulse == 0u || pulse > STEPRAMP_MAX_PULSE) {
        return STEPRAMP_EPULSE;
    }
    rc = stepramp_plan_change_info_ramp(&ch, &info, u, remaining, accel, decel, speed, dev->spr, dev->fclk,
                                        dev->prescale, dev->ramp);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    if (ch.has_back) {
        return STEPRAMP_EREVERSE;
    }
    /* the segment's shortest interval, in ticks: at its peak (t_cruise, f_tick / v_peak; 0.0 for a segment without
     * one) or at its start speed, whichever is faster; the STEP width + space must fit it, as for a move or a jog */
    f_tick = dev->fclk / (double)dev->prescale;
    shortest = (info.t_cruise > 0.0) ? info.t_cruise : (double)INFINITY;
    if (ch.start_speed > 0.0 && f_tick / ch.start_speed < shortest) {
        shortest = f_tick / ch.start_speed;
    }
    if (isfinite(shortest) && (double)dev->min_gap > floor(shortest) * (double)dev->prescale) {
        return STEPRAMP_EGAP;
    }
    /* the running direction, read last: the commit follows it as closely as the bus allows */
    (void)stepramp_status(dev, &st);
    if (!st.busy) {
        return STEPRAMP_EIDLE;
    }
    if (st.pending) {
        return STEPRAMP_EPENDING;
    }
    return stepramp_change(dev, &ch.segment, st.dir, pulse);
}

int stepramp_queue(stepramp_t *dev, const stepramp_plan_t *plan)
{
    if (dev == NULL || plan == NULL) {
        return STEPRAMP_ENULL;
    }
    (void)stepramp_program(dev, plan); /* clears SEGMENT .. HEAD_PROD_HI too when a jog or a change set them */
    command(dev, STEPRAMP_CTRL_QUEUE_MASK);
    return STEPRAMP_OK;
}

int stepramp_queue_move(stepramp_t *dev, int64_t steps, double accel, double decel, double speed)
{
    stepramp_plan_t plan;
    int rc = stepramp_plan(dev, &plan, steps, accel, decel, speed);

    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    return stepramp_queue(dev, &plan);
}

void stepramp_soft_stop(const stepramp_t *dev)
{
    command(dev, STEPRAMP_CTRL_SOFT_STOP_MASK);
}

void stepramp_hard_stop(const stepramp_t *dev)
{
    command(dev, STEPRAMP_CTRL_HARD_STOP_MASK);
}

void stepramp_enable_irq(const stepramp_t *dev, int done, int error)
{
    /* the input interrupt enables (bits 10 .. 14) share byte 1: kept as read */
    uint32_t value = read_reg(dev, STEPRAMP_REG_CTRL) &
                     (STEPRAMP_CTRL_IRQ_LIMIT_NEG_EN_MASK | STEPRAMP_CTRL_IRQ_LIMIT_POS_EN_MASK |
                      STEPRAMP_CTRL_IRQ_HOME_EN_MASK | STEPRAMP_CTRL_IRQ_ESTOP_EN_MASK | STEPRAMP_CTRL_IRQ_LATCH_EN_MASK);

    value |= (done ? STEPRAMP_CTRL_IRQ_DONE_EN_MASK : 0u) | (error ? STEPRAMP_CTRL_IRQ_ERROR_EN_MASK : 0u);
    STEPRAMP_WRITE8(CTRL_BYTE(dev, 1u), (uint8_t)(value >> 8)); /* byte 1 only: no command, ENABLE kept */
}

void stepramp_set_enable(const stepramp_t *dev, int on)
{
    STEPRAMP_WRITE8(CTRL_BYTE(dev, 2u), (uint8_t)(on ? (STEPRAMP_CTRL_ENABLE_MASK >> 16) : 0u));
}

int stepramp_configure_outputs(stepramp_t *dev, const stepramp_outputs_t *out)
{
    if (out == NULL || out->mode > 4u || out->ustep_log2 > 7u) {
        return STEPRAMP_EOUTPUTS;
    }
    if (out->mode != 0u && !dev->windings) {
        return STEPRAMP_EWINDINGS; /* StepRamp.configure_outputs: STEP/DIR only on a core without windings */
    }
    write_reg(dev, STEPRAMP_REG_DRIVE,
              (out->mode << STEPRAMP_DRIVE_MODE_SHIFT) | (out->ustep_log2 << STEPRAMP_DRIVE_USTEP_LOG2_SHIFT));
    write_reg(dev, STEPRAMP_REG_STEP_WIDTH, out->step_width);
    write_reg(dev, STEPRAMP_REG_DIR_TIMING,
              ((uint32_t)out->dir_setup << STEPRAMP_DIR_TIMING_SETUP_SHIFT) |
                  ((uint32_t)out->dir_hold << STEPRAMP_DIR_TIMING_HOLD_SHIFT));
    write_reg(dev, STEPRAMP_REG_PWM_PERIOD, out->pwm_period);
    write_reg(dev, STEPRAMP_REG_STEP_SPACE, out->step_space);
    dev->min_gap = (out->step_width > 1u ? out->step_width : 1u) + (out->step_space > 1u ? out->step_space : 1u);
    return STEPRAMP_OK;
}

uint32_t stepramp_status(const stepramp_t *dev, stepramp_status_t *status)
{
    uint32_t raw = read_reg(dev, STEPRAMP_REG_STATUS);

    if (status != NULL) {
        status->raw = raw;
        status->state = (raw & STEPRAMP_STATUS_STATE_MASK) >> STEPRAMP_STATUS_STATE_SHIFT;
        status->busy = (raw & STEPRAMP_STATUS_BUSY_MASK) != 0u;
        status->dir = (raw & STEPRAMP_STATUS_DIR_MASK) >> STEPRAMP_STATUS_DIR_SHIFT;
        status->done = (raw & STEPRAMP_STATUS_DONE_MASK) != 0u;
        status->error = (raw & STEPRAMP_STATUS_ERROR_MASK) != 0u;
        status->err_code = (raw & STEPRAMP_STATUS_ERR_CODE_MASK) >> STEPRAMP_STATUS_ERR_CODE_SHIFT;
        status->pending = (raw & STEPRAMP_STATUS_PENDING_MASK) != 0u;
        status->dir_fault = (raw & STEPRAMP_STATUS_DIR_FAULT_MASK) != 0u;
        status->levels = (raw >> STEPRAMP_STATUS_LIMIT_NEG_SHIFT) & STEPRAMP_INPUT_ALL;
        status->events = (raw >> STEPRAMP_STATUS_LIMIT_NEG_EV_SHIFT) & STEPRAMP_INPUT_ALL;
        status->latched = (raw & STEPRAMP_STATUS_LATCHED_MASK) != 0u;
    }
    return raw;
}

void stepramp_clear_flags(const stepramp_t *dev)
{
    /* a whole-word write of 1 to DONE and ERROR only: the other W1C bits (the input events, ESTOP_FAULT, LATCHED)
     * are written 0 and kept, the rest of STATUS is read only */
    write_reg(dev, STEPRAMP_REG_STATUS, STEPRAMP_STATUS_DONE_MASK | STEPRAMP_STATUS_ERROR_MASK);
}

/* The INPUT_CFG word of a configuration, or STEPRAMP_EINPUTS through *rc. */
static uint32_t input_cfg_word(const stepramp_inputs_t *in, int *rc)
{
    uint32_t word;

    if (in->filter > STEPRAMP_FILTER_MAX || (in->active_low & ~STEPRAMP_INPUT_ALL) != 0u ||
        in->latch_source > STEPRAMP_LATCH_LIMIT_POS ||
        (in->latch_source != STEPRAMP_LATCH_NONE && !in->latch_on_active && !in->latch_on_release)) {
        *rc = STEPRAMP_EINPUTS;
        return 0u;
    }
    word = in->active_low << STEPRAMP_INPUT_CFG_POL_LIMIT_NEG_SHIFT;
    word |= in->limit_enable ? STEPRAMP_INPUT_CFG_LIMIT_EN_MASK : 0u;
    word |= in->limit_hard ? STEPRAMP_INPUT_CFG_LIMIT_HARD_MASK : 0u;
    word |= in->latch_source << STEPRAMP_INPUT_CFG_LATCH_SRC_SHIFT;
    if (in->latch_source != STEPRAMP_LATCH_NONE) {
        word |= in->latch_on_active ? STEPRAMP_INPUT_CFG_LATCH_ON_ACTIVE_MASK : 0u;
        word |= in->latch_on_release ? STEPRAMP_INPUT_CFG_LATCH_ON_RELEASE_MASK : 0u;
    }
    *rc = STEPRAMP_OK;
    return word;
}

int stepramp_configure_inputs(stepramp_t *dev, const stepramp_inputs_t *in)
{
    int rc;
    uint32_t word;

    if (dev == NULL || in == NULL) {
        return STEPRAMP_EINPUTS;
    }
    word = input_cfg_word(in, &rc);
    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    write_reg(dev, STEPRAMP_REG_INPUT_FILTER, in->filter);
    write_reg(dev, STEPRAMP_REG_INPUT_CFG, word);
    dev->input_filter = in->filter;
    dev->input_cfg = word;
    return STEPRAMP_OK;
}

/* Write 1 to the STATUS bits of mask: the byte lanes that hold them, each a byte write (the W1C flags of the other
 * lanes are kept). */
static void clear_status_bits(const stepramp_t *dev, uint32_t mask)
{
    uint32_t k;

    for (k = 0u; k < 4u; k++) {
        uint32_t byte = (mask >> (8u * k)) & 0xFFu;
        if (byte != 0u) {
            STEPRAMP_WRITE8(REG(dev, STEPRAMP_REG_STATUS + (STEPRAMP_CMD_BYTE_LANE == 0u ? k : 3u - k)),
                            (uint8_t)byte);
        }
    }
}

int stepramp_arm_latch(stepramp_t *dev, uint32_t source, int on_active, int on_release)
{
    stepramp_inputs_t in;
    int rc;
    uint32_t word;
    const uint32_t latch_bits = STEPRAMP_INPUT_CFG_LATCH_SRC_MASK | STEPRAMP_INPUT_CFG_LATCH_ON_ACTIVE_MASK |
                                STEPRAMP_INPUT_CFG_LATCH_ON_RELEASE_MASK;

    if (dev == NULL) {
        return STEPRAMP_EINPUTS;
    }
    in.filter = dev->input_filter;
    in.active_low = 0u;
    in.limit_enable = 0;
    in.limit_hard = 0;
    in.latch_source = source;
    in.latch_on_active = on_active;
    in.latch_on_release = on_release;
    word = input_cfg_word(&in, &rc);
    if (rc != STEPRAMP_OK) {
        return rc; /* nothing written */
    }
    dev->input_cfg = (dev->input_cfg & ~latch_bits) | word;
    write_reg(dev, STEPRAMP_REG_INPUT_CFG, dev->input_cfg);
    stepramp_rearm_latch(dev);
    return STEPRAMP_OK;
}

void stepramp_rearm_latch(const stepramp_t *dev)
{
    clear_status_bits(dev, STEPRAMP_STATUS_LATCHED_MASK);
}

void stepramp_read_latch(const stepramp_t *dev, stepramp_latch_t *latch)
{
    uint32_t raw = read_reg(dev, STEPRAMP_REG_LATCH_POS);
    uint32_t lo = read_reg(dev, STEPRAMP_REG_LATCH_TIME_LO);
    uint32_t hi = read_reg(dev, STEPRAMP_REG_LATCH_TIME_HI);
    uint32_t n = dev->input_filter > 1u ? dev->input_filter : 1u;

    latch->position = raw <= UINT32_C(0x7FFFFFFF) ? (int32_t)raw : -(int32_t)(~raw) - 1;
    latch->time = (uint64_t)hi << 32 | lo;
    latch->pin_time = (int64_t)latch->time - (int64_t)n - 2; /* a 64-bit count of clocks stays far below 2^63 */
}

int stepramp_latch(const stepramp_t *dev, stepramp_latch_t *latch)
{
    if (dev == NULL || latch == NULL) {
        return STEPRAMP_ENULL;
    }
    if ((stepramp_status(dev, NULL) & STEPRAMP_STATUS_LATCHED_MASK) == 0u) {
        return STEPRAMP_ENOLATCH;
    }
    stepramp_read_latch(dev, latch);
    return STEPRAMP_OK;
}

uint64_t stepramp_time(const stepramp_t *dev)
{
    uint32_t lo = read_reg(dev, STEPRAMP_REG_TIME_LO); /* first: copies bits 63:32 into TIME_HI */
    uint32_t hi = read_reg(dev, STEPRAMP_REG_TIME_HI);

    return (uint64_t)hi << 32 | lo;
}

void stepramp_clear_events(const stepramp_t *dev, uint32_t inputs)
{
    clear_status_bits(dev, (inputs & (STEPRAMP_INPUT_LIMIT_NEG | STEPRAMP_INPUT_LIMIT_POS | STEPRAMP_INPUT_HOME))
                               << STEPRAMP_STATUS_LIMIT_NEG_EV_SHIFT);
}

int stepramp_clear_estop(const stepramp_t *dev, int enable)
{
    clear_status_bits(dev, STEPRAMP_STATUS_ESTOP_FAULT_MASK);
    if ((stepramp_status(dev, NULL) & STEPRAMP_STATUS_ESTOP_FAULT_MASK) != 0u) {
        return STEPRAMP_EESTOP;
    }
    if (enable) {
        stepramp_set_enable(dev, 1);
    }
    return STEPRAMP_OK;
}

void stepramp_enable_input_irq(const stepramp_t *dev, int done, int error, uint32_t events, int latch)
{
    uint32_t value = (done ? STEPRAMP_CTRL_IRQ_DONE_EN_MASK : 0u) | (error ? STEPRAMP_CTRL_IRQ_ERROR_EN_MASK : 0u);

    value |= (events & STEPRAMP_INPUT_ALL) << STEPRAMP_CTRL_IRQ_LIMIT_NEG_EN_SHIFT;
    value |= latch ? STEPRAMP_CTRL_IRQ_LATCH_EN_MASK : 0u;
    STEPRAMP_WRITE8(CTRL_BYTE(dev, 1u), (uint8_t)(value >> 8));
}

int32_t stepramp_position(const stepramp_t *dev)
{
    uint32_t raw = read_reg(dev, STEPRAMP_REG_POSITION);

    /* two's complement without implementation-defined conversion: raw >= 2^31 is raw - 2^32 = -(~raw) - 1 */
    return raw <= UINT32_C(0x7FFFFFFF) ? (int32_t)raw : -(int32_t)(~raw) - 1;
}

void stepramp_set_position(const stepramp_t *dev, int32_t position)
{
    write_reg(dev, STEPRAMP_REG_POSITION, (uint32_t)position); /* modulo 2^32: two's complement */
}

int stepramp_isr(const stepramp_t *dev, stepramp_status_t *status)
{
    stepramp_status_t st;
    uint32_t flags = stepramp_status(dev, &st) & (STEPRAMP_STATUS_DONE_MASK | STEPRAMP_STATUS_ERROR_MASK);

    if (status != NULL) {
        *status = st;
    }
    if (flags == 0u) {
        return STEPRAMP_ENOIRQ;
    }
    write_reg(dev, STEPRAMP_REG_STATUS, flags);
    return st.error ? STEPRAMP_ECORE(st.err_code) : STEPRAMP_OK;
}

int stepramp_wait_done(const stepramp_t *dev, uint32_t max_polls)
{
    uint32_t i;
    stepramp_status_t st;

    for (i = 0; i < max_polls; i++) {
        if (i != 0u) {
            STEPRAMP_IDLE();
        }
        (void)stepramp_status(dev, &st);
        if (st.done) {
            stepramp_clear_flags(dev);
            return st.error ? STEPRAMP_ECORE(st.err_code) : STEPRAMP_OK;
        }
    }
    return STEPRAMP_ETIMEOUT;
}

/* The error table of docs/registers.md (stepramp.board.regmap.ERROR_CODES): X(name, cause). */
#define STEPRAMP_CORE_ERRORS(X)                                                                                        \
    X(NONE, "no error")                                                                                                \
    X(PRESCALE, "PRESCALE is 0")                                                                                       \
    X(BOUNDS, "SA or SD outside 1 .. STEPS-1, or SA > SD")                                                             \
    X(C_FIRST, "C_FIRST below one tick while the move has intervals")                                                  \
    X(C_LAST, "C_LAST below one tick while used")                                                                      \
    X(C_SA, "C_SA below one tick while used")                                                                          \
    X(C_SD, "C_SD below one tick while used")                                                                          \
    X(CRUISE, "CRUISE below one tick while a cruise interval exists")                                                  \
    X(ACCEL_SEED, "ACCEL_SEED below one tick while the accel recurrence is used")                                      \
    X(DECEL_SEED, "DECEL_SEED below one tick while the decel recurrence is used")                                      \
    X(LATE, "the next delay was not ready in time (speed too high for the clock); the move stopped")                   \
    X(ZERO_TICKS, "an interval of zero ticks would have been emitted; the move stopped")                               \
    X(RANGE, "a recurrence value left its 48-bit range; the move stopped")                                             \
    X(STEPS, "STEPS is -2^31 (|steps| must be <= 2^31 - 1)")                                                           \
    X(POS_BUSY, "POSITION written while STATUS.BUSY (the write was ignored)")                                          \
    X(CFG_BUSY, "DRIVE, STEP_WIDTH, DIR_TIMING, PWM_PERIOD, STEP_SPACE, INPUT_FILTER or INPUT_CFG written while "     \
                "STATUS.BUSY (ignored)")                                                                                \
    X(STEP_SPACE, "a pulse would have come less than STEP_WIDTH + STEP_SPACE clocks after the previous one (the two "  \
                  "would merge on the STEP pin); it was not emitted and the move stopped")                             \
    X(SEGMENT, "a down head with HEAD_INDEX < SA, or an up head whose index HEAD_INDEX + SA - 1 passes "               \
               "2^31 - 1")                                                                                             \
    X(CHANGE, "a CHANGE or QUEUE commit was refused (idle, something already pending, a soft stop requested, STEPS' "  \
              "sign against the running direction, pulse CHANGE_AT - 1 already emitted or CHANGE_AT past the last "    \
              "pulse); the motion goes on unchanged")                                                                  \
    X(STAGED, "a staging register (STEPS .. STOP_RATIO, SEGMENT .. CHANGE_AT) was written while STATUS.PENDING; the "  \
              "write was ignored")                                                                                     \
    X(LIMIT, "a limit input stopped a motion towards it (soft or hard, INPUT_CFG.LIMIT_HARD), or a START or queued "   \
             "move towards an active limit was refused (nothing moved)")                                               \
    X(ESTOP, "the ESTOP input hard-stopped every motion and dropped ENABLE, or a START or QUEUE came while ESTOP "     \
             "was active or STATUS.ESTOP_FAULT was set (refused, nothing moved)")

#define CORE_TABLE_SIZE 32u /* ERR_CODE is 5 bits */
#define CAUSE(name, text) [STEPRAMP_ERR_##name] = text,
#define NAME(name, text) [STEPRAMP_ERR_##name] = #name,
#define RESULT(name, text) [STEPRAMP_ERR_##name] = "core error " #name ": " text,

static const char *const core_causes[CORE_TABLE_SIZE] = {STEPRAMP_CORE_ERRORS(CAUSE)};
static const char *const core_names[CORE_TABLE_SIZE] = {STEPRAMP_CORE_ERRORS(NAME)};
static const char *const core_results[CORE_TABLE_SIZE] = {STEPRAMP_CORE_ERRORS(RESULT)};

const char *stepramp_strcoreerror(uint32_t code)
{
    return code < CORE_TABLE_SIZE && core_causes[code] != NULL ? core_causes[code] : "unknown error code";
}

const char *stepramp_corename(uint32_t code)
{
    return code < CORE_TABLE_SIZE && core_names[code] != NULL ? core_names[code] : "UNKNOWN";
}

/* The driver's own results, STEPRAMP_EID .. STEPRAMP_EWINDINGS, in words: X(name, text). */
#define STEPRAMP_DRIVER_RESULTS(X)                                                                                     \
    X(EID, "the ID register does not identify a stepramp core at this address, or one built for the other ramp "       \
           "arithmetic (ID bit 15, G_RAMP) than the driver plans for (stepramp_init_ramp)")                            \
    X(ETIMEOUT, "no DONE within the allowed number of status polls")                                                   \
    X(ENOIRQ, "no interrupt from this core: neither STATUS.DONE nor STATUS.ERROR is set")                              \
    X(EOUTPUTS, "invalid stepping outputs: mode must be 0 .. 4 and ustep_log2 0 .. 7")                                 \
    X(EJOG_SPEED, "the jog speed must be a finite non-zero number of rad/s")                                           \
    X(EGAP, "STEP width + STEP space clocks does not fit the shortest interval of the move, jog or change: lower "     \
            "the speed, the STEP width or the space")                                                                  \
    X(EPULSE, "the take-over pulse must be in 1 .. 2^31 - 1")                                                          \
    X(EREVERSE, "the target lies inside the stop distance or behind the motor: the change needs a move back (soft "    \
                "stop and a queued move), not a take-over")                                                            \
    X(EIDLE, "the core is idle: there is no motion to change")                                                         \
    X(EPENDING, "a change or a queued move is pending (STATUS.PENDING): the staging registers are locked")             \
    X(EINPUTS, "invalid input configuration: the filter must be 0 .. 2^20 - 1 clocks, the latch source 0 .. 3 with "   \
               "an edge selected, the polarity bits among the four inputs")                                            \
    X(ENOLATCH, "nothing latched: STATUS.LATCHED is 0")                                                                \
    X(EESTOP, "the E-stop is active or its fault is set (STATUS.ESTOP_FAULT clears only once ESTOP is inactive)")      \
    X(EHOMING, "invalid homing: the switch must be HOME or a limit in its own direction, the direction -1 or +1, "     \
               "the speeds and accelerations finite and positive, max_travel and max_polls at least 1")                \
    X(ELATCH_SPEED, "the homing latch speed is too high for an exact zero: a step must last at least the filter + "    \
                    "the switch's settle time + 5 clocks")                                                             \
    X(ETRAVEL, "homing: no switch edge within max_travel steps (the motion was hard-stopped)")                         \
    X(EBUSY, "the axis is moving")                                                                                     \
    X(ESWITCH, "homing: the motion ended before the switch edge, or the switch was not active where the seek "         \
               "latched it")                                                                                           \
    X(EWINDINGS, "the core was built without winding outputs (ID bit 14 set, G_WINDINGS false): only the STEP/DIR "   \
                 "mode (0)")

#define DRIVER_RESULT(name, text) [STEPRAMP_##name - STEPRAMP_EID] = text,

static const char *const driver_results[] = {STEPRAMP_DRIVER_RESULTS(DRIVER_RESULT)};

#define DRIVER_RESULTS_SIZE (sizeof driver_results / sizeof driver_results[0])

const char *stepramp_strresult(int result)
{
    if (result >= STEPRAMP_EID && (size_t)(result - STEPRAMP_EID) < DRIVER_RESULTS_SIZE &&
        driver_results[result - STEPRAMP_EID] != NULL) {
        return driver_results[result - STEPRAMP_EID];
    }
    if (STEPRAMP_IS_ECORE(result)) {
        uint32_t code = STEPRAMP_ECORE_CODE(result);
        return core_results[code] != NULL ? core_results[code] : "core error: unknown error code";
    }
    if (result >= 0 && result < STEPRAMP_EID) {
        return stepramp_strerror((stepramp_err_t)result); /* "unknown error" past the enum */
    }
    return "unknown error";
}

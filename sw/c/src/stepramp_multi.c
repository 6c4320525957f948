/* SPDX-License-Identifier: MIT */
/*
 * stepramp multi-axis driver: see stepramp_multi.h. C99, no malloc, no stdio.
 */
#include "stepramp_bus_priv.h" /* first: STEPRAMP_CONFIG_HEADER, STEPRAMP_READ32 / _WRITE32 / _IDLE (as stepramp.c) */

#include "stepramp_multi.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

static uint32_t read_global(const stepramp_multi_t *m, uint32_t off)
{
    return (uint32_t)STEPRAMP_READ32(m->base + (uintptr_t)off);
}

static void write_global(const stepramp_multi_t *m, uint32_t off, uint32_t value)
{
    STEPRAMP_WRITE32(m->base + (uintptr_t)off, value);
}

/* The mask of the top's axes. */
static uint32_t all_axes(const stepramp_multi_t *m)
{
    return (m->axes >= 32u) ? UINT32_C(0xFFFFFFFF) : ((UINT32_C(1) << m->axes) - 1u);
}

/* STEPRAMP_ENULL without the top, STEPRAMP_EMULTI_AXES for a mask with a bit beyond its axes, else STEPRAMP_OK. */
static int check_mask(const stepramp_multi_t *m, uint32_t mask)
{
    if (m == NULL) {
        return STEPRAMP_ENULL;
    }
    return ((mask & ~all_axes(m)) != 0u) ? STEPRAMP_EMULTI_AXES : STEPRAMP_OK;
}

/* An axis mask into a global register (SYNC_START, SYNC_SOFT_STOP, IRQ_MASK), once check_mask has passed it. */
static int write_mask(const stepramp_multi_t *m, uint32_t off, uint32_t mask)
{
    int rc = check_mask(m, mask);

    if (rc == STEPRAMP_OK) {
        write_global(m, off, mask);
    }
    return rc;
}

int stepramp_multi_init(stepramp_multi_t *m, uintptr_t base, double fclk, double spr, uint32_t prescale)
{
    uint32_t id;
    uint32_t i;
    int rc = STEPRAMP_OK;

    if (m == NULL) {
        return STEPRAMP_ENULL;
    }
    m->base = base;
    m->failed_mask = 0u;
    for (i = 0; i < STEPRAMP_MULTI_MAX_AXES; i++) {
        m->results[i] = STEPRAMP_OK;
    }
    id = read_global(m, STEPRAMP_MULTI_REG_ID);
    m->axes = id & 0xFFu;
    m->version = (id >> 8) & 0xFFu;
    if ((id >> 16) != STEPRAMP_MULTI_ID_MAGIC || m->axes < 1u || m->axes > STEPRAMP_MULTI_MAX_AXES) {
        m->axes = 0u;
        return STEPRAMP_EMULTI_ID;
    }
    for (i = 0; i < m->axes; i++) {
        uintptr_t window = base + (uintptr_t)STEPRAMP_MULTI_AXIS_WINDOW * (uintptr_t)(i + 1u);
        if (stepramp_init(&m->axis[i], window, fclk, spr, prescale) != STEPRAMP_OK) {
            rc = STEPRAMP_EMULTI_ID;
        }
    }
    return rc;
}

stepramp_t *stepramp_multi_axis(stepramp_multi_t *m, uint32_t i)
{
    if (m == NULL || i >= m->axes) {
        return NULL;
    }
    return &m->axis[i];
}

int stepramp_multi_sync_start(const stepramp_multi_t *m, uint32_t mask)
{
    return write_mask(m, STEPRAMP_MULTI_REG_SYNC_START, mask);
}

int stepramp_multi_sync_soft_stop(const stepramp_multi_t *m, uint32_t mask)
{
    return write_mask(m, STEPRAMP_MULTI_REG_SYNC_SOFT_STOP, mask);
}

uint32_t stepramp_multi_status(const stepramp_multi_t *m, stepramp_axes_status_t *status)
{
    uint32_t raw;

    if (m == NULL) {
        return 0u;
    }
    raw = read_global(m, STEPRAMP_MULTI_REG_AXES_STATUS);
    if (status != NULL) {
        status->raw = raw;
        status->busy = (raw >> STEPRAMP_MULTI_AXES_STATUS_BUSY_SHIFT) & 0xFFu;
        status->done = (raw >> STEPRAMP_MULTI_AXES_STATUS_DONE_SHIFT) & 0xFFu;
        status->irq = (raw >> STEPRAMP_MULTI_AXES_STATUS_IRQ_SHIFT) & 0xFFu;
    }
    return raw;
}

int stepramp_multi_set_irq_mask(const stepramp_multi_t *m, uint32_t mask)
{
    return write_mask(m, STEPRAMP_MULTI_REG_IRQ_MASK, mask);
}

uint32_t stepramp_multi_irq_mask(const stepramp_multi_t *m)
{
    return (m == NULL) ? 0u : (read_global(m, STEPRAMP_MULTI_REG_IRQ_MASK) & 0xFFu);
}

int stepramp_multi_plan_coordinated(const stepramp_multi_t *m, stepramp_plan_t *plans, const int64_t *steps,
                                    uint32_t count, double accel, double decel, double speed)
{
    stepramp_plan_t out[STEPRAMP_MULTI_MAX_AXES];
    stepramp_coord_info_t info;
    uint32_t i;
    int rc;

    if (m == NULL || plans == NULL || steps == NULL) {
        return STEPRAMP_ENULL;
    }
    if (count > m->axes) {
        return STEPRAMP_EMULTI_AXES;
    }
    /* the axes share fclk, spr and prescale (stepramp_multi_init): axis 0's are the move's */
    rc = stepramp_plan_coordinated_info(out, &info, steps, count, accel, decel, speed, m->axis[0].spr,
                                        m->axis[0].fclk, m->axis[0].prescale);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    /* MultiAxis.plan_coordinated: each axis's STEP width + space must fit its shortest interval */
    for (i = 0; i < count; i++) {
        const stepramp_t *ax = &m->axis[i];
        if (out[i].steps > 1u && (double)ax->min_gap > floor(info.axis[i].min_interval) * (double)ax->prescale) {
            return STEPRAMP_EGAP;
        }
    }
    for (i = 0; i < count; i++) {
        plans[i] = out[i];
    }
    return STEPRAMP_OK;
}

uint32_t stepramp_multi_started(const stepramp_plan_t *plans, uint32_t count)
{
    uint32_t i;
    uint32_t mask = 0u;

    if (plans == NULL) {
        return 0u;
    }
    for (i = 0; i < count && i < STEPRAMP_MULTI_MAX_AXES; i++) {
        if (plans[i].steps > 0u) {
            mask |= UINT32_C(1) << i;
        }
    }
    return mask;
}

int stepramp_multi_program_sync(stepramp_multi_t *m, const stepramp_plan_t *plans, uint32_t count)
{
    uint32_t i;
    uint32_t mask;

    if (m == NULL || plans == NULL) {
        return STEPRAMP_ENULL;
    }
    if (count > m->axes) {
        return STEPRAMP_EMULTI_AXES;
    }
    mask = stepramp_multi_started(plans, count);
    for (i = 0; i < count; i++) {
        if ((mask >> i) & 1u) {
            (void)stepramp_program(&m->axis[i], &plans[i]);
        }
    }
    return stepramp_multi_sync_start(m, mask);
}

int stepramp_multi_move_coordinated(stepramp_multi_t *m, stepramp_plan_t *plans, const int64_t *steps,
                                    uint32_t count, double accel, double decel, double speed)
{
    int rc = stepramp_multi_plan_coordinated(m, plans, steps, count, accel, decel, speed);

    if (rc != STEPRAMP_OK) {
        return rc;
    }
    return stepramp_multi_program_sync(m, plans, count);
}

int stepramp_multi_wait_done(stepramp_multi_t *m, uint32_t mask, uint32_t max_polls)
{
    uint32_t poll;
    uint32_t i;
    stepramp_axes_status_t st;
    int rc = check_mask(m, mask);

    if (rc != STEPRAMP_OK) {
        return rc;
    }
    m->failed_mask = 0u;
    for (poll = 0; poll < max_polls; poll++) {
        if (poll != 0u) {
            STEPRAMP_IDLE();
        }
        (void)stepramp_multi_status(m, &st);
        if ((st.done & mask) == mask) {
            for (i = 0; i < m->axes; i++) {
                if ((mask >> i) & 1u) {
                    m->results[i] = stepramp_wait_done(&m->axis[i], 1u);
                    if (m->results[i] != STEPRAMP_OK) {
                        m->failed_mask |= UINT32_C(1) << i;
                    }
                }
            }
            return (m->failed_mask != 0u) ? STEPRAMP_EMULTI_AXIS : STEPRAMP_OK;
        }
    }
    return STEPRAMP_ETIMEOUT;
}

/* This driver's own results, STEPRAMP_EMULTI_ID .. STEPRAMP_EMULTI_AXIS, in words */
static const char *const multi_results[] = {
    [STEPRAMP_EMULTI_ID - STEPRAMP_EMULTI_ID] =
        "the ID register does not identify a multi-axis stepramp top (magic 'SM', 1 .. 8 axes) at this address",
    [STEPRAMP_EMULTI_AXES - STEPRAMP_EMULTI_ID] =
        "more plans or step counts than the top has axes, or an axis mask beyond its axes",
    [STEPRAMP_EMULTI_AXIS - STEPRAMP_EMULTI_ID] = "an axis flagged an error (see failed_mask and results[])"};

const char *stepramp_multi_strresult(int result)
{
    if (result >= STEPRAMP_EMULTI_ID && result <= STEPRAMP_EMULTI_AXIS) {
        return multi_results[result - STEPRAMP_EMULTI_ID];
    }
    return stepramp_strresult(result);
}

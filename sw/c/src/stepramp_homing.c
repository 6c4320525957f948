/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: homing on the position latch; see stepramp_homing.h. C99, no malloc, no stdio. Uses the driver's
 * public calls only, and STEPRAMP_IDLE() between polls as stepramp.c does.
 */
#ifdef STEPRAMP_CONFIG_HEADER
#include STEPRAMP_CONFIG_HEADER /* may define STEPRAMP_IDLE */
#endif

#include "stepramp_homing.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#ifndef STEPRAMP_IDLE
#define STEPRAMP_IDLE() ((void)0)
#endif

/* 2 * math.pi, as homing.py divides by it */
#define TWO_PI 6.283185307179586

static int positive(double x)
{
    return isfinite(x) && x > 0.0;
}

int stepramp_homing_check(const stepramp_t *dev, const stepramp_homing_t *cfg)
{
    double have;
    double need;

    if (dev == NULL || cfg == NULL) {
        return STEPRAMP_ENULL;
    }
    if (cfg->sw < STEPRAMP_LATCH_HOME || cfg->sw > STEPRAMP_LATCH_LIMIT_POS ||
        (cfg->direction != -1 && cfg->direction != 1) ||
        (cfg->sw == STEPRAMP_LATCH_LIMIT_NEG && cfg->direction != -1) ||
        (cfg->sw == STEPRAMP_LATCH_LIMIT_POS && cfg->direction != 1) || !positive(cfg->seek_speed) ||
        !positive(cfg->seek_accel) || !positive(cfg->latch_speed) || !positive(cfg->latch_accel) ||
        cfg->max_travel == 0u || cfg->max_polls == 0u) {
        return STEPRAMP_EHOMING;
    }
    /* int(fclk / prescale / (latch_speed * spr / 2 pi)) * prescale >= N + settle + margin, as Homing.check */
    have = floor(dev->fclk / (double)dev->prescale / (cfg->latch_speed * dev->spr / TWO_PI)) * (double)dev->prescale;
    need = (double)(dev->input_filter > 1u ? dev->input_filter : 1u) + (double)cfg->settle_clocks +
           (double)STEPRAMP_LATCH_MARGIN;
    return have >= need ? STEPRAMP_OK : STEPRAMP_ELATCH_SPEED;
}

/* stepramp_wait_done (wait for DONE, clear the flags) within cfg->max_polls, with STEPRAMP_ECORE(allowed) taken as
 * STEPRAMP_OK (allowed 0: no error is). */
static int finish(const stepramp_t *dev, const stepramp_homing_t *cfg, uint32_t allowed)
{
    int rc = stepramp_wait_done(dev, cfg->max_polls);

    return (allowed != 0u && rc == STEPRAMP_ECORE(allowed)) ? STEPRAMP_OK : rc;
}

/* |a - b| for two positions, in 64 bits */
static int64_t distance(int32_t a, int32_t b)
{
    int64_t d = (int64_t)a - (int64_t)b;
    return d < 0 ? -d : d;
}

/* Jog at speed (signed) until the armed latch holds, soft stop, wait for DONE, read the latch. */
static int jog_to_latch(stepramp_t *dev, const stepramp_homing_t *cfg, double speed, double accel,
                        stepramp_latch_t *latch)
{
    uint32_t allowed = cfg->sw == STEPRAMP_LATCH_HOME ? 0u : STEPRAMP_ERR_LIMIT;
    int32_t start = stepramp_position(dev);
    stepramp_status_t st;
    uint32_t i;
    int rc = stepramp_jog(dev, speed, accel, accel);

    if (rc != STEPRAMP_OK) {
        return rc;
    }
    for (i = 0u; i < cfg->max_polls; i++) {
        if (i != 0u) {
            STEPRAMP_IDLE();
        }
        (void)stepramp_status(dev, &st);
        if (st.latched) {
            stepramp_soft_stop(dev);
            rc = finish(dev, cfg, allowed);
            if (rc == STEPRAMP_OK) {
                stepramp_read_latch(dev, latch);
            }
            return rc;
        }
        if (st.done) { /* the motion ended before the switch edge: a stop of its own */
            rc = finish(dev, cfg, allowed);
            return rc != STEPRAMP_OK ? rc : STEPRAMP_ESWITCH;
        }
        if (distance(stepramp_position(dev), start) > (int64_t)cfg->max_travel) {
            stepramp_hard_stop(dev);
            (void)finish(dev, cfg, allowed);
            return STEPRAMP_ETRAVEL;
        }
    }
    stepramp_hard_stop(dev);
    return STEPRAMP_ETIMEOUT;
}

/* the STEPRAMP_INPUT_* bit of a latch source */
static uint32_t switch_bit(uint32_t sw)
{
    return sw == STEPRAMP_LATCH_HOME ? STEPRAMP_INPUT_HOME
           : sw == STEPRAMP_LATCH_LIMIT_NEG ? STEPRAMP_INPUT_LIMIT_NEG
                                            : STEPRAMP_INPUT_LIMIT_POS;
}

/* STATUS.<switch> level now (the filtered input, after polarity) */
static int switch_active(const stepramp_t *dev, uint32_t sw)
{
    stepramp_status_t st;

    (void)stepramp_status(dev, &st);
    return (st.levels & switch_bit(sw)) != 0u;
}

/* Steps 1 .. 5 of the homing from a stopped axis whose STATUS read `levels` (stepramp_home restores the input
 * configuration around it). */
static int run(stepramp_t *dev, const stepramp_homing_t *cfg, uint32_t levels, stepramp_homing_result_t *res)
{
    double away = (double)-cfg->direction;
    int64_t back;
    int64_t position;
    int rc;

    res->left_valid = 0;
    if ((levels & switch_bit(cfg->sw)) != 0u) {
        rc = stepramp_arm_latch(dev, cfg->sw, 0, 1);
        if (rc == STEPRAMP_OK) {
            rc = jog_to_latch(dev, cfg, away * cfg->seek_speed, cfg->seek_accel, &res->left);
        }
        if (rc != STEPRAMP_OK) {
            return rc;
        }
        res->left_valid = 1;
    }
    rc = stepramp_arm_latch(dev, cfg->sw, 1, 0);
    if (rc == STEPRAMP_OK) {
        rc = jog_to_latch(dev, cfg, (double)cfg->direction * cfg->seek_speed, cfg->seek_accel, &res->seek);
    }
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    back = (int64_t)res->seek.position - (int64_t)stepramp_position(dev);
    if (back != 0) {
        rc = stepramp_move(dev, back, cfg->seek_accel, cfg->seek_accel, cfg->seek_speed);
        if (rc == STEPRAMP_OK) {
            rc = finish(dev, cfg, 0u);
        }
        if (rc != STEPRAMP_OK) {
            return rc;
        }
    }
    if (!switch_active(dev, cfg->sw)) {
        return STEPRAMP_ESWITCH;
    }
    rc = stepramp_arm_latch(dev, cfg->sw, 0, 1);
    if (rc == STEPRAMP_OK) {
        rc = jog_to_latch(dev, cfg, away * cfg->latch_speed, cfg->latch_accel, &res->release);
    }
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    res->shift = (int64_t)cfg->offset - (int64_t)res->release.position;
    position = (int64_t)stepramp_position(dev) + res->shift;
    if (position < INT32_MIN || position > INT32_MAX) {
        return STEPRAMP_EHOMING; /* the new POSITION does not fit 32 bits */
    }
    res->position = (int32_t)position;
    stepramp_set_position(dev, res->position);
    return stepramp_position(dev) == res->position ? STEPRAMP_OK : STEPRAMP_EBUSY; /* a motion kept POSITION */
}

int stepramp_home(stepramp_t *dev, const stepramp_homing_t *cfg, stepramp_homing_result_t *result)
{
    stepramp_homing_result_t res;
    stepramp_status_t st;
    uint32_t saved_cfg;
    int rc = stepramp_homing_check(dev, cfg);

    if (rc != STEPRAMP_OK) {
        return rc;
    }
    (void)stepramp_status(dev, &st);
    if (st.busy) {
        return STEPRAMP_EBUSY;
    }
    if ((st.levels & STEPRAMP_INPUT_ESTOP) != 0u || (st.events & STEPRAMP_INPUT_ESTOP) != 0u) {
        return STEPRAMP_EESTOP;
    }
    stepramp_clear_flags(dev); /* a DONE left from an earlier motion would end the first poll at once */
    saved_cfg = dev->input_cfg;
    rc = run(dev, cfg, st.levels, &res);
    dev->input_cfg = saved_cfg;
    {
        stepramp_inputs_t in;
        in.filter = dev->input_filter;
        in.active_low = (saved_cfg & (STEPRAMP_INPUT_ALL << STEPRAMP_INPUT_CFG_POL_LIMIT_NEG_SHIFT)) >>
                        STEPRAMP_INPUT_CFG_POL_LIMIT_NEG_SHIFT;
        in.limit_enable = (saved_cfg & STEPRAMP_INPUT_CFG_LIMIT_EN_MASK) != 0u;
        in.limit_hard = (saved_cfg & STEPRAMP_INPUT_CFG_LIMIT_HARD_MASK) != 0u;
        in.latch_source = (saved_cfg & STEPRAMP_INPUT_CFG_LATCH_SRC_MASK) >> STEPRAMP_INPUT_CFG_LATCH_SRC_SHIFT;
        in.latch_on_active = (saved_cfg & STEPRAMP_INPUT_CFG_LATCH_ON_ACTIVE_MASK) != 0u;
        in.latch_on_release = (saved_cfg & STEPRAMP_INPUT_CFG_LATCH_ON_RELEASE_MASK) != 0u;
        (void)stepramp_configure_inputs(dev, &in); /* the words it was built from: always valid */
    }
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    if (cfg->sw == STEPRAMP_LATCH_HOME) {
        stepramp_clear_events(dev, STEPRAMP_INPUT_HOME);
    }
    if (result != NULL) {
        *result = res;
    }
    return STEPRAMP_OK;
}

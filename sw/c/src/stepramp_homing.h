/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: homing on the position latch (docs/homing.md); the C counterpart of
 * sw/stepramp/board/homing.py (home, Homing, HomingResult), step for step.
 *
 * stepramp_home finds a switch (HOME, or a limit used as home) and makes its edge a known POSITION:
 *   1. if the switch is active, jog away from it at the seek speed until the latch sees its release, soft stop;
 *   2. seek: latch armed on the activation edge, jog towards the switch at the seek speed; at STATUS.LATCHED soft
 *      stop (a limit used as home stops the motion itself with error LIMIT, which is expected); LATCH_POS = p_seek;
 *   3. back to p_seek at the seek speed (a positioning move; still on the switch);
 *   4. release: latch armed on the release edge, jog away at the slow latch speed; at STATUS.LATCHED soft stop;
 *      LATCH_POS = p_release, the position after the first step off the switch, exactly: a step at the latch speed
 *      lasts longer than the switch's delay and bounce (settle_clocks) plus the filter's N + 2 clocks;
 *   5. POSITION += offset - p_release.
 * The input configuration (dev->input_filter, dev->input_cfg) is written back at the end, the latch as it was.
 *
 * Every wait polls STATUS, with STEPRAMP_IDLE() between polls (as stepramp_wait_done), at most max_polls times.
 * Link with stepramp.c (and what it needs); on the host, compile with the same STEPRAMP_CONFIG_HEADER.
 *
 *   stepramp_homing_t h = {40.0, 400.0, 2.0, 400.0, STEPRAMP_LATCH_HOME, -1, 0, 350u, 100000u, 100000000u};
 *   stepramp_homing_result_t res;
 *   rc = stepramp_home(&motor, &h, &res);    (POSITION now reads 0 at the first step off the switch)
 */
#ifndef STEPRAMP_HOMING_H
#define STEPRAMP_HOMING_H

#include <stdint.h>

#include "stepramp.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Clocks the latch speed's step must last beyond the filter and the settle time (homing.LATCH_MARGIN). */
#define STEPRAMP_LATCH_MARGIN 5u

/** A homing run (Python's homing.Homing). */
typedef struct {
    double seek_speed;      /**< the fast search, rad/s */
    double seek_accel;      /**< its acceleration and deceleration, rad/s^2 */
    double latch_speed;     /**< the slow move off the switch whose edge becomes the zero, rad/s */
    double latch_accel;     /**< its acceleration and deceleration, rad/s^2 */
    uint32_t sw;            /**< the switch: STEPRAMP_LATCH_HOME, _LIMIT_NEG or _LIMIT_POS (a limit used as home) */
    int32_t direction;      /**< where the switch is: -1 (POSITION counting down) or +1; a limit's own direction */
    int32_t offset;         /**< the POSITION given to the first position off the switch */
    uint32_t settle_clocks; /**< the longest time from the STEP edge crossing the switch edge to the pin's last
                                 change (delay and bounce), clocks */
    uint32_t max_travel;    /**< the farthest each jog may go, steps (>= 1) */
    uint32_t max_polls;     /**< STATUS polls each wait may take (>= 1) */
} stepramp_homing_t;

/** What a homing run found, positions in the frame before it (Python's homing.HomingResult). */
typedef struct {
    int left_valid;           /**< 1: the switch was active at the start, the axis left it first (left is set) */
    stepramp_latch_t left;    /**< the release edge while leaving the switch */
    stepramp_latch_t seek;    /**< the activation edge at the seek speed */
    stepramp_latch_t release; /**< the release edge at the latch speed: the zero */
    int64_t shift;            /**< added to POSITION: offset - release.position */
    int32_t position;         /**< POSITION at the end */
} stepramp_homing_result_t;

/**
 * Check a homing run against the device (touches no register): the latch speed's step,
 * floor(f_tick / (latch_speed * spr / 2 pi)) * prescale clocks, must be at least max(dev->input_filter, 1) +
 * settle_clocks + STEPRAMP_LATCH_MARGIN (homing.Homing.check).
 *
 * @return STEPRAMP_OK; STEPRAMP_EHOMING for an argument out of range; STEPRAMP_ELATCH_SPEED; STEPRAMP_ENULL
 */
int stepramp_homing_check(const stepramp_t *dev, const stepramp_homing_t *cfg);

/**
 * Run the homing (see the top of this file) on a stopped axis.
 *
 * @param result filled in on success (may be NULL)
 * @return STEPRAMP_OK; stepramp_homing_check's error (nothing moves); STEPRAMP_EBUSY (the axis is moving),
 *         STEPRAMP_EESTOP (E-stop active or fault set): nothing moves; STEPRAMP_ETRAVEL; STEPRAMP_ESWITCH;
 *         STEPRAMP_ETIMEOUT; STEPRAMP_ECORE(code) for a core error (LIMIT is expected only when the switch is a
 *         limit); a plan error of a jog or move
 */
int stepramp_home(stepramp_t *dev, const stepramp_homing_t *cfg, stepramp_homing_result_t *result);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_HOMING_H */

/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: a coordinated linear move (docs/algorithm.md, "Coordinated moves"): one plan per axis, the axes
 * started on the same clock, every axis of 2 steps or more accelerating, cruising and decelerating with the lead
 * (the axis with the most steps) and putting its last pulse on the same tick.
 *
 * C99 port of sw/stepramp/board/coord.py, bit for bit, like stepramp_plan.h of plan.py: the same doubles in the
 * same order, the same rounding, the same checks in the same order (see stepramp_plan.h for the build and libm
 * assumptions). Freestanding-friendly: no malloc, no stdio; link with stepramp_plan.c and -lm.
 *
 *   const int64_t steps[3] = {400, -250, 3};
 *   stepramp_plan_t plans[3];
 *   stepramp_coord_info_t info;
 *   int rc = stepramp_plan_coordinated_info(plans, &info, steps, 3, 40.0, 40.0, 20.0, 400.0, 50e6, 50);
 *   if (rc != STEPRAMP_OK) printf("axis %u: %s\n", info.failed_axis, stepramp_strerror((stepramp_err_t)rc));
 */
#ifndef STEPRAMP_COORD_H
#define STEPRAMP_COORD_H

#include <stdint.h>

#include "stepramp_change.h"
#include "stepramp_plan.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most axes one coordinated move plans (coord.MAX_AXES). */
#define STEPRAMP_COORD_MAX_AXES 8u

/** The longest path, in ticks, whose end the doubles place on a tick (coord.MAX_END_TICKS = 2^48). */
#define STEPRAMP_COORD_MAX_END_TICKS 281474976710656.0

/** stepramp_coord_info_t.failed_axis when no axis failed (success, or an error of the move as a whole). */
#define STEPRAMP_COORD_NO_AXIS UINT32_C(0xFFFFFFFF)

/**
 * Informative values of a coordinated move (not registers): Python's coord.CoordInfo, and the axis of an error.
 */
typedef struct {
    uint32_t failed_axis; /**< the axis whose check or plan failed; STEPRAMP_COORD_NO_AXIS otherwise */
    uint32_t lead;        /**< the lead axis: the first of the axes with the most steps */
    uint32_t count;       /**< the number of axes; the arrays below hold count entries */
    double t_end;         /**< the ideal end of the path, ticks from pulse 0 (0.0 when the lead has < 2 steps) */
    double end_tick;      /**< the tick every axis of 2 steps or more ends on, an integer: floor(t_end + 1/2), or
                               later when an axis's last interval needs it (coord.CoordInfo.end_tick) */
    double ratio[STEPRAMP_COORD_MAX_AXES]; /**< L_i / L_lead (1.0 lead; 0.0 for 0 or 1 step): the scale of the path's
                                                accel, decel and speed */
    double last_interval[STEPRAMP_COORD_MAX_AXES]; /**< the last interval before its rounding, ticks (0.0 below 2
                                                        steps) */
    stepramp_info_t axis[STEPRAMP_COORD_MAX_AXES]; /**< each axis's stepramp_plan_move_info of its scaled values */
} stepramp_coord_info_t;

/**
 * Plan a coordinated linear move, exactly like Python's stepramp.board.coord.plan_coordinated.
 *
 * Axis i's accel, decel and speed are the path's times r_i = (|steps[i]| - 1) / (|steps[lead]| - 1), so that its
 * ideal trajectory is r_i times the lead's; its plan is stepramp_plan_move's of those values (its accel_seed
 * already without the accel recurrence's mean truncation) with the last interval (c_last, and c_first, c_sa or c_sd
 * where they are interval L) set so that its last pulse lies on the tick nearest the ideal end of the
 * path, floor(t_end + 1/2). An axis of 1 step pulses once at the start, one of 0 steps not at all.
 *
 * @param plans    output, count plans; written only on success (left untouched on error)
 * @param steps    each axis's signed step count, |steps[i]| <= 2^31 - 1, not all 0
 * @param count    the number of axes, 1 .. STEPRAMP_COORD_MAX_AXES
 * @param accel    the lead axis's acceleration, rad/s^2 (finite, > 0)
 * @param decel    the lead axis's deceleration, rad/s^2 (finite, > 0)
 * @param speed    the lead axis's cruise speed, rad/s (finite, > 0)
 * @param spr      steps per revolution (finite, > 0), every axis
 * @param fclk     engine clock frequency, Hz (finite, > 0), every axis
 * @param prescale base timer period in clocks, 1 .. 65535, every axis
 * @return STEPRAMP_OK, or the first failed check in coord.py's order: the number of axes (STEPRAMP_ECOORD_AXES), the
 *         arguments (STEPRAMP_EACCEL .. STEPRAMP_EPRESCALE), each step count (STEPRAMP_ESTEPS), all of them 0
 *         (STEPRAMP_ECOORD_ZERO), each axis's stepramp_plan_move error in axis order, a path of 2^48 ticks or more
 *         (STEPRAMP_ECOORD_LONG), then each axis's last interval in axis order (STEPRAMP_EOVERFLOW, or
 *         STEPRAMP_ECOORD_END: not expected); STEPRAMP_ENULL for a NULL plans or steps.
 *         stepramp_strerror((stepramp_err_t)rc) names any of them.
 */
int stepramp_plan_coordinated(stepramp_plan_t *plans, const int64_t *steps, uint32_t count, double accel,
                              double decel, double speed, double spr, double fclk, uint32_t prescale);

/**
 * Like stepramp_plan_coordinated, also filling in the informative values.
 *
 * @param info output, may be NULL. On success every field is written; on error only failed_axis (the axis of a step
 *             count, plan or last interval that failed, else STEPRAMP_COORD_NO_AXIS).
 */
int stepramp_plan_coordinated_info(stepramp_plan_t *plans, stepramp_coord_info_t *info, const int64_t *steps,
                                   uint32_t count, double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale);

/**
 * The predicted time (ticks) from pulse 0 to pulse N - 2 of a plan, like coord.time_before_last: its exact values
 * and, in closed form, its recurrence values from their seeds with the recurrences' mean truncation. 0.0 for fewer
 * than 3 steps or a NULL plan.
 */
double stepramp_time_before_last(const stepramp_plan_t *plan);

/** The ideal trajectory's duration in ticks from a stepramp_info_t, like coord.ideal_end; 0.0 without an interval
 * or for a NULL info. */
double stepramp_ideal_end(const stepramp_info_t *info);

/** One axis of a coordinated stop on the line: Python's coord.AxisStop. */
typedef struct {
    uint32_t pulse;        /**< P_i, the take-over pulse (0: the axis takes no CHANGE) */
    int has_change;        /**< 1: change holds the segment taken over at pulse (Python's change is not None) */
    double speed;          /**< u_i, its ideal speed at P_i, steps/s (0.0 without a take-over pulse) */
    int64_t natural;       /**< N_i = P_i + ceil(u_i^2 / (2 d_i)) (the ceil capped at 2^40), or L_i */
    int64_t target;        /**< T_i, the pulse it rests on */
    stepramp_change_t change; /**< plan_change(u_i, T_i - P_i, ...); all 0 when has_change is 0 */
} stepramp_coord_axis_stop_t;

/** A coordinated stop on the line: Python's coord.CoordStop. */
typedef struct {
    int64_t rest;           /**< R_L, the lead's rest (a pulse of the lead) */
    uint32_t count;         /**< the number of axes */
    uint32_t fallback_axis; /**< the axis whose plan_change failed (then SYNC_SOFT_STOP is the stop), or
                                 STEPRAMP_COORD_NO_AXIS */
    int fallback_err;       /**< that plan_change's error (STEPRAMP_OK when none) */
    stepramp_coord_axis_stop_t axis[STEPRAMP_COORD_MAX_AXES];
} stepramp_coord_stop_t;

/**
 * The take-overs that stop a running coordinated move on the line, exactly like Python's
 * stepramp.board.coord.plan_coordinated_stop_at (docs/algorithm.md, "Coordinated moves": the coordinated stop on the
 * line): N_i = P_i + ceil(u_i^2 / (2 d_i)) with u_i = stepramp_speed_at_pulse, R_L = min(L_lead, max_i
 * ceil(N_i L_lead / L_i)), T_i = round(L_i R_L / L_lead) (halves up), and stepramp_plan_change_ramp(u_i, T_i - P_i,
 * the path's accel, decel and speed times r_i, ...) for each axis with 0 < P_i < L_i and T_i < L_i.
 * @param out      output: every field written (on a fallback, the axes after fallback_axis are left 0)
 * @param plans    the coordinated move's plans (stepramp_plan_coordinated_info), count of them
 * @param info     its info (lead, ratio, axis[i].d and the moves for stepramp_speed_at_pulse)
 * @param pulses   each axis's take-over pulse P_i (0: none; the host picks it as change_pulse does)
 * @param count    the number of axes, 1 .. STEPRAMP_COORD_MAX_AXES
 * @return STEPRAMP_OK (a failed plan_change is a fallback, not an error); STEPRAMP_ENULL for a NULL pointer;
 *         STEPRAMP_ECOORD_AXES for a bad count
 */
int stepramp_plan_coordinated_stop(stepramp_coord_stop_t *out, const stepramp_plan_t *plans,
                                   const stepramp_coord_info_t *info, const uint32_t *pulses, uint32_t count,
                                   double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_COORD_H */

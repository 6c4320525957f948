/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: a change while moving (docs/algorithm.md, "Changes while moving"): the continuation segment that
 * takes over at a pulse P of the running motion, from the speed at P and the new accel, decel, speed and target.
 *
 * C99 port of sw/stepramp/board/change.py, bit for bit, like stepramp_plan.h of plan.py: the same doubles in the
 * same order, the same rounding, the same checks in the same order (see stepramp_plan.h for the build and libm
 * assumptions). Freestanding-friendly: no malloc, no stdio; link with stepramp_plan.c and -lm.
 *
 *   stepramp_info_t info;                           the running move's plan_move_info
 *   stepramp_change_t ch;
 *   double u = stepramp_speed_at_pulse(&info, p);   its speed at pulse p, steps/s
 *   int rc = stepramp_plan_change(&ch, u, STEPRAMP_ENDLESS, 40.0, 40.0, 30.0, 400.0, 50e6, 50);   jog at 30 rad/s
 *   if (rc != STEPRAMP_OK) puts(stepramp_strerror((stepramp_err_t)rc));
 *
 * stepramp_plan_change plans for the AVR446 core (G_RAMP = 0); stepramp_plan_change_ramp for either ramp arithmetic
 * (STEPRAMP_RAMP_EXACT: G_RAMP = 1), as Python's plan_change(..., prescale, ramp).
 */
#ifndef STEPRAMP_CHANGE_H
#define STEPRAMP_CHANGE_H

#include <stdint.h>

#include "stepramp_plan.h"

#ifdef __cplusplus
extern "C" {
#endif

/** remaining of stepramp_plan_change for an endless segment (jog): Python's remaining None. */
#define STEPRAMP_ENDLESS INT64_C(-1)

/** stepramp_segment_t.head: the kind of the ramp before sa (change.UP, change.DOWN). */
#define STEPRAMP_HEAD_UP 0u
#define STEPRAMP_HEAD_DOWN 1u

/**
 * The engine's inputs for a continuation: field by field Python's change.Segment. A plan over the segment's own
 * intervals 1 .. length with a head ramp that may start at speed: up, the accel recurrence from index head_index;
 * down, the decel recurrence towards a virtual rest at the end of interval head_index. c_* and the seeds are
 * Q32.16 (< 2^48), cruise is Q32.32.
 */
typedef struct {
    uint32_t length;     /**< L: intervals 1 .. L (0 .. 2^31-1); 0 when endless */
    uint32_t endless;    /**< 1: no target, a jog (Python's length None); 0: positioning */
    uint32_t head;       /**< STEPRAMP_HEAD_UP or STEPRAMP_HEAD_DOWN */
    uint32_t head_index; /**< up: n0; down: K (0 .. 2^31-1) */
    uint32_t prescale;   /**< base timer period in clocks (1 .. 65535) */
    uint32_t sa;         /**< first interval after the head, floor(x_h)+1 clamped to [1, L] */
    uint32_t sd;         /**< start of the final decel, floor(x_c)+1 clamped to [1, L]; 0 when endless */
    uint64_t c_first;    /**< exact interval 1 (plus half the up head's recurrence deficit; exact mode: none),
                              Q32.16 */
    uint64_t c_sa;       /**< exact interval sa, Q32.16 */
    uint64_t c_sd;       /**< exact interval sd, Q32.16; endless: 0, in exact mode the first interval of a soft stop
                              decided in the cruise (the cruise, then the decel at d to rest run_stop steps ahead) */
    uint64_t c_last;     /**< exact interval L; endless: cd0, the last step of a soft stop; Q32.16 */
    uint64_t accel_seed; /**< the head's recurrence seed (up: A_{n0}, down: D_{K-2}), Q32.16; exact mode: the head's
                              ramp constant (up: of c0 = f_tick sqrt(2 / a), down: of cd0) */
    uint64_t decel_seed; /**< final decel recurrence value at index L-sd-1, Q32.16; 0 when that is < 1; exact mode:
                              the ramp constant of cd0 whenever the segment has an interval (a soft stop needs it) */
    uint64_t cruise;     /**< cruise period f_tick / v_peak, Q32.32 */
    uint32_t stop_ratio; /**< accel / decel, Q16.16 (rounded, saturated) */
    uint32_t run_stop;   /**< endless: the steps of a soft stop decided in the cruise, ceil(v_peak^2 / (2 d)); else 0 */
    uint32_t ramp;       /**< not a register: the ramp arithmetic, STEPRAMP_RAMP_AVR446 or STEPRAMP_RAMP_EXACT
                              (Python's Segment.ramp, as stepramp_plan_t.ramp) */
} stepramp_segment_t;

/**
 * What stepramp_plan_change returns: Python's change.Change. The segment taken over at pulse P, the speed it
 * starts at (steps/s, snapped to its head ramp) and, when the target lies inside the stop distance, the move from
 * rest back to it (direction 1: against the segment's direction).
 */
typedef struct {
    stepramp_segment_t segment; /**< the continuation */
    double start_speed;         /**< steps/s, the same double as Python's */
    int has_back;               /**< 1 when back holds a move (Python's back is not None) */
    stepramp_plan_t back;       /**< the move back to the target; all 0 when has_back is 0 */
} stepramp_change_t;

/**
 * The register values of a change before rounding, in ticks (C extras, like stepramp_info_t's t_* fields: for
 * diagnostics and the bit-for-bit parity test with Python); 0.0 where the register is 0 without a rounding.
 */
typedef struct {
    double t_first;      /**< exact interval 1, plus half the up head's recurrence deficit (exact mode: none) */
    double t_last;       /**< exact interval L; endless: cd0 = f_tick sqrt(2 / d) */
    double t_sa;         /**< exact interval sa */
    double t_sd;         /**< exact interval sd; exact mode, endless: the first interval of a soft stop in the cruise */
    double t_accel_seed; /**< the head's seed, plus half its recurrence deficit spread over its values (an up head's
                              less its recurrence's mean truncation); exact mode: the head's c0 (ticks), whose ramp
                              constant accel_seed is */
    double t_decel_seed; /**< the final decel's seed, plus half its deficit; exact mode: cd0, whose ramp constant
                              decel_seed is */
    double t_cruise;     /**< f_tick / v_peak */
} stepramp_change_info_t;

/**
 * The continuation from speed u at pulse P, exactly like Python's stepramp.board.change.plan_change.
 *
 * @param out       output; written only on success (left untouched on error)
 * @param u         speed at the change, steps/s (finite, >= 0): stepramp_speed_at_pulse of the running move
 * @param remaining steps from P to the target (0 .. 2^31-1), or STEPRAMP_ENDLESS (jog at speed)
 * @param accel     new acceleration, rad/s^2 (finite, > 0)
 * @param decel     new deceleration, rad/s^2 (finite, > 0)
 * @param speed     new speed, rad/s (finite, > 0)
 * @param spr       steps per revolution (finite, > 0)
 * @param fclk      engine clock frequency, Hz (finite, > 0)
 * @param prescale  base timer period in clocks, 1 .. 65535
 * @return STEPRAMP_OK; the first failed check in change.py's order: the arguments (STEPRAMP_EACCEL ..
 *         STEPRAMP_EPRESCALE, STEPRAMP_ECHANGE_SPEED, STEPRAMP_EREMAINING), accel, decel, speed and f_tick in steps
 *         units (STEPRAMP_EACCEL_UNITS .. STEPRAMP_EFTICK: also when the square is not finite), the step counts
 *         (STEPRAMP_ESEGMENT: the stop distance, the up head's index or a jog's run_stop of 2^31 steps or more), the
 *         move back's own error when the target lies inside the stop distance (as stepramp_plan_move gives it), the
 *         speed limit (STEPRAMP_ETOOFAST), register overflows (STEPRAMP_EOVERFLOW); STEPRAMP_ENULL for a NULL out.
 *         stepramp_strerror((stepramp_err_t)rc) names any of them.
 */
int stepramp_plan_change(stepramp_change_t *out, double u, int64_t remaining, double accel, double decel,
                         double speed, double spr, double fclk, uint32_t prescale);

/**
 * Like stepramp_plan_change, also filling in the unrounded register values.
 *
 * @param info output, may be NULL; like out, written only on success
 */
int stepramp_plan_change_info(stepramp_change_t *out, stepramp_change_info_t *info, double u, int64_t remaining,
                              double accel, double decel, double speed, double spr, double fclk, uint32_t prescale);

/**
 * stepramp_plan_change for a core of either ramp arithmetic, exactly like Python's plan_change(..., prescale, ramp);
 * stepramp_plan_change is this function with STEPRAMP_RAMP_AVR446.
 *
 * In exact mode (STEPRAMP_RAMP_EXACT) the head's accel_seed is the ramp constant of f_tick sqrt(2 / a) (up head) or
 * f_tick sqrt(2 / d) (down head) and c_first has no deficit; decel_seed is the ramp constant of cd0 whenever the
 * segment has an interval (also an endless one); an endless segment's c_sd is the first interval of a soft stop in
 * its cruise; the speed limit is STEPRAMP_MIN_INTERVAL_CLKS_EXACT clocks; the move back is planned in exact mode too.
 *
 * @param ramp STEPRAMP_RAMP_AVR446 or STEPRAMP_RAMP_EXACT: the core's G_RAMP; out->segment.ramp (and out->back.ramp)
 *             hold it
 * @return as stepramp_plan_change; STEPRAMP_ERAMP (checked first, after out's NULL check) for another ramp;
 *         STEPRAMP_EOVERFLOW also for a ramp constant out of range (stepramp_ramp_constant)
 */
int stepramp_plan_change_ramp(stepramp_change_t *out, double u, int64_t remaining, double accel, double decel,
                              double speed, double spr, double fclk, uint32_t prescale, uint32_t ramp);

/**
 * stepramp_plan_change_ramp, also filling in the unrounded register values.
 *
 * @param info output, may be NULL; like out, written only on success
 */
int stepramp_plan_change_info_ramp(stepramp_change_t *out, stepramp_change_info_t *info, double u, int64_t remaining,
                                   double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale, uint32_t ramp);

/**
 * A move from rest as a segment, like Python's Segment.of_move: head up from index 0, its intervals 1 .. N - 1,
 * the same values (and the same ramp).
 *
 * @return STEPRAMP_OK, or STEPRAMP_ENULL for a NULL pointer (seg is then not written)
 */
int stepramp_segment_of_move(stepramp_segment_t *seg, const stepramp_plan_t *plan);

/**
 * The segment registers beyond a plan's (SEGMENT .. HEAD_PROD_HI), as Segment.registers gives them (Python's dict
 * of the same names); all 0 for a move from rest to rest.
 */
typedef struct {
    uint32_t head_down;  /**< SEGMENT.HEAD_DOWN: 1 for a down head */
    uint32_t endless;    /**< SEGMENT.ENDLESS: 1 for a jog */
    uint32_t head_index; /**< HEAD_INDEX: the segment's head_index */
    uint32_t run_stop;   /**< RUN_STOP: the segment's run_stop */
    uint64_t head_prod;  /**< HEAD_PROD (48 bits): stepramp_segment_head_prod */
} stepramp_segment_regs_t;

/**
 * HEAD_PROD of a segment, like Segment.head_prod: head_index * stop_ratio (Q31.16) for an up head, saturated at
 * 2^47 (bit 47 alone), 0 for a down head (and for a NULL seg).
 */
uint64_t stepramp_segment_head_prod(const stepramp_segment_t *seg);

/**
 * A segment's registers, like Segment.registers(direction): the plan (STEPS = length + 1, or 1 for an endless
 * segment: only its sign counts; the segment's own prescale .. stop_ratio, and its ramp) and the segment registers.
 *
 * @param direction 0: position counts up, 1: down (any nonzero value is 1; Python's Plan takes 0 or 1 only)
 * @param plan      output, written only on success
 * @param regs      output, written only on success
 * @return STEPRAMP_OK; STEPRAMP_ESTEPS (nothing written) when length + 1 does not fit the 31-bit STEPS (length
 *         2^31 - 1: Python's "Plan.steps = 2147483648 does not fit"); STEPRAMP_ENULL for a NULL pointer
 */
int stepramp_segment_registers(const stepramp_segment_t *seg, uint32_t direction, stepramp_plan_t *plan,
                               stepramp_segment_regs_t *regs);

/**
 * Speed (steps/s) of a planned move's trapezoid at its pulse p (position p), like change.speed_at_pulse: the u of
 * stepramp_plan_change. 0.0 at or before pulse 0, at or after the last pulse, and for a NULL info.
 *
 * @param info the move's stepramp_plan_move_info
 */
double stepramp_speed_at_pulse(const stepramp_info_t *info, int64_t p);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_CHANGE_H */

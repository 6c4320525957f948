/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: plan a move (physical units -> the engine's register values).
 *
 * C99 port of sw/stepramp/board/plan.py, bit for bit: the same double-precision expressions in the same
 * order, the same rounding (round half to even, like Python's round()), the same checks in the same
 * order. See docs/algorithm.md for the meaning of every field.
 *
 * Two ramp arithmetics, as the core's generic G_RAMP selects: STEPRAMP_RAMP_AVR446 (G_RAMP = 0, the default; what
 * stepramp_plan_move plans for) and STEPRAMP_RAMP_EXACT (G_RAMP = 1: differences of rounded square roots,
 * docs/algorithm.md "Exact step times"; stepramp_plan_move_ramp plans for either). A plan for one mode is wrong for a
 * core built with the other.
 *
 * Freestanding-friendly (MicroBlaze standalone): no malloc, no stdio; needs <math.h> (link with -lm).
 * Build with -ffp-contract=off (no fused multiply-add) so that every double is rounded like Python's.
 * Bit-for-bit parity also assumes the same libm results for sqrt (always correctly rounded), exp, log
 * and log1p (only used by stepramp_decel_product for a decel ramp longer than 256 steps).
 */
#ifndef STEPRAMP_PLAN_H
#define STEPRAMP_PLAN_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Fraction bits of the ramp values (Q32.16). */
#define STEPRAMP_FRAC_RAMP 16
/** Fraction bits of the cruise period (Q32.32). */
#define STEPRAMP_FRAC_CRUISE 32
/** Shortest interval, in clocks, that leaves the engine time to compute the next value. */
#define STEPRAMP_MIN_INTERVAL_CLKS 64
/** The same in exact mode (G_RAMP = 1) for a move whose ramp constants are below 2^48 (c0 and cd0 below 2^20 ticks):
 * a ramp value there takes one or two square roots (plan.py's MIN_INTERVAL_CLKS_EXACT). */
#define STEPRAMP_MIN_INTERVAL_CLKS_EXACT 256
/** The same for a move with a ramp constant of 2^48 or more (plan.py's MIN_INTERVAL_CLKS_EXACT_WIDE). */
#define STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE 304
/** stepramp_plan_t.ramp: the AVR446 recurrence (the core's G_RAMP = 0, the default; plan.RAMP_AVR446). */
#define STEPRAMP_RAMP_AVR446 0u
/** stepramp_plan_t.ramp: the exact ramp, differences of rounded square roots (G_RAMP = 1; plan.RAMP_EXACT). */
#define STEPRAMP_RAMP_EXACT 1u
/** Fraction bits of the exact ramp's root (exact.FRAC_EXACT): a ramp constant is round(c0^2 * 2^(2 * 4)). */
#define STEPRAMP_FRAC_EXACT 4
/** The largest scale e of an exact-mode seed word (exact.SCALE_MAX): C = m * 4^e, m in bits 59:0, e in 63:60. */
#define STEPRAMP_EXACT_SCALE_MAX 6
/** The largest ramp constant (exact.C_MAX = 2^72 - 2^36): c0 below 2^32 ticks. */
#define STEPRAMP_EXACT_C_MAX 4722366482800925736960.0
/** Largest |steps| of one move (the steps register is 31 bits wide). */
#define STEPRAMP_MAX_STEPS INT64_C(2147483647)
/** Largest PRESCALE (the prescale register is 16 bits wide). */
#define STEPRAMP_MAX_PRESCALE UINT32_C(65535)

/**
 * The engine's inputs for one move: field by field Python's plan.Plan and the table of
 * docs/algorithm.md. c_* and the seeds are Q32.16 (< 2^48; in exact mode the seeds are 64-bit seed words), cruise is
 * Q32.32.
 */
typedef struct {
    uint32_t steps;      /**< N = |steps| (0 .. 2^31-1) */
    uint32_t direction;  /**< 0: position counts up, 1: down (steps < 0) */
    uint32_t prescale;   /**< base timer period in clocks (1 .. 65535) */
    uint64_t c_first;    /**< exact interval 1 plus half the accel recurrence deficit (exact mode: none), Q32.16 */
    uint64_t c_last;     /**< exact interval L = N-1, Q32.16 */
    uint32_t sa;         /**< accel-side boundary interval index, floor(x_a)+1 clamped to [1, L] */
    uint64_t c_sa;       /**< exact interval sa, Q32.16 */
    uint32_t sd;         /**< decel-side boundary interval index, floor(x_d)+1 clamped to [1, L] */
    uint64_t c_sd;       /**< exact interval sd, Q32.16 */
    uint64_t accel_seed; /**< accel recurrence value at index 0, Q32.16; exact mode: the seed word of the accel's
                              ramp constant round(c0^2 * 2^8) (stepramp_ramp_constant) */
    uint64_t decel_seed; /**< decel recurrence value at index m0 = L-sd-1, Q32.16; 0 when m0 < 1; exact mode: the
                              seed word of the decel's ramp constant round(cd0^2 * 2^8), also when m0 < 1 */
    uint64_t cruise;     /**< cruise period f_tick / v, Q32.32 */
    uint32_t stop_ratio; /**< accel / decel, Q16.16 (rounded, saturated): sizes a soft stop's decel ramp */
    uint32_t ramp;       /**< not a register: the ramp arithmetic the plan is for, STEPRAMP_RAMP_AVR446 or
                              STEPRAMP_RAMP_EXACT (Python's Plan.ramp) */
} stepramp_plan_t;

/**
 * Informative values of a planned move (not registers): Python's plan.MoveInfo field by field, then the
 * unrounded register values (C extras, for diagnostics and the bit-for-bit parity test with Python).
 * a, d, v are in steps/s^2 and steps/s; delays are in ticks.
 */
typedef struct {
    double f_tick;       /**< fclk / prescale, ticks per second */
    int64_t length;      /**< L = N - 1 intervals (0 for N <= 1) */
    double a;            /**< acceleration, steps/s^2 */
    double d;            /**< deceleration, steps/s^2 */
    double v;            /**< cruise speed, steps/s */
    double x_a;          /**< end of the acceleration, steps */
    double x_d;          /**< start of the deceleration, steps */
    double v_peak;       /**< peak speed (v, or the triangle's peak), steps/s */
    int triangle;        /**< 1 when the move never reaches v (also for N <= 1) */
    double c0;           /**< f_tick sqrt(2 / a) */
    double cd0;          /**< f_tick sqrt(2 / d) */
    int64_t m0;          /**< decel recurrence start index L - sd - 1 (0 for N <= 1) */
    double min_interval; /**< shortest interval f_tick / v_peak, ticks (inf for N <= 1) */
    /* C extras: the register values before rounding, in ticks (0 where the register is 0) */
    double t_first;      /**< exact interval 1, plus half the accel recurrence's deficit (exact mode: none) */
    double t_last;       /**< exact interval L */
    double t_sa;         /**< exact interval sa */
    double t_sd;         /**< exact interval sd */
    double t_accel_seed; /**< SEED_FACTOR * c0, plus half the accel deficit spread over A_1 .. A_(sa-2), less the
                              recurrence's mean truncation (plan.accel_truncation); exact mode: c0, whose ramp
                              constant the seed is */
    double t_decel_seed; /**< SEED_FACTOR * cd0 * decel_product(m0) plus half the decel deficit; 0 when m0 < 1;
                              exact mode: cd0, whose ramp constant the seed is */
    double t_cruise;     /**< f_tick / v */
} stepramp_info_t;

/**
 * Result of stepramp_plan_move. Each error corresponds to one ValueError of plan.py (the comment gives
 * the start of its message); the checks run in the same order, so both report the same first error.
 */
typedef enum {
    STEPRAMP_OK = 0,       /**< success */
    STEPRAMP_EACCEL,       /**< "accel must be finite and > 0" */
    STEPRAMP_EDECEL,       /**< "decel must be finite and > 0" */
    STEPRAMP_ESPEED,       /**< "speed must be finite and > 0" */
    STEPRAMP_ESPR,         /**< "spr must be finite and > 0" */
    STEPRAMP_EFCLK,        /**< "fclk must be finite and > 0" */
    STEPRAMP_EPRESCALE,    /**< "prescale must be an integer in 1 .. 65535" */
    STEPRAMP_ESTEPS,       /**< "|steps| must be <= 2^31 - 1" */
    STEPRAMP_EOVERFLOW,    /**< "<field> = ... ticks overflows its register": a delay >= 2^32 ticks; in exact mode
                                also "exact ramp: c0 = ... gives a ramp constant outside 1 .. 2^72 - 2^36" (c0 or cd0
                                of 2^32 ticks or more, or below 1/32 tick: stepramp_ramp_constant) */
    STEPRAMP_ETICK,        /**< "interval shorter than 1 tick" at the peak speed */
    STEPRAMP_ETOOFAST,     /**< "speed too high for the hardware to compute the next delay in time" */
    STEPRAMP_EACCEL_UNITS, /**< "accel in steps units is out of range" (0 or inf after / (2 pi / spr)) */
    STEPRAMP_EDECEL_UNITS, /**< "decel in steps units is out of range" */
    STEPRAMP_ESPEED_UNITS, /**< "speed in steps units is out of range" */
    STEPRAMP_EFTICK,       /**< "f_tick in steps units is out of range" (fclk / prescale underflows) */
    STEPRAMP_EPEAK,        /**< "peak speed underflows: the delays would overflow their registers" */
    STEPRAMP_ENULL,        /**< plan is a NULL pointer (no Python counterpart) */
    STEPRAMP_ERAMP         /**< "ramp must be 0 (avr446) or 1 (exact)": neither STEPRAMP_RAMP_AVR446 nor _EXACT */
} stepramp_err_t;

/**
 * The results of stepramp_plan_change (stepramp_change.h) and stepramp_plan_coordinated (stepramp_coord.h) beyond
 * stepramp_err_t, which stays plan.py's errors one to one: the ValueErrors that change.py and coord.py add. Values
 * 32 .. 63, between stepramp_err_t and the driver's results (stepramp.h); stepramp_strerror names them too.
 */
enum {
    STEPRAMP_ECHANGE_SPEED = 32, /**< "the speed at the change must be finite and >= 0" */
    STEPRAMP_EREMAINING = 33,    /**< "remaining must be in 0 .. 2^31 - 1 steps" */
    STEPRAMP_ESEGMENT = 34,      /**< a step count of the segment does not fit 31 bits: "the stop distance from the
                                      speed at the change is ... more than 2^31 - 1", "the stop from the jog speed
                                      ...", "the accel ramp's index at the speed at the change ... does not fit 31
                                      bits", or "Segment.<field> = ... does not fit" (a negative register value) */
    STEPRAMP_ECOORD_AXES = 35,   /**< stepramp_plan_coordinated (stepramp_coord.h): "no axes" or "... axes: at most 8
                                      axes are coordinated" */
    STEPRAMP_ECOORD_ZERO = 36,   /**< stepramp_plan_coordinated: "every axis has 0 steps" */
    STEPRAMP_ECOORD_END = 37,    /**< stepramp_plan_coordinated: an axis's last interval, set to end with the path,
                                      "would be ... shorter than the move's shortest interval" (not expected) */
    STEPRAMP_ECOORD_LONG = 38    /**< stepramp_plan_coordinated: "the path lasts ... ticks, 2^48 or more" */
};

/**
 * Plan a move for an AVR446 core (G_RAMP = 0), exactly like Python's stepramp.board.plan.plan_move (ramp
 * RAMP_AVR446; plan->ramp is STEPRAMP_RAMP_AVR446). stepramp_plan_move_ramp plans for either core.
 *
 * @param plan     output; written only on success (left untouched on error)
 * @param steps    signed step count; its sign gives the direction; |steps| <= 2^31 - 1
 * @param accel    acceleration, rad/s^2 (finite, > 0)
 * @param decel    deceleration, rad/s^2 (finite, > 0)
 * @param speed    cruise speed, rad/s (finite, > 0)
 * @param spr      steps per revolution (finite, > 0)
 * @param fclk     engine clock frequency, Hz (finite, > 0)
 * @param prescale base timer period in clocks, 1 .. 65535
 * @return STEPRAMP_OK, or the first failed check (in plan.py's order). For N = |steps| <= 1 every ramp
 *         field and cruise are 0 and the speed limits are not checked.
 */
stepramp_err_t stepramp_plan_move(stepramp_plan_t *plan, int64_t steps, double accel, double decel, double speed,
                                  double spr, double fclk, uint32_t prescale);

/**
 * Like stepramp_plan_move, also filling in the informative values (Python's plan_move_info).
 *
 * @param info output, may be NULL; like plan, written only on success
 */
stepramp_err_t stepramp_plan_move_info(stepramp_plan_t *plan, stepramp_info_t *info, int64_t steps, double accel,
                                       double decel, double speed, double spr, double fclk, uint32_t prescale);

/**
 * stepramp_plan_move for a core of either ramp arithmetic, exactly like Python's plan_move(..., prescale, ramp).
 * stepramp_plan_move is this function with STEPRAMP_RAMP_AVR446.
 *
 * In exact mode (STEPRAMP_RAMP_EXACT) c_first, c_last, c_sa and c_sd are the exact intervals without the recurrence
 * deficit, accel_seed and decel_seed the ramp constants of c0 and cd0 (stepramp_ramp_constant; decel_seed also when
 * m0 < 1), cruise and stop_ratio as in AVR446 mode, and the speed limit is STEPRAMP_MIN_INTERVAL_CLKS_EXACT clocks
 * (STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE when a ramp constant is 2^48 or more).
 *
 * @param ramp STEPRAMP_RAMP_AVR446 or STEPRAMP_RAMP_EXACT: the core's G_RAMP; plan->ramp holds it
 * @return as stepramp_plan_move; STEPRAMP_ERAMP (checked first, after plan's NULL check) for another ramp;
 *         STEPRAMP_EOVERFLOW also for a ramp constant out of range (exact mode)
 */
stepramp_err_t stepramp_plan_move_ramp(stepramp_plan_t *plan, int64_t steps, double accel, double decel, double speed,
                                       double spr, double fclk, uint32_t prescale, uint32_t ramp);

/**
 * stepramp_plan_move_ramp, also filling in the informative values (Python's plan_move_info(..., ramp)).
 *
 * @param info output, may be NULL; like plan, written only on success
 */
stepramp_err_t stepramp_plan_move_info_ramp(stepramp_plan_t *plan, stepramp_info_t *info, int64_t steps,
                                            double accel, double decel, double speed, double spr, double fclk,
                                            uint32_t prescale, uint32_t ramp);

/**
 * The exact ramp's constant C = round(c0^2 * 2^(2 * STEPRAMP_FRAC_EXACT)) of a ramp whose first interval from rest is
 * c0 ticks, as its seed word: C = m * 4^e, the mantissa m in bits 59:0 and the scale e (0 .. 6, the smallest whose m
 * is below 2^60) in bits 63:60 (Python's stepramp.models.exact.ramp_constant: the same double c0 * c0 * 256, rounded
 * half to even, and divided by 4^e).
 *
 * @param constant output, written only on success
 * @return STEPRAMP_OK; STEPRAMP_EOVERFLOW when C is not in 1 .. 2^72 - 2^36 (c0 of 2^32 ticks or more: raise the
 *         prescale; or below about 0.044 ticks), also for a c0 whose square is not finite or NaN; STEPRAMP_ENULL for
 *         a NULL constant
 */
stepramp_err_t stepramp_ramp_constant(double c0_ticks, uint64_t *constant);

/**
 * The reason for an error in words, like plan.py's (and change.py's) ValueError messages without the numbers.
 *
 * @param err a stepramp_err_t, or a result of stepramp_plan_change or stepramp_plan_coordinated (STEPRAMP_ECHANGE_SPEED
 *            .. STEPRAMP_ECOORD_LONG, cast)
 * @return a static string; "success" for STEPRAMP_OK, "unknown error" for a value that is none of these
 */
const char *stepramp_strerror(stepramp_err_t err);

/**
 * prod_{k=1..m} (4k-1)/(4k+1) = Gamma(m+3/4) Gamma(5/4) / (Gamma(m+5/4) Gamma(3/4)), like plan.decel_product:
 * the plain product for m <= 256, above it a Stirling series without cancellation (about 1e-14 relative).
 * 1.0 for m <= 0.
 */
double stepramp_decel_product(int64_t m);

/** Gamma(3/4) / (2 Gamma(5/4)) = 0.67597824...: the same double as plan.SEED_FACTOR. */
extern const double stepramp_seed_factor;

/** lgamma(5/4) - lgamma(3/4): the same double as plan._LGAMMA_RATIO_0 (CPython's own lgamma, not libm's). */
extern const double stepramp_lgamma_ratio_0;

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_PLAN_H */

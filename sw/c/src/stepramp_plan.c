/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: plan a move. A line-by-line port of sw/stepramp/board/plan.py (the reference): every double
 * expression keeps Python's operand order, Python's round() (half to even) is rint() in the default
 * rounding mode, math.floor is floor(), and Python's min()/max() are mirrored including their choice of
 * operand, so the register values are identical bit for bit. Compile with -ffp-contract=off. The exact mode's ramp
 * constant (sw/stepramp/models/exact.py, ramp_constant) is here too.
 */
#include "stepramp_plan.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "stepramp_plan_priv.h"

/*
 * CPython computes math.gamma / math.lgamma with its own Lanczos code, whose last bit differs from libm's
 * (glibc gives 0.6759782400672848 and -0.3015527878531085). So the two constants are literals: 17
 * significant digits of plan.SEED_FACTOR (0x1.5a19d1e3cb126p-1) and plan._LGAMMA_RATIO_0
 * (-0x1.34ca4107630b8p-2), which read back as exactly those doubles (checked by sw/tests/test_c_plan.py).
 */
const double stepramp_seed_factor = 0.67597824006728469;
const double stepramp_lgamma_ratio_0 = -0.30155278785310768;

#define PRODUCT_LOOP_MAX 256

/* a value that plan._check_positive (without the type checks) wants finite and > 0, and the error if it is not */
typedef struct {
    double value;
    stepramp_err_t err;
} positive_check_t;

/* the first check in the table whose value is not finite and > 0 (NaN fails), or with squares whose square is not
 * finite and > 0, gives its error; else STEPRAMP_OK */
static stepramp_err_t check_positive(const positive_check_t *checks, size_t count, int squares)
{
    size_t i;
    for (i = 0; i < count; i++) {
        double value = checks[i].value;
        if (!(isfinite(value) && value > 0.0) || (squares && !(isfinite(value * value) && value * value > 0.0))) {
            return checks[i].err;
        }
    }
    return STEPRAMP_OK;
}

/* decel_product above PRODUCT_LOOP_MAX: the Stirling series of the log ratio, from the double m */
static double decel_product_series(double m)
{
    double z1 = m + 0.75;
    double z2 = m + 1.25;
    double log_ratio = (m + 0.25) * log1p(-0.5 / z2) - 0.5 * log(z2) + 0.5;
    double zi2;
    double s1;
    double s2;

    /* series(z) = (1/12 - zi2 * (1/360 - zi2 / 1260)) / z, zi2 = 1 / (z * z) */
    zi2 = 1.0 / (z1 * z1);
    s1 = (1.0 / 12.0 - zi2 * (1.0 / 360.0 - zi2 / 1260.0)) / z1;
    zi2 = 1.0 / (z2 * z2);
    s2 = (1.0 / 12.0 - zi2 * (1.0 / 360.0 - zi2 / 1260.0)) / z2;
    return exp(log_ratio + s1 - s2 + stepramp_lgamma_ratio_0);
}

double stepramp_decel_product(int64_t m)
{
    if (m <= PRODUCT_LOOP_MAX) {
        double p = 1.0;
        int64_t k;
        for (k = 1; k <= m; k++) {
            p *= (double)(4 * k - 1) / (double)(4 * k + 1);
        }
        return p;
    }
    return decel_product_series((double)m);
}

double stepramp_priv_decel_product(double m)
{
    if (m <= (double)PRODUCT_LOOP_MAX) { /* also for a negative m: the empty product */
        return (m >= 1.0) ? stepramp_decel_product((int64_t)m) : 1.0;
    }
    return decel_product_series(m);
}

/* plan._to_fixed: round(ticks * 2^frac) below 2^width, else STEPRAMP_EOVERFLOW, also when ticks or the product is
 * not finite (a delay so long that its scaling overflows a double), as in Python. */
stepramp_err_t stepramp_priv_to_fixed(double ticks, double scale, double limit, uint64_t *out)
{
    double value;
    if (!isfinite(ticks)) {
        return STEPRAMP_EOVERFLOW;
    }
    value = rint(ticks * scale);
    if (!(value < limit)) {
        return STEPRAMP_EOVERFLOW;
    }
    *out = (uint64_t)value;
    return STEPRAMP_OK;
}

stepramp_err_t stepramp_priv_cruise(double f_tick, double v, uint64_t *out)
{
    return stepramp_priv_to_fixed(f_tick / v, TWO_POW_32, TWO_POW_64, out);
}

uint32_t stepramp_priv_stop_ratio(double accel, double decel)
{
    double ratio = accel / decel * TWO_POW_16;
    return (ratio < 4294967295.0) ? (uint32_t)rint(ratio) : UINT32_MAX;
}

double stepramp_priv_accel_truncation(int64_t n)
{
    return (double)n - (2.0 * ((double)n + 0.75) * stepramp_decel_product(n) - 1.5);
}

double stepramp_priv_decel_seed(double cd0, int64_t m0)
{
    double seed_d = stepramp_seed_factor * cd0 * stepramp_decel_product(m0);
    double unit_d = 2.0 * ((double)m0 + 0.75) - 1.5 / stepramp_decel_product(m0); /* (D_1 + .. + D_m0) / D_m0 */
    double half_d = (cd0 * (sqrt((double)m0 + 1.0) - 1.0) - seed_d * unit_d) / 2.0;
    return seed_d + half_d / unit_d;
}

stepramp_err_t stepramp_priv_check_args(double accel, double decel, double speed, double spr, double fclk,
                                        uint32_t prescale)
{
    const positive_check_t args[] = {{accel, STEPRAMP_EACCEL}, {decel, STEPRAMP_EDECEL}, {speed, STEPRAMP_ESPEED},
                                     {spr, STEPRAMP_ESPR}, {fclk, STEPRAMP_EFCLK}};
    stepramp_err_t err = check_positive(args, sizeof args / sizeof args[0], 0);
    if (err == STEPRAMP_OK && (prescale < 1 || prescale > STEPRAMP_MAX_PRESCALE)) {
        err = STEPRAMP_EPRESCALE;
    }
    return err;
}

stepramp_err_t stepramp_priv_check_units(double a, double d, double v, double f_tick, int squares)
{
    const positive_check_t units[] = {{a, STEPRAMP_EACCEL_UNITS}, {d, STEPRAMP_EDECEL_UNITS},
                                      {v, STEPRAMP_ESPEED_UNITS}, {f_tick, STEPRAMP_EFTICK}};
    return check_positive(units, sizeof units / sizeof units[0], squares);
}

/* plan._Ramp: the piecewise exact trajectory. */
typedef struct {
    int64_t length;
    int triangle;
    double x_a;
    double x_d;
    double n_d;
    double v_peak;
    double k_a;
    double k_d;
    double k_c;
} ramp_t;

static void ramp_init(ramp_t *r, int64_t length, double a, double d, double v, double f_tick)
{
    double n_a = v * v / (2.0 * a);
    double n_d = v * v / (2.0 * d);
    double x_d = (double)length - n_d;

    r->length = length;
    if (isfinite(x_d) && n_a <= x_d) {
        r->triangle = 0;
        r->x_a = n_a;
        r->x_d = x_d;
        r->n_d = n_d;
        r->v_peak = v;
    } else {
        double x_p = (double)length * (d / (a + d));
        r->triangle = 1;
        r->x_a = x_p;
        r->x_d = x_p;
        r->n_d = (double)length * (a / (a + d));
        r->v_peak = sqrt(2.0 * a * x_p);
    }
    r->k_a = f_tick * sqrt(2.0 / a); /* c0 */
    r->k_d = f_tick * sqrt(2.0 / d); /* cd0 */
    r->k_c = (r->v_peak > 0.0) ? f_tick / r->v_peak : (double)INFINITY;
}

/* _Ramp.boundary: floor(x) + 1 clamped to [1, L]. x is finite and in [0, L] here; the clamp is done in
 * doubles (exact for integers of this size) so that no value can overflow the conversion. */
static int64_t ramp_boundary(const ramp_t *r, double x)
{
    double b = floor(x) + 1.0;
    if (!(b >= 1.0)) {
        b = 1.0;
    }
    if (b > (double)r->length) {
        b = (double)r->length;
    }
    return (int64_t)b;
}

/* _Ramp.interval: exact interval i (from position i-1 to i) in ticks. */
static double ramp_interval(const ramp_t *r, int64_t i)
{
    double p = (double)(i - 1);
    double q = (double)(r->length - i);
    double ov_a = py_min(py_max(r->x_a - p, 0.0), 1.0);
    double ov_d = py_min(py_max(r->n_d - q, 0.0), 1.0);
    double ov_c = py_max(1.0 - ov_a - ov_d, 0.0);
    double t = 0.0;

    if (ov_a > 0.0) {
        t += r->k_a * ov_a / (sqrt(p + ov_a) + sqrt(p));
    }
    if (ov_c > 0.0 && !r->triangle) {
        t += r->k_c * ov_c;
    }
    if (ov_d > 0.0) {
        t += r->k_d * ov_d / (sqrt(q + ov_d) + sqrt(q));
    }
    return t;
}

stepramp_err_t stepramp_ramp_constant(double c0_ticks, uint64_t *constant)
{
    /* exact.ramp_constant: C = round(c0 * c0 * 2^8) in 1 .. 2^72 - 2^36 as the seed word m | e << 60, the smallest
     * scale e (0 .. 6) whose mantissa m = round(c0 * c0 * 2^8 / 4^e) is below 2^60 (a division by a power of two:
     * exact, as in Python); a square that is not finite or a NaN gives m = 0 and fails the range check */
    double scaled;
    double value = 0.0;
    int scale = 0;
    if (constant == NULL) {
        return STEPRAMP_ENULL;
    }
    scaled = c0_ticks * c0_ticks * (double)(1 << (2 * STEPRAMP_FRAC_EXACT));
    if (isfinite(scaled)) {
        value = rint(scaled);
        while (value >= TWO_POW_60 && scale < STEPRAMP_EXACT_SCALE_MAX) {
            scale += 1;
            value = rint(scaled / ldexp(1.0, 2 * scale));
        }
    }
    if (!(value >= 1.0 && ldexp(value, 2 * scale) <= STEPRAMP_EXACT_C_MAX)) {
        return STEPRAMP_EOVERFLOW;
    }
    *constant = ((uint64_t)scale << 60) | (uint64_t)value;
    return STEPRAMP_OK;
}

/* plan.exact_narrow: the ramp constant of c0 is below 2^48 (the same double comparison) */
static int exact_narrow(double c0_ticks)
{
    return c0_ticks * c0_ticks * 256.0 < TWO_POW_48 - 0.5;
}

uint32_t stepramp_priv_min_interval_clks(uint32_t ramp, double c0_a, double c0_d)
{
    if (ramp != STEPRAMP_RAMP_EXACT) {
        return STEPRAMP_MIN_INTERVAL_CLKS;
    }
    return (exact_narrow(c0_a) && exact_narrow(c0_d)) ? STEPRAMP_MIN_INTERVAL_CLKS_EXACT
                                                      : STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE;
}

/* The four interval fields of a plan from the info's exact intervals (Q32.16), in the order Python evaluates them
 * (the first overflow wins: EOVERFLOW) */
static stepramp_err_t interval_fields(stepramp_plan_t *out, const stepramp_info_t *inf)
{
    stepramp_err_t err = stepramp_priv_to_fixed(inf->t_first, TWO_POW_16, TWO_POW_48, &out->c_first);

    if (err == STEPRAMP_OK) {
        err = stepramp_priv_to_fixed(inf->t_last, TWO_POW_16, TWO_POW_48, &out->c_last);
    }
    if (err == STEPRAMP_OK) {
        err = stepramp_priv_to_fixed(inf->t_sa, TWO_POW_16, TWO_POW_48, &out->c_sa);
    }
    if (err == STEPRAMP_OK) {
        err = stepramp_priv_to_fixed(inf->t_sd, TWO_POW_16, TWO_POW_48, &out->c_sd);
    }
    return err;
}

/* plan._exact_plan: the exact intervals without the recurrence deficit, the ramp constants of c0 and cd0 in the
 * seeds, in the order Python evaluates Plan's fields (the first failure wins; all are EOVERFLOW) */
static stepramp_err_t exact_fields(stepramp_plan_t *out, stepramp_info_t *inf, const ramp_t *ramp, int64_t sa,
                                   int64_t sd)
{
    stepramp_err_t err;

    inf->t_first = ramp_interval(ramp, 1);
    inf->t_last = ramp_interval(ramp, ramp->length);
    inf->t_sa = ramp_interval(ramp, sa);
    inf->t_sd = ramp_interval(ramp, sd);
    inf->t_accel_seed = ramp->k_a;
    inf->t_decel_seed = ramp->k_d;
    err = interval_fields(out, inf);
    if (err == STEPRAMP_OK) {
        err = stepramp_ramp_constant(ramp->k_a, &out->accel_seed);
    }
    if (err == STEPRAMP_OK) {
        err = stepramp_ramp_constant(ramp->k_d, &out->decel_seed);
    }
    return err;
}

/* plan.register_doubles and the Plan of an AVR446 move: exact intervals and seeds with the recurrences' time deficits
 * put back (half into each seed, the accel ramp's other half into interval 1) and the accel seed without the accel
 * recurrence's mean truncation (plan.accel_truncation), the same doubles in the same order;
 * then the fields in the order Python evaluates them (the first overflow wins; all are EOVERFLOW) */
static stepramp_err_t avr446_fields(stepramp_plan_t *out, stepramp_info_t *inf, const ramp_t *ramp, int64_t sa,
                                    int64_t sd, int64_t m0)
{
    stepramp_err_t err;
    double seed_a = stepramp_seed_factor * ramp->k_a;
    double seed_d = (m0 >= 1) ? stepramp_priv_decel_seed(ramp->k_d, m0) : 0.0;
    double first_extra = 0.0;
    int64_t n_a = sa - 2;

    if (n_a >= 1) {
        double unit_a = 2.0 * ((double)n_a + 0.75) * stepramp_decel_product(n_a) - 1.5;
        double half_a = (ramp->k_a * (sqrt((double)n_a + 1.0) - 1.0) - seed_a * unit_a) / 2.0;
        first_extra = half_a;
        seed_a = seed_a + half_a / unit_a - stepramp_priv_accel_truncation(n_a) / unit_a / TWO_POW_16;
    }
    inf->t_first = ramp_interval(ramp, 1) + first_extra;
    inf->t_last = ramp_interval(ramp, ramp->length);
    inf->t_sa = ramp_interval(ramp, sa);
    inf->t_sd = ramp_interval(ramp, sd);
    inf->t_accel_seed = seed_a;
    inf->t_decel_seed = seed_d;

    err = interval_fields(out, inf);
    if (err == STEPRAMP_OK) {
        err = stepramp_priv_to_fixed(inf->t_accel_seed, TWO_POW_16, TWO_POW_48, &out->accel_seed);
    }
    if (err == STEPRAMP_OK && m0 >= 1) {
        err = stepramp_priv_to_fixed(inf->t_decel_seed, TWO_POW_16, TWO_POW_48, &out->decel_seed);
    }
    return err;
}

stepramp_err_t stepramp_plan_move_info_ramp(stepramp_plan_t *plan, stepramp_info_t *info, int64_t steps,
                                            double accel, double decel, double speed, double spr, double fclk,
                                            uint32_t prescale, uint32_t ramp)
{
    stepramp_plan_t out;
    stepramp_info_t inf;
    ramp_t curve;
    stepramp_err_t err;
    int64_t n;
    int64_t length;
    int64_t sa;
    int64_t sd;
    int64_t m0;
    double f_tick;
    double alpha;
    double a;
    double d;
    double v;
    double min_interval;

    if (plan == NULL) {
        return STEPRAMP_ENULL;
    }
    if (ramp != STEPRAMP_RAMP_AVR446 && ramp != STEPRAMP_RAMP_EXACT) { /* check_ramp, plan_move_info's first */
        return STEPRAMP_ERAMP;
    }
    err = stepramp_priv_check_args(accel, decel, speed, spr, fclk, prescale); /* in plan_move_info's order */
    if (err != STEPRAMP_OK) {
        return err;
    }
    if (steps > STEPRAMP_MAX_STEPS || steps < -STEPRAMP_MAX_STEPS) {
        return STEPRAMP_ESTEPS;
    }

    n = (steps < 0) ? -steps : steps;
    length = n - 1;
    f_tick = fclk / (double)prescale;
    alpha = 2.0 * STEPRAMP_PI / spr;
    a = accel / alpha;
    d = decel / alpha;
    v = speed / alpha;
    err = stepramp_priv_check_units(a, d, v, f_tick, 0); /* the same check in steps units, in plan_move_info's order */
    if (err != STEPRAMP_OK) {
        return err;
    }

    /* the Plan and MoveInfo of a move with no interval: every field not named here is 0 (0.0) */
    out = (stepramp_plan_t){.steps = (uint32_t)n, .direction = (steps < 0) ? 1u : 0u, .prescale = prescale,
                            .ramp = ramp};
    inf = (stepramp_info_t){.f_tick = f_tick, .length = (length > 0) ? length : 0, .a = a, .d = d, .v = v,
                            .triangle = 1, .min_interval = (double)INFINITY};
    if (length < 1) { /* N = 0 or 1: no interval, nothing for the engine to compute */
        *plan = out;
        if (info != NULL) {
            *info = inf;
        }
        return STEPRAMP_OK;
    }

    ramp_init(&curve, length, a, d, v, f_tick);
    min_interval = curve.k_c;
    if (!isfinite(min_interval)) {
        return STEPRAMP_EPEAK;
    }
    if (!(min_interval >= 1.0)) {
        return STEPRAMP_ETICK;
    }
    /* Python multiplies the exact integers; the double product is exact below 2^53 and rounds monotonically
     * above, so the comparison with 64 (exact mode: 256) has the same outcome. */
    if (floor(min_interval) * (double)prescale < (double)stepramp_priv_min_interval_clks(ramp, curve.k_a, curve.k_d)) {
        return STEPRAMP_ETOOFAST;
    }

    sa = ramp_boundary(&curve, curve.x_a);
    sd = ramp_boundary(&curve, curve.x_d);
    m0 = length - sd - 1;
    out.sa = (uint32_t)sa;
    out.sd = (uint32_t)sd;
    inf.x_a = curve.x_a;
    inf.x_d = curve.x_d;
    inf.v_peak = curve.v_peak;
    inf.triangle = curve.triangle;
    inf.c0 = curve.k_a;
    inf.cd0 = curve.k_d;
    inf.m0 = m0;
    inf.min_interval = min_interval;
    inf.t_cruise = f_tick / v;
    if (ramp == STEPRAMP_RAMP_EXACT) {
        err = exact_fields(&out, &inf, &curve, sa, sd);
    } else {
        err = avr446_fields(&out, &inf, &curve, sa, sd, m0);
    }
    if (err == STEPRAMP_OK) { /* plan._cruise: round(f_tick / v * 2^32) < 2^64 */
        err = stepramp_priv_cruise(f_tick, v, &out.cruise);
    }
    if (err == STEPRAMP_OK) { /* plan._stop_ratio: round(accel / decel * 2^16), saturated at 2^32 - 1 */
        out.stop_ratio = stepramp_priv_stop_ratio(accel, decel);
    }
    if (err != STEPRAMP_OK) {
        return err;
    }
    *plan = out;
    if (info != NULL) {
        *info = inf;
    }
    return STEPRAMP_OK;
}

stepramp_err_t stepramp_plan_move_info(stepramp_plan_t *plan, stepramp_info_t *info, int64_t steps, double accel,
                                       double decel, double speed, double spr, double fclk, uint32_t prescale)
{
    return stepramp_plan_move_info_ramp(plan, info, steps, accel, decel, speed, spr, fclk, prescale,
                                        STEPRAMP_RAMP_AVR446);
}

stepramp_err_t stepramp_plan_move_ramp(stepramp_plan_t *plan, int64_t steps, double accel, double decel, double speed,
                                       double spr, double fclk, uint32_t prescale, uint32_t ramp)
{
    return stepramp_plan_move_info_ramp(plan, NULL, steps, accel, decel, speed, spr, fclk, prescale, ramp);
}

stepramp_err_t stepramp_plan_move(stepramp_plan_t *plan, int64_t steps, double accel, double decel, double speed,
                                  double spr, double fclk, uint32_t prescale)
{
    return stepramp_plan_move_info_ramp(plan, NULL, steps, accel, decel, speed, spr, fclk, prescale,
                                        STEPRAMP_RAMP_AVR446);
}

const char *stepramp_strerror(stepramp_err_t err)
{
    switch ((int)err) { /* an int: the results of stepramp_plan_change and _coordinated beyond the enum too */
    case STEPRAMP_OK:
        return "success";
    case STEPRAMP_EACCEL:
        return "accel must be finite and > 0";
    case STEPRAMP_EDECEL:
        return "decel must be finite and > 0";
    case STEPRAMP_ESPEED:
        return "speed must be finite and > 0";
    case STEPRAMP_ESPR:
        return "spr must be finite and > 0";
    case STEPRAMP_EFCLK:
        return "fclk must be finite and > 0";
    case STEPRAMP_EPRESCALE:
        return "prescale must be an integer in 1 .. 65535";
    case STEPRAMP_ESTEPS:
        return "|steps| must be <= 2^31 - 1";
    case STEPRAMP_EOVERFLOW:
        return "a delay overflows its register (integer part >= 2^32 ticks): delay too long; "
               "use a larger accel/decel/speed, a lower f_clk or a larger prescale; or, in exact mode, c0 or cd0 "
               "gives a ramp constant outside 1 .. 2^72 - 2^36 (c0 must be below 2^32 ticks)";
    case STEPRAMP_ETICK:
        return "interval shorter than 1 tick at the peak speed: lower the speed or raise f_clk / lower the prescale";
    case STEPRAMP_ETOOFAST:
        return "speed too high for the hardware to compute the next delay in time: "
               "shortest interval in ticks * prescale < 64 clocks (exact mode: 256 clocks, 304 with a ramp "
               "constant of 2^48 or more)";
    case STEPRAMP_EACCEL_UNITS:
        return "accel in steps units is out of range; check spr and the units";
    case STEPRAMP_EDECEL_UNITS:
        return "decel in steps units is out of range; check spr and the units";
    case STEPRAMP_ESPEED_UNITS:
        return "speed in steps units is out of range; check spr and the units";
    case STEPRAMP_EFTICK:
        return "f_tick in steps units is out of range; check spr and the units";
    case STEPRAMP_EPEAK:
        return "peak speed underflows: the delays would overflow their registers";
    case STEPRAMP_ENULL:
        return "plan is a NULL pointer";
    case STEPRAMP_ERAMP:
        return "ramp must be 0 (avr446) or 1 (exact): STEPRAMP_RAMP_AVR446 or STEPRAMP_RAMP_EXACT";
    case STEPRAMP_ECHANGE_SPEED:
        return "the speed at the change must be finite and >= 0";
    case STEPRAMP_EREMAINING:
        return "remaining must be in 0 .. 2^31 - 1 steps (or STEPRAMP_ENDLESS)";
    case STEPRAMP_ESEGMENT:
        return "a step count of the segment is more than 2^31 - 1 (does not fit 31 bits): the stop distance from the "
               "speed at the change, the stop from the jog speed or the accel ramp's index at the speed at the change; "
               "or a Segment.<field> does not fit its register";
    case STEPRAMP_ECOORD_AXES:
        return "no axes, or more than 8 axes: at most 8 axes are coordinated";
    case STEPRAMP_ECOORD_ZERO:
        return "every axis has 0 steps: there is no move to coordinate";
    case STEPRAMP_ECOORD_END:
        return "an axis's last interval, set to end with the path, would be shorter than the move's shortest interval";
    case STEPRAMP_ECOORD_LONG:
        return "the path lasts 2^48 ticks or more: too long to put the axes' ends on one tick; use a larger prescale";
    default:
        return "unknown error";
    }
}

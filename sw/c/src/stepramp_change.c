/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: a change while moving. A line-by-line port of sw/stepramp/board/change.py (the reference), in
 * the manner of stepramp_plan.c: every double expression keeps Python's operand order, round() is rint() (half to
 * even in the default rounding mode), math.floor / math.ceil are floor() / ceil(), min() / max() are py_min() /
 * py_max(). Compile with -ffp-contract=off.
 *
 * change.py's ramp indices (k, n0) are Python ints of any size; here they are integer-valued doubles, and every
 * integer expression of them is one double operation on exact operands, so it rounds to the same double as
 * Python's float() of the exact integer (decel_product of a large index uses only that double).
 *
 * change.py checks a, d, v and f_tick in steps units (finite, > 0, the square finite) and every step count it
 * derives (the stop distance, the up head's index, a jog's run_stop: below 2^31) before it rounds them. Where it
 * still fails with an arithmetic exception rather than a ValueError (a division by zero, math.floor or round of an
 * infinite double: sw/tests/test_c_change.py lists these inputs as change.py's crashes), this port does not mirror
 * the crash: it takes the double the expression gives (inf) and goes on, so that the next check decides. round(inf)
 * is an index of 2^31 or more (STEPRAMP_ESEGMENT); floor(inf) of the positioning cap is no cap; an infinite shortest
 * interval passes the speed check; a zero speed over a step gives an infinite interval or cruise period, which
 * overflows its register (STEPRAMP_EOVERFLOW, as plan._to_fixed and plan._cruise say of any non-finite value).
 */
#include "stepramp_change.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "stepramp_plan_priv.h"

#define MAX_STEPS_D 2147483647.0
#define TWO_POW_31 2147483648.0
#define HEAD_PROD_MAX (UINT64_C(1) << 47) /* HEAD_PROD saturates at bit 47 alone */
#define MAX_PIECES 3 /* a head, the cruise, the final decel */

/* what plan_change derives from its arguments before it plans */
typedef struct {
    uint32_t ramp;
    uint32_t prescale;
    double f_tick;
    double a;
    double d;
    double v;
} change_args_t;

/* change._Profile: pieces where the squared speed is linear in the position x (counted from pulse P) */
typedef struct {
    double x_start;
    double x_end;
    double s0;
    double slope;
} piece_t;

typedef struct {
    double f_tick;
    int count;
    piece_t pieces[MAX_PIECES];
} profile_t;

/* _Profile.add: s^2(x) = s0 + slope * x on [x_start, x_end], kept only when x_end > x_start */
static void profile_add(profile_t *prof, double x_start, double x_end, double s0, double slope)
{
    if (x_end > x_start && prof->count < MAX_PIECES) {
        piece_t *piece = &prof->pieces[prof->count++];
        piece->x_start = x_start;
        piece->x_end = x_end;
        piece->s0 = s0;
        piece->slope = slope;
    }
}

/* _Profile.interval: exact interval i in ticks; a zero speed over a whole stretch (s1 + s2 == 0, Python's
 * ZeroDivisionError) makes it inf */
static double profile_interval(const profile_t *prof, int64_t i)
{
    double sum = 0.0;
    int j;
    for (j = 0; j < prof->count; j++) {
        const piece_t *piece = &prof->pieces[j];
        double x1 = py_max(piece->x_start, (double)i - 1.0);
        double x2 = py_min(piece->x_end, (double)i);
        if (x2 > x1) {
            double s1 = sqrt(py_max(piece->s0 + piece->slope * x1, 0.0));
            double s2 = sqrt(py_max(piece->s0 + piece->slope * x2, 0.0));
            sum += 2.0 * (x2 - x1) / (s1 + s2);
        }
    }
    return sum * prof->f_tick;
}

/* _sum_products: P(lo + 1) + .. + P(hi), P = decel_product; S(n) = 2 (n + 3/4) P(n) - 3/2 telescopes */
static double sum_products(double lo, double hi)
{
    double s_hi = 2.0 * (hi + 0.75) * stepramp_priv_decel_product(hi) - 1.5;
    double s_lo = 2.0 * (lo + 0.75) * stepramp_priv_decel_product(lo) - 1.5;
    return s_hi - s_lo;
}

/* change._steps: a step count x below 2^31 rounded down (up: rounded up) into *out, else STEPRAMP_ESEGMENT */
static int steps_31(double x, int up, double *out)
{
    if (!(x < TWO_POW_31)) {
        return STEPRAMP_ESEGMENT;
    }
    *out = up ? ceil(x) : floor(x);
    return STEPRAMP_OK;
}

/* plan_change's boundary(x): min(max(floor(min(x, last)) + 1, 1), last). x is never NaN nor -inf here (math.floor
 * would raise); the clamp to 1 would take them. */
static int64_t boundary(double x, double last)
{
    double b = floor(py_min(x, last)) + 1.0;
    if (!(b >= 1.0)) {
        b = 1.0;
    }
    return (int64_t)py_min(b, last);
}

/* _check_speed: the shortest interval, f_tick / fastest, must leave the engine its MIN_INTERVAL_CLKS (exact mode:
 * MIN_INTERVAL_CLKS_EXACT); an infinite one (a zero or underflowing speed, math.floor's OverflowError in change.py)
 * passes */
static int check_speed(double f_tick, double fastest, uint32_t prescale, uint32_t ramp, double a, double d)
{
    double shortest = (fastest > 0.0) ? f_tick / fastest : (double)INFINITY;
    if (!(shortest >= 1.0)) {
        return STEPRAMP_ETOOFAST;
    }
    /* Python multiplies the exact integers; the double product rounds monotonically: the same outcome */
    if (floor(shortest) * (double)prescale <
        (double)stepramp_priv_min_interval_clks(ramp, f_tick * sqrt(2.0 / a), f_tick * sqrt(2.0 / d))) {
        return STEPRAMP_ETOOFAST;
    }
    return STEPRAMP_OK;
}

/* _to_fixed of a ramp value (kept in *raw) into a segment field; Python returns a negative value (and Segment refuses
 * it later, which *negative records) */
static int seg_fixed(double ticks, double *raw, uint64_t *out, int *negative)
{
    double scaled = ticks * TWO_POW_16;
    *raw = ticks;
    if (isfinite(scaled) && rint(scaled) < 0.0) {
        *negative = 1;
        return STEPRAMP_OK;
    }
    return stepramp_priv_to_fixed(ticks, TWO_POW_16, TWO_POW_48, out);
}

/* _run_stop_first: interval 1 of an exact-mode soft stop in a jog's cruise at sqrt(peak2), in ticks: m =
 * ceil(peak2 / 2d) steps, the cruise for m - peak2 / 2d of a step, then the decel at d to rest at step m */
static int run_stop_first(double peak2, double d, double f_tick, double *out)
{
    profile_t prof = {0};
    double n_d = peak2 / (2.0 * d);
    double m;
    int err = steps_31(n_d, 1, &m);

    if (err != STEPRAMP_OK) {
        return err;
    }
    prof.f_tick = f_tick;
    profile_add(&prof, 0.0, m - n_d, peak2, 0.0);
    profile_add(&prof, m - n_d, m, 2.0 * d * m, -2.0 * d); /* the squared speed s0 + slope x is 0 at x = m */
    *out = profile_interval(&prof, 1);
    return STEPRAMP_OK;
}

/* _fields: c_first, c_last, c_sa, c_sd and decel_seed (the final ramp's, half its deficit put back as in a move; in
 * exact mode the ramp constant of cd0, which a soft stop needs even where the segment has no final ramp); length
 * STEPRAMP_ENDLESS: c_last is cd0, the last step of a soft stop, and in exact mode c_sd the first interval of a soft
 * stop in the cruise at sqrt(peak2) */
static int seg_fields(stepramp_segment_t *seg, stepramp_change_info_t *raw, const profile_t *prof, int64_t length,
                      int64_t sa, int64_t sd, double d, double t_first, uint32_t ramp, double peak2, int *negative)
{
    int err;
    int64_t m0 = length - sd - 1;
    double cd0;

    seg->c_first = seg->c_last = seg->c_sa = seg->c_sd = seg->decel_seed = 0;
    if (length != STEPRAMP_ENDLESS && length < 1) {
        return STEPRAMP_OK;
    }
    cd0 = prof->f_tick * sqrt(2.0 / d);
    err = seg_fixed(t_first, &raw->t_first, &seg->c_first, negative);
    if (err == STEPRAMP_OK) {
        err = seg_fixed(profile_interval(prof, sa), &raw->t_sa, &seg->c_sa, negative);
    }
    if (err == STEPRAMP_OK && ramp == STEPRAMP_RAMP_EXACT) {
        raw->t_decel_seed = cd0;
        err = stepramp_ramp_constant(cd0, &seg->decel_seed);
    }
    if (err != STEPRAMP_OK) {
        return err;
    }
    if (length == STEPRAMP_ENDLESS) {
        err = seg_fixed(cd0, &raw->t_last, &seg->c_last, negative);
        if (err == STEPRAMP_OK && ramp == STEPRAMP_RAMP_EXACT) {
            double first = 0.0;
            err = run_stop_first(peak2, d, prof->f_tick, &first);
            if (err == STEPRAMP_OK) {
                err = seg_fixed(first, &raw->t_sd, &seg->c_sd, negative);
            }
        }
        return err;
    }
    err = seg_fixed(profile_interval(prof, length), &raw->t_last, &seg->c_last, negative);
    if (err == STEPRAMP_OK) {
        err = seg_fixed(profile_interval(prof, sd), &raw->t_sd, &seg->c_sd, negative);
    }
    if (err == STEPRAMP_OK && m0 >= 1 && ramp == STEPRAMP_RAMP_AVR446) {
        double seed_d = stepramp_priv_decel_seed(cd0, m0);
        err = seg_fixed(seed_d, &raw->t_decel_seed, &seg->decel_seed, negative);
    }
    return err;
}

/* Segment.__post_init__: the fields that may not fit their 31-bit registers (length, head_index, run_stop, exact
 * integers in doubles) or came out negative; then they are stored */
static int seg_fit(stepramp_segment_t *seg, double length, double head_index, double run_stop, int negative)
{
    if (negative || length > MAX_STEPS_D || head_index > MAX_STEPS_D || run_stop > MAX_STEPS_D) {
        return STEPRAMP_ESEGMENT;
    }
    seg->length = (uint32_t)length;
    seg->head_index = (uint32_t)head_index;
    seg->run_stop = (uint32_t)run_stop;
    return STEPRAMP_OK;
}

/* _stop_segment: a decel at d to rest k steps ahead (0 <= k < 2^31): no head, the decel ramp of a move */
static int stop_segment(stepramp_segment_t *seg, stepramp_change_info_t *raw, int64_t k, const change_args_t *args)
{
    profile_t prof = {0};
    int negative = 0;
    int err;

    prof.f_tick = args->f_tick;
    profile_add(&prof, 0.0, (double)k, 2.0 * args->d * (double)k, -2.0 * args->d);
    err = seg_fields(seg, raw, &prof, k, 1, 1, args->d, (k >= 1) ? profile_interval(&prof, 1) : 0.0, args->ramp, 0.0,
                     &negative);
    seg->sa = seg->sd = (k >= 1) ? 1u : 0u;
    seg->head = STEPRAMP_HEAD_UP;
    seg->ramp = args->ramp;
    return (err == STEPRAMP_OK) ? seg_fit(seg, (double)k, 0.0, 0.0, negative) : err;
}

/*
 * The head's seed (an up head's without its recurrence's mean truncation) and the half of its recurrence deficit
 * that goes into interval 1 (plan_change's head == UP /
 * DOWN branches): *seed and *t_first updated. index: n0 (up) or K (down); n = sa - 2 recurrence intervals.
 */
static void head_seed(uint32_t head, double index, int64_t n, const change_args_t *args, double *seed,
                      double *t_first)
{
    double nd = (double)n;
    double c0;
    double unit = 0.0;
    double half = 0.0;
    double trunc = 0.0;

    if (head == STEPRAMP_HEAD_UP) {
        c0 = args->f_tick * sqrt(2.0 / args->a);
        *seed = stepramp_seed_factor * c0 * stepramp_priv_decel_product(index);
        if (n >= 1) { /* A_{n0+1} .. A_{n0+n} against the ideal from virtual position n0 + 1 to n0 + n + 1 */
            unit = sum_products(index, index + nd) / stepramp_priv_decel_product(index);
            half = (c0 * (sqrt(index + nd + 1.0) - sqrt(index + 1.0)) - *seed * unit) / 2.0;
            /* the integer recurrence's mean truncation from index n0 with r = 0 (change.py's doubles) */
            trunc = nd - (2.0 * index + 3.0) / (4.0 * index + 3.0) * unit;
        }
    } else {
        c0 = args->f_tick * sqrt(2.0 / args->d); /* cd0 */
        *seed = stepramp_seed_factor * c0 * stepramp_priv_decel_product((index - 2.0 > 0.0) ? index - 2.0 : 0.0);
        if (n >= 1) { /* D_{K-2} .. D_{K-1-n} against the ideal from K - 1 to K - 1 - n steps before the rest
                       * (n <= K - 1: sa - 1 <= floor(x_h) <= K) */
            unit = sum_products(index - (2.0 + nd), index - 2.0) / stepramp_priv_decel_product(index - 2.0);
            half = (c0 * (sqrt(index - 1.0) - sqrt(index - 1.0 - nd)) - *seed * unit) / 2.0;
        }
    }
    if (n >= 1) { /* unit > 0: n >= 1 positive products summed (by telescoping), over a positive product */
        *t_first = *t_first + half;
        *seed = *seed + half / unit - trunc / unit / TWO_POW_16;
    }
}

/*
 * plan_change after its checks, the stop case and the target at P: the head (up from n0, or down towards the rest
 * k steps ahead), the cruise, the final decel to the target (none for remaining STEPRAMP_ENDLESS); *start2_out is
 * the snapped start speed squared.
 */
static int plan_segment(stepramp_segment_t *seg, stepramp_change_info_t *raw, double *start2_out, double u,
                        int64_t remaining, double k, const change_args_t *args)
{
    const double a = args->a;
    const double d = args->d;
    const double v = args->v;
    const int positioning = (remaining != STEPRAMP_ENDLESS);
    const double end = positioning ? (double)remaining : (double)INFINITY;
    const double cap2 = 2.0 * d * end; /* the fastest start that still stops at the target */
    profile_t prof = {0};
    uint32_t head = STEPRAMP_HEAD_UP;
    double index = 0.0;
    double x_h = 0.0;
    double start2;
    double peak2;
    double x_c;
    double v_peak;
    double t_first = 0.0;
    double seed = 0.0;
    double run_stop = 0.0;
    int64_t sa;
    int64_t sd;
    int negative = 0;
    int err;

    prof.f_tick = args->f_tick;
    if (u < v) {
        double n0 = rint(u * u / (2.0 * a)); /* round(inf) (OverflowError in change.py): inf, 2^31 or more */
        if (n0 >= TWO_POW_31) {
            return STEPRAMP_ESEGMENT; /* "the accel ramp's index at the speed at the change ... does not fit 31 bits" */
        }
        if (positioning) { /* floor(inf) (OverflowError in change.py): inf, no cap */
            n0 = py_min(n0, floor(cap2 / (2.0 * a)));
        }
        start2 = 2.0 * a * n0;
        peak2 = positioning ? py_min(v * v, 2.0 * a * d * (end + n0) / (a + d)) : v * v;
        if (start2 < peak2) { /* the head: the accel ramp of a virtual move from rest n0 steps behind P */
            index = n0;
            x_h = (peak2 - start2) / (2.0 * a);
            profile_add(&prof, 0.0, x_h, start2, 2.0 * a);
        } else { /* the snap reaches the speed: cruise from interval 1 */
            start2 = peak2 = py_min(v * v, cap2);
        }
    } else {
        start2 = 2.0 * d * k;
        peak2 = v * v;
        if (start2 > peak2) { /* the head: the decel ramp towards a virtual rest k steps ahead, down to v */
            head = STEPRAMP_HEAD_DOWN;
            index = k;
            x_h = (start2 - peak2) / (2.0 * d);
            profile_add(&prof, 0.0, x_h, start2, -2.0 * d);
        } else { /* the snap is at or below the speed: cruise at v from interval 1 */
            start2 = peak2 = py_min(v * v, cap2);
        }
    }
    x_c = end - peak2 / (2.0 * d);
    profile_add(&prof, x_h, x_c, peak2, 0.0);
    if (positioning) {
        profile_add(&prof, x_c, end, cap2, -2.0 * d);
    }
    v_peak = sqrt(peak2);
    err = check_speed(args->f_tick, py_max(v_peak, sqrt(start2)), args->prescale, args->ramp, a, d);
    if (err != STEPRAMP_OK) {
        return err;
    }
    sa = boundary(x_h, positioning ? (double)remaining : MAX_STEPS_D);
    sd = positioning ? boundary(x_c, (double)remaining) : 0;
    if (positioning && sd < sa) { /* sa <= sd for the engine's BOUNDS check (a triangle's x_h may round past x_c) */
        sd = sa;
    }
    t_first = profile_interval(&prof, 1);
    if (args->ramp == STEPRAMP_RAMP_AVR446) {
        head_seed(head, index, sa - 2, args, &seed, &t_first);
    }
    /* Segment(...): its arguments in Python's order, then __post_init__ */
    seg->endless = positioning ? 0u : 1u;
    seg->sa = (uint32_t)sa;
    seg->sd = (uint32_t)sd;
    seg->head = head;
    seg->ramp = args->ramp;
    if (args->ramp == STEPRAMP_RAMP_EXACT) { /* the head's ramp constant (a down head decelerates at d), no deficit */
        raw->t_accel_seed = args->f_tick * sqrt(2.0 / ((head == STEPRAMP_HEAD_UP) ? a : d));
        err = stepramp_ramp_constant(raw->t_accel_seed, &seg->accel_seed);
    } else {
        err = seg_fixed(seed, &raw->t_accel_seed, &seg->accel_seed, &negative);
    }
    if (err == STEPRAMP_OK) { /* plan._cruise: f_tick / v_peak (inf for a zero peak, ZeroDivisionError in Python) */
        raw->t_cruise = args->f_tick / v_peak;
        err = stepramp_priv_cruise(args->f_tick, v_peak, &seg->cruise);
    }
    if (err == STEPRAMP_OK && !positioning) { /* a soft stop in the cruise of a jog: v^2 / (2 d) rounded up */
        err = steps_31(peak2 / (2.0 * d), 1, &run_stop);
    }
    if (err == STEPRAMP_OK) {
        err = seg_fields(seg, raw, &prof, remaining, sa, sd, d, t_first, args->ramp, peak2, &negative);
    }
    if (err == STEPRAMP_OK) {
        err = seg_fit(seg, positioning ? (double)remaining : 0.0, index, run_stop, negative);
    }
    *start2_out = start2;
    return err;
}

int stepramp_plan_change_info_ramp(stepramp_change_t *out, stepramp_change_info_t *info, double u, int64_t remaining,
                                   double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale, uint32_t ramp)
{
    stepramp_change_t ch;
    stepramp_change_info_t raw = {0};
    change_args_t args;
    double alpha;
    double k = 0.0;
    double start2 = 0.0;
    int err;

    if (out == NULL) {
        return STEPRAMP_ENULL;
    }
    if (ramp != STEPRAMP_RAMP_AVR446 && ramp != STEPRAMP_RAMP_EXACT) { /* check_ramp, plan_change's first */
        return STEPRAMP_ERAMP;
    }
    /* the argument checks, in plan_change's order */
    err = stepramp_priv_check_args(accel, decel, speed, spr, fclk, prescale);
    if (err == STEPRAMP_OK && !(isfinite(u) && u >= 0.0)) {
        err = STEPRAMP_ECHANGE_SPEED;
    }
    if (err == STEPRAMP_OK && remaining != STEPRAMP_ENDLESS && (remaining < 0 || remaining > STEPRAMP_MAX_STEPS)) {
        err = STEPRAMP_EREMAINING;
    }
    if (err != STEPRAMP_OK) {
        return err;
    }
    alpha = 2.0 * STEPRAMP_PI / spr;
    args = (change_args_t){.ramp = ramp, .prescale = prescale, .f_tick = fclk / (double)prescale, .a = accel / alpha,
                           .d = decel / alpha, .v = speed / alpha};
    err = stepramp_priv_check_units(args.a, args.d, args.v, args.f_tick, 1);
    if (err == STEPRAMP_OK) { /* the decel ramp's index at u: rest k steps ahead (floored), "the stop distance" */
        err = steps_31(u * u / (2.0 * args.d), 0, &k);
    }
    if (err != STEPRAMP_OK) {
        return err;
    }
    ch = (stepramp_change_t){
        .segment = {.prescale = prescale, .stop_ratio = stepramp_priv_stop_ratio(accel, decel), .ramp = ramp}};

    if (remaining != STEPRAMP_ENDLESS && (double)remaining < k) {
        /* the target is inside the stop distance (or behind the motor): to rest k steps ahead, then back from rest;
         * the move back's error is returned as it is (change.py names it in "the target lies ... the move back") */
        err = stepramp_plan_move_ramp(&ch.back, -((int64_t)k - remaining), accel, decel, speed, spr, fclk, prescale,
                                      ramp);
        if (err == STEPRAMP_OK) {
            err = stop_segment(&ch.segment, &raw, (int64_t)k, &args);
        }
        ch.has_back = 1;
        ch.start_speed = sqrt(2.0 * args.d * k);
    } else if (remaining == 0) { /* at the target, at rest: the empty segment */
        err = stop_segment(&ch.segment, &raw, 0, &args);
        ch.start_speed = 0.0;
    } else {
        err = plan_segment(&ch.segment, &raw, &start2, u, remaining, k, &args);
        ch.start_speed = sqrt(start2);
    }
    if (err == STEPRAMP_OK) {
        *out = ch;
        if (info != NULL) {
            *info = raw;
        }
    }
    return err;
}

int stepramp_plan_change_info(stepramp_change_t *out, stepramp_change_info_t *info, double u, int64_t remaining,
                              double accel, double decel, double speed, double spr, double fclk, uint32_t prescale)
{
    return stepramp_plan_change_info_ramp(out, info, u, remaining, accel, decel, speed, spr, fclk, prescale,
                                          STEPRAMP_RAMP_AVR446);
}

int stepramp_plan_change_ramp(stepramp_change_t *out, double u, int64_t remaining, double accel, double decel,
                              double speed, double spr, double fclk, uint32_t prescale, uint32_t ramp)
{
    return stepramp_plan_change_info_ramp(out, NULL, u, remaining, accel, decel, speed, spr, fclk, prescale, ramp);
}

int stepramp_plan_change(stepramp_change_t *out, double u, int64_t remaining, double accel, double decel,
                         double speed, double spr, double fclk, uint32_t prescale)
{
    return stepramp_plan_change_info_ramp(out, NULL, u, remaining, accel, decel, speed, spr, fclk, prescale,
                                          STEPRAMP_RAMP_AVR446);
}

int stepramp_segment_of_move(stepramp_segment_t *seg, const stepramp_plan_t *plan)
{
    if (seg == NULL || plan == NULL) {
        return STEPRAMP_ENULL;
    }
    *seg = (stepramp_segment_t){.length = (plan->steps > 0u) ? plan->steps - 1u : 0u, .prescale = plan->prescale,
                                .c_first = plan->c_first, .c_last = plan->c_last, .sa = plan->sa, .c_sa = plan->c_sa,
                                .sd = plan->sd, .c_sd = plan->c_sd, .accel_seed = plan->accel_seed,
                                .decel_seed = plan->decel_seed, .cruise = plan->cruise,
                                .stop_ratio = plan->stop_ratio, .head = STEPRAMP_HEAD_UP, .ramp = plan->ramp};
    return STEPRAMP_OK;
}

uint64_t stepramp_segment_head_prod(const stepramp_segment_t *seg)
{
    uint64_t prod;
    if (seg == NULL || seg->head == STEPRAMP_HEAD_DOWN) {
        return 0u;
    }
    prod = (uint64_t)seg->head_index * seg->stop_ratio; /* < 2^64: two 32-bit factors */
    return (prod < HEAD_PROD_MAX) ? prod : HEAD_PROD_MAX;
}

int stepramp_segment_registers(const stepramp_segment_t *seg, uint32_t direction, stepramp_plan_t *plan,
                               stepramp_segment_regs_t *regs)
{
    if (seg == NULL || plan == NULL || regs == NULL) {
        return STEPRAMP_ENULL;
    }
    if (!seg->endless && seg->length >= (uint32_t)STEPRAMP_MAX_STEPS) {
        return STEPRAMP_ESTEPS;
    }
    *plan = (stepramp_plan_t){.steps = seg->endless ? 1u : seg->length + 1u, .direction = (direction != 0u) ? 1u : 0u,
                              .prescale = seg->prescale, .c_first = seg->c_first, .c_last = seg->c_last,
                              .sa = seg->sa, .c_sa = seg->c_sa, .sd = seg->sd, .c_sd = seg->c_sd,
                              .accel_seed = seg->accel_seed, .decel_seed = seg->decel_seed, .cruise = seg->cruise,
                              .stop_ratio = seg->stop_ratio, .ramp = seg->ramp};
    *regs = (stepramp_segment_regs_t){.head_down = (seg->head == STEPRAMP_HEAD_DOWN) ? 1u : 0u,
                                      .endless = seg->endless ? 1u : 0u, .head_index = seg->head_index,
                                      .run_stop = seg->run_stop, .head_prod = stepramp_segment_head_prod(seg)};
    return STEPRAMP_OK;
}

double stepramp_speed_at_pulse(const stepramp_info_t *info, int64_t p)
{
    double x;
    if (info == NULL || info->length <= 0 || p <= 0 || p >= info->length) {
        return 0.0;
    }
    x = (double)p;
    if (x <= info->x_a) {
        return sqrt(2.0 * info->a * x);
    }
    if (x <= info->x_d) {
        return info->v_peak;
    }
    return sqrt(2.0 * info->d * ((double)info->length - x));
}

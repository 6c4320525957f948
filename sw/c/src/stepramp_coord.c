/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: a coordinated linear move. A line-by-line port of sw/stepramp/board/coord.py (the reference), in
 * the manner of stepramp_plan.c: every double expression keeps Python's operand order, round() is rint() (half to
 * even in the default rounding mode), math.floor is floor(). Compile with -ffp-contract=off.
 *
 * Python's int operands become doubles here where Python converts them: an int / float or int * float converts the
 * int (exactly, every value here is below 2^53, but the cruise register: float(cruise) rounds it, as (double) does),
 * and L_i / L_lead is the correctly rounded quotient of two exact integers in both.
 */
#include "stepramp_coord.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "stepramp_plan_priv.h"

/* coord._decel_bias: the decel recurrence's mean truncation over D_(m0-1) .. D_1, Q32.16 LSB */
static double decel_bias(int64_t m0)
{
    int64_t big_m = m0 - 1;
    if (big_m < 1) {
        return 0.0;
    }
    return 2.0 * (double)m0 / (4.0 * (double)m0 - 1.0) *
               (2.0 * ((double)big_m + 0.75) - 1.5 / stepramp_decel_product(big_m)) -
           (double)big_m;
}

double stepramp_time_before_last(const stepramp_plan_t *plan)
{
    int64_t length;
    int64_t sa;
    int64_t sd;
    int64_t n;
    int64_t m0;
    int64_t cruise_count;
    double t;

    if (plan == NULL) {
        return 0.0;
    }
    length = (int64_t)plan->steps - 1;
    if (length < 2) {
        return 0.0;
    }
    sa = plan->sa;
    sd = plan->sd;
    t = (double)plan->c_first / TWO_POW_16;
    if (1 < sa && sa < length) {
        t += (double)plan->c_sa / TWO_POW_16;
    }
    if (1 < sd && sd < length && sd != sa) {
        t += (double)plan->c_sd / TWO_POW_16;
    }
    n = sa - 2;
    if (n >= 1) { /* intervals 2 .. sa - 1: A_1 .. A_n */
        double unit_a = 2.0 * ((double)n + 0.75) * stepramp_decel_product(n) - 1.5;
        t += ((double)plan->accel_seed * unit_a + stepramp_priv_accel_truncation(n)) / TWO_POW_16;
    }
    m0 = length - sd - 1;
    if (m0 >= 1) { /* intervals sd + 1 .. L - 1: D_m0 .. D_1 */
        double unit_d = 2.0 * ((double)m0 + 0.75) - 1.5 / stepramp_decel_product(m0);
        t += ((double)plan->decel_seed * unit_d + decel_bias(m0)) / TWO_POW_16;
    }
    cruise_count = sd - sa - 1;
    if (cruise_count >= 1) { /* intervals sa + 1 .. sd - 1 */
        t += (double)plan->cruise * (double)cruise_count / TWO_POW_32;
    }
    return t;
}

double stepramp_ideal_end(const stepramp_info_t *info)
{
    double t_a;
    double t_d;

    if (info == NULL || info->length < 1) {
        return 0.0;
    }
    t_a = info->v_peak / info->a;
    t_d = t_a + (info->x_d - info->x_a) / info->v_peak;
    return (t_d + info->v_peak / info->d) * info->f_tick;
}

/* coord._end_on: the last interval (rest: the plan's time_before_last) set so that
 * pulse N - 1 lies at target ticks (N >= 2), into *plan, and the interval's value before rounding into *last; the
 * plan is left alone on error */
static int end_on(stepramp_plan_t *plan, const stepramp_info_t *info, double rest, double target, double *last)
{
    int64_t length = (int64_t)plan->steps - 1;
    double t_last = target - rest;
    uint64_t value;
    stepramp_err_t err;

    if (!(t_last >= floor(info->min_interval))) { /* not expected: the end tick leaves 1/4 tick (doubles err 1/16) */
        return STEPRAMP_ECOORD_END;
    }
    err = stepramp_priv_to_fixed(t_last, TWO_POW_16, TWO_POW_48, &value);
    if (err != STEPRAMP_OK) {
        return err;
    }
    plan->c_last = value;
    if (length == 1) {
        plan->c_first = value;
    }
    if ((int64_t)plan->sa == length) {
        plan->c_sa = value;
    }
    if ((int64_t)plan->sd == length) {
        plan->c_sd = value;
    }
    *last = t_last;
    return STEPRAMP_OK;
}

int stepramp_plan_coordinated_info(stepramp_plan_t *plans, stepramp_coord_info_t *info, const int64_t *steps,
                                   uint32_t count, double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale)
{
    stepramp_plan_t out[STEPRAMP_COORD_MAX_AXES];
    stepramp_coord_info_t inf = {0};
    int64_t lengths[STEPRAMP_COORD_MAX_AXES];
    double rests[STEPRAMP_COORD_MAX_AXES];
    int64_t lead_length;
    uint32_t axis;
    uint32_t lead;
    int any_steps = 0;
    int rc;
    double target;

    if (info != NULL) {
        info->failed_axis = STEPRAMP_COORD_NO_AXIS;
    }
    if (plans == NULL || (steps == NULL && count > 0)) {
        return STEPRAMP_ENULL;
    }
    if (count < 1 || count > STEPRAMP_COORD_MAX_AXES) {
        return STEPRAMP_ECOORD_AXES;
    }
    rc = stepramp_priv_check_args(accel, decel, speed, spr, fclk, prescale);
    if (rc != STEPRAMP_OK) {
        return rc;
    }
    for (axis = 0; axis < count; axis++) {
        if (steps[axis] > STEPRAMP_MAX_STEPS || steps[axis] < -STEPRAMP_MAX_STEPS) {
            if (info != NULL) {
                info->failed_axis = axis;
            }
            return STEPRAMP_ESTEPS;
        }
        any_steps |= steps[axis] != 0;
    }
    if (!any_steps) {
        return STEPRAMP_ECOORD_ZERO;
    }

    lead = 0;
    for (axis = 0; axis < count; axis++) {
        lengths[axis] = ((steps[axis] < 0) ? -steps[axis] : steps[axis]) - 1;
        if (lengths[axis] > lengths[lead]) {
            lead = axis;
        }
    }
    lead_length = lengths[lead];
    inf.lead = lead;
    inf.count = count;
    for (axis = 0; axis < count; axis++) {
        /* 0 and 1 step: no interval, no distance (r = 0 would be no move); planned with the path's values */
        double ratio = (lengths[axis] >= 1) ? (double)lengths[axis] / (double)lead_length : 0.0;
        if (ratio > 0.0) {
            rc = stepramp_plan_move_info(&out[axis], &inf.axis[axis], steps[axis], accel * ratio, decel * ratio,
                                         speed * ratio, spr, fclk, prescale);
        } else {
            rc = stepramp_plan_move_info(&out[axis], &inf.axis[axis], steps[axis], accel, decel, speed, spr, fclk,
                                         prescale);
        }
        if (rc != STEPRAMP_OK) {
            if (info != NULL) {
                info->failed_axis = axis;
            }
            return rc;
        }
        inf.ratio[axis] = ratio;
    }

    /* the time each axis needs before its last interval (the seeds are already without the accel truncation) */
    for (axis = 0; axis < count; axis++) {
        if (out[axis].steps >= 2) {
            rests[axis] = stepramp_time_before_last(&out[axis]);
        } else {
            rests[axis] = 0.0;
        }
    }
    /* the end tick: the one nearest t_end, whose middle is 0 to 1 tick after it, or later when an axis's last interval
     * would otherwise be shorter than floor(min_interval) + 1/4: the same tick for every axis (coord.py) */
    inf.t_end = stepramp_ideal_end(&inf.axis[lead]);
    if (!(inf.t_end < STEPRAMP_COORD_MAX_END_TICKS)) {
        return STEPRAMP_ECOORD_LONG;
    }
    inf.end_tick = floor(inf.t_end + 0.5);
    for (axis = 0; axis < count; axis++) {
        if (out[axis].steps >= 2) {
            inf.end_tick = py_max(inf.end_tick, ceil(rests[axis] + floor(inf.axis[axis].min_interval) - 0.25));
        }
    }
    target = inf.end_tick + 0.5;
    for (axis = 0; axis < count; axis++) {
        if (out[axis].steps >= 2) {
            rc = end_on(&out[axis], &inf.axis[axis], rests[axis], target, &inf.last_interval[axis]);
            if (rc != STEPRAMP_OK) {
                if (info != NULL) {
                    info->failed_axis = axis;
                }
                return rc;
            }
        }
    }
    for (axis = 0; axis < count; axis++) {
        plans[axis] = out[axis];
    }
    inf.failed_axis = STEPRAMP_COORD_NO_AXIS;
    if (info != NULL) {
        *info = inf;
    }
    return STEPRAMP_OK;
}

int stepramp_plan_coordinated(stepramp_plan_t *plans, const int64_t *steps, uint32_t count, double accel,
                              double decel, double speed, double spr, double fclk, uint32_t prescale)
{
    return stepramp_plan_coordinated_info(plans, NULL, steps, count, accel, decel, speed, spr, fclk, prescale);
}

/* ceil(a / b) for a >= 0, b >= 1 (Python's -(-a // b)) */
static uint64_t ceil_div(uint64_t a, uint64_t b)
{
    return a / b + (a % b != 0u ? 1u : 0u);
}

int stepramp_plan_coordinated_stop(stepramp_coord_stop_t *out, const stepramp_plan_t *plans,
                                   const stepramp_coord_info_t *info, const uint32_t *pulses, uint32_t count,
                                   double accel, double decel, double speed, double spr, double fclk,
                                   uint32_t prescale)
{
    uint32_t i;
    uint64_t lead_len, need = 0u, rest;
    int moving[STEPRAMP_COORD_MAX_AXES];
    if (out == NULL || plans == NULL || info == NULL || pulses == NULL) {
        return STEPRAMP_ENULL;
    }
    if (count < 1u || count > STEPRAMP_COORD_MAX_AXES || info->lead >= count) {
        return STEPRAMP_ECOORD_AXES;
    }
    *out = (stepramp_coord_stop_t){0};
    out->count = count;
    out->fallback_axis = STEPRAMP_COORD_NO_AXIS;
    out->fallback_err = STEPRAMP_OK;
    lead_len = plans[info->lead].steps >= 1u ? (uint64_t)plans[info->lead].steps - 1u : 0u;
    for (i = 0; i < count; i++) {
        moving[i] = plans[i].steps >= 2u && lead_len >= 1u;
        if (moving[i]) {
            uint64_t length = (uint64_t)plans[i].steps - 1u;
            uint32_t pulse = pulses[i];
            stepramp_coord_axis_stop_t *ax = &out->axis[i];
            if (pulse == 0u || pulse >= length) {
                ax->natural = (int64_t)length;
                need = need > ceil_div((2u * length - 1u) * lead_len, 2u * length)
                           ? need
                           : ceil_div((2u * length - 1u) * lead_len, 2u * length);
            } else {
                double u = stepramp_speed_at_pulse(&info->axis[i], (int64_t)pulse);
                double stop = ceil(u * u / (2.0 * info->axis[i].d));
                uint64_t n_i;
                if (!(stop < 1099511627776.0)) {
                    stop = 1099511627776.0; /* 2^40 (Python's min(.., 1 << 40)) */
                }
                n_i = (uint64_t)pulse + (uint64_t)stop;
                ax->speed = u;
                ax->natural = (int64_t)n_i;
                need = need > ceil_div(n_i * lead_len, length) ? need : ceil_div(n_i * lead_len, length);
            }
        }
    }
    rest = lead_len < need ? lead_len : need;
    out->rest = (int64_t)rest;
    for (i = 0; i < count; i++) {
        stepramp_coord_axis_stop_t *ax = &out->axis[i];
        uint64_t length, target;
        uint32_t pulse;
        double ratio;
        int rc;
        if (!moving[i]) {
            *ax = (stepramp_coord_axis_stop_t){0};
            ax->target = plans[i].steps >= 1u ? (int64_t)plans[i].steps - 1 : 0;
            continue;
        }
        length = (uint64_t)plans[i].steps - 1u;
        target = (2u * length * rest + lead_len) / (2u * lead_len);
        pulse = pulses[i] > 0u && pulses[i] < length ? pulses[i] : 0u;
        ax->pulse = pulse;
        if (pulse == 0u || target >= length) {
            ax->target = (int64_t)length;
            continue;
        }
        ratio = info->ratio[i];
        rc = stepramp_plan_change_ramp(&ax->change, ax->speed, (int64_t)(target - pulse), accel * ratio,
                                       decel * ratio, speed * ratio, spr, fclk, prescale, plans[i].ramp);
        if (rc == STEPRAMP_OK && ax->change.has_back) {
            rc = STEPRAMP_ECOORD_END; /* (T_i >= N_i: not expected) */
        }
        if (rc != STEPRAMP_OK) {
            uint32_t j;
            ax->change = (stepramp_change_t){0};
            out->fallback_axis = i;
            out->fallback_err = rc;
            for (j = i; j < count; j++) {
                out->axis[j] = (stepramp_coord_axis_stop_t){0};
            }
            return STEPRAMP_OK;
        }
        ax->target = (int64_t)target;
        ax->has_change = 1;
    }
    return STEPRAMP_OK;
}

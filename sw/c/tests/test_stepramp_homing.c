/* SPDX-License-Identifier: MIT */
/*
 * Host tests of the homing (stepramp_homing.c) on the fake register bank, with a small model of the core and the
 * axis behind it (the bank's hook, stepramp_fakebus_set_hook): every STATUS read is one clock interval of the motion
 * in which the carriage moves one step; a switch is active on one side of a position; its filtered edge trails the
 * crossing by a delay in clocks (the filter and the bounce), so at a step of T clocks the latch takes the position
 * floor(delay / T) steps past the crossing -- the seek's latch lands inside the switch by a varying amount, the
 * release latch at the latch speed (T > delay) exactly at the first position off it. The model acts on START,
 * SOFT_STOP (a few more steps, then DONE) and HARD_STOP, a limit's own stop (LIMIT_EN: a soft stop, ERROR LIMIT),
 * refuses a START towards an active limit, and latches as INPUT_CFG selects. The expectations come from the model's
 * switch (the physics), not from the driver. Exit status 0 when every check passes.
 */
#include "stepramp_homing.h"
#include "stepramp_fakebus.h"
#include "stepramp_hostbus.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "test_check.h"

#define BASE ((uintptr_t)0x40A00000u)
#define FCLK 1e6
#define SPR 200.0
#define ALPHA (6.283185307179586 / SPR)
#define W(name) (STEPRAMP_REG_##name / 4u)

static stepramp_fakebus_t *const bus = &stepramp_fakebus;

/* the core and the axis */
static struct {
    int32_t carriage;       /* mechanical position, steps (POSITION counts the same steps from its own origin) */
    int32_t at;             /* the switch: active for carriage <= at (side -1) or >= at (side +1) */
    int side;
    uint32_t pin;           /* STEPRAMP_INPUT_* bit the switch drives */
    uint32_t delay;         /* clocks from the crossing to the filtered edge (filter + bounce) */
    int busy, jog, dir;     /* dir: +1 or -1 */
    uint32_t remaining;     /* steps left of a positioning move */
    uint32_t stopping;      /* steps left of a soft stop (0: none) */
    uint32_t stop_steps;    /* the soft stop's length in steps */
    int pending;            /* a filtered edge is on its way */
    uint32_t pending_steps; /* steps until it arrives */
    int pending_active;
    int limit_stopped;      /* the limit stopped this motion (once) */
    int error_after;        /* > 0: the motion ends with ERROR LIMIT after this many steps (an unrelated limit) */
    uint32_t starts, soft_stops, hard_stops;
    uint32_t moves;         /* motions started */
    uint32_t max_steps;     /* the longest motion so far */
    uint32_t steps;         /* steps of the current motion */
} m;

static int switch_active(int32_t pos)
{
    return m.side < 0 ? pos <= m.at : pos >= m.at;
}

static void set_status_bits(uint32_t mask, int on)
{
    if (on) {
        bus->regs[W(STATUS)] |= mask;
    } else {
        bus->regs[W(STATUS)] &= ~mask;
    }
}

static void end_motion(uint32_t err_code)
{
    m.busy = 0;
    m.stopping = 0;
    set_status_bits(STEPRAMP_STATUS_BUSY_MASK | STEPRAMP_STATUS_STATE_MASK, 0);
    set_status_bits(STEPRAMP_STATUS_DONE_MASK, 1);
    if (err_code != 0u) {
        set_status_bits(STEPRAMP_STATUS_ERROR_MASK, 1);
        bus->regs[W(STATUS)] = (bus->regs[W(STATUS)] & ~STEPRAMP_STATUS_ERR_CODE_MASK) | err_code << 8;
    }
}

/* the limit bit a motion in direction dir runs towards */
static uint32_t limit_towards(int dir)
{
    return dir < 0 ? STEPRAMP_INPUT_LIMIT_NEG : STEPRAMP_INPUT_LIMIT_POS;
}

/* the filtered edge arrives: level, event, latch, a limit's stop */
static void filtered_edge(int active)
{
    uint32_t cfg = bus->regs[W(INPUT_CFG)];
    uint32_t src = (cfg & STEPRAMP_INPUT_CFG_LATCH_SRC_MASK) >> STEPRAMP_INPUT_CFG_LATCH_SRC_SHIFT;
    uint32_t src_pin = src == 1u   ? STEPRAMP_INPUT_HOME
                       : src == 2u ? STEPRAMP_INPUT_LIMIT_NEG
                                   : STEPRAMP_INPUT_LIMIT_POS;
    int edge_on = active ? (cfg & STEPRAMP_INPUT_CFG_LATCH_ON_ACTIVE_MASK) != 0u
                         : (cfg & STEPRAMP_INPUT_CFG_LATCH_ON_RELEASE_MASK) != 0u;

    set_status_bits(m.pin << STEPRAMP_STATUS_LIMIT_NEG_SHIFT, active);
    if (active) {
        set_status_bits(m.pin << STEPRAMP_STATUS_LIMIT_NEG_EV_SHIFT, 1);
    }
    if (src != 0u && src_pin == m.pin && edge_on && !(bus->regs[W(STATUS)] & STEPRAMP_STATUS_LATCHED_MASK)) {
        bus->regs[W(LATCH_POS)] = bus->regs[W(POSITION)];
        bus->regs[W(LATCH_TIME_LO)] = m.steps; /* any time: the homing does not use it */
        set_status_bits(STEPRAMP_STATUS_LATCHED_MASK, 1);
    }
    if (active && m.busy && m.pin == limit_towards(m.dir) && (cfg & STEPRAMP_INPUT_CFG_LIMIT_EN_MASK) &&
        !m.limit_stopped) {
        m.limit_stopped = 1;
        set_status_bits(STEPRAMP_STATUS_ERROR_MASK, 1);
        bus->regs[W(STATUS)] = (bus->regs[W(STATUS)] & ~STEPRAMP_STATUS_ERR_CODE_MASK) | STEPRAMP_ERR_LIMIT << 8;
        if (m.stopping == 0u) {
            m.stopping = m.stop_steps;
        }
    }
}

/* one step of the running motion */
static void step(void)
{
    uint32_t ticks = bus->regs[W(CRUISE_HI)]; /* clocks per step at the speed the motion holds (PRESCALE 1) */
    int was = switch_active(m.carriage);

    m.carriage += m.dir;
    bus->regs[W(POSITION)] += (uint32_t)m.dir;
    m.steps++;
    if (m.steps > m.max_steps) {
        m.max_steps = m.steps;
    }
    if (m.pending) { /* the filtered edge trails the crossing by delay clocks: floor(delay / T) more steps */
        if (m.pending_steps == 0u) {
            m.pending = 0;
            filtered_edge(m.pending_active);
        } else {
            m.pending_steps--;
        }
    }
    if (switch_active(m.carriage) != was) {
        m.pending = 1;
        m.pending_active = !was;
        m.pending_steps = ticks == 0u ? 0u : m.delay / ticks;
        if (m.pending_steps == 0u) {
            m.pending = 0;
            filtered_edge(m.pending_active);
        } else {
            m.pending_steps--;
        }
    }
}

static void on_command(void)
{
    if (bus->hard_stops != m.hard_stops) {
        m.hard_stops = bus->hard_stops;
        if (m.busy) {
            end_motion(0u);
        }
    }
    if (bus->soft_stops != m.soft_stops) {
        m.soft_stops = bus->soft_stops;
        if (m.busy && m.stopping == 0u) {
            m.stopping = m.stop_steps;
        }
    }
    if (bus->starts != m.starts) {
        uint32_t steps = bus->regs[W(STEPS)];
        int dir = (steps >> 31) ? -1 : 1;
        uint32_t cfg = bus->regs[W(INPUT_CFG)];
        uint32_t levels = (bus->regs[W(STATUS)] >> STEPRAMP_STATUS_LIMIT_NEG_SHIFT) & STEPRAMP_INPUT_ALL;

        m.starts = bus->starts;
        if (m.busy) {
            return;
        }
        if ((cfg & STEPRAMP_INPUT_CFG_LIMIT_EN_MASK) && (levels & limit_towards(dir))) {
            end_motion(STEPRAMP_ERR_LIMIT); /* refused: nothing moves */
            return;
        }
        m.busy = 1;
        m.dir = dir;
        m.jog = (bus->regs[W(SEGMENT)] & STEPRAMP_SEGMENT_ENDLESS_MASK) != 0u;
        m.remaining = dir < 0 ? 0u - steps : steps;
        m.limit_stopped = 0;
        m.steps = 0u;
        m.moves++;
        set_status_bits(STEPRAMP_STATUS_BUSY_MASK, 1);
        bus->regs[W(STATUS)] = (bus->regs[W(STATUS)] & ~STEPRAMP_STATUS_DIR_MASK) |
                               (dir < 0 ? STEPRAMP_STATUS_DIR_MASK : 0u);
    }
}

/* every STATUS read is one step interval of a running motion */
static void hook(uint32_t offset, int write)
{
    if (write) {
        if (offset == STEPRAMP_REG_CTRL) {
            on_command();
        }
        return;
    }
    if (offset != STEPRAMP_REG_STATUS || !m.busy) {
        return;
    }
    step();
    if (m.error_after > 0 && (int)m.steps >= m.error_after) {
        end_motion(STEPRAMP_ERR_LIMIT);
    } else if (m.stopping > 0u) {
        if (--m.stopping == 0u) {
            end_motion(0u);
        }
    } else if (!m.jog && --m.remaining == 0u) {
        end_motion(0u);
    }
}

/* a fresh core and axis: carriage at `carriage`, POSITION at `position`, the switch, the filter */
static stepramp_t setup(int32_t carriage, int32_t position, int32_t at, int side, uint32_t pin, uint32_t delay,
                        uint32_t filter)
{
    stepramp_t dev;
    stepramp_inputs_t in = {0u, 0u, 1, 0, STEPRAMP_LATCH_NONE, 0, 0};

    stepramp_fakebus_reset(BASE, STEPRAMP_ID_VALUE);
    memset(&m, 0, sizeof m);
    m.carriage = carriage;
    m.at = at;
    m.side = side;
    m.pin = pin;
    m.delay = delay;
    m.stop_steps = 3u;
    bus->regs[W(POSITION)] = (uint32_t)position;
    set_status_bits(pin << STEPRAMP_STATUS_LIMIT_NEG_SHIFT, switch_active(carriage));
    CHECK(stepramp_init(&dev, BASE, FCLK, SPR, 1u) == STEPRAMP_OK);
    in.filter = filter;
    CHECK(stepramp_configure_inputs(&dev, &in) == STEPRAMP_OK);
    stepramp_fakebus_set_hook(hook);
    return dev;
}

/* seek at one step per 100 clocks, release at one per 500 */
static stepramp_homing_t homing(uint32_t sw, int32_t direction, int32_t offset)
{
    stepramp_homing_t h;

    h.seek_speed = ALPHA * FCLK / 100.0;
    h.seek_accel = h.seek_speed * h.seek_speed / (2.0 * 12.0 * ALPHA);
    h.latch_speed = ALPHA * FCLK / 500.0;
    h.latch_accel = h.latch_speed * h.latch_speed / (2.0 * 2.0 * ALPHA);
    h.sw = sw;
    h.direction = direction;
    h.offset = offset;
    h.settle_clocks = 300u;
    h.max_travel = 5000u;
    h.max_polls = 100000u;
    return h;
}

/* the zero in carriage steps: where POSITION reads the offset */
static int32_t zero_of(int32_t offset)
{
    return m.carriage - ((int32_t)bus->regs[W(POSITION)] - offset);
}

/* home on HOME (active for carriage <= -40) from many starts and edge delays: the zero is the first position off the
 * switch every time, the seek's latch lands inside the switch by floor(delay / 100) steps */
static void test_home_switch(void)
{
    static const int32_t starts[] = {100, 1, 0, -39, -40, -41, -75};
    static const uint32_t delays[] = {62u, 150u, 299u, 355u};
    size_t i, j;

    for (i = 0; i < sizeof starts / sizeof starts[0]; i++) {
        for (j = 0; j < sizeof delays / sizeof delays[0]; j++) {
            stepramp_t dev = setup(starts[i], 5000 - (int32_t)(i * 77u), -40, -1, STEPRAMP_INPUT_HOME, delays[j], 55u);
            stepramp_homing_t h = homing(STEPRAMP_LATCH_HOME, -1, 1000);
            stepramp_homing_result_t res;
            int32_t shift0 = m.carriage - (int32_t)bus->regs[W(POSITION)];
            int rc = stepramp_home(&dev, &h, &res);

            CHECK(rc == STEPRAMP_OK);
            if (rc != STEPRAMP_OK) {
                printf("start %d, delay %u: %s\n", (int)starts[i], (unsigned)delays[j], stepramp_strresult(rc));
                continue;
            }
            CHECK(zero_of(1000) == -39);
            CHECK(res.left_valid == (starts[i] <= -40));
            CHECK(m.moves == (res.left_valid ? 4u : 3u)); /* (leave,) seek, back, release */
            CHECK(res.seek.position + shift0 == -40 - (int32_t)(delays[j] / 100u));
            CHECK(res.release.position + shift0 == -39);
            CHECK(res.shift == 1000 - (int64_t)res.release.position);
            CHECK(res.position == (int32_t)bus->regs[W(POSITION)]);
            CHECK(!m.busy && m.carriage > -39 && m.carriage <= -39 + 3);
            CHECK(dev.input_cfg == STEPRAMP_INPUT_CFG_LIMIT_EN_MASK && bus->regs[W(INPUT_CFG)] == dev.input_cfg);
            CHECK(bus->regs[W(INPUT_FILTER)] == 55u);
            CHECK((bus->regs[W(STATUS)] & (STEPRAMP_STATUS_HOME_EV_MASK | STEPRAMP_STATUS_DONE_MASK)) == 0u);
        }
    }
}

/* the switch on the + side: the zero is its first position off it on the - side */
static void test_positive_side(void)
{
    stepramp_t dev = setup(-20, 0, 300, 1, STEPRAMP_INPUT_HOME, 120u, 40u);
    stepramp_homing_t h = homing(STEPRAMP_LATCH_HOME, 1, -7);

    CHECK(stepramp_home(&dev, &h, NULL) == STEPRAMP_OK);
    CHECK(zero_of(-7) == 299);
}

/* LIMIT_NEG used as home: the limit stops the seek itself (ERROR LIMIT, expected), the zero as with HOME; a LIMIT
 * error during a seek for HOME is an error */
static void test_limit_as_home(void)
{
    stepramp_t dev = setup(60, 0, 0, -1, STEPRAMP_INPUT_LIMIT_NEG, 200u, 60u);
    stepramp_homing_t h = homing(STEPRAMP_LATCH_LIMIT_NEG, -1, 0);
    stepramp_homing_result_t res;

    CHECK(stepramp_home(&dev, &h, &res) == STEPRAMP_OK);
    CHECK(zero_of(0) == 1);
    CHECK(m.soft_stops >= 1u);
    /* a limit on the way to HOME */
    dev = setup(60, 0, -400, -1, STEPRAMP_INPUT_HOME, 200u, 60u);
    m.error_after = 30;
    h = homing(STEPRAMP_LATCH_HOME, -1, 0);
    CHECK(stepramp_home(&dev, &h, &res) == STEPRAMP_ECORE(STEPRAMP_ERR_LIMIT));
    CHECK(!m.busy);
    CHECK(dev.input_cfg == bus->regs[W(INPUT_CFG)] && dev.input_cfg == STEPRAMP_INPUT_CFG_LIMIT_EN_MASK);
}

/* refusals: arguments (nothing read or written), the latch speed, a busy axis, the E-stop, the travel */
static void test_refusals(void)
{
    stepramp_t dev = setup(60, 0, -40, -1, STEPRAMP_INPUT_HOME, 100u, 60u);
    stepramp_homing_t h = homing(STEPRAMP_LATCH_HOME, -1, 0);
    stepramp_homing_t bad;
    double fast;

    stepramp_fakebus_clear_log();
    bad = h;
    bad.direction = 0;
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    bad = h;
    bad.sw = STEPRAMP_LATCH_LIMIT_POS; /* a limit in the other direction */
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    bad = h;
    bad.sw = STEPRAMP_LATCH_NONE;
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    bad = h;
    bad.seek_speed = -1.0;
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    bad = h;
    bad.latch_accel = NAN;
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    bad = h;
    bad.max_polls = 0u;
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_EHOMING);
    CHECK(stepramp_home(NULL, &h, NULL) == STEPRAMP_ENULL);
    CHECK(stepramp_home(&dev, NULL, NULL) == STEPRAMP_ENULL);
    /* the latch speed: a step of at least filter 60 + settle 300 + 5 = 365 clocks */
    bad = h;
    fast = ALPHA * FCLK / 365.5; /* (365.0 may round to 364.99...) */
    bad.latch_speed = fast;
    CHECK(stepramp_homing_check(&dev, &bad) == STEPRAMP_OK);
    bad.latch_speed = ALPHA * FCLK / 364.0;
    CHECK(stepramp_homing_check(&dev, &bad) == STEPRAMP_ELATCH_SPEED);
    CHECK(stepramp_home(&dev, &bad, NULL) == STEPRAMP_ELATCH_SPEED);
    CHECK(bus->writes == 0u && bus->reads == 0u);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ELATCH_SPEED), "latch speed") != NULL);
    /* busy, E-stop: one STATUS read, nothing written */
    stepramp_fakebus_set_status(STEPRAMP_STATE_RUN, 1u, 0u, 0u, 0u);
    CHECK(stepramp_home(&dev, &h, NULL) == STEPRAMP_EBUSY);
    stepramp_fakebus_set_status(STEPRAMP_STATE_STOP, 0u, 0u, 0u, 0u);
    set_status_bits(STEPRAMP_STATUS_ESTOP_FAULT_MASK, 1);
    CHECK(stepramp_home(&dev, &h, NULL) == STEPRAMP_EESTOP);
    CHECK(bus->writes == 0u && bus->status_reads == 2u);
    set_status_bits(STEPRAMP_STATUS_ESTOP_FAULT_MASK, 0);
    /* no switch within max_travel: hard-stopped */
    dev = setup(60, 0, -4000, -1, STEPRAMP_INPUT_HOME, 100u, 60u);
    h.max_travel = 200u;
    CHECK(stepramp_home(&dev, &h, NULL) == STEPRAMP_ETRAVEL);
    CHECK(m.hard_stops == 1u && !m.busy && m.max_steps <= 202u);
    CHECK(dev.input_cfg == bus->regs[W(INPUT_CFG)]);
    /* polls run out */
    dev = setup(60, 0, -4000, -1, STEPRAMP_INPUT_HOME, 100u, 60u);
    h.max_travel = 100000u;
    h.max_polls = 50u;
    CHECK(stepramp_home(&dev, &h, NULL) == STEPRAMP_ETIMEOUT);
    CHECK(strstr(stepramp_strresult(STEPRAMP_ETRAVEL), "max_travel") != NULL);
}

int main(void)
{
    test_home_switch();
    test_positive_side();
    test_limit_as_home();
    test_refusals();
    return test_report("test_stepramp_homing");
}

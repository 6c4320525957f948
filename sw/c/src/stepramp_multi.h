/* SPDX-License-Identifier: MIT */
/*
 * stepramp multi-axis driver: the C counterpart of sw/stepramp/board/multi.py (class MultiAxis), for the multi-axis
 * tops stepramp_multi_plb / stepramp_multi_axil (docs/stepramp_multi.md).
 *
 * The top holds G_AXES (1 .. 8) stepramp cores behind one slave with a 12-bit address: a global window at byte offset
 * 0x000 (ID / AXES, SYNC_START, AXES_STATUS, IRQ_MASK, SYNC_SOFT_STOP) and axis i's register window at
 * 0x100 * (i + 1). Each axis is an ordinary stepramp core, driven by stepramp.h's functions on its own stepramp_t
 * (stepramp_multi_axis); this driver adds the global window: the axis count, SYNC_START (the selected axes' pulse 0
 * on one clock edge), SYNC_SOFT_STOP (their soft stop on one clock edge), the status word, the interrupt mask, and
 * coordinated linear moves planned by stepramp_plan_coordinated (stepramp_coord.h) and started together. Register access as in stepramp.h (STEPRAMP_READ32 / STEPRAMP_WRITE32,
 * STEPRAMP_CONFIG_HEADER); the global registers are written as whole words. C99, no malloc, no stdio. Link
 * stepramp.c, stepramp_plan.c, stepramp_change.c and stepramp_coord.c with it.
 *
 *   stepramp_multi_t xyz;
 *   stepramp_plan_t plans[3];
 *   const int64_t steps[3] = {3200, -1600, 800};
 *   if (stepramp_multi_init(&xyz, XPAR_STEPRAMP_MULTI_0_BASEADDR, 50e6, 400.0 * 16, 50) != STEPRAMP_OK) { ... }
 *   rc = stepramp_multi_move_coordinated(&xyz, plans, steps, 3, 40.0, 40.0, 20.0);
 *   if (rc == STEPRAMP_OK) rc = stepramp_multi_wait_done(&xyz, stepramp_multi_started(plans, 3), 100000000u);
 *   if (rc != STEPRAMP_OK) puts(stepramp_multi_strresult(rc));
 */
#ifndef STEPRAMP_MULTI_H
#define STEPRAMP_MULTI_H

#include <stdint.h>

#include "stepramp.h"
#include "stepramp_coord.h"
#include "stepramp_plan.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The multi-axis top's map (hdl/stepramp_multi_pkg.vhd; sw/tests/test_multi.py checks the copies agree). */
#define STEPRAMP_MULTI_ADDR_BITS 12u
#define STEPRAMP_MULTI_MAX_AXES 8u
/** Bytes of each window: axis i's starts at STEPRAMP_MULTI_AXIS_WINDOW * (i + 1). */
#define STEPRAMP_MULTI_AXIS_WINDOW 0x100u
/** ID bits 31:16 ('SM') and 15:8; bits 7:0 hold G_AXES. */
#define STEPRAMP_MULTI_ID_MAGIC 0x534Du
#define STEPRAMP_MULTI_ID_VERSION 0x01u
/** Byte offsets of the global window. */
#define STEPRAMP_MULTI_REG_ID 0x000u
#define STEPRAMP_MULTI_REG_SYNC_START 0x004u
#define STEPRAMP_MULTI_REG_AXES_STATUS 0x008u
#define STEPRAMP_MULTI_REG_IRQ_MASK 0x00Cu
#define STEPRAMP_MULTI_REG_SYNC_SOFT_STOP 0x010u
/** AXES_STATUS: bit i of each field is axis i: BUSY, DONE, and the axis's irq line (before IRQ_MASK). */
#define STEPRAMP_MULTI_AXES_STATUS_BUSY_SHIFT 0u
#define STEPRAMP_MULTI_AXES_STATUS_DONE_SHIFT 8u
#define STEPRAMP_MULTI_AXES_STATUS_IRQ_SHIFT 16u

/** Results of this driver beyond stepramp.h's (values 96 .. 99 are kept for it). */
enum {
    STEPRAMP_EMULTI_ID = 96,   /**< the global ID does not hold STEPRAMP_MULTI_ID_MAGIC with 1 .. 8 axes, or an axis
                                    window holds no stepramp core */
    STEPRAMP_EMULTI_AXES = 97, /**< more plans or step counts than the top has axes, or an axis mask with a bit at or
                                    above the axis count */
    STEPRAMP_EMULTI_AXIS = 98  /**< stepramp_multi_wait_done: an axis flagged an error (failed_mask, results[]) */
};

/** One multi-axis top: its base address, axis count, and a stepramp_t per axis (set by stepramp_multi_init). */
typedef struct {
    uintptr_t base;                             /**< bus address of the top (the global window) */
    uint32_t axes;                              /**< G_AXES, from ID bits 7:0 */
    uint32_t version;                           /**< ID bits 15:8 */
    stepramp_t axis[STEPRAMP_MULTI_MAX_AXES];   /**< axis i's driver: base + 0x100 * (i + 1) */
    uint32_t failed_mask;                       /**< stepramp_multi_wait_done: the axes that flagged an error */
    int results[STEPRAMP_MULTI_MAX_AXES];       /**< stepramp_multi_wait_done: each waited axis's stepramp_wait_done
                                                     result (STEPRAMP_OK or STEPRAMP_ECORE(code)) */
} stepramp_multi_t;

/** AXES_STATUS decoded (like multi.AxesStatus): bit i of each mask is axis i. */
typedef struct {
    uint32_t raw;  /**< the word as read */
    uint32_t busy; /**< STATUS.BUSY of each axis */
    uint32_t done; /**< STATUS.DONE of each axis */
    uint32_t irq;  /**< each axis's irq line, before IRQ_MASK */
} stepramp_axes_status_t;

/**
 * Read ID, check it, and set up a stepramp_t per axis (stepramp_init at base + 0x100 * (i + 1) with fclk, spr and
 * prescale, which every axis's moves use: a coordinated move needs them shared).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_ID when ID is not a multi-axis top's (magic, 1 .. 8 axes) or an axis window's
 *         ID is not a stepramp core's; STEPRAMP_ENULL if m is NULL
 */
int stepramp_multi_init(stepramp_multi_t *m, uintptr_t base, double fclk, double spr, uint32_t prescale);

/** Axis i's driver (stepramp.h's functions on it), or NULL when i is not an axis of the top (or m is NULL). */
stepramp_t *stepramp_multi_axis(stepramp_multi_t *m, uint32_t i);

/**
 * SYNC_START: a START of every axis in mask on one clock edge, as if CTRL.START were written to each at that edge
 * (with the same refusals: a busy axis ignores it; bad STEPS, ESTOP or a limit end it with DONE and ERROR).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXES (nothing written) for a bit at or above the axis count; STEPRAMP_ENULL
 */
int stepramp_multi_sync_start(const stepramp_multi_t *m, uint32_t mask);

/**
 * SYNC_SOFT_STOP: a SOFT_STOP of every axis in mask on one clock edge, as if CTRL.SOFT_STOP were written to each at
 * that edge (Python's MultiAxis.sync_soft_stop; docs/algorithm.md, "Coordinated moves": the coordinated soft stop).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXES (nothing written) for a bit at or above the axis count; STEPRAMP_ENULL
 */
int stepramp_multi_sync_soft_stop(const stepramp_multi_t *m, uint32_t mask);

/**
 * Read AXES_STATUS.
 *
 * @param status output, may be NULL
 * @return the raw word (0 if m is NULL)
 */
uint32_t stepramp_multi_status(const stepramp_multi_t *m, stepramp_axes_status_t *status);

/**
 * IRQ_MASK: only the axes in mask reach the top's irq output (all of them after reset).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXES for a bit at or above the axis count; STEPRAMP_ENULL
 */
int stepramp_multi_set_irq_mask(const stepramp_multi_t *m, uint32_t mask);

/** IRQ_MASK as read (0 if m is NULL). */
uint32_t stepramp_multi_irq_mask(const stepramp_multi_t *m);

/**
 * Plans of a coordinated linear move, one per axis from axis 0 (stepramp_plan_coordinated_info with the axes' fclk,
 * spr and prescale; Python's MultiAxis.plan_coordinated): accel, decel (rad/s^2) and speed (rad/s) are the lead
 * axis's. Touches no register.
 *
 * @param plans output, count plans, written only on success
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXES when count exceeds the axis count; stepramp_plan_coordinated's error;
 *         STEPRAMP_EGAP when an axis's STEP width + STEP space (its min_gap) does not fit its shortest interval,
 *         floor(min_interval) * prescale clocks; STEPRAMP_ENULL
 */
int stepramp_multi_plan_coordinated(const stepramp_multi_t *m, stepramp_plan_t *plans, const int64_t *steps,
                                    uint32_t count, double accel, double decel, double speed);

/** The axes a set of plans starts: those with at least one step (an axis of 0 steps is left alone). */
uint32_t stepramp_multi_started(const stepramp_plan_t *plans, uint32_t count);

/**
 * Program plan i into axis i (stepramp_program; safe while the axes move: they latch their moves at START) for
 * every plan with steps, then one SYNC_START of those axes (Python's MultiAxis.program_sync).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXES (nothing written) when count exceeds the axis count; STEPRAMP_ENULL
 */
int stepramp_multi_program_sync(stepramp_multi_t *m, const stepramp_plan_t *plans, uint32_t count);

/**
 * Plan a coordinated linear move (stepramp_multi_plan_coordinated), program every axis and start them with one
 * SYNC_START (Python's MultiAxis.move_coordinated).
 *
 * @param plans output, count plans (wait for stepramp_multi_started(plans, count))
 * @return STEPRAMP_OK, or the plan's error -- then no register has been written
 */
int stepramp_multi_move_coordinated(stepramp_multi_t *m, stepramp_plan_t *plans, const int64_t *steps,
                                    uint32_t count, double accel, double decel, double speed);

/**
 * Poll AXES_STATUS until every axis in mask has DONE (STEPRAMP_IDLE() between polls), then stepramp_wait_done each
 * of them once (clears its flags; its result in m->results[i]).
 *
 * @return STEPRAMP_OK; STEPRAMP_EMULTI_AXIS when an axis flagged an error (m->failed_mask; every waited axis's flags
 *         are cleared); STEPRAMP_ETIMEOUT (nothing cleared) when DONE did not come within max_polls reads;
 *         STEPRAMP_EMULTI_AXES for a bit at or above the axis count; STEPRAMP_ENULL
 */
int stepramp_multi_wait_done(stepramp_multi_t *m, uint32_t mask, uint32_t max_polls);

/** Any result of this driver in words: this driver's own, else stepramp_strresult's. */
const char *stepramp_multi_strresult(int result);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_MULTI_H */

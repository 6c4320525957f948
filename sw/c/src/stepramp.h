/* SPDX-License-Identifier: MIT */
/*
 * stepramp driver: the C counterpart of sw/stepramp/board/driver.py (class StepRamp), for MicroBlaze standalone.
 *
 * The same operations with the same register semantics as the Python driver: stepramp_program writes every
 * motion register (STEPS .. STOP_RATIO) in address order, like driver.plan_writes(), and the segment registers
 * (SEGMENT .. HEAD_PROD_HI, driver.segment_writes()) unless the driver knows them to hold 0 (they are written at the
 * first program after stepramp_init and after a jog or a change); START, SOFT_STOP, HARD_STOP, CHANGE and QUEUE are
 * written to byte 0 of CTRL only, so the interrupt enables in byte 1 are kept; STATUS.DONE and STATUS.ERROR are
 * cleared by writing 1. The register map is docs/registers.md (stepramp_regs.h in C).
 *
 * C99, no malloc, no stdio. Register access goes through three macros, which stepramp.c defines to the Xilinx
 * standalone BSP's functions (and includes "xil_io.h") unless they are already defined -- on the compiler's
 * command line, or in a header named by STEPRAMP_CONFIG_HEADER (-DSTEPRAMP_CONFIG_HEADER='"my_bus.h"'):
 *
 *   STEPRAMP_READ32(addr)         default Xil_In32(addr)   32-bit read
 *   STEPRAMP_WRITE32(addr, value) default Xil_Out32(addr, value)  32-bit write, all four byte enables
 *   STEPRAMP_WRITE8(addr, value)  default Xil_Out8(addr, value)   8-bit write: one byte enable
 *
 * The CTRL commands are byte writes (STEPRAMP_WRITE8) rather than a whole word built from a shadow of the
 * interrupt enables: the driver keeps no copy of hardware state, so enables changed elsewhere (an interrupt
 * handler, a debugger) are never overwritten, exactly like the Python driver's strobe-0x1 write. The byte lane
 * that holds CTRL bits 7:0 is at byte address CTRL + STEPRAMP_CMD_BYTE_LANE: 0 on a little-endian bus (AXI
 * MicroBlaze, x86), 3 on a big-endian one (PLB MicroBlaze); the default follows the compiler's byte order
 * (__BYTE_ORDER__) and may be overridden with -DSTEPRAMP_CMD_BYTE_LANE=n. Every other access is a 32-bit word.
 *
 * Results are int: STEPRAMP_OK (0); a stepramp_err_t of stepramp_plan.h (bad move parameters, NULL pointer) or a
 * result of stepramp_plan_change (a jog's plan); one of the driver's own (STEPRAMP_EID, STEPRAMP_ETIMEOUT, ...); or
 * STEPRAMP_ECORE(code) for an error the core flagged in STATUS.ERR_CODE. stepramp_strresult() gives any of them in
 * words. Link stepramp_plan.c and stepramp_change.c with it.
 *
 *   stepramp_t motor;
 *   if (stepramp_init(&motor, XPAR_STEPRAMP_0_BASEADDR, 50e6, 400.0 * 16, 50) != STEPRAMP_OK) { ... }
 *   stepramp_enable_irq(&motor, 1, 1);
 *   rc = stepramp_move(&motor, 3200, 40.0, 40.0, 20.0);      (steps, rad/s^2, rad/s^2, rad/s)
 *   if (rc == STEPRAMP_OK) rc = stepramp_wait_done(&motor, 100000000u);
 *   if (rc != STEPRAMP_OK) puts(stepramp_strresult(rc));
 *   rc = stepramp_jog(&motor, -20.0, 40.0, 40.0);            (signed rad/s, rad/s^2, rad/s^2): until a stop
 *
 * A core built with G_RAMP = 1 (the exact ramp) needs plans in exact mode: set it up with
 * stepramp_init_ramp(&motor, base, fclk, spr, prescale, STEPRAMP_RAMP_EXACT) (Python's StepRamp(..., ramp)); every
 * move, jog and change of the driver is then planned for it (dev->ramp). stepramp_init is stepramp_init_ramp with
 * STEPRAMP_RAMP_AVR446. Either checks the core's ramp in ID bit 15 against the driver's.
 *
 * While a motion runs: stepramp_change_to(&motor, p, u, remaining, accel, decel, speed) takes a new plan over at
 * pulse p (u: the speed there, stepramp_speed_at_pulse), stepramp_queue_move(&motor, steps, ...) starts a move when
 * the running one ends.
 *
 * The machine inputs (docs/algorithm.md, "Machine inputs"): stepramp_configure_inputs (filter, polarities, limits,
 * latch), stepramp_arm_latch / stepramp_latch (the position latch), stepramp_time, stepramp_clear_events,
 * stepramp_clear_estop; homing on them is stepramp_homing.h.
 */
#ifndef STEPRAMP_H
#define STEPRAMP_H

#include <stdint.h>

#include "stepramp_change.h"
#include "stepramp_plan.h"
#include "stepramp_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

/** ID register bits 31:16 of every stepramp core ('SR'). */
#define STEPRAMP_ID_MAGIC 0x5352u
/** ID register bit 15: the core's ramp arithmetic, its G_RAMP (0: STEPRAMP_RAMP_AVR446, 1: STEPRAMP_RAMP_EXACT);
 * the version is in bits 13:0 (regmap.ID_RAMP_BIT). */
#define STEPRAMP_ID_RAMP_BIT 15u
/** ID register bit 14, NO_WINDINGS: set by a core built with G_WINDINGS false, which has no winding outputs (A1 .. B2
 * stay '0', DRIVE.MODE reads 0 and ignores writes): stepramp_configure_outputs then takes the STEP/DIR mode only
 * (regmap.ID_WINDINGS_BIT). */
#define STEPRAMP_ID_WINDINGS_BIT 14u

/** STOP_RATIO value 1.0 (Q16.16): accel equal to decel. */
#define STEPRAMP_STOP_RATIO_ONE 0x00010000u

/** Driver results beyond stepramp_err_t (whose values stay below 64). */
enum {
    STEPRAMP_EID = 64,        /**< the ID register does not hold STEPRAMP_ID_MAGIC in bits 31:16, or its bit 15 (the
                                   core's G_RAMP) is not the driver's ramp (dev->ramp) */
    STEPRAMP_ETIMEOUT = 65,   /**< stepramp_wait_done: no STATUS.DONE within max_polls reads */
    STEPRAMP_EOUTPUTS = 66,   /**< stepramp_configure_outputs: NULL, mode > 4 or ustep_log2 > 7 */
    STEPRAMP_ENOIRQ = 67,     /**< stepramp_isr: neither STATUS.DONE nor STATUS.ERROR was set (not this core) */
    STEPRAMP_EJOG_SPEED = 68, /**< stepramp_jog: the jog speed is 0, inf or NaN */
    STEPRAMP_EGAP = 69,       /**< STEP width + STEP space does not fit the shortest interval of the move, the jog or
                                   the change */
    STEPRAMP_EPULSE = 70,     /**< stepramp_change: the take-over pulse is 0 or does not fit CHANGE_AT's 31 bits */
    STEPRAMP_EREVERSE = 71,   /**< stepramp_change_to: the target lies inside the stop distance or behind the motor,
                                   the change would need a move back (SOFT_STOP + QUEUE, not a take-over) */
    STEPRAMP_EIDLE = 72,      /**< stepramp_change_to: STATUS.BUSY is 0, there is no motion to take over */
    STEPRAMP_EPENDING = 73,   /**< stepramp_change_to: STATUS.PENDING, a change or a queued move is pending (the
                                   staging registers are locked) */
    STEPRAMP_EINPUTS = 74,    /**< stepramp_configure_inputs / stepramp_arm_latch: NULL, a filter above
                                   STEPRAMP_FILTER_MAX, an unknown input bit or latch source, or a latch source with
                                   neither edge selected */
    STEPRAMP_ENOLATCH = 75,   /**< stepramp_latch: STATUS.LATCHED is 0, nothing latched since the latch was armed */
    STEPRAMP_EESTOP = 76,     /**< stepramp_clear_estop: ESTOP_FAULT still set (the ESTOP input is active);
                                   stepramp_home: the E-stop is active or its fault is set */
    STEPRAMP_EHOMING = 77,    /**< stepramp_home: an argument out of range (switch, direction, speeds, travel) */
    STEPRAMP_ELATCH_SPEED = 78, /**< stepramp_home: the latch speed is too high for an exact zero (a step must
                                     last at least filter + settle + STEPRAMP_LATCH_MARGIN clocks) */
    STEPRAMP_ETRAVEL = 79,    /**< stepramp_home: no switch edge within max_travel steps (hard-stopped) */
    STEPRAMP_EBUSY = 80,      /**< stepramp_home: the axis is moving */
    STEPRAMP_ESWITCH = 81,    /**< stepramp_home: the motion ended before the switch edge, or the switch is not
                                   active where the seek latched it */
    STEPRAMP_EWINDINGS = 82,  /**< stepramp_configure_outputs: a winding mode (1 .. 4) on a core without winding
                                   outputs (ID bit 14 set, G_WINDINGS false: dev->windings 0), STEP/DIR only */
    STEPRAMP_ECORE_BASE = 128 /**< STEPRAMP_ECORE(code): the core flagged STATUS.ERROR with ERR_CODE code */
};

/** The largest pulse a take-over can name (CHANGE_AT and STEP_COUNT are 31 bits). */
#define STEPRAMP_MAX_PULSE UINT32_C(0x7FFFFFFF)

/** The result for a core error: STATUS.ERR_CODE code (0 .. 31) offset by STEPRAMP_ECORE_BASE. */
#define STEPRAMP_ECORE(code) (STEPRAMP_ECORE_BASE + (int)(code))
/** Nonzero when result r is a core error (STEPRAMP_ECORE(code)). */
#define STEPRAMP_IS_ECORE(r) ((r) >= STEPRAMP_ECORE_BASE && (r) < STEPRAMP_ECORE_BASE + 32)
/** The STATUS.ERR_CODE of a core-error result. */
#define STEPRAMP_ECORE_CODE(r) ((uint32_t)((r)-STEPRAMP_ECORE_BASE))

/** STATUS.STATE values. */
#define STEPRAMP_STATE_STOP 0u
#define STEPRAMP_STATE_ACCEL 1u
#define STEPRAMP_STATE_RUN 2u
#define STEPRAMP_STATE_DECEL 3u

/** STEP width + STEP space after reset (1 + 1 clocks): stepramp_t.min_gap until stepramp_configure_outputs. */
#define STEPRAMP_MIN_GAP_RESET (STEPRAMP_STEP_WIDTH_RESET + STEPRAMP_STEP_SPACE_RESET)

/** The machine inputs as bits (INPUT_CFG.POL_*, stepramp_status_t.levels and .events, stepramp_clear_events). */
#define STEPRAMP_INPUT_LIMIT_NEG 0x1u
#define STEPRAMP_INPUT_LIMIT_POS 0x2u
#define STEPRAMP_INPUT_HOME 0x4u
#define STEPRAMP_INPUT_ESTOP 0x8u
#define STEPRAMP_INPUT_ALL 0xFu

/** INPUT_CFG.LATCH_SRC values: the input the position latch takes its edges from. */
#define STEPRAMP_LATCH_NONE 0u
#define STEPRAMP_LATCH_HOME 1u
#define STEPRAMP_LATCH_LIMIT_NEG 2u
#define STEPRAMP_LATCH_LIMIT_POS 3u

/** The largest INPUT_FILTER (20 bits), clocks. */
#define STEPRAMP_FILTER_MAX UINT32_C(0xFFFFF)

/* INPUT_CFG after reset (stepramp_t.input_cfg after stepramp_init): STEPRAMP_INPUT_CFG_RESET of stepramp_regs.h
 * (LIMIT_EN set, everything else 0). */

/**
 * One stepramp core: its base address and the parameters every move is planned with, and what the driver knows of
 * the registers it wrote (set by stepramp_init; the driver's own business, like the Python driver's attributes).
 */
typedef struct {
    uintptr_t base;         /**< bus address of the core's register window (offset 0 = ID) */
    double fclk;            /**< engine clock frequency, Hz */
    double spr;             /**< steps per revolution (with microstepping) */
    uint32_t prescale;      /**< base timer period in clocks, 1 .. 65535 */
    uint32_t ramp;          /**< the core's ramp arithmetic every move, jog and change is planned for:
                                 STEPRAMP_RAMP_AVR446 (stepramp_init) or STEPRAMP_RAMP_EXACT (stepramp_init_ramp) */
    uint32_t version;       /**< ID bits 13:0 read by stepramp_init: major << 8 | minor */
    uint32_t windings;      /**< 1: the core has winding outputs (ID bit 14 clear, as read by stepramp_init); 0: it
                                 was built with G_WINDINGS false, stepramp_configure_outputs takes mode 0 only */
    uint32_t segment_dirty; /**< 1: SEGMENT .. HEAD_PROD_HI may hold anything but 0, so the next program writes them
                                 (0 for a move from rest to rest): unknown after stepramp_init (an earlier program
                                 without a core reset, or another master, may have left them set), or set by a jog;
                                 0: this driver last wrote them all 0, a program with no segment leaves them */
    uint32_t min_gap;       /**< STEP width + STEP space, clocks (each 0 acting as 1), as stepramp_configure_outputs
                                 last wrote them (STEPRAMP_MIN_GAP_RESET after stepramp_init): a jog's shortest
                                 interval must hold it */
    uint32_t input_filter;  /**< INPUT_FILTER as the driver last wrote it (0 after stepramp_init, the reset value):
                                 stepramp_read_latch's pin_time uses max(input_filter, 1) */
    uint32_t input_cfg;     /**< INPUT_CFG as the driver last wrote it (STEPRAMP_INPUT_CFG_RESET after init):
                                 stepramp_arm_latch keeps its polarity and limit bits */
} stepramp_t;

/** STATUS decoded (like driver.Status). */
typedef struct {
    uint32_t raw;      /**< the STATUS word as read */
    uint32_t state;    /**< STEPRAMP_STATE_STOP, _ACCEL, _RUN or _DECEL */
    int busy;          /**< 1 while a move runs */
    uint32_t dir;      /**< direction of the current or last move (1: position counts down) */
    int done;          /**< sticky: a move ended (normally, stopped or rejected) */
    int error;         /**< sticky: a move was rejected or stopped on an error */
    uint32_t err_code; /**< cause of the last error, STEPRAMP_ERR_* of stepramp_regs.h (kept after clearing) */
    int pending;       /**< STATUS.PENDING: a CHANGE or a QUEUE is pending, the staging registers are locked until
                            it is taken (or dropped) */
    int dir_fault;     /**< STATUS.DIR_FAULT (never expected) */
    uint32_t levels;   /**< the filtered input levels after polarity, STEPRAMP_INPUT_* bits (1: active) */
    uint32_t events;   /**< sticky: STEPRAMP_INPUT_LIMIT_NEG / _LIMIT_POS / _HOME for LIMIT_NEG_EV, LIMIT_POS_EV,
                            HOME_EV (the input became active), STEPRAMP_INPUT_ESTOP for ESTOP_FAULT */
    int latched;       /**< sticky: STATUS.LATCHED, LATCH_POS and LATCH_TIME hold the selected edge */
} stepramp_status_t;

/** The machine inputs' configuration (registers INPUT_FILTER and INPUT_CFG; Python's driver.Inputs). */
typedef struct {
    uint32_t filter;       /**< clocks a synchronised level must hold, 0 .. STEPRAMP_FILTER_MAX (0 acts as 1) */
    uint32_t active_low;   /**< STEPRAMP_INPUT_* bits of the inputs that are active low */
    int limit_enable;      /**< nonzero: an active limit stops a motion towards it and refuses a START towards it */
    int limit_hard;        /**< nonzero: a limit stops with a hard stop, else a soft stop at the decel in force */
    uint32_t latch_source; /**< STEPRAMP_LATCH_NONE, _HOME, _LIMIT_NEG or _LIMIT_POS */
    int latch_on_active;   /**< nonzero: latch on the source's activation edge (filtered) */
    int latch_on_release;  /**< nonzero: latch on the source's release edge (filtered) */
} stepramp_inputs_t;

/** What the position latch took at its source's filtered edge F (Python's driver.Latch). */
typedef struct {
    int32_t position;  /**< LATCH_POS: POSITION after edge F */
    uint64_t time;     /**< LATCH_TIME: TIME at edge F (clock edges since reset) */
    int64_t pin_time;  /**< LATCH_TIME - N - 2, N = max(filter, 1): the pin changed between TIME's clock edges
                            pin_time and pin_time + 1 (exact for a pin driven from the core's clock, within one clock
                            for an asynchronous one) */
} stepramp_latch_t;

/**
 * Set up the device structure and check that a stepramp core of the AVR446 ramp (G_RAMP = 0, ID bit 15 clear) answers
 * at base (reads ID only; writes nothing); stepramp_init_ramp for a core of the exact ramp. The
 * driver assumes the core's stepping outputs at their reset values (dev->min_gap), but not its segment registers:
 * dev->segment_dirty is 1, so the first stepramp_program writes SEGMENT .. HEAD_PROD_HI (0 for a move from rest to
 * rest) whatever an earlier program or another master left in them.
 *
 * @param dev      device structure to fill in (filled in even when the ID check fails)
 * @param base     bus address of the core
 * @param fclk     engine clock frequency, Hz; spr: steps per revolution; prescale: base timer period in clocks.
 *                 These are checked when a move is planned (stepramp_plan_move), not here.
 * @return STEPRAMP_OK; STEPRAMP_EID when ID bits 31:16 are not STEPRAMP_ID_MAGIC; STEPRAMP_ENULL if dev is NULL
 */
int stepramp_init(stepramp_t *dev, uintptr_t base, double fclk, double spr, uint32_t prescale);

/**
 * stepramp_init for a core of either ramp arithmetic (Python's StepRamp(access, fclk, spr, prescale, ramp) and its
 * check_id): dev->ramp = ramp, which stepramp_plan, stepramp_move, stepramp_queue_move, stepramp_plan_jog,
 * stepramp_jog and stepramp_change_to plan for (stepramp_plan_move_ramp, stepramp_plan_change_ramp). stepramp_init is
 * this function with STEPRAMP_RAMP_AVR446.
 *
 * @param ramp STEPRAMP_RAMP_AVR446 for a core built with G_RAMP = 0, STEPRAMP_RAMP_EXACT for G_RAMP = 1
 * @return STEPRAMP_OK; STEPRAMP_EID when ID bits 31:16 are not STEPRAMP_ID_MAGIC or ID bit 15 (the core's G_RAMP) is
 *         not ramp; STEPRAMP_ERAMP (dev untouched, nothing read) when ramp is neither STEPRAMP_RAMP_AVR446 nor
 *         STEPRAMP_RAMP_EXACT; STEPRAMP_ENULL if dev is NULL
 */
int stepramp_init_ramp(stepramp_t *dev, uintptr_t base, double fclk, double spr, uint32_t prescale, uint32_t ramp);

/**
 * Plan a move with the device's fclk, spr, prescale and ramp (stepramp_plan_move_ramp; Python's StepRamp.plan).
 * Touches no register.
 *
 * @param plan  output, written only on success
 * @param steps signed step count; accel, decel in rad/s^2; speed in rad/s
 * @return STEPRAMP_OK or the stepramp_err_t of the first failed check; STEPRAMP_EGAP when the STEP width + STEP
 *         space (stepramp_configure_outputs) does not fit the move's shortest interval; STEPRAMP_ENULL if dev or
 *         plan is NULL
 */
int stepramp_plan(const stepramp_t *dev, stepramp_plan_t *plan, int64_t steps, double accel, double decel,
                  double speed);

/**
 * Write every motion register of a plan, in address order (Python's plan_writes): STEPS as the signed step
 * count in two's complement (-steps when direction is 1), PRESCALE, each wide value as _LO (bits 31:0) and _HI
 * (the bits above), SA, SD, STOP_RATIO. The core latches them at START, so this is safe during a move (it
 * prepares the next one). Does not start the move. Unless the segment registers are known to hold 0
 * (dev->segment_dirty is 0), they follow, cleared to 0 (a move from rest to rest): so after stepramp_init (their
 * contents unknown) and after a jog, the first program writes them, later ones do not:
 * stepramp_program_segment(dev, plan, NULL), Python's program(plan).
 *
 * STOP_RATIO: plan->stop_ratio.
 *
 * @return STEPRAMP_OK; STEPRAMP_ENULL (nothing written) if dev or plan is NULL
 */
int stepramp_program(stepramp_t *dev, const stepramp_plan_t *plan);

/**
 * Python's program(plan, segment): the plan's registers as stepramp_program, then, when segment is not NULL or
 * dev->segment_dirty, SEGMENT (HEAD_DOWN, ENDLESS), HEAD_INDEX, RUN_STOP, HEAD_PROD_LO, HEAD_PROD_HI in address
 * order (driver.segment_writes; all 0 for a NULL segment). dev->segment_dirty is then 1 when they hold anything but
 * 0, and 0 when they were all written 0.
 *
 * @param segment the segment registers (stepramp_segment_registers), or NULL for a move from rest to rest
 * @return STEPRAMP_OK; STEPRAMP_ENULL (nothing written) if dev or plan is NULL
 */
int stepramp_program_segment(stepramp_t *dev, const stepramp_plan_t *plan, const stepramp_segment_regs_t *segment);

/** START: begin the programmed move (ignored by the core while busy). Byte 0 of CTRL only. */
void stepramp_start(const stepramp_t *dev);

/**
 * Plan, program and start a move (Python's StepRamp.move).
 *
 * @param steps signed step count (|steps| <= 2^31 - 1); accel, decel in rad/s^2; speed in rad/s
 * @return STEPRAMP_OK, or the plan's error (stepramp_err_t) -- then no register has been written
 */
int stepramp_move(stepramp_t *dev, int64_t steps, double accel, double decel, double speed);

/**
 * The registers of a jog from rest (Python's StepRamp.plan_jog), touching no register: the continuation from speed
 * 0 with no target (stepramp_plan_change_ramp(u = 0, STEPRAMP_ENDLESS) at |speed| with the device's spr, fclk,
 * prescale and ramp) as its plan and segment registers (stepramp_segment_registers, direction 1 for a negative speed).
 *
 * @param plan  output, written only on success
 * @param regs  output, written only on success
 * @param speed signed jog speed, rad/s (its sign gives the direction); accel, decel in rad/s^2
 * @return STEPRAMP_OK; STEPRAMP_EJOG_SPEED for a speed 0, inf or NaN; stepramp_plan_change's error; STEPRAMP_EGAP
 *         when dev->min_gap exceeds the jog's shortest interval, int(f_tick / v) * prescale clocks at v = |speed| in
 *         steps/s; STEPRAMP_ENULL if dev, plan or regs is NULL
 */
int stepramp_plan_jog(const stepramp_t *dev, stepramp_plan_t *plan, stepramp_segment_regs_t *regs, double speed,
                      double accel, double decel);

/**
 * Jog from rest (Python's StepRamp.jog): accelerate at accel to |speed| in the direction of its sign and hold it
 * until stepramp_soft_stop (which decelerates at decel to rest) or stepramp_hard_stop. Plans (stepramp_plan_jog),
 * writes the plan's and the segment registers (stepramp_program_segment) and START; the next stepramp_program or
 * stepramp_move clears the segment registers again.
 *
 * @return STEPRAMP_OK, or stepramp_plan_jog's error -- then no register has been written
 */
int stepramp_jog(stepramp_t *dev, double speed, double accel, double decel);

/**
 * Take a segment over at pulse `pulse` of the running motion (docs/algorithm.md, "The take-over, the queue and the
 * script contract"): its registers into the staging registers, as stepramp_segment_registers(seg, direction) gives
 * them (STEPS = its length + 1 with the sign of direction, or +-1 for an endless segment) through
 * stepramp_program_segment (STEPS .. STOP_RATIO, then SEGMENT .. HEAD_PROD_HI, in address order), then CHANGE_AT =
 * pulse and CTRL.CHANGE (byte 0 of CTRL only). Pulse `pulse` is the segment's pulse 0, the segment's interval 1
 * follows it; STEP_COUNT and POSITION carry on.
 *
 * The driver checks the arguments only; the core checks the rest at the commit and refuses it (nothing changes in
 * the motion; STATUS.ERROR with ERR_CODE CHANGE) when it is idle, a change or a queued move is pending, direction is
 * not the running motion's (STATUS.DIR), a soft stop is requested, pulse - 1 is already emitted (STEP_COUNT >=
 * pulse) or pulse lies past the running positioning segment's last pulse. Staging writes while STATUS.PENDING are
 * ignored (ERR_CODE STAGED). So the pulse should leave the bus writes time: stepramp.models.engine.change_pulse
 * names one at least 2 pulses and 400 clocks after the commit. seg->prescale should be the running motion's.
 *
 * @param seg       the segment (stepramp_plan_change's out->segment, planned from the speed at pulse)
 * @param direction the running motion's direction, STATUS.DIR (0: position counts up, 1: down; nonzero is 1)
 * @param pulse     the take-over pulse, counted as STEP_COUNT counts (1 .. STEPRAMP_MAX_PULSE)
 * @return STEPRAMP_OK; STEPRAMP_EPULSE for a pulse of 0 or above STEPRAMP_MAX_PULSE; STEPRAMP_ESTEPS for a segment of
 *         length 2^31 - 1 (STEPS would not fit); STEPRAMP_ENULL if dev or seg is NULL -- then nothing is written
 */
int stepramp_change(stepramp_t *dev, const stepramp_segment_t *seg, uint32_t direction, uint32_t pulse);

/**
 * Plan a change and commit it at pulse `pulse` in the running direction: stepramp_plan_change_ramp from speed u with
 * the device's spr, fclk, prescale and ramp, then one STATUS read and stepramp_change(dev, segment, STATUS.DIR,
 * pulse).
 *
 * @param pulse     the take-over pulse (1 .. STEPRAMP_MAX_PULSE), far enough ahead (see stepramp_change)
 * @param u         the running motion's speed at pulse, steps/s (stepramp_speed_at_pulse of its stepramp_info_t)
 * @param remaining steps from pulse to the new target in the running direction (0 .. 2^31 - 1), or
 *                  STEPRAMP_ENDLESS: no target, hold speed until a stop (a jog); as stepramp_plan_change takes it
 * @param accel     new acceleration, decel new deceleration (rad/s^2), speed new speed (rad/s)
 * @return STEPRAMP_OK; STEPRAMP_EPULSE (as stepramp_change); stepramp_plan_change's error; STEPRAMP_EREVERSE when the
 *         target lies inside the stop distance from u (the plan has a move back: reverse with stepramp_soft_stop and
 *         a queued move instead); STEPRAMP_EGAP when the STEP width + space (dev->min_gap) does not fit the
 *         segment's shortest interval, floor(f_tick / max(start speed, peak speed)) * prescale clocks;
 *         STEPRAMP_EIDLE when STATUS.BUSY is 0; STEPRAMP_EPENDING when STATUS.PENDING is set; STEPRAMP_ENULL if dev
 *         is NULL. On any error nothing is written (STATUS is read only after the plan passed).
 */
int stepramp_change_to(stepramp_t *dev, uint32_t pulse, double u, int64_t remaining, double accel, double decel,
                       double speed);

/**
 * Queue a move after the running one: stepramp_program(plan) into the staging registers (with SEGMENT ..
 * HEAD_PROD_HI cleared when they may hold a segment, e.g. after a jog or a change) and CTRL.QUEUE (byte 0 of CTRL
 * only). The core keeps it (STATUS.PENDING, staging locked) and starts it when the running motion ends without
 * error, exactly as a START written at that edge (its DONE is still raised: stepramp_wait_done returns at the end
 * of the running motion, the queued move then runs). It refuses the QUEUE (STATUS.ERROR, ERR_CODE CHANGE) when it
 * is idle or something is pending; a soft or hard stop, or an error of the running motion, drops the queued move.
 *
 * @return STEPRAMP_OK; STEPRAMP_ENULL (nothing written) if dev or plan is NULL
 */
int stepramp_queue(stepramp_t *dev, const stepramp_plan_t *plan);

/**
 * Plan a move (stepramp_plan) and queue it after the running motion (stepramp_queue).
 *
 * @param steps signed step count from where the running motion ends; accel, decel in rad/s^2; speed in rad/s
 * @return STEPRAMP_OK, or stepramp_plan's error -- then no register has been written
 */
int stepramp_queue_move(stepramp_t *dev, int64_t steps, double accel, double decel, double speed);

/** SOFT_STOP: decelerate at the programmed decel to zero, then DONE. Byte 0 of CTRL only. */
void stepramp_soft_stop(const stepramp_t *dev);

/** HARD_STOP: no further step pulse from the next clock on, then DONE. Byte 0 of CTRL only. */
void stepramp_hard_stop(const stepramp_t *dev);

/**
 * Set the interrupt enables (CTRL.IRQ_DONE_EN, CTRL.IRQ_ERROR_EN): the level irq output follows STATUS.DONE /
 * STATUS.ERROR where enabled. CTRL is read, then byte 1 written with the input interrupt enables (bits 10 .. 14,
 * stepramp_enable_input_irq) as read: they are kept; it starts nothing and keeps CTRL.ENABLE.
 *
 * @param done  nonzero: interrupt on DONE; error: nonzero: interrupt on ERROR
 */
void stepramp_enable_irq(const stepramp_t *dev, int done, int error);

/** CTRL.ENABLE (the ENABLE output; off also switches the H-bridge windings off): a byte write of CTRL byte 2. */
void stepramp_set_enable(const stepramp_t *dev, int on);

/** The stepping outputs (registers DRIVE, STEP_WIDTH, DIR_TIMING, PWM_PERIOD, STEP_SPACE; docs/registers.md). */
typedef struct {
    uint32_t mode;       /**< 0 STEP/DIR only, 1 wave, 2 full step, 3 half step, 4 sine/cosine PWM */
    uint32_t ustep_log2; /**< PWM microsteps per full step = 2^ustep_log2 (0 .. 7, at most the core's G_MICROSTEPS) */
    uint16_t step_width; /**< STEP high time, clocks (0 acts as 1); width + space must fit the shortest interval */
    uint16_t dir_setup;  /**< DIR setup before a STEP rising edge, clocks */
    uint16_t dir_hold;   /**< DIR hold after a STEP rising edge, clocks */
    uint16_t pwm_period; /**< PWM carrier period, clocks (0 or 1: windings off in mode 4) */
    uint16_t step_space; /**< shortest STEP low time, clocks (0 acts as 1; the reset value is 1) */
} stepramp_outputs_t;

/**
 * Write the stepping output registers. Only while stopped: the core ignores these writes during a move and flags
 * ERROR with ERR_CODE CFG_BUSY. Records STEP width + STEP space in dev->min_gap (the jog's check).
 *
 * @return STEPRAMP_OK, or STEPRAMP_EOUTPUTS (nothing written) for a NULL pointer, mode > 4 or ustep_log2 > 7;
 *         STEPRAMP_EWINDINGS (nothing written) for a mode 1 .. 4 on a core without windings (dev->windings 0)
 */
int stepramp_configure_outputs(stepramp_t *dev, const stepramp_outputs_t *out);

/**
 * Read and decode STATUS.
 *
 * @param status output, may be NULL
 * @return the raw STATUS word
 */
uint32_t stepramp_status(const stepramp_t *dev, stepramp_status_t *status);

/** Clear the sticky STATUS.DONE and STATUS.ERROR (write 1 to both; ERR_CODE keeps the last cause). */
void stepramp_clear_flags(const stepramp_t *dev);

/** The signed 32-bit position counter, in steps. */
int32_t stepramp_position(const stepramp_t *dev);

/**
 * Set the position counter. Only while stopped: during a move the core ignores the write and flags
 * STATUS.ERROR with ERR_CODE POS_BUSY (which the next stepramp_wait_done reports).
 */
void stepramp_set_position(const stepramp_t *dev, int32_t position);

/**
 * Poll STATUS until DONE (Python's StepRamp.wait_done), then clear DONE and ERROR.
 * Between two polls the macro STEPRAMP_IDLE() runs (default: nothing; define it to sleep or yield).
 *
 * @param max_polls at most this many STATUS reads (0: none, the result is STEPRAMP_ETIMEOUT)
 * @return STEPRAMP_OK when the move ended without error; STEPRAMP_ECORE(err_code) when the core flagged ERROR
 *         (the flags are cleared in both cases); STEPRAMP_ETIMEOUT (flags untouched) when DONE never came
 */
int stepramp_wait_done(const stepramp_t *dev, uint32_t max_polls);

/**
 * The work of an interrupt handler for the core's irq line (CTRL.IRQ_DONE / IRQ_ERROR enabled): read STATUS once,
 * clear the flags that read '1' among DONE and ERROR (write 1 to exactly those, so a flag that rises after the read
 * stays set and keeps irq high), which drops irq, and report.
 *
 * @param status filled in with the STATUS word as read (may be NULL)
 * @return with DONE set, the move's result as stepramp_wait_done gives it: STEPRAMP_OK, or STEPRAMP_ECORE(err_code)
 *         when ERROR was set too; with ERROR alone (a POSITION write during the move: the move goes on, status->done
 *         is 0), STEPRAMP_ECORE(err_code); with neither, STEPRAMP_ENOIRQ (nothing written)
 */
int stepramp_isr(const stepramp_t *dev, stepramp_status_t *status);

/**
 * Configure the machine inputs: INPUT_FILTER, then INPUT_CFG. Only while stopped (the core ignores the writes during a
 * motion and flags CFG_BUSY). Records both in dev->input_filter and dev->input_cfg.
 *
 * @return STEPRAMP_OK; STEPRAMP_EINPUTS (nothing written) for NULL, a filter above STEPRAMP_FILTER_MAX, active_low
 *         bits outside STEPRAMP_INPUT_ALL, a latch source above STEPRAMP_LATCH_LIMIT_POS, or a latch source with
 *         neither edge selected
 */
int stepramp_configure_inputs(stepramp_t *dev, const stepramp_inputs_t *in);

/**
 * Select the latch's source and edges (INPUT_CFG with the polarity and limit bits of dev->input_cfg; only while
 * stopped), then clear STATUS.LATCHED, which arms it: the first selected filtered edge from now on takes POSITION
 * and TIME. STEPRAMP_LATCH_NONE switches the latch off (the edges are then ignored).
 *
 * @return STEPRAMP_OK; STEPRAMP_EINPUTS (nothing written) for NULL, an unknown source, or a source with neither edge
 */
int stepramp_arm_latch(stepramp_t *dev, uint32_t source, int on_active, int on_release);

/** Clear STATUS.LATCHED (write 1, byte 3 only): the latch takes the next selected edge (allowed while moving). */
void stepramp_rearm_latch(const stepramp_t *dev);

/**
 * Read LATCH_POS and LATCH_TIME (LO then HI) into latch, with pin_time from dev->input_filter, whether STATUS.LATCHED
 * is set or not.
 */
void stepramp_read_latch(const stepramp_t *dev, stepramp_latch_t *latch);

/**
 * The latch if STATUS.LATCHED is set (one STATUS read, then stepramp_read_latch).
 *
 * @return STEPRAMP_OK (latch filled in); STEPRAMP_ENOLATCH (latch untouched) when nothing is latched;
 *         STEPRAMP_ENULL if dev or latch is NULL
 */
int stepramp_latch(const stepramp_t *dev, stepramp_latch_t *latch);

/** TIME, the 64-bit clock count since reset: TIME_LO first (the read copies bits 63:32 into TIME_HI), then TIME_HI. */
uint64_t stepramp_time(const stepramp_t *dev);

/**
 * Clear sticky input events (write 1 to LIMIT_NEG_EV, LIMIT_POS_EV, HOME_EV for the STEPRAMP_INPUT_LIMIT_NEG,
 * _LIMIT_POS, _HOME bits of inputs; byte 2 of STATUS only: DONE, ERROR, ESTOP_FAULT and LATCHED are kept). Nothing
 * is written for a mask without those bits.
 */
void stepramp_clear_events(const stepramp_t *dev, uint32_t inputs);

/**
 * Clear STATUS.ESTOP_FAULT (write 1) and, with enable, set CTRL.ENABLE again (the fault cleared it). The core keeps
 * the fault while ESTOP is active.
 *
 * @return STEPRAMP_OK; STEPRAMP_EESTOP when the fault is still set (ENABLE then left as it is)
 */
int stepramp_clear_estop(const stepramp_t *dev, int enable);

/**
 * Every interrupt enable of CTRL byte 1 (a byte write: no command, ENABLE kept): irq follows STATUS.DONE (done),
 * STATUS.ERROR (error), the input events of the STEPRAMP_INPUT_* bits in events (STEPRAMP_INPUT_ESTOP:
 * ESTOP_FAULT) and STATUS.LATCHED (latch).
 */
void stepramp_enable_input_irq(const stepramp_t *dev, int done, int error, uint32_t events, int latch);

/**
 * A STATUS.ERR_CODE value in words: the cause column of the error table of docs/registers.md
 * (for example "PRESCALE is 0" for STEPRAMP_ERR_PRESCALE).
 *
 * @return a static string; "unknown error code" for a code not in the table
 */
const char *stepramp_strcoreerror(uint32_t code);

/**
 * The name of a STATUS.ERR_CODE value ("NONE", "PRESCALE", ..., "POS_BUSY"), like driver.Status.err_name.
 *
 * @return a static string; "UNKNOWN" for a code not in the table
 */
const char *stepramp_corename(uint32_t code);

/**
 * Any result of this driver in words: stepramp_strerror() for a stepramp_err_t, the ID and timeout errors,
 * and "core error: " cause texts for STEPRAMP_ECORE(code).
 *
 * @return a static string; "unknown error" for a value that is none of these
 */
const char *stepramp_strresult(int result);

#ifdef __cplusplus
}
#endif

#endif /* STEPRAMP_H */

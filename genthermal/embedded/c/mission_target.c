/* mission_target.c -- run a mission through the generated model on a bare-metal Cortex-M4F.
 *
 * Built by genthermal.embedded (codegen/ABI.md, "Cortex-M4F (bare metal) and single precision") for one
 * precision: casadi_real is double, or float with -Dcasadi_real=float -fsingle-precision-constant.
 * The generated CasADi functions are called directly with casadi_real arrays, so both variants
 * run the same code; the mission inputs (mission_data.c) are stored in double and converted.
 *
 * Printed on the host through semihosting, one line each:
 *   "x <hex> ... <hex>"  the state after every step, each value as the hex of its IEEE bits;
 *   "cost stack <bytes>" the deepest stack the run used (startup.c paints the stack);
 *   "peak <hex>"         the winding's peak over a prediction of PREDICT_STEPS steps from the
 *                         filtered final state, the last inputs held (a loop of step calls);
 *   "cost <name> <ticks>" SysTick ticks (processor clock) of one step, one kalman_update and that
 *                         prediction; under QEMU -icount the host turns them into instructions.
 * Nothing is allocated; the work arrays are static storage of this program.
 */
#include <stdint.h>
#include <string.h>

#include "gt.h"
#include "gt_casadi.h"
#include "board.h"

#define PREDICT_STEPS GT_PREDICT_STEPS     /* from the compiler command line */
#define WINDING GT_WINDING_STATE            /* index of the winding sensor's node */

#define MAX2(a, b) ((a) > (b) ? (a) : (b))

typedef int (*casadi_entry)(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);

extern const double mission_inputs[];
extern const int mission_n_rows;

static casadi_real work[1 + MAX2(gt_cg_step_SZ_W, gt_cg_kalman_update_SZ_W)];
static casadi_int iwork[1 + MAX2(gt_cg_step_SZ_IW, gt_cg_kalman_update_SZ_IW)];
static char line[24 * (GT_N_STATES + 1)];

static int call(casadi_entry function, const casadi_real* in0, const casadi_real* in1, const casadi_real* in2,
                casadi_real* out0, casadi_real* out1)
{
    const casadi_real* arg[3];
    casadi_real* res[2];
    arg[0] = in0;
    arg[1] = in1;
    arg[2] = in2;
    res[0] = out0;
    res[1] = out1;
    return function(arg, res, iwork, work, 0);
}

static char* append_hex(char* cursor, const casadi_real* value)
{
    static const char digits[] = "0123456789abcdef";
    unsigned char bytes[sizeof(casadi_real)];
    int i;
    memcpy(bytes, value, sizeof bytes);
    *cursor++ = ' ';
    for (i = (int)sizeof bytes - 1; i >= 0; --i) {
        *cursor++ = digits[bytes[i] >> 4];
        *cursor++ = digits[bytes[i] & 15];
    }
    return cursor;
}

static void append_number(char* cursor, uint64_t value)
{
    char reversed[24];
    int n = 0;
    do reversed[n++] = (char)('0' + (int)(value % 10u)); while ((value /= 10u) != 0u);
    while (n) *cursor++ = reversed[--n];
    *cursor++ = '\n';
    *cursor = '\0';
}

static void report_cost(const char* name, uint64_t ticks)
{
    size_t length = strlen(name);
    memcpy(line, "cost ", 5);
    memcpy(line + 5, name, length);
    line[5 + length] = ' ';
    append_number(line + 6 + length, ticks);
    semihost_write(line);
}

int main(void)
{
    casadi_real x[GT_N_STATES], u[GT_N_INPUTS], y[GT_N_OUTPUTS], filtered[GT_N_STATES], next[GT_N_STATES], peak;
    uint64_t start;
    int i, k;
    for (i = 0; i < GT_N_STATES; ++i) x[i] = (casadi_real)mission_inputs[GT_N_INPUTS - 1]; /* cold: T_ambient */
    for (k = 0; k + 1 < mission_n_rows; ++k) {
        char* cursor = line;
        for (i = 0; i < GT_N_INPUTS; ++i) u[i] = (casadi_real)mission_inputs[k * GT_N_INPUTS + i];
        start = board_ticks();
        if (call(gt_cg_step, x, u, 0, next, 0)) return 1;
        if (k == 0) report_cost("step", board_ticks() - start);
        memcpy(x, next, sizeof x);
        *cursor++ = 'x';
        for (i = 0; i < GT_N_STATES; ++i) cursor = append_hex(cursor, &x[i]);
        *cursor++ = '\n';
        *cursor = '\0';
        semihost_write(line);
    }
    for (i = 0; i < GT_N_OUTPUTS; ++i) y[i] = x[WINDING] + (casadi_real)0.5; /* a measurement near the state */
    start = board_ticks();
    if (call(gt_cg_kalman_update, x, u, y, filtered, next)) return 1;
    report_cost("kalman_update", board_ticks() - start);
    start = board_ticks();
    peak = filtered[WINDING];
    memcpy(x, filtered, sizeof x);
    for (k = 0; k < PREDICT_STEPS; ++k) {
        if (call(gt_cg_step, x, u, 0, next, 0)) return 1;
        memcpy(x, next, sizeof x);
        if (x[WINDING] > peak) peak = x[WINDING];
    }
    report_cost("predict", board_ticks() - start);
    memcpy(line, "peak", 4);
    *append_hex(line + 4, &peak) = '\0';
    semihost_write(line);
    semihost_write("\n");
    report_cost("stack", (uint32_t)stack_used_bytes());
    return 0;
}

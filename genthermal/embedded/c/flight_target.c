/* flight_target.c -- a closed-loop flight on the bare-metal Cortex-M4F: the onboard manager
 * (manager.c, on the generated design-model library "gt") against the true plants ("gtp",
 * "gtb", their generated CasADi step functions called directly), with the measurement noise of
 * flight_data.c.
 *
 * Printed through semihosting, one line per sample:
 *   "s <resting> <decided> <rest_remaining> <displaced> <hot> <infeasible> <hex>..." with the
 *   hex IEEE bits of: both currents applied (A), both plants' measured winding (degC), both
 *   filtered windings (degC), both predicted peaks of the last decision (degC);
 * then "cost manager_max <ticks>" (the longest gtm_step), "cost manager_total <ticks>",
 * "cost stack <bytes>".
 */
#include <string.h>

#include "board.h"
#include "flight.h"
#include "gtp_casadi.h"
#include "gtb_casadi.h"

typedef int (*casadi_entry)(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);

#define MAX2(a, b) ((a) > (b) ? (a) : (b))
static double work[1 + MAX2(GT_WORK_SIZE, MAX2(gtp_cg_step_SZ_W, gtb_cg_step_SZ_W))];
static casadi_int iwork[1 + MAX2(gtp_cg_step_SZ_IW, gtb_cg_step_SZ_IW)];
static char line[512];

static int plant_step(casadi_entry step, double* x, const double* u)
{
    double next[GT_N_STATES];
    const casadi_real* arg[2];
    casadi_real* res[1];
    arg[0] = x;
    arg[1] = u;
    res[0] = next;
    if (step(arg, res, iwork, work, 0)) return -1;
    memcpy(x, next, sizeof next);
    return 0;
}

static char* append_hex(char* cursor, double value)
{
    static const char digits[] = "0123456789abcdef";
    unsigned char bytes[sizeof(double)];
    int i;
    memcpy(bytes, &value, sizeof bytes);
    *cursor++ = ' ';
    for (i = (int)sizeof bytes - 1; i >= 0; --i) {
        *cursor++ = digits[bytes[i] >> 4];
        *cursor++ = digits[bytes[i] & 15];
    }
    return cursor;
}

static char* append_number(char* cursor, uint64_t value)
{
    char reversed[24];
    int n = 0;
    *cursor++ = ' ';
    do reversed[n++] = (char)('0' + (int)(value % 10u)); while ((value /= 10u) != 0u);
    while (n) *cursor++ = reversed[--n];
    return cursor;
}

static void report(const char* name, uint64_t value)
{
    char* cursor = line;
    memcpy(cursor, "cost ", 5);
    cursor += 5;
    memcpy(cursor, name, strlen(name));
    cursor = append_number(cursor + strlen(name), value);
    *cursor++ = '\n';
    *cursor = '\0';
    semihost_write(line);
}

int main(void)
{
    const gtm_settings_t* s = &flight_settings;
    const flight_plant_t* plant = &flight_plant;
    gtm_state_t manager;
    double x[GTM_N_GENERATORS][GT_N_STATES], y[GTM_N_GENERATORS * GT_N_OUTPUTS], inlet[GTM_N_GENERATORS];
    double currents[GTM_N_GENERATORS], u[GT_N_INPUTS];
    uint64_t longest = 0, total = 0;
    int g, i, k, resting, status = GT_OK;
    if (gtm_init(&manager, s) != GT_OK) return 2;
    for (g = 0; g < GTM_N_GENERATORS; ++g)
        for (i = 0; i < GT_N_STATES; ++i) x[g][i] = s->ambient_C;
    for (k = 0; k < plant->max_samples; ++k) {
        char* cursor = line;
        uint64_t start;
        for (g = 0; g < GTM_N_GENERATORS; ++g) {
            for (i = 0; i < GT_N_OUTPUTS; ++i)
                y[g * GT_N_OUTPUTS + i] = x[g][plant->sensor_states[i]] +
                                          flight_noise[(k * GTM_N_GENERATORS + g) * GT_N_OUTPUTS + i];
            inlet[g] = plant->inlet_C + (g == 0 && k >= plant->onset_sample ? plant->inlet_rise_C : 0.0);
        }
        start = board_ticks();
        status = gtm_step(&manager, s, y, inlet, currents, &resting, work);
        start = board_ticks() - start;
        total += start;
        if (start > longest) longest = start;
        if (status == GTM_MISSION_DONE) break;
        if (status != GT_OK) return 3;
        *cursor++ = 's';
        cursor = append_number(cursor, (uint64_t)resting);
        cursor = append_number(cursor, (uint64_t)manager.decided);
        cursor = append_number(cursor, (uint64_t)manager.rest_remaining);
        cursor = append_number(cursor, (uint64_t)manager.displaced);
        cursor = append_number(cursor, (uint64_t)manager.hot);
        cursor = append_number(cursor, (uint64_t)manager.infeasible);
        for (g = 0; g < GTM_N_GENERATORS; ++g) cursor = append_hex(cursor, currents[g]);
        for (g = 0; g < GTM_N_GENERATORS; ++g) cursor = append_hex(cursor, x[g][plant->sensor_states[0]]);
        for (g = 0; g < GTM_N_GENERATORS; ++g) cursor = append_hex(cursor, manager.x_filtered[g][s->winding_state]);
        for (g = 0; g < GTM_N_GENERATORS; ++g) cursor = append_hex(cursor, manager.predicted_peak_C[g]);
        *cursor++ = '\n';
        *cursor = '\0';
        semihost_write(line);
        for (g = 0; g < GTM_N_GENERATORS; ++g) {
            u[0] = u[1] = u[2] = currents[g];
            u[3] = s->field_no_load_A + s->field_gain * currents[g];
            u[4] = inlet[g];
            u[5] = s->ambient_C;
            if (plant_step(g == 0 && k >= plant->onset_sample ? gtb_cg_step : gtp_cg_step, x[g], u)) return 4;
        }
    }
    if (status != GTM_MISSION_DONE) return 5; /* the noise table ended before the mission */
    report("manager_max", longest);
    report("manager_total", total);
    report("stack", stack_used_bytes());
    return 0;
}

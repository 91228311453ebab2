/* manager.c -- the onboard load manager (see manager.h for the rule). */
#include "manager.h"

#define NO_PEAK (-1e300)

/* Phase currents of both generators at mission sample `index` under the displacement plan. */
static void mission_currents(const gtm_settings_t* s, int index, int displaced, int hot, double* currents)
{
    double nominal = s->profile_A[index], shift = 0.0;
    int g;
    if (displaced) {
        shift = s->current_limit_A - nominal < nominal - s->rest_current_A ? s->current_limit_A - nominal
                                                                           : nominal - s->rest_current_A;
        if (shift < 0.0) shift = 0.0;
    }
    for (g = 0; g < GTM_N_GENERATORS; ++g) currents[g] = displaced ? (g == hot ? nominal - shift : nominal + shift)
                                                                   : nominal;
}

/* Model input of one generator: three phase currents, the exciter law, inlet and ambient. */
static void model_input(const gtm_settings_t* s, double current, double inlet_C, double* u)
{
    u[0] = u[1] = u[2] = current;
    u[3] = s->field_no_load_A + s->field_gain * current;
    u[4] = inlet_C;
    u[5] = s->ambient_C;
}

/* Peak winding temperature of generator g predicted from its filtered state: `rest` samples of
 * rest, then the mission from `index` to its end (the states after each step: the present one
 * cannot be changed, -1e300 for an empty horizon). Stops early above `stop_above_C`. */
static int predict_peak(const gtm_settings_t* s, const double* x0, int g, int rest, int index, int displaced,
                        int hot, double inlet_C, double stop_above_C, double* peak, double* work)
{
    double x[GT_N_STATES], u[GT_N_INPUTS], currents[GTM_N_GENERATORS];
    int i, k;
    for (i = 0; i < GT_N_STATES; ++i) x[i] = x0[i];
    *peak = NO_PEAK;
    model_input(s, s->rest_current_A, inlet_C, u);
    for (k = 0; k < rest && *peak <= stop_above_C; ++k) {
        if (gt_step(x, u, x, work, GT_WORK_SIZE) != GT_OK) return GT_ERR_EVALUATION;
        if (x[s->winding_state] > *peak) *peak = x[s->winding_state];
    }
    for (k = index; k < s->n_profile && *peak <= stop_above_C; ++k) {
        mission_currents(s, k, displaced, hot, currents);
        model_input(s, currents[g], inlet_C, u);
        if (gt_step(x, u, x, work, GT_WORK_SIZE) != GT_OK) return GT_ERR_EVALUATION;
        if (x[s->winding_state] > *peak) *peak = x[s->winding_state];
    }
    return GT_OK;
}

/* 1 if either generator's prediction under the plan (rest, displaced, hot) passes the limit. */
static int breach_predicted(gtm_state_t* m, const gtm_settings_t* s, int rest, int displaced, int hot,
                            const double* inlet_C, double stop_above_C, double* work, int* status)
{
    int g, breach = 0;
    for (g = 0; g < GTM_N_GENERATORS; ++g) {
        *status |= predict_peak(s, m->x_filtered[g], g, rest, m->mission_index, displaced, hot, inlet_C[g],
                                stop_above_C, &m->predicted_peak_C[g], work);
        if (m->predicted_peak_C[g] > s->limit_C) breach = 1;
    }
    return breach;
}

static int decide(gtm_state_t* m, const gtm_settings_t* s, const double* inlet_C, double* work)
{
    const double no_stop = 1e300;
    int status = GT_OK, rest;
    if (!breach_predicted(m, s, m->rest_remaining, m->displaced, m->hot, inlet_C, no_stop, work, &status))
        return status;
    if (!m->displaced) {
        m->displaced = 1;
        m->hot = m->predicted_peak_C[1] > m->predicted_peak_C[0] ? 1 : 0;
        if (!breach_predicted(m, s, m->rest_remaining, 1, m->hot, inlet_C, no_stop, work, &status)) return status;
    }
    for (rest = m->rest_remaining + s->rest_quantum_steps; rest <= s->max_rest_steps; rest += s->rest_quantum_steps) {
        if (!breach_predicted(m, s, rest, 1, m->hot, inlet_C, s->limit_C, work, &status)) {
            m->rest_remaining = rest;
            return status;
        }
    }
    if (s->max_rest_steps > m->rest_remaining) m->rest_remaining = s->max_rest_steps;
    m->infeasible = 1;
    return status;
}

int gtm_init(gtm_state_t* state, const gtm_settings_t* settings)
{
    int g, i;
    if (!state || !settings || !settings->profile_A) return GT_ERR_NULL_POINTER;
    if (settings->n_profile < 1 || settings->cycle_steps < 1 || settings->rest_quantum_steps < 1 ||
        settings->max_rest_steps < 0 || settings->winding_state < 0 || settings->winding_state >= GT_N_STATES)
        return GT_ERR_BAD_ARGUMENT;
    for (g = 0; g < GTM_N_GENERATORS; ++g) {
        for (i = 0; i < GT_N_STATES; ++i) state->x_pred[g][i] = state->x_filtered[g][i] = settings->ambient_C;
        state->predicted_peak_C[g] = settings->ambient_C;
    }
    state->samples = state->mission_index = state->rest_remaining = 0;
    state->displaced = state->hot = state->infeasible = state->decided = 0;
    return GT_OK;
}

int gtm_step(gtm_state_t* state, const gtm_settings_t* settings, const double* y, const double* inlet_C,
             double* currents_A, int* resting, double* work)
{
    double u[GT_N_INPUTS], ignored[GT_N_STATES];
    int g, status = GT_OK;
    if (!state || !settings || !y || !inlet_C || !currents_A || !resting || !work) return GT_ERR_NULL_POINTER;
    if (state->mission_index >= settings->n_profile && state->rest_remaining == 0) return GTM_MISSION_DONE;
    for (g = 0; g < GTM_N_GENERATORS; ++g) { /* the update; its one-step prediction is redone below */
        model_input(settings, 0.0, inlet_C[g], u);
        status |= gt_kalman_update(state->x_pred[g], u, y + g * GT_N_OUTPUTS, state->x_filtered[g], ignored, work, GT_WORK_SIZE);
    }
    state->decided = state->samples % settings->cycle_steps == 0;
    if (state->decided) status |= decide(state, settings, inlet_C, work);
    *resting = state->rest_remaining > 0;
    if (*resting) {
        for (g = 0; g < GTM_N_GENERATORS; ++g) currents_A[g] = settings->rest_current_A;
        --state->rest_remaining;
    } else {
        mission_currents(settings, state->mission_index, state->displaced, state->hot, currents_A);
        ++state->mission_index;
    }
    for (g = 0; g < GTM_N_GENERATORS; ++g) {
        model_input(settings, currents_A[g], inlet_C[g], u);
        status |= gt_step(state->x_filtered[g], u, state->x_pred[g], work, GT_WORK_SIZE);
    }
    ++state->samples;
    return status ? GT_ERR_EVALUATION : GT_OK;
}

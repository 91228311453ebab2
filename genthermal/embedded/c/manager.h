/* manager.h -- the onboard load manager of two generators, in C on the generated model's ABI.
 *
 * One call of gtm_step per sample (every gt_dt_s seconds) with both generators' measured sensor
 * temperatures and coolant inlet temperatures. It updates each generator's Kalman filter (the
 * generated gt_kalman_update of the linear design model, steady-state gain) and, every
 * cycle_steps samples, predicts both windings to the end of the mission and applies the rule
 * below. It returns the phase currents to apply over the next sample.
 *
 * The rule (an engineer's heuristic; genthermal/embedded/manager.py holds the same rule in Python):
 *   1. predict both generators to the end of the mission under the current plan (rests still
 *      pending, then the remaining mission, the measured inlet temperatures held);
 *   2. if a winding is predicted above limit_C and no load is displaced yet: displace the maximum
 *      load from the hotter generator to the other for the rest of the mission -- at nominal
 *      current I the hotter carries I - d and the other I + d, d = max(0, min(I_limit - I,
 *      I - I_rest)) -- and predict again;
 *   3. if a breach is still predicted: add rest (both generators at I_rest, the mission paused) in
 *      steps of rest_quantum_steps until the prediction stays within limit_C, at most
 *      max_rest_steps in all; if none does, rest the maximum and set the infeasible flag.
 *
 * Reentrant: every state is in the caller's gtm_state_t, the work memory is the caller's
 * (gt_work_size() doubles), nothing is allocated and there is no mutable static data.
 */
#ifndef GTM_MANAGER_H
#define GTM_MANAGER_H

#include "gt.h"

#define GTM_N_GENERATORS 2

/* Settings: constant over a flight. */
typedef struct {
    const double* profile_A; /* nominal phase current per sample of the mission, A RMS */
    int n_profile;           /* samples of the mission */
    double limit_C;          /* planning limit of the winding (theta_max - margin), degC */
    double rest_current_A;   /* phase current while resting, A RMS */
    double current_limit_A;  /* highest phase current of a generator, A RMS */
    double field_no_load_A;  /* exciter law: I_exc = field_no_load_A + field_gain * I */
    double field_gain;       /* A/A */
    double ambient_C;        /* ambient temperature, degC */
    int winding_state;       /* index of the state the winding sensor measures */
    int cycle_steps;         /* samples between decisions */
    int rest_quantum_steps;  /* samples of rest added at a time */
    int max_rest_steps;      /* most rest pending at once, samples */
} gtm_settings_t;

/* State of the manager: the filters and the plan. */
typedef struct {
    double x_pred[GTM_N_GENERATORS][GT_N_STATES];     /* filter predictions for this sample, degC */
    double x_filtered[GTM_N_GENERATORS][GT_N_STATES]; /* filtered states at this sample, degC */
    double predicted_peak_C[GTM_N_GENERATORS];        /* peaks of the last prediction, degC */
    int samples;        /* samples seen */
    int mission_index;  /* next mission sample to fly */
    int rest_remaining; /* samples of rest still to fly */
    int displaced;      /* 1: load displaced from generator `hot` */
    int hot;            /* generator relieved by the displacement */
    int infeasible;     /* 1: no rest within max_rest_steps removed the breach */
    int decided;        /* 1: this sample was a decision point */
} gtm_state_t;

/* Return codes beyond GT_OK and GT_ERR_*: the mission is over. */
#define GTM_MISSION_DONE 10

/* Start a flight: cold generators at the ambient temperature, no plan. */
int gtm_init(gtm_state_t* state, const gtm_settings_t* settings);

/* One sample: y = measured (T_winding, T_iron) of each generator (degC, row per generator),
 * inlet_C = coolant inlet of each (degC). Writes the phase current of each generator for the
 * next sample (A RMS) and whether it rests. Returns GTM_MISSION_DONE once the mission is flown. */
int gtm_step(gtm_state_t* state, const gtm_settings_t* settings, const double* y, const double* inlet_C,
             double* currents_A, int* resting, double* work);

#endif

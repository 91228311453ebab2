/* flight.h -- the data of a closed-loop flight on the target (written by genthermal, flight_data.c). */
#ifndef FLIGHT_H
#define FLIGHT_H

#include "manager.h"

/* The true plants: the nominal model with its mismatch (prefix gtp) and, on generator 0 from the
 * fault's onset, the faulty model (prefix gtb) with the inlet temperature risen. */
typedef struct {
    int onset_sample;       /* first sample of the fault on generator 0 */
    double inlet_C;         /* coolant inlet before the fault, degC */
    double inlet_rise_C;    /* rise of generator 0's inlet from the onset, K */
    int sensor_states[GT_N_OUTPUTS]; /* plant state each sensor (T_winding, T_iron) reads */
    int max_samples;        /* samples of measurement noise, the longest flight */
} flight_plant_t;

extern const gtm_settings_t flight_settings;
extern const flight_plant_t flight_plant;
extern const double flight_profile_A[];
extern const double flight_noise[]; /* max_samples x generators x sensors, K */

#endif

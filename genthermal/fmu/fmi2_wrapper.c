/* fmi2_wrapper.c -- FMI 2.0 model exchange and co-simulation interface of a genthermal model.
 *
 * Written by genthermal's FMU export (genthermal/fmu/) around the generated C library "@PREFIX@"
 * (codegen/ABI.md). The FMI 2.0 types below are declared here from the standard's text so that
 * the FMU's sources compile without the standard headers.
 *
 * Variables (value references): states x[0..NX), their derivatives, inputs u, sensor outputs y,
 * then the parameters p -- one contiguous array of reals in the instance, laid out as in
 * modelDescription.xml. Derivatives and outputs are computed from (x, u, p) when read.
 * Co-simulation integrates dx/dt = f(x, u, p) over each communication step with u held, by an
 * adaptive Dormand-Prince 5(4) method (error per step below the tolerances ATOL_K, RTOL).
 * Directional derivatives come from the generated Jacobians of f and of the outputs.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "@PREFIX@.h"

/* --- FMI 2.0 types (FMI 2.0.x standard, section 2.1) ------------------------------------- */
typedef void* fmi2Component;
typedef void* fmi2ComponentEnvironment;
typedef void* fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char* fmi2String;
typedef char fmi2Byte;
#define fmi2True 1
#define fmi2False 0
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef void* (*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void*);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;

#if defined(_WIN32)
#define FMI2_EXPORT __declspec(dllexport)
#else
#define FMI2_EXPORT __attribute__((visibility("default")))
#endif

/* --- layout of the variables --------------------------------------------------------------- */
#define NX @PREFIX_UPPER@_N_STATES
#define NU @PREFIX_UPPER@_N_INPUTS
#define NY @PREFIX_UPPER@_N_OUTPUTS
#define NP @PREFIX_UPPER@_N_PARAMS
#define VR_X 0
#define VR_DX (VR_X + NX)
#define VR_U (VR_DX + NX)
#define VR_Y (VR_U + NU)
#define VR_P (VR_Y + NY)
#define N_VARIABLES (VR_P + NP)
#define GUID "@GUID@"
#define ATOL_K @ATOL_K@
#define RTOL @RTOL@
#define MAX_SUBSTEPS 100000

static const double state_start[NX] = {@STATE_START@};
static const double input_start[NU] = {@INPUT_START@};

typedef enum { STATE_INSTANTIATED, STATE_INITIALISATION, STATE_RUNNING, STATE_TERMINATED } phase_t;

typedef struct {
    double values[N_VARIABLES]; /* x, dx/dt, u, y, p */
    double time_s;
    double work[@PREFIX_UPPER@_WORK_SIZE];
    double jacobian[(NX + NY) * (NX + NU)]; /* d(dx/dt, y)/d(x, u), row-major */
    fmi2Type type;
    phase_t phase;
    int logging;
    char name[64];
    fmi2CallbackFunctions callbacks;
} instance_t;

static void log_message(instance_t* c, fmi2Status status, const char* category, const char* format, ...)
{
    char text[512];
    va_list arguments;
    if (!c->callbacks.logger || (status == fmi2OK && !c->logging)) return;
    va_start(arguments, format);
    vsnprintf(text, sizeof text, format, arguments);
    va_end(arguments);
    c->callbacks.logger(c->callbacks.componentEnvironment, c->name, status, category, "%s", text);
}

/* Derivatives and outputs from the current (x, u, p). */
static int evaluate(instance_t* c)
{
    double* v = c->values;
    if (@PREFIX@_rhs(v + VR_X, v + VR_U, v + VR_P, v + VR_DX, c->work, @PREFIX_UPPER@_WORK_SIZE) != @PREFIX_UPPER@_OK) return -1;
    return @PREFIX@_outputs(v + VR_X, v + VR_U, v + VR_P, v + VR_Y, c->work, @PREFIX_UPPER@_WORK_SIZE) == @PREFIX_UPPER@_OK ? 0 : -1;
}

/* The full Jacobian of (dx/dt, y) with respect to (x, u). */
static int evaluate_jacobian(instance_t* c)
{
    double block[(NX > NY ? NX : NY) * (NX > NU ? NX : NU)];
    const double* v = c->values;
    int i, j, status = 0;
    status |= @PREFIX@_jac_x(v + VR_X, v + VR_U, v + VR_P, block, c->work, @PREFIX_UPPER@_WORK_SIZE);
    for (i = 0; i < NX; ++i) for (j = 0; j < NX; ++j) c->jacobian[i * (NX + NU) + j] = block[i * NX + j];
    status |= @PREFIX@_jac_u(v + VR_X, v + VR_U, v + VR_P, block, c->work, @PREFIX_UPPER@_WORK_SIZE);
    for (i = 0; i < NX; ++i) for (j = 0; j < NU; ++j) c->jacobian[i * (NX + NU) + NX + j] = block[i * NU + j];
    status |= @PREFIX@_output_jac_x(v + VR_X, v + VR_U, v + VR_P, block, c->work, @PREFIX_UPPER@_WORK_SIZE);
    for (i = 0; i < NY; ++i) for (j = 0; j < NX; ++j) c->jacobian[(NX + i) * (NX + NU) + j] = block[i * NX + j];
    status |= @PREFIX@_output_jac_u(v + VR_X, v + VR_U, v + VR_P, block, c->work, @PREFIX_UPPER@_WORK_SIZE);
    for (i = 0; i < NY; ++i) for (j = 0; j < NU; ++j) c->jacobian[(NX + i) * (NX + NU) + NX + j] = block[i * NU + j];
    return status ? -1 : 0;
}

static fmi2Status fail(instance_t* c, const char* format, const char* detail)
{
    log_message(c, fmi2Error, "logStatusError", format, detail);
    return fmi2Error;
}

/* --- common functions ---------------------------------------------------------------------- */
FMI2_EXPORT const char* fmi2GetTypesPlatform(void) { return "default"; }
FMI2_EXPORT const char* fmi2GetVersion(void) { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean on, size_t n, const fmi2String categories[])
{
    (void)n;
    (void)categories;
    ((instance_t*)component)->logging = on;
    return fmi2OK;
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                          const fmi2CallbackFunctions* callbacks, fmi2Boolean visible,
                                          fmi2Boolean logging)
{
    instance_t* c;
    (void)location;
    (void)visible;
    if (!callbacks || !callbacks->allocateMemory || !callbacks->freeMemory) return NULL;
    if (!guid || strcmp(guid, GUID) != 0) {
        if (callbacks->logger)
            callbacks->logger(callbacks->componentEnvironment, name, fmi2Error, "logStatusError",
                              "GUID %s does not match this FMU's " GUID, guid ? guid : "(null)");
        return NULL;
    }
    c = callbacks->allocateMemory(1, sizeof *c);
    if (!c) return NULL;
    memset(c, 0, sizeof *c);
    c->callbacks = *callbacks;
    c->type = type;
    c->logging = logging;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "genthermal");
    memcpy(c->values + VR_X, state_start, sizeof state_start);
    memcpy(c->values + VR_U, input_start, sizeof input_start);
    memcpy(c->values + VR_P, @PREFIX@_default_params, NP * sizeof(double));
    c->phase = STATE_INSTANTIATED;
    return c;
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component component)
{
    instance_t* c = component;
    if (c) c->callbacks.freeMemory(c);
}

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean tolerance_defined, fmi2Real tolerance,
                                           fmi2Real start_time, fmi2Boolean stop_time_defined, fmi2Real stop_time)
{
    (void)tolerance_defined;
    (void)tolerance;
    (void)stop_time_defined;
    (void)stop_time;
    ((instance_t*)component)->time_s = start_time;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component component)
{
    ((instance_t*)component)->phase = STATE_INITIALISATION;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component component)
{
    instance_t* c = component;
    c->phase = STATE_RUNNING;
    return evaluate(c) ? fail(c, "%s", "the model could not be evaluated at the start values") : fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component component)
{
    ((instance_t*)component)->phase = STATE_TERMINATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component component)
{
    instance_t* c = component;
    memcpy(c->values + VR_X, state_start, sizeof state_start);
    memcpy(c->values + VR_U, input_start, sizeof input_start);
    memcpy(c->values + VR_P, @PREFIX@_default_params, NP * sizeof(double));
    c->time_s = 0.0;
    c->phase = STATE_INSTANTIATED;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component component, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    instance_t* c = component;
    size_t i;
    if (n && evaluate(c)) return fail(c, "%s", "the model could not be evaluated");
    for (i = 0; i < n; ++i) {
        if (vr[i] >= N_VARIABLES) return fail(c, "fmi2GetReal: unknown value reference%s", "");
        value[i] = c->values[vr[i]];
    }
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component component, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    instance_t* c = component;
    size_t i;
    for (i = 0; i < n; ++i) {
        unsigned int r = vr[i];
        if (r >= N_VARIABLES || (r >= VR_DX && r < VR_U) || (r >= VR_Y && r < VR_P))
            return fail(c, "fmi2SetReal: value reference %s cannot be set (derivative, output or unknown)", "");
        if (r < VR_DX && c->phase == STATE_RUNNING)
            return fail(c, "fmi2SetReal: %s", "states are set by fmi2SetContinuousStates after initialisation");
        c->values[r] = value[i];
    }
    return fmi2OK;
}

#define NO_VARIABLES_OF_TYPE(function, type)                                                         \
    FMI2_EXPORT fmi2Status function(fmi2Component component, const fmi2ValueReference vr[], size_t n, type value[]) \
    {                                                                                                \
        (void)vr;                                                                                    \
        (void)value;                                                                                 \
        return n ? fail(component, "%s: the model has only real variables", #function) : fmi2OK;    \
    }
NO_VARIABLES_OF_TYPE(fmi2GetInteger, fmi2Integer)
NO_VARIABLES_OF_TYPE(fmi2GetBoolean, fmi2Boolean)
NO_VARIABLES_OF_TYPE(fmi2GetString, fmi2String)
NO_VARIABLES_OF_TYPE(fmi2SetInteger, const fmi2Integer)
NO_VARIABLES_OF_TYPE(fmi2SetBoolean, const fmi2Boolean)
NO_VARIABLES_OF_TYPE(fmi2SetString, const fmi2String)

#define NOT_SUPPORTED(function, ...)                                                                 \
    FMI2_EXPORT fmi2Status function(fmi2Component component, __VA_ARGS__)                           \
    {                                                                                                \
        return fail(component, "%s is not supported (see modelDescription.xml capabilities)", #function); \
    }
NOT_SUPPORTED(fmi2GetFMUstate, fmi2FMUstate* state)
NOT_SUPPORTED(fmi2SetFMUstate, fmi2FMUstate state)
NOT_SUPPORTED(fmi2FreeFMUstate, fmi2FMUstate* state)
NOT_SUPPORTED(fmi2SerializedFMUstateSize, fmi2FMUstate state, size_t* size)
NOT_SUPPORTED(fmi2SerializeFMUstate, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
NOT_SUPPORTED(fmi2DeSerializeFMUstate, const fmi2Byte bytes[], size_t size, fmi2FMUstate* state)
NOT_SUPPORTED(fmi2SetRealInputDerivatives, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[],
              const fmi2Real value[])
NOT_SUPPORTED(fmi2GetRealOutputDerivatives, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[],
              fmi2Real value[])

/* Column of (x, u) a known value reference stands for, or -1; row of (dx/dt, y) of an unknown, or -1. */
static int known_column(fmi2ValueReference r)
{
    if (r < VR_DX) return (int)r;
    if (r >= VR_U && r < VR_Y) return NX + (int)(r - VR_U);
    return -1;
}

static int unknown_row(fmi2ValueReference r)
{
    if (r >= VR_DX && r < VR_U) return (int)(r - VR_DX);
    if (r >= VR_Y && r < VR_P) return NX + (int)(r - VR_Y);
    return -1;
}

FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component component, const fmi2ValueReference unknown[],
                                                    size_t n_unknown, const fmi2ValueReference known[], size_t n_known,
                                                    const fmi2Real seed[], fmi2Real sensitivity[])
{
    instance_t* c = component;
    size_t i, j;
    if (evaluate_jacobian(c)) return fail(c, "%s", "the Jacobian could not be evaluated");
    for (i = 0; i < n_unknown; ++i) {
        int row = unknown_row(unknown[i]);
        if (row < 0) return fail(c, "fmi2GetDirectionalDerivative: %s", "unknowns must be derivatives or outputs");
        sensitivity[i] = 0.0;
        for (j = 0; j < n_known; ++j) {
            int column = known_column(known[j]);
            if (column < 0) return fail(c, "fmi2GetDirectionalDerivative: %s", "knowns must be states or inputs");
            sensitivity[i] += c->jacobian[row * (NX + NU) + column] * seed[j];
        }
    }
    return fmi2OK;
}

/* --- model exchange ------------------------------------------------------------------------ */
FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component component) { (void)component; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component component, fmi2EventInfo* info)
{
    (void)component;
    memset(info, 0, sizeof *info);
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component component) { (void)component; return fmi2OK; }

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component component, fmi2Boolean no_set_state_prior,
                                                   fmi2Boolean* enter_event_mode, fmi2Boolean* terminate)
{
    (void)component;
    (void)no_set_state_prior;
    *enter_event_mode = fmi2False;
    *terminate = fmi2False;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component component, fmi2Real time)
{
    ((instance_t*)component)->time_s = time;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component component, const fmi2Real x[], size_t n)
{
    instance_t* c = component;
    if (n != NX) return fail(c, "fmi2SetContinuousStates: %s", "wrong number of states");
    memcpy(c->values + VR_X, x, NX * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component component, fmi2Real derivatives[], size_t n)
{
    instance_t* c = component;
    if (n != NX) return fail(c, "fmi2GetDerivatives: %s", "wrong number of states");
    if (evaluate(c)) return fail(c, "%s", "the model could not be evaluated");
    memcpy(derivatives, c->values + VR_DX, NX * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component component, fmi2Real indicators[], size_t n)
{
    (void)indicators;
    return n ? fail(component, "%s", "the model has no event indicators") : fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component component, fmi2Real x[], size_t n)
{
    instance_t* c = component;
    if (n != NX) return fail(c, "fmi2GetContinuousStates: %s", "wrong number of states");
    memcpy(x, c->values + VR_X, NX * sizeof(double));
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component component, fmi2Real nominals[], size_t n)
{
    size_t i;
    (void)component;
    for (i = 0; i < n; ++i) nominals[i] = 1.0;
    return fmi2OK;
}

/* --- co-simulation: adaptive Dormand-Prince 5(4) over one communication step --------------- */
static int rhs_at(instance_t* c, const double* x, double* xdot)
{
    return @PREFIX@_rhs(x, c->values + VR_U, c->values + VR_P, xdot, c->work, @PREFIX_UPPER@_WORK_SIZE) == @PREFIX_UPPER@_OK ? 0 : -1;
}

static int integrate(instance_t* c, double h_total)
{
    static const double a21 = 1.0 / 5, a31 = 3.0 / 40, a32 = 9.0 / 40, a41 = 44.0 / 45, a42 = -56.0 / 15,
                        a43 = 32.0 / 9, a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                        a54 = -212.0 / 729, a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                        a64 = 49.0 / 176, a65 = -5103.0 / 18656, b1 = 35.0 / 384, b3 = 500.0 / 1113,
                        b4 = 125.0 / 192, b5 = -2187.0 / 6784, b6 = 11.0 / 84, e1 = 71.0 / 57600,
                        e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200, e6 = 22.0 / 525,
                        e7 = -1.0 / 40;
    double* x = c->values + VR_X;
    double k1[NX], k2[NX], k3[NX], k4[NX], k5[NX], k6[NX], k7[NX], stage[NX], next[NX];
    double done = 0.0, h = h_total < 1.0 ? h_total : 1.0;
    int i, substeps = 0;
    if (rhs_at(c, x, k1)) return -1;
    while (done < h_total) {
        double error = 0.0;
        if (++substeps > MAX_SUBSTEPS) return -1;
        if (done + h > h_total) h = h_total - done;
        for (i = 0; i < NX; ++i) stage[i] = x[i] + h * a21 * k1[i];
        if (rhs_at(c, stage, k2)) return -1;
        for (i = 0; i < NX; ++i) stage[i] = x[i] + h * (a31 * k1[i] + a32 * k2[i]);
        if (rhs_at(c, stage, k3)) return -1;
        for (i = 0; i < NX; ++i) stage[i] = x[i] + h * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
        if (rhs_at(c, stage, k4)) return -1;
        for (i = 0; i < NX; ++i) stage[i] = x[i] + h * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
        if (rhs_at(c, stage, k5)) return -1;
        for (i = 0; i < NX; ++i)
            stage[i] = x[i] + h * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
        if (rhs_at(c, stage, k6)) return -1;
        for (i = 0; i < NX; ++i) next[i] = x[i] + h * (b1 * k1[i] + b3 * k3[i] + b4 * k4[i] + b5 * k5[i] + b6 * k6[i]);
        if (rhs_at(c, next, k7)) return -1;
        for (i = 0; i < NX; ++i) {
            double scale = ATOL_K + RTOL * fmax(fabs(x[i]), fabs(next[i]));
            double local = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]) / scale;
            error = fmax(error, fabs(local));
        }
        if (error <= 1.0) {
            done += h;
            memcpy(x, next, sizeof next);
            memcpy(k1, k7, sizeof k7); /* first same as last */
        }
        h *= fmin(5.0, fmax(0.2, 0.9 * pow(error > 1e-300 ? error : 1e-300, -0.2)));
    }
    return 0;
}

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component component, fmi2Real current_time, fmi2Real step, fmi2Boolean no_set_prior)
{
    instance_t* c = component;
    (void)no_set_prior;
    if (!(step >= 0.0)) return fail(c, "fmi2DoStep: %s", "the communication step must be >= 0");
    if (integrate(c, step)) return fail(c, "fmi2DoStep: %s", "integration failed");
    c->time_s = current_time + step;
    return evaluate(c) ? fail(c, "%s", "the model could not be evaluated") : fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component component)
{
    return fail(component, "%s", "fmi2CancelStep: steps are never asynchronous");
}

FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Status* value)
{
    (void)kind;
    (void)value;
    return fail(component, "%s", "fmi2GetStatus: steps are never asynchronous");
}

FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Real* value)
{
    instance_t* c = component;
    if (kind != fmi2LastSuccessfulTime) return fail(c, "%s", "fmi2GetRealStatus: only fmi2LastSuccessfulTime");
    *value = c->time_s;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Integer* value)
{
    (void)kind;
    (void)value;
    return fail(component, "%s", "fmi2GetIntegerStatus: no integer status");
}

FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Boolean* value)
{
    instance_t* c = component;
    if (kind != fmi2Terminated) return fail(c, "%s", "fmi2GetBooleanStatus: only fmi2Terminated");
    *value = fmi2False;
    return fmi2OK;
}

FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component component, const fmi2StatusKind kind, fmi2String* value)
{
    (void)kind;
    (void)value;
    return fail(component, "%s", "fmi2GetStringStatus: no string status");
}

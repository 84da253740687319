/* Shared by the C host's modes (host.c: test, bench; fuzz.c: fuzz): the FMU's functions loaded
 * with dlopen and typed by the cbindgen header's prototypes, the model description text and its
 * guid, value references by name. */
#ifndef BISTABLE_FMU_HOST_H
#define BISTABLE_FMU_HOST_H

#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bistable_impact.h"
#include "md_text.h"

#define FMI_FUNCTIONS(X)                                                                      \
    X(fmi2GetTypesPlatform) X(fmi2GetVersion) X(fmi2SetDebugLogging) X(fmi2Instantiate)      \
    X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)                \
    X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) X(fmi2GetReal)               \
    X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) X(fmi2SetReal) X(fmi2SetInteger)    \
    X(fmi2SetBoolean) X(fmi2SetString) X(fmi2GetFMUstate) X(fmi2SetFMUstate)                 \
    X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate)               \
    X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative)                               \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep)             \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus)          \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus) X(fmi2EnterEventMode)                   \
    X(fmi2NewDiscreteStates) X(fmi2EnterContinuousTimeMode) X(fmi2CompletedIntegratorStep)  \
    X(fmi2SetTime) X(fmi2SetContinuousStates) X(fmi2GetDerivatives)                          \
    X(fmi2GetEventIndicators) X(fmi2GetContinuousStates)                                     \
    X(fmi2GetNominalsOfContinuousStates)

/* The FMI 3.0 functions `host bench` times (the FMI 3.0 host of tests/fmu_host/fmi3 tests the
 * whole FMI 3.0 interface). */
#define FMI3_BENCH_FUNCTIONS(X)                                                               \
    X(fmi3InstantiateCoSimulation) X(fmi3InstantiateModelExchange)                           \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3EnterStepMode)        \
    X(fmi3EnterEventMode) X(fmi3UpdateDiscreteStates) X(fmi3DoStep) X(fmi3FreeInstance)      \
    X(fmi3GetFloat64) X(fmi3SetFloat64) X(fmi3SetInt64) X(fmi3SetTime)                       \
    X(fmi3SetContinuousStates) X(fmi3GetContinuousStateDerivatives) X(fmi3GetEventIndicators) \
    X(fmi3GetContinuousStates) X(fmi3CompletedIntegratorStep) X(fmi3EnterContinuousTimeMode)

struct fmi_table {
#define FIELD(f) __typeof__(&f) f;
    FMI_FUNCTIONS(FIELD)
    FMI3_BENCH_FUNCTIONS(FIELD)
#undef FIELD
};

/* The loaded functions (host.c). */
extern struct fmi_table F;
/* Loads every fmi2 function (and the FMI 3.0 ones of the bench) from the library at `path`; 0 on
 * success. */
int load(const char *path);
/* modelDescription.xml as text, and its guid. */
extern char *xml;
extern char guid[64];
/* The value reference of the variable `name` (exits if absent). */
fmi2ValueReference vr(const char *name);
/* Monotonic wall time (s). */
double now(void);

/* ---- test helpers (host.c) ---- */
/* Callbacks with the host's variadic logger: it keeps the last message and, for every logged
 * "impact N at t=T s ..." line, stores T in impact_t[N] (when N < MAX_IMPACTS). */
extern fmi2CallbackFunctions callbacks;
#define MAX_IMPACTS 8192
extern double impact_t[MAX_IMPACTS];
/* Counts a passed or failed check (printing the failure with the last log message). */
void hcheck(int ok, const char *what);
/* An expected refusal: fmi2Error and a logged message containing `needle`. */
void hrefused(fmi2Status s, const char *needle, const char *what);

/* `host test`, Model Exchange part (me.c): the ME driver against co-simulation, illegal calls. */
void me_tests(void);
/* The ME driver (me.c): settles an event (fmi2NewDiscreteStates until done, then continuous-time
 * mode), `*next` the next time event or INFINITY; 0 on success. */
int me_settle(fmi2Component c, double *next);
/* The ME driver: continuous-time mode from t0 to t_end with RK4 steps h, indicator sign changes
 * bisected to 1e-12 s, time event at `next`; `*events` counts event modes. 0 on success, -1 on a
 * refused call, ME_NO_PROGRESS when the next time event is not after the current time (the step
 * would be 0; a host honouring it would loop at one instant). */
#define ME_NO_PROGRESS (-2)
int me_run(fmi2Component c, double t0, double t_end, double h, double next, long *events);

/* `host bench` (bench.c): the host-loop table (FMI 2.0 and 3.0, co-simulation and Model
 * Exchange). */
void bench(void);

/* `host fuzz` (fuzz.c): arguments after the mode and the two paths. */
int fuzz_main(const char *seeds, const char *ncalls);

#endif

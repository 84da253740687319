/* Shared by the FMI 3.0 host's modes (host3.c: test; fuzz3.c: fuzz): the FMU's fmi3 functions
 * loaded with dlopen and typed by the OFFICIAL FMI 3.0 headers (fmi3Functions.h,
 * fmi3FunctionTypes.h, fmi3PlatformTypes.h as shipped with fmpy), a few fmi2 functions of the
 * same binary typed by the official fmi2FunctionTypes.h (for the bit-for-bit comparison of the
 * two APIs), the model description (FMI 3.0 modelDescription.xml) and value references by name. */
#ifndef BISTABLE_FMU_HOST3_H
#define BISTABLE_FMU_HOST3_H

#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi3Functions.h"
#include "../md_text.h"
#include "fmi2FunctionTypes.h"

/* Every function of fmi3Functions.h; all are exported by the binary (the ones the FMU does not
 * provide refuse every call with a logged reason). */
#define FMI3_FUNCTIONS(X)                                                                         \
    X(fmi3GetVersion) X(fmi3SetDebugLogging) X(fmi3InstantiateModelExchange)                      \
    X(fmi3InstantiateCoSimulation) X(fmi3InstantiateScheduledExecution) X(fmi3FreeInstance)       \
    X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode) X(fmi3EnterEventMode)            \
    X(fmi3Terminate) X(fmi3Reset) X(fmi3GetFloat32) X(fmi3GetFloat64) X(fmi3GetInt8)              \
    X(fmi3GetUInt8) X(fmi3GetInt16) X(fmi3GetUInt16) X(fmi3GetInt32) X(fmi3GetUInt32)             \
    X(fmi3GetInt64) X(fmi3GetUInt64) X(fmi3GetBoolean) X(fmi3GetString) X(fmi3GetBinary)          \
    X(fmi3GetClock) X(fmi3SetFloat32) X(fmi3SetFloat64) X(fmi3SetInt8) X(fmi3SetUInt8)            \
    X(fmi3SetInt16) X(fmi3SetUInt16) X(fmi3SetInt32) X(fmi3SetUInt32) X(fmi3SetInt64)             \
    X(fmi3SetUInt64) X(fmi3SetBoolean) X(fmi3SetString) X(fmi3SetBinary) X(fmi3SetClock)          \
    X(fmi3GetNumberOfVariableDependencies) X(fmi3GetVariableDependencies) X(fmi3GetFMUState)      \
    X(fmi3SetFMUState) X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize)                          \
    X(fmi3SerializeFMUState) X(fmi3DeserializeFMUState) X(fmi3GetDirectionalDerivative)           \
    X(fmi3GetAdjointDerivative) X(fmi3EnterConfigurationMode) X(fmi3ExitConfigurationMode)        \
    X(fmi3GetIntervalDecimal) X(fmi3GetIntervalFraction) X(fmi3GetShiftDecimal)                   \
    X(fmi3GetShiftFraction) X(fmi3SetIntervalDecimal) X(fmi3SetIntervalFraction)                  \
    X(fmi3SetShiftDecimal) X(fmi3SetShiftFraction) X(fmi3EvaluateDiscreteStates)                  \
    X(fmi3UpdateDiscreteStates) X(fmi3EnterContinuousTimeMode) X(fmi3CompletedIntegratorStep)     \
    X(fmi3SetTime) X(fmi3SetContinuousStates) X(fmi3GetContinuousStateDerivatives)                \
    X(fmi3GetEventIndicators) X(fmi3GetContinuousStates) X(fmi3GetNominalsOfContinuousStates)     \
    X(fmi3GetNumberOfEventIndicators) X(fmi3GetNumberOfContinuousStates) X(fmi3EnterStepMode)     \
    X(fmi3GetOutputDerivatives) X(fmi3DoStep) X(fmi3ActivateModelPartition)

/* The fmi2 functions of the same binary used by the host (scenario (b) and the cross-API
 * refusals). */
#define FMI2_FUNCTIONS(X)                                                                         \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode)  \
    X(fmi2ExitInitializationMode) X(fmi2DoStep) X(fmi2GetReal) X(fmi2GetInteger)                  \
    X(fmi2GetBoolean) X(fmi2SetReal) X(fmi2GetFMUstate)

struct fmi3_table {
#define FIELD3(f) f##TYPE *f;
    FMI3_FUNCTIONS(FIELD3)
    FMI2_FUNCTIONS(FIELD3)
#undef FIELD3
};

/* The loaded functions (host3.c). */
extern struct fmi3_table F3;
/* Loads every function from the library at `path`; 0 on success. */
int load3(const char *path);
/* modelDescription.xml (FMI 3.0) as text, and its instantiationToken. */
extern char *xml3;
extern char token[64];
/* The value reference of the variable `name` (exits if absent). */
fmi3ValueReference vr3(const char *name);
/* Monotonic wall time (s). */
double now3(void);

/* The host's logMessage callback (host3.c): keeps the last message and its status; counts
 * messages; prints them with HOST_VERBOSE=1. */
void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
             fmi3String message);
extern char last_msg3[2048];
extern int last_status3;
extern long n_msgs3;

/* Variables of the FMI 3.0 model description (host3.c parses them). */
enum { T_F64, T_I32, T_I64, T_BOOL };
enum { C_PARAM, C_INPUT, C_OUTPUT, C_LOCAL, C_INDEPENDENT };
#define MAXV3 64
typedef struct {
    char name[48];
    fmi3ValueReference vr;
    int type, caus, tunable;
    double start, min, max;
} Var3;
extern Var3 vars3[MAXV3];
extern int nv3;
/* Index of the variable `name` in vars3 (exits if absent). */
int var3_index(const char *name);
/* Index of the variable with value reference `r`, -1 if none. */
int var3_of(fmi3ValueReference r);

/* All outputs, read with the three getters, in vars3 order (Float64, Int32, Boolean). */
#define MAXOUT 48
typedef struct {
    double f[MAXOUT];
    int32_t i[MAXOUT];
    bool b[MAXOUT];
    int nf, ni, nb;
} Outputs;
/* Reads every output of an fmi3 instance; fmi3OK or the first failing status. */
fmi3Status read_outputs3(fmi3Instance c, Outputs *o);

/* `host3 fuzz` (fuzz3.c): arguments after the mode and the two paths. */
int fuzz3_main(const char *seeds, const char *ncalls);

#endif

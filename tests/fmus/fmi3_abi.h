/*
 * The FMI 3.0 C interface as dsmcosim's FMI 3.0 test FMU exports it, written out here
 * from the standard's definitions: the scalar types, the status codes, the callback
 * types and every function an importer may look up by name. An importer such as FMPy
 * resolves the whole set when it loads an FMU, whatever kind of instance it then makes,
 * so the test FMU defines each one (those it does not support answer fmi3Error).
 */
#ifndef DSMCOSIM_FMI3_ABI_H
#define DSMCOSIM_FMI3_ABI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Functions looked up by name must be visible outside the shared library. */
#define FMI3_Export __attribute__((visibility("default")))

typedef void *fmi3Instance;            /* the FMU's instance */
typedef void *fmi3InstanceEnvironment; /* the importer's pointer, handed back to it */
typedef void *fmi3FMUState;            /* a saved state */
typedef uint32_t fmi3ValueReference;
typedef float fmi3Float32;
typedef double fmi3Float64;
typedef int8_t fmi3Int8;
typedef uint8_t fmi3UInt8;
typedef int16_t fmi3Int16;
typedef uint16_t fmi3UInt16;
typedef int32_t fmi3Int32;
typedef uint32_t fmi3UInt32;
typedef int64_t fmi3Int64;
typedef uint64_t fmi3UInt64;
typedef bool fmi3Boolean; /* C99 bool, one byte on the platforms FMI 3.0 names */
typedef char fmi3Char;
typedef const fmi3Char *fmi3String;
typedef uint8_t fmi3Byte;
typedef const fmi3Byte *fmi3Binary;
typedef bool fmi3Clock;

typedef enum {
    fmi3OK = 0,
    fmi3Warning = 1,
    fmi3Discard = 2,
    fmi3Error = 3,
    fmi3Fatal = 4
} fmi3Status;

typedef enum {
    fmi3Independent = 0,
    fmi3Constant = 1,
    fmi3Fixed = 2,
    fmi3Tunable = 3,
    fmi3Discrete = 4,
    fmi3Dependent = 5
} fmi3DependencyKind;

typedef enum {
    fmi3IntervalNotYetKnown = 0,
    fmi3IntervalUnchanged = 1,
    fmi3IntervalChanged = 2
} fmi3IntervalQualifier;

/* Callbacks. Unlike FMI 2.0's logger this one is not variadic: the message is final. */
typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status,
                                       fmi3String category, fmi3String message);
typedef void (*fmi3IntermediateUpdateCallback)(
    fmi3InstanceEnvironment, fmi3Float64 intermediateUpdateTime, fmi3Boolean intermediateVariableSetRequested,
    fmi3Boolean intermediateVariableGetAllowed, fmi3Boolean intermediateStepFinished,
    fmi3Boolean canReturnEarly, fmi3Boolean *earlyReturnRequested,
    fmi3Float64 *earlyReturnTime);
typedef void (*fmi3ClockUpdateCallback)(fmi3InstanceEnvironment);
typedef void (*fmi3LockPreemptionCallback)(void);
typedef void (*fmi3UnlockPreemptionCallback)(void);

/* Inquiry, logging, life cycle. */
FMI3_Export const char *fmi3GetVersion(void);
FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[]);
FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName,
                                                      fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn,
                                                      fmi3InstanceEnvironment instanceEnvironment,
                                                      fmi3LogMessageCallback logMessage);
FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate);
FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption);
FMI3_Export void fmi3FreeInstance(fmi3Instance);

/* Modes. */
FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined,
                                                   fmi3Float64 stopTime);
FMI3_Export fmi3Status fmi3ExitInitializationMode(fmi3Instance);
FMI3_Export fmi3Status fmi3EnterEventMode(fmi3Instance);
FMI3_Export fmi3Status fmi3Terminate(fmi3Instance);
FMI3_Export fmi3Status fmi3Reset(fmi3Instance);
FMI3_Export fmi3Status fmi3EnterConfigurationMode(fmi3Instance);
FMI3_Export fmi3Status fmi3ExitConfigurationMode(fmi3Instance);

/* Values: one getter and one setter per type, each given the value count as well. */
#define FMI3_GET_SET(Name, Type)                                                            \
    FMI3_Export fmi3Status fmi3Get##Name(fmi3Instance, const fmi3ValueReference vr[],       \
                                         size_t nvr, Type values[], size_t nValues);         \
    FMI3_Export fmi3Status fmi3Set##Name(fmi3Instance, const fmi3ValueReference vr[],       \
                                         size_t nvr, const Type values[], size_t nValues);
FMI3_GET_SET(Float32, fmi3Float32)
FMI3_GET_SET(Float64, fmi3Float64)
FMI3_GET_SET(Int8, fmi3Int8)
FMI3_GET_SET(UInt8, fmi3UInt8)
FMI3_GET_SET(Int16, fmi3Int16)
FMI3_GET_SET(UInt16, fmi3UInt16)
FMI3_GET_SET(Int32, fmi3Int32)
FMI3_GET_SET(UInt32, fmi3UInt32)
FMI3_GET_SET(Int64, fmi3Int64)
FMI3_GET_SET(UInt64, fmi3UInt64)
FMI3_GET_SET(Boolean, fmi3Boolean)
FMI3_GET_SET(String, fmi3String)
#undef FMI3_GET_SET
FMI3_Export fmi3Status fmi3GetBinary(fmi3Instance, const fmi3ValueReference vr[], size_t nvr,
                                     size_t valueSizes[], fmi3Binary values[], size_t nValues);
FMI3_Export fmi3Status fmi3SetBinary(fmi3Instance, const fmi3ValueReference vr[], size_t nvr,
                                     const size_t valueSizes[], const fmi3Binary values[],
                                     size_t nValues);
FMI3_Export fmi3Status fmi3GetClock(fmi3Instance, const fmi3ValueReference vr[], size_t nvr,
                                    fmi3Clock values[]);
FMI3_Export fmi3Status fmi3SetClock(fmi3Instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Clock values[]);

/* Structure. */
FMI3_Export fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance, fmi3ValueReference vr,
                                                           size_t *nDependencies);
FMI3_Export fmi3Status fmi3GetVariableDependencies(
    fmi3Instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[],
    fmi3ValueReference independents[], size_t elementIndicesOfIndependents[],
    fmi3DependencyKind dependencyKinds[], size_t nDependencies);

/* Saved states. */
FMI3_Export fmi3Status fmi3GetFMUState(fmi3Instance, fmi3FMUState *state);
FMI3_Export fmi3Status fmi3SetFMUState(fmi3Instance, fmi3FMUState state);
FMI3_Export fmi3Status fmi3FreeFMUState(fmi3Instance, fmi3FMUState *state);
FMI3_Export fmi3Status fmi3SerializedFMUStateSize(fmi3Instance, fmi3FMUState, size_t *size);
FMI3_Export fmi3Status fmi3SerializeFMUState(fmi3Instance, fmi3FMUState, fmi3Byte bytes[],
                                             size_t size);
FMI3_Export fmi3Status fmi3DeserializeFMUState(fmi3Instance, const fmi3Byte bytes[], size_t size,
                                               fmi3FMUState *state);

/* Derivatives. */
FMI3_Export fmi3Status fmi3GetDirectionalDerivative(
    fmi3Instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
    fmi3Float64 sensitivity[], size_t nSensitivity);
FMI3_Export fmi3Status fmi3GetAdjointDerivative(
    fmi3Instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
    fmi3Float64 sensitivity[], size_t nSensitivity);
FMI3_Export fmi3Status fmi3GetOutputDerivatives(fmi3Instance, const fmi3ValueReference vr[],
                                                size_t nvr, const fmi3Int32 orders[],
                                                fmi3Float64 values[], size_t nValues);

/* Clocks (scheduled execution and event mode). */
FMI3_Export fmi3Status fmi3GetIntervalDecimal(fmi3Instance, const fmi3ValueReference vr[],
                                              size_t nvr, fmi3Float64 intervals[],
                                              fmi3IntervalQualifier qualifiers[]);
FMI3_Export fmi3Status fmi3GetIntervalFraction(fmi3Instance, const fmi3ValueReference vr[],
                                               size_t nvr, fmi3UInt64 counters[],
                                               fmi3UInt64 resolutions[],
                                               fmi3IntervalQualifier qualifiers[]);
FMI3_Export fmi3Status fmi3GetShiftDecimal(fmi3Instance, const fmi3ValueReference vr[],
                                           size_t nvr, fmi3Float64 shifts[]);
FMI3_Export fmi3Status fmi3GetShiftFraction(fmi3Instance, const fmi3ValueReference vr[],
                                            size_t nvr, fmi3UInt64 counters[],
                                            fmi3UInt64 resolutions[]);
FMI3_Export fmi3Status fmi3SetIntervalDecimal(fmi3Instance, const fmi3ValueReference vr[],
                                              size_t nvr, const fmi3Float64 intervals[]);
FMI3_Export fmi3Status fmi3SetIntervalFraction(fmi3Instance, const fmi3ValueReference vr[],
                                               size_t nvr, const fmi3UInt64 counters[],
                                               const fmi3UInt64 resolutions[]);
FMI3_Export fmi3Status fmi3SetShiftDecimal(fmi3Instance, const fmi3ValueReference vr[],
                                           size_t nvr, const fmi3Float64 shifts[]);
FMI3_Export fmi3Status fmi3SetShiftFraction(fmi3Instance, const fmi3ValueReference vr[],
                                            size_t nvr, const fmi3UInt64 counters[],
                                            const fmi3UInt64 resolutions[]);
FMI3_Export fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance);
FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined,
                                                fmi3Float64 *nextEventTime);

/* Model exchange. */
FMI3_Export fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance);
FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance,
                                                   fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode,
                                                   fmi3Boolean *terminateSimulation);
FMI3_Export fmi3Status fmi3SetTime(fmi3Instance, fmi3Float64 time);
FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance, const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates);
FMI3_Export fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance, fmi3Float64 derivatives[],
                                                         size_t nContinuousStates);
FMI3_Export fmi3Status fmi3GetEventIndicators(fmi3Instance, fmi3Float64 eventIndicators[],
                                              size_t nEventIndicators);
FMI3_Export fmi3Status fmi3GetContinuousStates(fmi3Instance, fmi3Float64 continuousStates[],
                                               size_t nContinuousStates);
FMI3_Export fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance, fmi3Float64 nominals[],
                                                         size_t nContinuousStates);
FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance, size_t *nEventIndicators);
FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance, size_t *nContinuousStates);

/* Co-simulation. */
FMI3_Export fmi3Status fmi3EnterStepMode(fmi3Instance);
FMI3_Export fmi3Status fmi3DoStep(fmi3Instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize,
                                  fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime);

/* Scheduled execution. */
FMI3_Export fmi3Status fmi3ActivateModelPartition(fmi3Instance, fmi3ValueReference clockReference,
                                                  fmi3Float64 activationTime);

#endif

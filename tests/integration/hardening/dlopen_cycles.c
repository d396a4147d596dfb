/* dlopen/dlclose cycles of the FMU binary, for valgrind memcheck and
 * AddressSanitizer (tests/integration/hardening.sh runs it under both).
 *
 *   dlopen_cycles LIBRARY.so GUID CYCLES VR_REFUSED VR_STEPPED OUTPUT_VRS [--panic]
 *
 * (OUTPUT_VRS comma-separated; tests/integration/hardening.sh reads all of these from
 * modelDescription.xml.)
 *
 * Each cycle loads the library, looks up the functions, instantiates two
 * instances, initializes, sets inputs, steps, reads every output (must be
 * finite), gets, serializes, deserializes, restores and frees FMU states,
 * makes a few calls that must fail (so error paths and their log messages
 * run too), terminates, frees, and unloads the library. With --panic (a
 * library built with the test-only feature test-hooks) every cycle also
 * makes a step panic inside the FMU: it must come back as fmi2Error, the
 * instance must refuse a getter, and fmi2Reset must make it usable again.
 *
 * Prints "N passed, M failed" (cycles) and exits non-zero on a failure.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#include "library.h"

/* Counts messages per status; formats each one as a real importer would. */
typedef struct {
    int messages[6];
} Log;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    Log *log = (Log *)env;
    char buffer[2048];
    va_list args;
    va_start(args, message);
    vsnprintf(buffer, sizeof buffer, message, args);
    va_end(args);
    if (instance == NULL || category == NULL || status > fmi2Pending) {
        fprintf(stderr, "malformed log call\n");
        abort();
    }
    log->messages[status]++;
}

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2SetDebugLoggingTYPE *set_debug_logging;
    fmi2GetRealTYPE *get_real;
    fmi2SetRealTYPE *set_real;
    fmi2DoStepTYPE *do_step;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *serialized_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
} Api;

static int failures;

#define CHECK(cond, ...)                                                                                               \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            if (failures < 5) {                                                                                        \
                fprintf(stderr, "cycle %d: ", cycle);                                                                  \
                fprintf(stderr, __VA_ARGS__);                                                                          \
                fprintf(stderr, " (%s:%d)\n", __FILE__, __LINE__);                                                     \
            }                                                                                                          \
            return 1;                                                                                                  \
        }                                                                                                              \
    } while (0)

static void *lookup(Library lib, const char *name) {
    void *f = find_symbol(lib, name);
    if (f == NULL) {
        fprintf(stderr, "%s is not exported: %s\n", name, library_error());
        exit(2);
    }
    return f;
}

/* Value references, from the command line. */
static fmi2ValueReference VR_REFUSED, VR_STEPPED;
#define MAX_OUTPUTS 64
static fmi2ValueReference OUTPUTS[MAX_OUTPUTS];
static size_t N_OUTPUTS;

static int run_instance(const Api *api, const char *guid, int cycle, int panic) {
    Log log = {{0}};
    fmi2CallbackFunctions functions = {logger, NULL, NULL, NULL, &log};
    fmi2Component c = api->instantiate("cycle", fmi2CoSimulation, guid, NULL, &functions, 0, cycle % 2);
    CHECK(c != NULL, "fmi2Instantiate failed");
    /* A wrong GUID is refused with a message, and nothing leaks. */
    CHECK(api->instantiate("bad", fmi2CoSimulation, "{not-the-guid}", NULL, &functions, 0, 0) == NULL,
          "a wrong GUID was accepted");
    CHECK(api->setup(c, 1, 1e-6, 0.0, 0, 0.0) == fmi2OK, "fmi2SetupExperiment");
    CHECK(api->enter_init(c) == fmi2OK, "fmi2EnterInitializationMode");
    CHECK(api->exit_init(c) == fmi2OK, "fmi2ExitInitializationMode");
    double t = 0.0, h = 0.01;
    fmi2FMUstate saved = NULL;
    for (int k = 0; k < 20; k++) {
        fmi2Real speed = 5.0 + 0.01 * k;
        CHECK(api->set_real(c, &VR_STEPPED, 1, &speed) == fmi2OK, "fmi2SetReal");
        CHECK(api->do_step(c, t, h, 1) == fmi2OK, "fmi2DoStep at %g", t);
        t += h;
        if (k == 10) {
            CHECK(api->get_state(c, &saved) == fmi2OK && saved != NULL, "fmi2GetFMUstate");
        }
    }
    fmi2Real out[MAX_OUTPUTS];
    CHECK(api->get_real(c, OUTPUTS, N_OUTPUTS, out) == fmi2OK, "fmi2GetReal");
    for (size_t i = 0; i < N_OUTPUTS; i++) {
        CHECK(isfinite(out[i]), "output %u = %g", OUTPUTS[i], out[i]);
    }
    /* Serialize, deserialize into a new state, restore it, free both. */
    size_t size = 0;
    CHECK(api->serialized_size(c, saved, &size) == fmi2OK && size > 0, "fmi2SerializedFMUstateSize");
    fmi2Byte *bytes = malloc(size);
    CHECK(api->serialize(c, saved, bytes, size) == fmi2OK, "fmi2SerializeFMUstate");
    fmi2FMUstate copy = NULL;
    CHECK(api->deserialize(c, bytes, size, &copy) == fmi2OK && copy != NULL, "fmi2DeSerializeFMUstate");
    bytes[size / 2] ^= 0x10;
    fmi2FMUstate corrupt = NULL;
    CHECK(api->deserialize(c, bytes, size, &corrupt) == fmi2Error && corrupt == NULL, "corrupted bytes accepted");
    free(bytes);
    CHECK(api->reset(c) == fmi2OK, "fmi2Reset after an error");
    CHECK(api->set_state(c, copy) == fmi2OK, "fmi2SetFMUstate");
    CHECK(api->do_step(c, 0.11, h, 1) == fmi2OK, "fmi2DoStep after restoring");
    CHECK(api->free_state(c, &copy) == fmi2OK && copy == NULL, "fmi2FreeFMUstate");
    fmi2FMUstate stale = saved;
    CHECK(api->free_state(c, &saved) == fmi2OK && saved == NULL, "fmi2FreeFMUstate");
    /* A double free is refused, not done. */
    CHECK(api->free_state(c, &stale) == fmi2Error, "a double free of an FMU state was accepted");
    CHECK(api->reset(c) == fmi2OK, "fmi2Reset");
    fmi2Real nan = NAN;
    CHECK(api->set_real(c, &VR_REFUSED, 1, &nan) == fmi2Error, "NaN accepted");
    CHECK(log.messages[fmi2Error] >= 4, "errors without log messages (%d)", log.messages[fmi2Error]);
    CHECK(api->reset(c) == fmi2OK, "fmi2Reset after an error");
    if (panic) {
        CHECK(api->reset(c) == fmi2OK, "fmi2Reset");
        CHECK(api->setup(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK && api->enter_init(c) == fmi2OK &&
                  api->exit_init(c) == fmi2OK,
              "initialization");
        const fmi2String hook[] = {"testHook.panicInNextDoStep"};
        CHECK(api->set_debug_logging(c, 1, 1, hook) == fmi2OK, "arming the test hook (library without test-hooks?)");
        CHECK(api->do_step(c, 0.0, h, 1) == fmi2Error, "a panic in the step did not give fmi2Error");
        CHECK(api->get_real(c, OUTPUTS, N_OUTPUTS, out) == fmi2Error, "a poisoned instance answered fmi2GetReal");
        CHECK(api->reset(c) == fmi2OK, "fmi2Reset of a poisoned instance");
        CHECK(api->setup(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK && api->enter_init(c) == fmi2OK &&
                  api->exit_init(c) == fmi2OK && api->do_step(c, 0.0, h, 1) == fmi2OK,
              "the instance does not work after fmi2Reset");
    } else {
        CHECK(api->setup(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK && api->enter_init(c) == fmi2OK &&
                  api->exit_init(c) == fmi2OK && api->do_step(c, 0.0, h, 1) == fmi2OK,
              "initialization after reset");
    }
    CHECK(api->terminate(c) == fmi2OK, "fmi2Terminate");
    /* One state left unfreed on purpose: fmi2FreeInstance must free it. */
    fmi2FMUstate left = NULL;
    CHECK(api->get_state(c, &left) == fmi2OK, "fmi2GetFMUstate");
    api->free_instance(c);
    api->free_instance(NULL);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: %s LIBRARY.so GUID CYCLES VR_REFUSED VR_STEPPED OUTPUT_VRS [--panic]\n", argv[0]);
        return 2;
    }
    const char *path = argv[1], *guid = argv[2];
    int cycles = atoi(argv[3]);
    VR_REFUSED = (fmi2ValueReference)strtoul(argv[4], NULL, 10);
    VR_STEPPED = (fmi2ValueReference)strtoul(argv[5], NULL, 10);
    for (char *p = argv[6]; *p && N_OUTPUTS < MAX_OUTPUTS;) {
        OUTPUTS[N_OUTPUTS++] = (fmi2ValueReference)strtoul(p, &p, 10);
        if (*p == ',') p++;
    }
    int panic = argc > 7 && strcmp(argv[7], "--panic") == 0;
    int passed = 0, unloaded = 0;
    for (int cycle = 0; cycle < cycles; cycle++) {
        Library lib = open_library(path);
        if (lib == NULL) {
            fprintf(stderr, "loading %s: %s\n", path, library_error());
            return 2;
        }
        Api api = {
            lookup(lib, "fmi2Instantiate"), lookup(lib, "fmi2FreeInstance"),
            lookup(lib, "fmi2SetupExperiment"), lookup(lib, "fmi2EnterInitializationMode"),
            lookup(lib, "fmi2ExitInitializationMode"), lookup(lib, "fmi2Terminate"),
            lookup(lib, "fmi2Reset"), lookup(lib, "fmi2SetDebugLogging"),
            lookup(lib, "fmi2GetReal"), lookup(lib, "fmi2SetReal"),
            lookup(lib, "fmi2DoStep"), lookup(lib, "fmi2GetFMUstate"),
            lookup(lib, "fmi2SetFMUstate"), lookup(lib, "fmi2FreeFMUstate"),
            lookup(lib, "fmi2SerializedFMUstateSize"), lookup(lib, "fmi2SerializeFMUstate"),
            lookup(lib, "fmi2DeSerializeFMUstate"),
        };
        int failed = run_instance(&api, guid, cycle, panic) || run_instance(&api, guid, cycle, panic);
        close_library(lib);
        /* Was the library really unloaded (no instance keeps a reference)? */
        if (!library_is_loaded(path)) {
            unloaded++;
        }
        if (failed) {
            failures++;
        } else {
            passed++;
        }
    }
    printf("dlopen_cycles: %d cycles of %s%s, unloaded after dlclose in %d\n", cycles, path,
           panic ? " with a caught panic each" : "", unloaded);
    printf("%d passed, %d failed\n", passed, failures);
    return failures != 0;
}

/*
 * A minimal FMI 2.0 co-simulation importer for ConvertingSpan, written
 * against FMPy's copy of the standard headers, portable: dlopen on Linux,
 * LoadLibrary on Windows. tests/integration/python/test_c_importer.py compiles it with
 *
 *     gcc -Wall -Werror -I <fmpy>/c-code importer.c -o importer -ldl
 *
 * (tests/integration/cross/test_platforms.py also with x86_64-w64-mingw32-gcc and
 * aarch64-linux-gnu-gcc, run under Wine and QEMU) and runs it as
 *
 *     importer <path of binaries/<platform>/ConvertingSpan.<so|dll>> <GUID> name=vr ...
 *
 * or, for the scripted scenes of the cross-platform tests, as
 *
 *     importer <library> <GUID> --script <file>       (see run_script below)
 *     importer <library> <GUID> --reload <input vr> <output vr>   (see run_reload below)
 *
 * The value references come from the command line (the test reads them from
 * modelDescription.xml); none is written here. Results go to stdout as CSV:
 *
 *     param,<name>,<value>                  a parameter or input this program set
 *     info,<what>,<text>                    fmi2GetVersion, fmi2GetTypesPlatform
 *     status,<label>,<fmi2Status>           a call that must succeed
 *     illegal,<label>,<fmi2Status>          a call that the standard forbids here
 *     row,<k>,<t>,<T>,<strain>,<x>,<v>      outputs after k steps (k = 0: after init)
 *     feedthrough,<k>,<T before>,<T after>  T read before and after an input change
 *     cont,<run>,<i>,<t>,<T>,<strain>,<x>   continuation runs after the FMU state tests
 *     check,<what>,<0|1>                    a comparison made here
 *
 * Log messages of the FMU go to stderr as log,<instance>,<status>,<category>,<message>.
 * The exit code is 0 if every call that must succeed did, 1 otherwise, 2 on
 * a usage or loading problem.
 */

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#include "library.h"

/* ---- the API, looked up by name and typed with the header's TYPEs ---- */

typedef struct {
    fmi2GetVersionTYPE *getVersion;
    fmi2GetTypesPlatformTYPE *getTypesPlatform;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *freeInstance;
    fmi2SetupExperimentTYPE *setupExperiment;
    fmi2EnterInitializationModeTYPE *enterInitializationMode;
    fmi2ExitInitializationModeTYPE *exitInitializationMode;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2GetRealTYPE *getReal;
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetBooleanTYPE *setBoolean;
    fmi2SetDebugLoggingTYPE *setDebugLogging;
    fmi2DoStepTYPE *doStep;
    fmi2GetFMUstateTYPE *getFMUstate;
    fmi2SetFMUstateTYPE *setFMUstate;
    fmi2FreeFMUstateTYPE *freeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *serializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *serializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *deSerializeFMUstate;
} Api;

/* #sym and sym##TYPE take the argument before macro expansion, so
   LOAD(instantiate, fmi2Instantiate) looks up "fmi2Instantiate" and casts
   to fmi2InstantiateTYPE*. */
#define LOAD(field, sym)                                                        \
    do {                                                                        \
        api->field = (sym##TYPE *)find_symbol(lib, #sym);                       \
        if (api->field == NULL) {                                               \
            fprintf(stderr, "importer: %s not found: %s\n", #sym, library_error()); \
            return 0;                                                           \
        }                                                                       \
    } while (0)

static int load_api(Library lib, Api *api)
{
    LOAD(getVersion, fmi2GetVersion);
    LOAD(getTypesPlatform, fmi2GetTypesPlatform);
    LOAD(instantiate, fmi2Instantiate);
    LOAD(freeInstance, fmi2FreeInstance);
    LOAD(setupExperiment, fmi2SetupExperiment);
    LOAD(enterInitializationMode, fmi2EnterInitializationMode);
    LOAD(exitInitializationMode, fmi2ExitInitializationMode);
    LOAD(terminate, fmi2Terminate);
    LOAD(reset, fmi2Reset);
    LOAD(getReal, fmi2GetReal);
    LOAD(setReal, fmi2SetReal);
    LOAD(setInteger, fmi2SetInteger);
    LOAD(setBoolean, fmi2SetBoolean);
    LOAD(setDebugLogging, fmi2SetDebugLogging);
    LOAD(doStep, fmi2DoStep);
    LOAD(getFMUstate, fmi2GetFMUstate);
    LOAD(setFMUstate, fmi2SetFMUstate);
    LOAD(freeFMUstate, fmi2FreeFMUstate);
    LOAD(serializedFMUstateSize, fmi2SerializedFMUstateSize);
    LOAD(serializeFMUstate, fmi2SerializeFMUstate);
    LOAD(deSerializeFMUstate, fmi2DeSerializeFMUstate);
    return 1;
}

/* ---- logger: variadic, formats with vsnprintf like any FMI importer ---- */

static void logger(fmi2ComponentEnvironment env, fmi2String instanceName, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    char text[4096];
    va_list args;
    (void)env;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "(null)", args);
    va_end(args);
    fprintf(stderr, "log,%s,%d,%s,%s\n", instanceName ? instanceName : "(null)", (int)status,
            category ? category : "(null)", text);
}

/* ---- value references from the command line ---- */

static int n_refs;
static char **ref_args;

static fmi2ValueReference vr_of(const char *name)
{
    size_t n = strlen(name);
    for (int i = 0; i < n_refs; i++) {
        if (strncmp(ref_args[i], name, n) == 0 && ref_args[i][n] == '=') {
            return (fmi2ValueReference)strtoul(ref_args[i] + n + 1, NULL, 10);
        }
    }
    fprintf(stderr, "importer: no value reference given for %s (pass %s=<vr>)\n", name, name);
    exit(2);
}

/* ---- bookkeeping ---- */

static int failures;

static fmi2Status must(const char *label, fmi2Status status)
{
    printf("status,%s,%d\n", label, (int)status);
    if (status != fmi2OK) {
        failures++;
    }
    return status;
}

static void illegal(const char *label, fmi2Status status)
{
    printf("illegal,%s,%d\n", label, (int)status);
}

static void set_real(const Api *api, fmi2Component c, const char *name, double value)
{
    fmi2ValueReference vr = vr_of(name);
    char label[128];
    snprintf(label, sizeof label, "set %s", name);
    must(label, api->setReal(c, &vr, 1, &value));
    printf("param,%s,%.17g\n", name, value);
}

static void set_integer(const Api *api, fmi2Component c, const char *name, int value)
{
    fmi2ValueReference vr = vr_of(name);
    fmi2Integer v = value;
    char label[128];
    snprintf(label, sizeof label, "set %s", name);
    must(label, api->setInteger(c, &vr, 1, &v));
    printf("param,%s,%d\n", name, value);
}

static void set_boolean(const Api *api, fmi2Component c, const char *name, int value)
{
    fmi2ValueReference vr = vr_of(name);
    fmi2Boolean v = value ? fmi2True : fmi2False;
    char label[128];
    snprintf(label, sizeof label, "set %s", name);
    must(label, api->setBoolean(c, &vr, 1, &v));
    printf("param,%s,%d\n", name, value ? 1 : 0);
}

enum { O_T, O_STRAIN, O_X, O_V, N_OUT };

static void get_outputs(const Api *api, fmi2Component c, double out[N_OUT])
{
    fmi2ValueReference vrs[N_OUT] = {vr_of("T"), vr_of("summary_Strain"), vr_of("unstretchedLength"), vr_of("v")};
    fmi2Status s = api->getReal(c, vrs, N_OUT, out);
    if (s != fmi2OK) {
        must("get outputs", s);
    }
}

/* The scene. The test reads it back from the param lines. */
#define H 1e-3
#define N_STEPS 1000
#define N_CONT 100

/* n steps from t, with web_b.v changed at step n/2; values into rec[n][3]. */
static int continuation(const Api *api, fmi2Component c, double t, int n, double rec[][3])
{
    fmi2ValueReference vb = vr_of("web_b.v");
    for (int i = 0; i < n; i++) {
        if (i == n / 2) {
            double v = 4.999;
            if (api->setReal(c, &vb, 1, &v) != fmi2OK) {
                return 0;
            }
        }
        if (api->doStep(c, t + i * H, H, fmi2True) != fmi2OK) {
            return 0;
        }
        double out[N_OUT];
        get_outputs(api, c, out);
        rec[i][0] = out[O_T];
        rec[i][1] = out[O_STRAIN];
        rec[i][2] = out[O_X];
    }
    return 1;
}

static void print_cont(const char *run, double t, int n, double rec[][3])
{
    for (int i = 0; i < n; i++) {
        printf("cont,%s,%d,%.17g,%.17g,%.17g,%.17g\n", run, i + 1, t + (i + 1) * H, rec[i][0], rec[i][1], rec[i][2]);
    }
}

/* ---- scripted scenes (--script): the same calls on every platform ----
 *
 * One command per line; values are the 16 hex digits of an IEEE double's bits,
 * so no platform's strtod or printf takes part:
 *
 *     resources <URI>                     the resource location of later instances (a Line FMU's)
 *     instance <name>                     fmi2Instantiate (co-simulation, logging on)
 *     setup <stop bits>                   fmi2SetupExperiment from 0
 *     real|integer|boolean <vr> <value>   one set (integer and boolean values in decimal)
 *     enter | exit | terminate | reset    the lifecycle calls
 *     outputs <vr> ...                    the Reals printed after every step
 *     steps <n> <h bits>                  n calls of fmi2DoStep from the instance's time
 *     save <file>                         serialize the FMU state to a file
 *     load <file> <t bits>                set the FMU state from one; t: its time
 *     hook                                arm the test-only panic of the next step
 *     free                                fmi2FreeInstance
 *
 * Output: call,<line>,<command>,<fmi2Status> for every call and
 * out,<line>,<k>,<bits>... after every step; the FMU's log to stderr. */

static double from_bits(const char *text)
{
    uint64_t bits = strtoull(text, NULL, 16);
    double value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

static uint64_t to_bits(double value)
{
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    return bits;
}

static int run_script(const Api *api, const char *guid, const char *path)
{
    FILE *script = fopen(path, "r");
    if (script == NULL) {
        fprintf(stderr, "importer: cannot open %s\n", path);
        return 2;
    }
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = NULL;
    fmi2ValueReference outputs[64];
    int n_outputs = 0, line_no = 0;
    double t = 0.0;
    char line[4096];
    char resources[4096] = "file:///nonexistent/resources";
    while (fgets(line, sizeof line, script) != NULL) {
        char *words[70];
        int n = 0;
        line_no++;
        for (char *w = strtok(line, " \t\r\n"); w != NULL && n < 70; w = strtok(NULL, " \t\r\n")) {
            words[n++] = w;
        }
        if (n == 0) {
            continue;
        }
        const char *cmd = words[0];
        fmi2Status s = fmi2OK;
        if (strcmp(cmd, "resources") == 0 && n == 2) {
            snprintf(resources, sizeof resources, "%s", words[1]);
            continue;
        }
        if (strcmp(cmd, "instance") == 0 && n == 2) {
            c = api->instantiate(words[1], fmi2CoSimulation, guid, resources, &callbacks,
                                 fmi2False, fmi2True);
            t = 0.0;
            s = c != NULL ? fmi2OK : fmi2Error;
        } else if (c == NULL) {
            fprintf(stderr, "importer: line %d: no instance\n", line_no);
            fclose(script);
            return 2;
        } else if (strcmp(cmd, "setup") == 0 && n == 2) {
            s = api->setupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, from_bits(words[1]));
        } else if (strcmp(cmd, "real") == 0 && n == 3) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(words[1], NULL, 10);
            double v = from_bits(words[2]);
            s = api->setReal(c, &vr, 1, &v);
        } else if (strcmp(cmd, "integer") == 0 && n == 3) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(words[1], NULL, 10);
            fmi2Integer v = (fmi2Integer)strtol(words[2], NULL, 10);
            s = api->setInteger(c, &vr, 1, &v);
        } else if (strcmp(cmd, "boolean") == 0 && n == 3) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(words[1], NULL, 10);
            fmi2Boolean v = (fmi2Boolean)strtol(words[2], NULL, 10);
            s = api->setBoolean(c, &vr, 1, &v);
        } else if (strcmp(cmd, "enter") == 0) {
            s = api->enterInitializationMode(c);
        } else if (strcmp(cmd, "exit") == 0) {
            s = api->exitInitializationMode(c);
        } else if (strcmp(cmd, "terminate") == 0) {
            s = api->terminate(c);
        } else if (strcmp(cmd, "reset") == 0) {
            s = api->reset(c);
            t = 0.0;
        } else if (strcmp(cmd, "outputs") == 0) {
            n_outputs = n - 1;
            for (int i = 1; i < n; i++) {
                outputs[i - 1] = (fmi2ValueReference)strtoul(words[i], NULL, 10);
            }
            continue;
        } else if (strcmp(cmd, "steps") == 0 && n == 3) {
            int steps = atoi(words[1]);
            double h = from_bits(words[2]), t0 = t, values[64];
            for (int k = 1; k <= steps && s == fmi2OK; k++) {
                s = api->doStep(c, t0 + (k - 1) * h, h, fmi2True);
                if (s == fmi2OK && n_outputs > 0) {
                    s = api->getReal(c, outputs, (size_t)n_outputs, values);
                    printf("out,%d,%d", line_no, k);
                    for (int i = 0; i < n_outputs; i++) {
                        printf(",%016" PRIx64, to_bits(values[i]));
                    }
                    printf("\n");
                }
                t = t0 + k * h;
            }
        } else if (strcmp(cmd, "save") == 0 && n == 2) {
            fmi2FMUstate state = NULL;
            size_t size = 0;
            s = api->getFMUstate(c, &state);
            if (s == fmi2OK) s = api->serializedFMUstateSize(c, state, &size);
            fmi2Byte *bytes = malloc(size ? size : 1);
            if (s == fmi2OK) s = api->serializeFMUstate(c, state, bytes, size);
            FILE *f = fopen(words[1], "wb");
            if (s == fmi2OK && (f == NULL || fwrite(bytes, 1, size, f) != size)) s = fmi2Fatal;
            if (f != NULL) fclose(f);
            free(bytes);
            if (state != NULL) api->freeFMUstate(c, &state);
        } else if (strcmp(cmd, "load") == 0 && n == 3) {
            FILE *f = fopen(words[1], "rb");
            static fmi2Byte bytes[1 << 20];
            size_t size = f != NULL ? fread(bytes, 1, sizeof bytes, f) : 0;
            fmi2FMUstate state = NULL;
            if (f != NULL) fclose(f);
            s = api->deSerializeFMUstate(c, bytes, size, &state);
            if (s == fmi2OK) s = api->setFMUstate(c, state);
            if (state != NULL) api->freeFMUstate(c, &state);
            t = from_bits(words[2]);
        } else if (strcmp(cmd, "hook") == 0) {
            const fmi2String hook[] = {"testHook.panicInNextDoStep"};
            s = api->setDebugLogging(c, fmi2True, 1, hook);
        } else if (strcmp(cmd, "free") == 0) {
            api->freeInstance(c);
            c = NULL;
        } else {
            fprintf(stderr, "importer: line %d: cannot read the command %s\n", line_no, cmd);
            fclose(script);
            return 2;
        }
        printf("call,%d,%s,%d\n", line_no, cmd, (int)s);
    }
    fclose(script);
    return 0;
}

/* ---- --reload: an importer that unloads the library under a live instance ----
 * One co-simulation engine closes the FMU's library and opens it again when it
 * instantiates the same FMU a second time, while the first instance lives.
 * Instance A is made through the first load, the library closed and opened
 * again, instance B made, both stepped with the same inputs (their outputs
 * must agree) and freed through the second load; then the library must
 * unload. Prints reload,<k>,<A>,<B> rows and reload,unloaded,<0|1>. */
static int run_reload(const char *path, const char *guid, fmi2ValueReference in, fmi2ValueReference out)
{
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    Api first, second;
    Library lib = open_library(path);
    if (lib == NULL || !load_api(lib, &first)) {
        fprintf(stderr, "importer: loading %s failed: %s\n", path, library_error());
        return 2;
    }
    fmi2Component a = first.instantiate("A", fmi2CoSimulation, guid, "file:///nonexistent/resources", &callbacks, fmi2False, fmi2False);
    if (a == NULL) return 1;
    must("A setup", first.setupExperiment(a, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    must("A enter init", first.enterInitializationMode(a));
    close_library(lib);
    lib = open_library(path);
    if (lib == NULL || !load_api(lib, &second)) {
        fprintf(stderr, "importer: loading %s again failed: %s\n", path, library_error());
        return 2;
    }
    fmi2Component b = second.instantiate("B", fmi2CoSimulation, guid, "file:///nonexistent/resources", &callbacks, fmi2False, fmi2False);
    if (b == NULL) return 1;
    must("B setup", second.setupExperiment(b, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    must("B enter init", second.enterInitializationMode(b));
    must("A exit init", second.exitInitializationMode(a));
    must("B exit init", second.exitInitializationMode(b));
    double t = 0.0, h = 1e-3;
    for (int k = 0; k < 10; k++) {
        double u, ya = 0.0, yb = 0.0;
        must("A get input", second.getReal(a, &in, 1, &u));
        u += 1e-3 * (k % 3);
        must("A set", second.setReal(a, &in, 1, &u));
        must("B set", second.setReal(b, &in, 1, &u));
        must("A step", second.doStep(a, t, h, fmi2True));
        must("B step", second.doStep(b, t, h, fmi2True));
        must("A get", second.getReal(a, &out, 1, &ya));
        must("B get", second.getReal(b, &out, 1, &yb));
        printf("reload,%d,%.17g,%.17g\n", k, ya, yb);
        if (ya != yb) failures++;
        t += h;
    }
    second.freeInstance(a);
    second.freeInstance(b);
    close_library(lib);
    printf("reload,unloaded,%d\n", !library_is_loaded(path));
    return failures == 0 ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc == 6 && strcmp(argv[3], "--reload") == 0) {
        return run_reload(argv[1], argv[2], (fmi2ValueReference)strtoul(argv[4], NULL, 10),
                          (fmi2ValueReference)strtoul(argv[5], NULL, 10));
    }
    if (argc == 5 && strcmp(argv[3], "--script") == 0) {
        Api api;
        Library lib = open_library(argv[1]);
        if (lib == NULL) {
            fprintf(stderr, "importer: loading %s failed: %s\n", argv[1], library_error());
            return 2;
        }
        if (!load_api(lib, &api)) {
            return 2;
        }
        int code = run_script(&api, argv[2], argv[4]);
        close_library(lib);
        return code;
    }
    if (argc < 4) {
        fprintf(stderr, "usage: %s <library.so> <GUID> name=vr ...\n", argv[0]);
        return 2;
    }
    const char *library = argv[1];
    const char *guid = argv[2];
    n_refs = argc - 3;
    ref_args = argv + 3;

    Library lib = open_library(library);
    if (lib == NULL) {
        fprintf(stderr, "importer: loading %s failed: %s\n", library, library_error());
        return 2;
    }
    Api api_storage;
    Api *api = &api_storage;
    if (!load_api(lib, api)) {
        return 2;
    }
    printf("info,version,%s\n", api->getVersion());
    printf("info,platform,%s\n", api->getTypesPlatform());

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const char *resources = "file:///nonexistent/resources";

    /* ---------------- the scene ---------------- */
    fmi2Component c = api->instantiate("scene", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2True);
    printf("check,instantiate,%d\n", c != NULL);
    if (c == NULL) {
        return 1;
    }
    must("setupExperiment", api->setupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, 2.0));
    set_real(api, c, "L", 2.0);
    set_real(api, c, "wp2.width", 1.3);
    set_real(api, c, "wp2.d_r", 0.01);
    set_boolean(api, c, "includeDamping", 1);
    set_integer(api, c, "toUnitV", 2); /* m/min */
    must("enterInitializationMode", api->enterInitializationMode(c));
    set_real(api, c, "web_a.v", 5.0);
    set_real(api, c, "web_a.eps", 1e-3);
    set_real(api, c, "web_b.v", 5.0);
    must("exitInitializationMode", api->exitInitializationMode(c));

    double out[N_OUT];
    get_outputs(api, c, out);
    printf("row,0,%.17g,%.17g,%.17g,%.17g,%.17g\n", 0.0, out[O_T], out[O_STRAIN], out[O_X], out[O_V]);

    fmi2ValueReference vb = vr_of("web_b.v");
    int step_failures = 0;
    for (int k = 0; k < N_STEPS; k++) {
        double t = k * H;
        if (k == N_STEPS / 2) {
            double before[N_OUT], after[N_OUT], v = 5.005;
            get_outputs(api, c, before);
            must("set web_b.v halfway", api->setReal(c, &vb, 1, &v));
            printf("param,web_b.v@%d,%.17g\n", k, v);
            get_outputs(api, c, after);
            printf("feedthrough,%d,%.17g,%.17g\n", k, before[O_T], after[O_T]);
        }
        fmi2Status s = api->doStep(c, t, H, fmi2True);
        if (s != fmi2OK) {
            step_failures++;
            must("doStep", s);
            break;
        }
        get_outputs(api, c, out);
        printf("row,%d,%.17g,%.17g,%.17g,%.17g,%.17g\n", k + 1, (k + 1) * H, out[O_T], out[O_STRAIN], out[O_X], out[O_V]);
    }
    printf("check,all steps ok,%d\n", step_failures == 0);

    /* ---------------- FMU state: save, continue, restore, continue ---------------- */
    double t_end = N_STEPS * H;
    static double run_a[N_CONT][3], run_b[N_CONT][3], run_c[N_CONT][3];
    fmi2FMUstate state = NULL;
    must("getFMUstate", api->getFMUstate(c, &state));
    printf("check,continuation a,%d\n", continuation(api, c, t_end, N_CONT, run_a));
    must("setFMUstate", api->setFMUstate(c, state));
    printf("check,continuation b,%d\n", continuation(api, c, t_end, N_CONT, run_b));
    printf("check,restore identical,%d\n", memcmp(run_a, run_b, sizeof run_a) == 0);
    print_cont("a", t_end, N_CONT, run_a);

    /* ---------------- serialize, deserialize into a second instance ---------------- */
    size_t size = 0;
    must("serializedFMUstateSize", api->serializedFMUstateSize(c, state, &size));
    printf("info,serialized size,%zu\n", size);
    fmi2Byte *bytes = malloc(size);
    must("serializeFMUstate", api->serializeFMUstate(c, state, bytes, size));

    fmi2Component c2 = api->instantiate("copy", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2False);
    printf("check,instantiate copy,%d\n", c2 != NULL);
    if (c2 == NULL) {
        return 1;
    }
    fmi2FMUstate state2 = NULL;
    must("deSerializeFMUstate", api->deSerializeFMUstate(c2, bytes, size, &state2));
    must("setFMUstate copy", api->setFMUstate(c2, state2));
    printf("check,continuation c,%d\n", continuation(api, c2, t_end, N_CONT, run_c));
    printf("check,deserialized identical,%d\n", memcmp(run_a, run_c, sizeof run_a) == 0);

    /* a corrupted serialized state is refused */
    bytes[size / 2] ^= 0x20;
    fmi2FMUstate state3 = NULL;
    illegal("deSerializeFMUstate corrupted", api->deSerializeFMUstate(c2, bytes, size, &state3));
    printf("check,corrupted gives no state,%d\n", state3 == NULL);
    free(bytes);

    must("freeFMUstate copy", api->freeFMUstate(c2, &state2));
    api->freeInstance(c2);
    must("freeFMUstate", api->freeFMUstate(c, &state));
    printf("check,freed state is NULL,%d\n", state == NULL);
    must("terminate", api->terminate(c));
    illegal("doStep after terminate", api->doStep(c, t_end, H, fmi2True));
    api->freeInstance(c);

    /* ---------------- illegal calls ---------------- */
    fmi2Component bad = api->instantiate("illegal", fmi2CoSimulation, "{00000000-0000-0000-0000-000000000000}",
                                         resources, &callbacks, fmi2False, fmi2False);
    printf("check,wrong GUID gives NULL,%d\n", bad == NULL);
    /* The FMU quotes the GUID in its message: a '%' in it must reach the
       logger escaped as "%%", or vsnprintf would read arguments that are not there. */
    bad = api->instantiate("illegal", fmi2CoSimulation, "{100%-wrong-%s-%d-guid}", resources, &callbacks,
                           fmi2False, fmi2False);
    printf("check,percent GUID gives NULL,%d\n", bad == NULL);
    /* The same binary serves Model Exchange; a co-simulation call there is illegal. */
    fmi2Component me = api->instantiate("illegal", fmi2ModelExchange, guid, resources, &callbacks, fmi2False, fmi2False);
    printf("check,model exchange instantiates,%d\n", me != NULL);
    if (me != NULL) {
        illegal("doStep on a model exchange instance", api->doStep(me, 0.0, H, fmi2True));
        api->freeInstance(me);
    }

    fmi2Component d = api->instantiate("illegal", fmi2CoSimulation, guid, resources, &callbacks, fmi2False, fmi2False);
    printf("check,instantiate illegal,%d\n", d != NULL);
    if (d == NULL) {
        return 1;
    }
    illegal("doStep before init", api->doStep(d, 0.0, H, fmi2True));
    must("reset after error", api->reset(d));
    illegal("exitInitializationMode before enter", api->exitInitializationMode(d));
    must("reset after error 2", api->reset(d));
    {
        fmi2ValueReference vr = vr_of("T");
        double value = 1.0;
        illegal("getReal before init", api->getReal(d, &vr, 1, &value));
        must("reset after error 3", api->reset(d));
        illegal("setReal output T", api->setReal(d, &vr, 1, &value));
        must("reset after error 4", api->reset(d));
    }
    must("setupExperiment illegal", api->setupExperiment(d, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    must("enterInitializationMode illegal", api->enterInitializationMode(d));
    illegal("doStep in initialization mode", api->doStep(d, 0.0, H, fmi2True));
    must("reset after error 5", api->reset(d));
    must("setupExperiment illegal 2", api->setupExperiment(d, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    must("enterInitializationMode illegal 2", api->enterInitializationMode(d));
    must("exitInitializationMode illegal 2", api->exitInitializationMode(d));
    illegal("doStep at the wrong time", api->doStep(d, 0.5, H, fmi2True));
    must("reset after error 6", api->reset(d));
    must("setupExperiment illegal 3", api->setupExperiment(d, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    must("enterInitializationMode illegal 3", api->enterInitializationMode(d));
    must("exitInitializationMode illegal 3", api->exitInitializationMode(d));
    must("doStep after reset", api->doStep(d, 0.0, H, fmi2True));
    must("terminate illegal", api->terminate(d));
    api->freeInstance(d);

    close_library(lib);
    printf("check,failures,%d\n", failures == 0);
    return failures == 0 ? 0 : 1;
}

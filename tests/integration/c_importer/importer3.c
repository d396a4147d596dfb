/*
 * A minimal FMI 3.0 importer for ConvertingSpan, written against FMPy's copy
 * of the FMI 3.0 headers: the scene of importer.c (its row lines must be
 * identical), FMU states, and the state machine and bad inputs of the FMI 3.0
 * layer. tests/integration/python/test_c_importer.py compiles it with
 *
 *     gcc -Wall -Werror -I <fmpy>/c-code importer3.c -o importer3 -ldl
 *
 * (tests/integration/cross/test_platforms.py also for win64 and aarch64) and runs it as
 *
 *     importer3 <binaries/x86_64-linux/ConvertingSpan.so> <instantiationToken> name=vr ...
 *
 * Output lines as importer.c's: status,<label>,<fmi3Status> for a call that
 * must succeed, illegal,<label>,<fmi3Status> for one that must be refused,
 * row,<k>,<t>,<T>,<strain>,<x>,<v>, check,<what>,<0|1>. The FMU's log goes to
 * stderr as log,<status>,<category>,<message>. Exit code 0 if every call
 * that must succeed did, 1 otherwise, 2 on a usage or loading problem.
 */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "library.h"

/* ---- the API, looked up by name and typed with the header's TYPEs ---- */

#define API(X)                                                                                                    \
    X(GetVersion) X(InstantiateCoSimulation) X(InstantiateModelExchange) X(InstantiateScheduledExecution)         \
    X(FreeInstance) X(EnterInitializationMode) X(ExitInitializationMode) X(Terminate) X(Reset) X(GetFloat64)      \
    X(SetFloat64) X(SetInt64) X(GetInt64) X(SetInt32) X(SetBoolean) X(DoStep) X(GetFMUState) X(SetFMUState)       \
    X(FreeFMUState) X(SerializedFMUStateSize) X(SerializeFMUState) X(DeserializeFMUState) X(EnterEventMode)       \
    X(EnterStepMode) X(UpdateDiscreteStates) X(EnterContinuousTimeMode) X(GetContinuousStates)                    \
    X(GetNumberOfContinuousStates) X(GetDirectionalDerivative) X(SetClock) X(GetFloat32)

#define FIELD(name) fmi3##name##TYPE *name;
typedef struct {
    API(FIELD)
} Api;

static int load_api(Library lib, Api *api)
{
#define LOAD(name)                                                                                                \
    api->name = (fmi3##name##TYPE *)find_symbol(lib, "fmi3" #name);                                                     \
    if (api->name == NULL) {                                                                                      \
        fprintf(stderr, "importer3: fmi3" #name " is missing\n");                                                 \
        return 0;                                                                                                 \
    }
    API(LOAD)
    return 1;
}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    fprintf(stderr, "log,%d,%s,%s\n", (int)status, category, message);
}

static int n_refs;
static char **ref_args;

static fmi3ValueReference vr_of(const char *name)
{
    size_t n = strlen(name);
    for (int i = 0; i < n_refs; i++) {
        if (strncmp(ref_args[i], name, n) == 0 && ref_args[i][n] == '=') {
            return (fmi3ValueReference)strtoul(ref_args[i] + n + 1, NULL, 10);
        }
    }
    fprintf(stderr, "importer3: no value reference given for %s\n", name);
    exit(2);
}

static int failures;

static void must(const char *label, fmi3Status status)
{
    printf("status,%s,%d\n", label, (int)status);
    failures += status != fmi3OK;
}

static void illegal(const char *label, fmi3Status status)
{
    printf("illegal,%s,%d\n", label, (int)status);
}

static void set_float64(const Api *api, fmi3Instance c, const char *name, double value)
{
    fmi3ValueReference vr = vr_of(name);
    must(name, api->SetFloat64(c, &vr, 1, &value, 1));
}

enum { O_T, O_STRAIN, O_X, O_V, N_OUT };

static void get_outputs(const Api *api, fmi3Instance c, double out[N_OUT])
{
    fmi3ValueReference vrs[N_OUT] = {vr_of("T"), vr_of("summary_Strain"), vr_of("unstretchedLength"), vr_of("v")};
    fmi3Status s = api->GetFloat64(c, vrs, N_OUT, out, N_OUT);
    if (s != fmi3OK) {
        must("get outputs", s);
    }
}

static fmi3Status step(const Api *api, fmi3Instance c, double t, double h)
{
    fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
    double reached = -1.0;
    fmi3Status s = api->DoStep(c, t, h, fmi3True, &event, &terminate, &early, &reached);
    if (s == fmi3OK && (event || terminate || early || reached != t + h)) {
        printf("check,doStep out-arguments,0\n");
        failures++;
    }
    return s;
}

/* The scene of importer.c. */
#define H 1e-3
#define N_STEPS 1000
#define N_CONT 100

static void scene(const Api *api, fmi3Instance c)
{
    must("enterInitializationMode", api->EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3True, 2.0));
    set_float64(api, c, "L", 2.0);
    set_float64(api, c, "wp2.width", 1.3);
    set_float64(api, c, "wp2.d_r", 0.01);
    fmi3ValueReference vr = vr_of("includeDamping");
    fmi3Boolean yes = fmi3True;
    must("set includeDamping", api->SetBoolean(c, &vr, 1, &yes, 1));
    vr = vr_of("toUnitV");
    fmi3Int64 per_minute = 2;
    must("set toUnitV", api->SetInt64(c, &vr, 1, &per_minute, 1));
    set_float64(api, c, "web_a.v", 5.0);
    set_float64(api, c, "web_a.eps", 1e-3);
    set_float64(api, c, "web_b.v", 5.0);
    must("exitInitializationMode", api->ExitInitializationMode(c));
    double out[N_OUT];
    get_outputs(api, c, out);
    printf("row,0,%.17g,%.17g,%.17g,%.17g,%.17g\n", 0.0, out[O_T], out[O_STRAIN], out[O_X], out[O_V]);
    for (int k = 0; k < N_STEPS; k++) {
        if (k == N_STEPS / 2) {
            set_float64(api, c, "web_b.v", 5.005);
        }
        fmi3Status s = step(api, c, k * H, H);
        if (s != fmi3OK) {
            must("doStep", s);
            return;
        }
        get_outputs(api, c, out);
        printf("row,%d,%.17g,%.17g,%.17g,%.17g,%.17g\n", k + 1, (k + 1) * H, out[O_T], out[O_STRAIN], out[O_X], out[O_V]);
    }
}

static int continuation(const Api *api, fmi3Instance c, double t, double rec[N_CONT])
{
    for (int i = 0; i < N_CONT; i++) {
        double out[N_OUT];
        if (step(api, c, t + i * H, H) != fmi3OK) {
            return 0;
        }
        get_outputs(api, c, out);
        rec[i] = out[O_T];
    }
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: %s <library.so> <instantiationToken> name=vr ...\n", argv[0]);
        return 2;
    }
    const char *token = argv[2];
    n_refs = argc - 3;
    ref_args = argv + 3;
    Library lib = open_library(argv[1]);
    Api api_storage, *api = &api_storage;
    if (lib == NULL || !load_api(lib, api)) {
        fprintf(stderr, "importer3: loading %s failed: %s\n", argv[1], lib ? "" : library_error());
        return 2;
    }
    printf("info,version,%s\n", api->GetVersion());
    const char *resources = "/nonexistent/resources/";

    /* ---------------- the scene, then FMU states ---------------- */
    fmi3Instance c = api->InstantiateCoSimulation("scene", token, resources, fmi3False, fmi3True, fmi3False, fmi3False,
                                                  NULL, 0, NULL, logger, NULL);
    printf("check,instantiate,%d\n", c != NULL);
    if (c == NULL) {
        return 1;
    }
    scene(api, c);
    double t_end = N_STEPS * H;
    static double run_a[N_CONT], run_b[N_CONT], run_c[N_CONT];
    fmi3FMUState state = NULL;
    must("getFMUState", api->GetFMUState(c, &state));
    printf("check,continuation a,%d\n", continuation(api, c, t_end, run_a));
    must("setFMUState", api->SetFMUState(c, state));
    printf("check,continuation b,%d\n", continuation(api, c, t_end, run_b));
    printf("check,restore identical,%d\n", memcmp(run_a, run_b, sizeof run_a) == 0);
    size_t size = 0;
    must("serializedFMUStateSize", api->SerializedFMUStateSize(c, state, &size));
    fmi3Byte *bytes = malloc(size);
    illegal("serializeFMUState into a short buffer", api->SerializeFMUState(c, state, bytes, size - 1));
    must("reset after a short buffer", api->Reset(c));
    must("serializeFMUState", api->SerializeFMUState(c, state, bytes, size));
    fmi3Instance c2 = api->InstantiateCoSimulation("copy", token, resources, fmi3False, fmi3False, fmi3False, fmi3False,
                                                   NULL, 0, NULL, logger, NULL);
    fmi3FMUState state2 = NULL;
    must("deserializeFMUState", api->DeserializeFMUState(c2, bytes, size, &state2));
    must("setFMUState copy", api->SetFMUState(c2, state2));
    printf("check,continuation c,%d\n", continuation(api, c2, t_end, run_c));
    printf("check,deserialized identical,%d\n", memcmp(run_a, run_c, sizeof run_a) == 0);
    bytes[size / 2] ^= 0x20;
    fmi3FMUState state3 = NULL;
    illegal("deserializeFMUState corrupted", api->DeserializeFMUState(c2, bytes, size, &state3));
    printf("check,corrupted gives no state,%d\n", state3 == NULL);
    free(bytes);
    illegal("setFMUState of another instance", api->SetFMUState(c, state2));
    must("freeFMUState copy", api->FreeFMUState(c2, &state2));
    api->FreeInstance(c2);
    must("freeFMUState", api->FreeFMUState(c, &state));
    printf("check,freed state is NULL,%d\n", state == NULL);
    api->FreeInstance(c);

    /* ---------------- instantiation refused ---------------- */
    printf("check,wrong token gives NULL,%d\n",
           api->InstantiateCoSimulation("x", "{00000000-0000-0000-0000-000000000000}", resources, fmi3False, fmi3False,
                                        fmi3False, fmi3False, NULL, 0, NULL, logger, NULL) == NULL);
    printf("check,NULL token gives NULL,%d\n",
           api->InstantiateCoSimulation("x", NULL, resources, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                        logger, NULL) == NULL);
    fmi3ValueReference required = 1;
    printf("check,intermediate variables give NULL,%d\n",
           api->InstantiateCoSimulation("x", token, resources, fmi3False, fmi3False, fmi3False, fmi3False, &required, 1,
                                        NULL, logger, NULL) == NULL);
    printf("check,scheduled execution gives NULL,%d\n",
           api->InstantiateScheduledExecution("x", token, resources, fmi3False, fmi3False, NULL, logger, NULL, NULL,
                                              NULL) == NULL);
    /* NULL and foreign instances: refused without a crash. */
    illegal("doStep on NULL", step(api, NULL, 0.0, H));
    double not_an_instance[8] = {0};
    illegal("reset on a foreign pointer", api->Reset(not_an_instance));

    /* ---------------- the state machine and bad arguments, each followed by a reset ---------------- */
    fmi3Instance d = api->InstantiateCoSimulation("illegal", token, resources, fmi3False, fmi3False, fmi3True, fmi3False,
                                                  NULL, 0, NULL, logger, NULL);
    printf("check,instantiate illegal,%d\n", d != NULL);
    if (d == NULL) {
        return 1;
    }
    fmi3ValueReference vr_T = vr_of("T"), vr_L = vr_of("L"), vr_damping = vr_of("includeDamping");
    fmi3ValueReference vr_unit = vr_of("toUnitV");
    double x = 1.0;
    illegal("doStep before init", step(api, d, 0.0, H));
    must("reset 1", api->Reset(d));
    illegal("exitInitializationMode before enter", api->ExitInitializationMode(d));
    must("reset 2", api->Reset(d));
    illegal("getFloat64 before init", api->GetFloat64(d, &vr_T, 1, &x, 1));
    must("reset 3", api->Reset(d));
    illegal("setFloat64 output T", api->SetFloat64(d, &vr_T, 1, &x, 1));
    must("reset 4", api->Reset(d));
    illegal("setFloat64 NULL values", api->SetFloat64(d, &vr_L, 1, NULL, 1));
    must("reset 5", api->Reset(d));
    illegal("setFloat64 nValues differs", api->SetFloat64(d, &vr_L, 1, &x, 2));
    must("reset 6", api->Reset(d));
    /* A byte other than 0 and 1 where a C bool belongs (another language's importer). */
    unsigned char two[sizeof(fmi3Boolean)] = {2};
    illegal("setBoolean byte 2", api->SetBoolean(d, &vr_damping, 1, (const fmi3Boolean *)two, 1));
    must("reset 7", api->Reset(d));
    fmi3Int64 huge = 1LL << 40;
    illegal("setInt64 beyond Int32", api->SetInt64(d, &vr_unit, 1, &huge, 1));
    must("reset 8", api->Reset(d));
    fmi3Int32 one = 1;
    illegal("setInt32 on an enumeration", api->SetInt32(d, &vr_unit, 1, &one, 1));
    must("reset 9", api->Reset(d));
    illegal("getFloat32 of a value reference", api->GetFloat32(d, &vr_T, 1, (float *)&x, 1));
    must("reset 10", api->Reset(d));
    illegal("enterEventMode in co-simulation", api->EnterEventMode(d));
    must("reset 11", api->Reset(d));
    must("enterInitializationMode", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    illegal("doStep in initialization mode", step(api, d, 0.0, H));
    must("reset 12", api->Reset(d));
    illegal("enterInitializationMode with NaN start", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0 / 0.0, fmi3False, 0.0));
    must("reset 13", api->Reset(d));
    must("enterInitializationMode 2", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    must("exitInitializationMode 2", api->ExitInitializationMode(d));
    illegal("enterStepMode", api->EnterStepMode(d));
    must("reset 14", api->Reset(d));
    must("enterInitializationMode 3", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    must("exitInitializationMode 3", api->ExitInitializationMode(d));
    illegal("doStep at the wrong time", step(api, d, 0.5, H));
    must("reset 15", api->Reset(d));
    must("enterInitializationMode 4", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    must("exitInitializationMode 4", api->ExitInitializationMode(d));
    fmi3Boolean flag;
    illegal("doStep with NULL earlyReturn", api->DoStep(d, 0.0, H, fmi3True, &flag, &flag, NULL, &x));
    must("reset 16", api->Reset(d));
    must("enterInitializationMode 5", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    must("exitInitializationMode 5", api->ExitInitializationMode(d));
    illegal("getDirectionalDerivative with a parameter as known", api->GetDirectionalDerivative(d, &vr_T, 1, &vr_L, 1, &x, 1, &x, 1));
    must("reset 17", api->Reset(d));
    illegal("setClock", api->SetClock(d, &vr_T, 1, &flag));
    must("reset 18", api->Reset(d));
    must("enterInitializationMode 6", api->EnterInitializationMode(d, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    must("exitInitializationMode 6", api->ExitInitializationMode(d));
    must("doStep after the resets", step(api, d, 0.0, H));
    must("terminate", api->Terminate(d));
    illegal("doStep after terminate", step(api, d, H, H));
    api->FreeInstance(d);

    /* ---------------- Model Exchange: its calls, and co-simulation's refused ---------------- */
    fmi3Instance me = api->InstantiateModelExchange("me", token, resources, fmi3False, fmi3False, NULL, logger);
    printf("check,model exchange instantiates,%d\n", me != NULL);
    if (me != NULL) {
        size_t nx = 0;
        must("getNumberOfContinuousStates", api->GetNumberOfContinuousStates(me, &nx));
        printf("check,one state,%d\n", nx == 1);
        illegal("doStep on model exchange", step(api, me, 0.0, H));
        must("reset me", api->Reset(me));
        must("enterInitializationMode me", api->EnterInitializationMode(me, fmi3False, 0.0, 0.0, fmi3False, 0.0));
        must("exitInitializationMode me", api->ExitInitializationMode(me));
        fmi3Boolean b[5];
        double next;
        must("updateDiscreteStates", api->UpdateDiscreteStates(me, &b[0], &b[1], &b[2], &b[3], &b[4], &next));
        illegal("updateDiscreteStates NULL", api->UpdateDiscreteStates(me, &b[0], NULL, &b[2], &b[3], &b[4], &next));
        must("reset me 2", api->Reset(me));
        must("enterInitializationMode me 2", api->EnterInitializationMode(me, fmi3False, 0.0, 0.0, fmi3False, 0.0));
        must("exitInitializationMode me 2", api->ExitInitializationMode(me));
        must("enterContinuousTimeMode", api->EnterContinuousTimeMode(me));
        double states[2];
        illegal("getContinuousStates with 2", api->GetContinuousStates(me, states, 2));
        api->FreeInstance(me);
    }
    close_library(lib);
    printf("check,failures,%d\n", failures == 0);
    return failures == 0 ? 0 : 1;
}

/* Native cost of one co-simulation step, as an importer pays it: set the
 * three inputs, fmi2DoStep, get two outputs. Loads the library (library.h),
 * so two builds can be measured side by side in one run.
 *
 *   step_cost LIB.so GUID STEPS REPEATS VR_INPUTS(3,comma) VR_OUTPUTS(2,comma) [VR=VALUE ...]
 *
 * VR=VALUE pairs set parameters before initialization: "b:12=1" a Boolean,
 * "i:34=3" an Integer, "r:1=0.5" a Real. Prints the median ns per step and
 * the spread (min, max) over the repeats, then the final outputs (so that the
 * work cannot be optimized away and two builds can be compared). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "fmi2Functions.h"

#include "library.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)category;
    if (status >= fmi2Warning) fprintf(stderr, "[%d] %s\n", status, message);
}

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e9 + ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void parse_vrs(const char *s, fmi2ValueReference *out, int n) {
    for (int i = 0; i < n; i++) { out[i] = (fmi2ValueReference)strtoul(s, (char **)&s, 10); if (*s == ',') s++; }
}

#define LOAD(name) name##TYPE *name = (name##TYPE *)find_symbol(lib, #name); if (!name) { fprintf(stderr, "no %s\n", #name); return 2; }

int main(int argc, char **argv) {
    if (argc < 7) { fprintf(stderr, "usage: see the comment at the top of step_cost.c\n"); return 2; }
    Library lib = open_library(argv[1]);
    if (!lib) { fprintf(stderr, "%s\n", library_error()); return 2; }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2GetReal) LOAD(fmi2SetBoolean)
    LOAD(fmi2SetInteger) LOAD(fmi2DoStep) LOAD(fmi2FreeInstance)
    long steps = atol(argv[3]);
    int repeats = atoi(argv[4]);
    fmi2ValueReference in[3], out[2];
    parse_vrs(argv[5], in, 3);
    parse_vrs(argv[6], out, 2);
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    double *ns = calloc(repeats, sizeof(double));
    fmi2Real y[2] = {0, 0};
    for (int r = 0; r < repeats; r++) {
        fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], "", &cb, fmi2False, fmi2False);
        if (!c) return 3;
        fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
        for (int a = 7; a < argc; a++) {
            char kind = argv[a][0];
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[a] + 2, NULL, 10);
            const char *value = strchr(argv[a], '=') + 1;
            fmi2Status s = kind == 'b' ? fmi2SetBoolean(c, &vr, 1, (fmi2Boolean[]){atoi(value)})
                         : kind == 'i' ? fmi2SetInteger(c, &vr, 1, (fmi2Integer[]){atoi(value)})
                         : fmi2SetReal(c, &vr, 1, (fmi2Real[]){atof(value)});
            if (s != fmi2OK) return 4;
        }
        fmi2EnterInitializationMode(c);
        if (fmi2ExitInitializationMode(c) != fmi2OK) return 5;
        const double h = 1e-3;
        double t0 = now_ns();
        for (long k = 0; k < steps; k++) {
            /* A gentle speed oscillation keeps every step doing real work. */
            fmi2Real u[3] = {5.0, 1e-3, 5.0 + 0.005 * (double)(k & 1023) / 1024.0};
            fmi2SetReal(c, in, 3, u);
            if (fmi2DoStep(c, k * h, h, fmi2True) != fmi2OK) return 6;
            fmi2GetReal(c, out, 2, y);
        }
        ns[r] = (now_ns() - t0) / (double)steps;
        fmi2FreeInstance(c);
    }
    qsort(ns, repeats, sizeof(double), cmp);
    printf("%.2f %.2f %.2f %.17g %.17g\n", ns[repeats / 2], ns[0], ns[repeats - 1], y[0], y[1]);
    free(ns);
    close_library(lib);
    return 0;
}

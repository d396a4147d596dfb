/* What one communication step of a Line FMU costs natively (bench/line_fmu.py).
 *
 *   line_cost LIB GUID RESOURCE_URI TAU_VR OUT_VR H STEPS ROUNDS [TOL_VR TOL]
 *
 * A controller's loop, as a PLC or a Simulink model drives the FMU: every
 * step set a motor torque (TAU_VR, a small ripple around 0), fmi2DoStep(H),
 * get one output (OUT_VR); TOL sets the line's `tolerance` parameter. Each round instantiates and initializes the line
 * afresh and times STEPS steps with the thread's CPU clock; prints the ns per
 * step of every round, then the last output (so the work cannot be skipped). */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2Functions.h"

#include "library.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String cat,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)cat;
    if (status >= fmi2Warning) fprintf(stderr, "[%d] %s\n", status, message);
}

static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e9 + t.tv_nsec;
}

#define SYMBOL(name) fmi2##name##TYPE *name = (fmi2##name##TYPE *)find_symbol(lib, "fmi2" #name); \
    if (!name) { fprintf(stderr, "line_cost: %s has no fmi2%s\n", argv[1], #name); return 2; }

int main(int argc, char **argv) {
    if (argc != 9 && argc != 11) {
        fprintf(stderr, "usage: line_cost LIB GUID RESOURCE_URI TAU_VR OUT_VR H STEPS ROUNDS [TOL_VR TOL]\n");
        return 2;
    }
    Library lib = open_library(argv[1]);
    if (!lib) { fprintf(stderr, "line_cost: cannot load %s: %s\n", argv[1], library_error()); return 2; }
    SYMBOL(Instantiate) SYMBOL(FreeInstance) SYMBOL(SetupExperiment) SYMBOL(EnterInitializationMode)
    SYMBOL(ExitInitializationMode) SYMBOL(SetReal) SYMBOL(GetReal) SYMBOL(DoStep)
    fmi2ValueReference tau = (fmi2ValueReference)atoi(argv[4]), out = (fmi2ValueReference)atoi(argv[5]);
    double h = atof(argv[6]), y = 0.0;
    long steps = atol(argv[7]), rounds = atol(argv[8]);
    for (long r = 0; r < rounds; r++) {
        fmi2Component c = Instantiate("line", fmi2CoSimulation, argv[2], argv[3], &callbacks, fmi2False, fmi2False);
        if (c && argc == 11) {
            fmi2ValueReference tol_vr = (fmi2ValueReference)atoi(argv[9]);
            fmi2Real tol = atof(argv[10]);
            if (SetReal(c, &tol_vr, 1, &tol) > fmi2Warning) { fprintf(stderr, "line_cost: tolerance refused\n"); return 1; }
        }
        if (!c || SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning ||
            EnterInitializationMode(c) > fmi2Warning || ExitInitializationMode(c) > fmi2Warning) {
            fprintf(stderr, "line_cost: the line does not initialize\n");
            return 1;
        }
        double t = 0.0, start = now();
        for (long k = 0; k < steps; k++) {
            fmi2Real u = 0.01 * (double)((k % 64) - 32) / 32.0;
            if (SetReal(c, &tau, 1, &u) > fmi2Warning || DoStep(c, t, h, fmi2True) > fmi2Warning ||
                GetReal(c, &out, 1, &y) > fmi2Warning) {
                fprintf(stderr, "line_cost: step %ld failed\n", k);
                return 1;
            }
            t += h;
        }
        printf("%.1f\n", (now() - start) / (double)steps);
        FreeInstance(c);
    }
    printf("%.17g\n", y);
    close_library(lib);
    return 0;
}

/* Native costs for the accuracy-cost study (bench/study.py).
 *
 *   native_cost step ROUNDS STEPS  TARGET...
 *   native_cost calls ROUNDS CALLS cs|all TARGET
 *   native_cost instances N TARGET
 *
 * A TARGET is five arguments: LIB GUID IN_VRS(3, comma) OUT_VRS(2, comma)
 * U(4, comma: a,b,c,d).
 *
 * step: ns per communication step as an importer pays it: set the three
 *   inputs {a, b, c + d*(k mod 1024)/1024}, fmi2DoStep(h = 1e-3), get the two
 *   outputs (the loop of bench/step_cost.c). Several targets are measured
 *   side by side: every round visits every target once (STEPS steps each).
 *   Prints per target: the ns/step of every round, then the final outputs.
 * calls: ns per call of the FMI functions an importer calls per step
 *   (Co-Simulation: fmi2SetReal(3), fmi2GetReal(2), fmi2DoStep; Model Exchange:
 *   fmi2SetTime, fmi2SetContinuousStates, fmi2GetDerivatives,
 *   fmi2GetEventIndicators, fmi2GetContinuousStates, fmi2SetReal(3),
 *   fmi2GetReal(2)), median over the rounds; used to split FMPy's run time.
 *   "cs" measures the Co-Simulation calls only.
 * instances: N Co-Simulation instances in this process, each instantiated,
 *   set up and initialized (fmi2Instantiate, fmi2SetupExperiment,
 *   fmi2EnterInitializationMode, fmi2ExitInitializationMode); prints the ns per
 *   instance for that, the growth of the resident set (VmRSS) and of the heap
 *   in use (mallinfo2) per instance, and the ns per fmi2FreeInstance. */
#include <malloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#include "library.h"

typedef struct {
    fmi2InstantiateTYPE *Instantiate; fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment; fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode; fmi2SetRealTYPE *SetReal; fmi2GetRealTYPE *GetReal;
    fmi2DoStepTYPE *DoStep; fmi2NewDiscreteStatesTYPE *NewDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE *EnterContinuousTimeMode; fmi2SetTimeTYPE *SetTime;
    fmi2SetContinuousStatesTYPE *SetContinuousStates; fmi2GetContinuousStatesTYPE *GetContinuousStates;
    fmi2GetDerivativesTYPE *GetDerivatives; fmi2GetEventIndicatorsTYPE *GetEventIndicators;
} Api;

typedef struct {
    Api api;
    const char *lib, *guid;
    fmi2ValueReference in[3], out[2];
    double u[4];
} Target;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String cat,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)cat;
    if (status >= fmi2Warning) fprintf(stderr, "[%d] %s\n", status, message);
}

static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

/* The thread's CPU time: time while other processes have the core does not count. */
static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e9 + ts.tv_nsec;
}

static void *sym(void *lib, const char *name, int required) {
    void *p = find_symbol(lib, name);
    if (!p && required) { fprintf(stderr, "no %s\n", name); exit(2); }
    return p;
}

static void parse_vrs(const char *s, fmi2ValueReference *out, int n) {
    for (int i = 0; i < n; i++) { out[i] = (fmi2ValueReference)strtoul(s, (char **)&s, 10); if (*s == ',') s++; }
}

static void parse_doubles(const char *s, double *out, int n) {
    for (int i = 0; i < n; i++) { out[i] = strtod(s, (char **)&s); if (*s == ',') s++; }
}

static char **load(Target *t, char **argv) {
    t->lib = argv[0];
    t->guid = argv[1];
    parse_vrs(argv[2], t->in, 3);
    parse_vrs(argv[3], t->out, 2);
    parse_doubles(argv[4], t->u, 4);
    Library lib = open_library(t->lib);
    if (!lib) { fprintf(stderr, "%s\n", library_error()); exit(2); }
    Api *a = &t->api;
#define L(n, req) a->n = (fmi2##n##TYPE *)sym(lib, "fmi2" #n, req)
    L(Instantiate, 1); L(FreeInstance, 1); L(SetupExperiment, 1); L(EnterInitializationMode, 1);
    L(ExitInitializationMode, 1); L(SetReal, 1); L(GetReal, 1); L(DoStep, 1); L(NewDiscreteStates, 0);
    L(EnterContinuousTimeMode, 0); L(SetTime, 0); L(SetContinuousStates, 0); L(GetContinuousStates, 0);
    L(GetDerivatives, 0); L(GetEventIndicators, 0);
#undef L
    return argv + 5;
}

static fmi2Component start(Target *t, fmi2Type type) {
    Api *a = &t->api;
    fmi2Component c = a->Instantiate("bench", type, t->guid, "", &callbacks, fmi2False, fmi2False);
    if (!c) { fprintf(stderr, "instantiate failed: %s\n", t->lib); exit(3); }
    a->SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
    if (a->EnterInitializationMode(c) != fmi2OK || a->ExitInitializationMode(c) != fmi2OK) {
        fprintf(stderr, "initialization failed: %s\n", t->lib);
        exit(4);
    }
    return c;
}

static int step_mode(int rounds, long steps, int nt, Target *ts) {
    double *ns = calloc((size_t)rounds * nt, sizeof(double));
    fmi2Real y[64][2];
    for (int r = 0; r < rounds; r++)
        for (int i = 0; i < nt; i++) {
            Target *t = &ts[i];
            Api *a = &t->api;
            fmi2Component c = start(t, fmi2CoSimulation);
            const double h = 1e-3;
            double t0 = now_ns();
            for (long k = 0; k < steps; k++) {
                fmi2Real u[3] = {t->u[0], t->u[1], t->u[2] + t->u[3] * (double)(k & 1023) / 1024.0};
                a->SetReal(c, t->in, 3, u);
                if (a->DoStep(c, k * h, h, fmi2True) != fmi2OK) { fprintf(stderr, "step failed\n"); return 6; }
                a->GetReal(c, t->out, 2, y[i]);
            }
            ns[r * nt + i] = (now_ns() - t0) / (double)steps;
            a->FreeInstance(c);
        }
    for (int i = 0; i < nt; i++) {
        printf("%d", i);
        for (int r = 0; r < rounds; r++) printf(" %.3f", ns[r * nt + i]);
        printf(" y %.17g %.17g\n", y[i][0], y[i][1]);
    }
    return 0;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* ns per call of one function, median over the rounds (loop overhead included,
 * a few cycles). */
#define TIME_CALLS(name, call)                                                   \
    do {                                                                         \
        double v[64];                                                            \
        for (int r = 0; r < rounds; r++) {                                       \
            double t0 = now_ns();                                                \
            for (long k = 0; k < calls; k++) { call; }                           \
            v[r] = (now_ns() - t0) / (double)calls;                              \
        }                                                                        \
        qsort(v, rounds, sizeof(double), cmp);                                   \
        printf("%s %.3f\n", name, v[rounds / 2]);                                \
    } while (0)

static int calls_mode(int rounds, long calls, int me, Target *t) {
    Api *a = &t->api;
    if (rounds > 64) rounds = 64;
    fmi2Real u[3] = {t->u[0], t->u[1], t->u[2]}, y[2], x, dx, z;
    /* Co-Simulation */
    fmi2Component c = start(t, fmi2CoSimulation);
    TIME_CALLS("cs.fmi2SetReal", a->SetReal(c, t->in, 3, u));
    TIME_CALLS("cs.fmi2GetReal", a->GetReal(c, t->out, 2, y));
    double time = 0;
    const double h = 1e-3;
    TIME_CALLS("cs.fmi2DoStep", a->DoStep(c, time, h, fmi2True); time += h);
    a->FreeInstance(c);
    if (!me || !a->SetTime) return 0;
    /* Model Exchange, in continuous-time mode */
    c = a->Instantiate("bench", fmi2ModelExchange, t->guid, "", &callbacks, fmi2False, fmi2False);
    a->SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
    a->EnterInitializationMode(c);
    a->ExitInitializationMode(c);
    fmi2EventInfo info;
    memset(&info, 0, sizeof info);
    info.newDiscreteStatesNeeded = fmi2True;
    while (info.newDiscreteStatesNeeded) a->NewDiscreteStates(c, &info);
    a->EnterContinuousTimeMode(c);
    a->GetContinuousStates(c, &x, 1);
    TIME_CALLS("me.fmi2SetTime", a->SetTime(c, 0.5));
    TIME_CALLS("me.fmi2SetContinuousStates", a->SetContinuousStates(c, &x, 1));
    TIME_CALLS("me.fmi2GetDerivatives", a->GetDerivatives(c, &dx, 1));
    TIME_CALLS("me.fmi2GetEventIndicators", a->GetEventIndicators(c, &z, 1));
    TIME_CALLS("me.fmi2GetContinuousStates", a->GetContinuousStates(c, &x, 1));
    TIME_CALLS("me.fmi2SetReal", a->SetReal(c, t->in, 3, u));
    TIME_CALLS("me.fmi2GetReal", a->GetReal(c, t->out, 2, y));
    a->FreeInstance(c);
    return 0;
}

static long rss_kb(void) {
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, "VmRSS:", 6)) kb = atol(line + 6);
    if (f) fclose(f);
    return kb;
}

static int instances_mode(long n, Target *t) {
    Api *a = &t->api;
    fmi2Component *cs = calloc(n, sizeof *cs);
    /* warm up: one instance, so that one-time costs (page faults of the code,
     * lazy binding) are not counted per instance */
    a->FreeInstance(start(t, fmi2CoSimulation));
    malloc_trim(0);
    long rss0 = rss_kb();
    struct mallinfo2 m0 = mallinfo2();
    double t0 = now_ns();
    for (long i = 0; i < n; i++) cs[i] = start(t, fmi2CoSimulation);
    double t1 = now_ns();
    long rss1 = rss_kb();
    struct mallinfo2 m1 = mallinfo2();
    for (long i = 0; i < n; i++) a->FreeInstance(cs[i]);
    double t2 = now_ns();
    double heap = (double)(m1.uordblks + m1.hblkhd) - (double)(m0.uordblks + m0.hblkhd);
    printf("instances %ld init_ns %.1f free_ns %.1f rss_bytes %.1f heap_bytes %.1f rss_total_mb %.3f\n", n,
           (t1 - t0) / n, (t2 - t1) / n, (rss1 - rss0) * 1024.0 / n, heap / n, (rss1 - rss0) / 1024.0);
    free(cs);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 5) { fprintf(stderr, "usage: see the comment at the top of native_cost.c\n"); return 2; }
    Target ts[64];
    if (!strcmp(argv[1], "step")) {
        int rounds = atoi(argv[2]);
        long steps = atol(argv[3]);
        int nt = 0;
        for (char **p = argv + 4; p + 5 <= argv + argc && nt < 64; nt++) p = load(&ts[nt], p);
        return step_mode(rounds, steps, nt, ts);
    }
    if (!strcmp(argv[1], "calls")) {
        load(&ts[0], argv + 5);
        return calls_mode(atoi(argv[2]), atol(argv[3]), !strcmp(argv[4], "all"), &ts[0]);
    }
    if (!strcmp(argv[1], "instances")) {
        load(&ts[0], argv + 3);
        return instances_mode(atol(argv[2]), &ts[0]);
    }
    return 2;
}

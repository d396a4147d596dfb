/* The native side of the accuracy-cost study (bench/study.py): runs one
 * scene with many methods through the FMU's C API, as an importer does, and
 * times them side by side.
 *
 *   study_driver LIB GUID SCENE_FILE JOBS_FILE OUT_DIR ROUNDS MIN_NS
 *
 * Co-Simulation jobs ("cs"): at every communication point t_k = k*h set the
 * scene's inputs u(t_k) (and, with derivatives, their first derivatives by
 * fmi2SetRealInputDerivatives), fmi2DoStep, get the outputs.
 *
 * Model Exchange jobs ("me"): the FMU's Model Exchange interface integrated by
 * CVode (SUNDIALS, BDF with a dense linear solver, rtol given, atol = rtol *
 * nominal, maximum step (stop - start)/50: FMPy's settings). The right-hand
 * side sets the inputs at the time CVode asks for (moving inputs), the time
 * and the state, and gets the derivative; kinks of piecewise-linear inputs are
 * stop times where CVode restarts. At every output point t_k (CVode's
 * interpolated state) the outputs are read as in co-simulation.
 *
 * Timing: every job is run once untimed (its outputs at every t_k go to
 * OUT_DIR/<id>.bin as float64, rows of the scene's outputs), then ROUNDS rounds
 * visit every job in turn (interleaved, so that load from other processes
 * spreads over all jobs alike); in a round a job is repeated from its initial
 * state until MIN_NS of stepping time have passed. Only the stepping loop is
 * timed, in the thread's CPU time (CLOCK_THREAD_CPUTIME_ID). OUT_DIR/results.txt gets one line per job:
 *   id status steps ns_per_step(round 1) ... ns_per_step(round R) [me: nst nfe nsetups netf]
 *
 * Scene file lines:
 *   stop T
 *   param b|i|r VR VALUE                          (before initialization)
 *   input VR const V
 *   input VR pwl T0 V0 T1 V1 ...                  (linear between points; kinks are ME stop times)
 *   input VR sin OFFSET AMPLITUDE FREQUENCY_HZ
 *   input VR scurve T0 T1 V0 V1                   (V0 + (V1-V0)(1-cos(pi s))/2, s = (t-T0)/(T1-T0) in [0,1])
 *   output VR
 * Jobs file lines:
 *   cs ID H DERIVS NPARAMS b|i|r:VR=VALUE ...
 *   me ID H RTOL NPARAMS b|i|r:VR=VALUE ...
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "fmi2Functions.h"

#include "library.h"

#define MAX_INPUTS 8
#define MAX_PTS 64
#define MAX_OUTPUTS 4
#define MAX_PARAMS 16
#define MAX_JOBS 512

/* ---------------------------------------------------------------- inputs */

enum { CONST, PWL, SIN, SCURVE };

typedef struct {
    fmi2ValueReference vr;
    int kind, n;
    double t[MAX_PTS], v[MAX_PTS]; /* pwl points; const: v[0]; sin: v[0..2]; scurve: t[0], t[1], v[0], v[1] */
} Signal;

typedef struct {
    double stop;
    int n_in, n_out, n_par, n_moving;
    Signal in[MAX_INPUTS];
    fmi2ValueReference out[MAX_OUTPUTS];
    char par[MAX_PARAMS][80];
    double breaks[MAX_PTS];
    int n_breaks;
} Scene;

static double sig_value(const Signal *s, double t) {
    switch (s->kind) {
    case CONST: return s->v[0];
    case SIN: return s->v[0] + s->v[1] * sin(2 * M_PI * s->v[2] * t);
    case SCURVE: {
        double x = (t - s->t[0]) / (s->t[1] - s->t[0]);
        if (x <= 0) return s->v[0];
        if (x >= 1) return s->v[1];
        return s->v[0] + (s->v[1] - s->v[0]) * 0.5 * (1 - cos(M_PI * x));
    }
    default: {
        if (t <= s->t[0]) return s->v[0];
        for (int i = 0; i + 1 < s->n; i++)
            if (t <= s->t[i + 1]) {
                double w = (t - s->t[i]) / (s->t[i + 1] - s->t[i]);
                return s->v[i] + w * (s->v[i + 1] - s->v[i]);
            }
        return s->v[s->n - 1];
    }
    }
}

/* The first derivative at t, from the right (the slope over the step that
 * starts at t: what an importer gives with fmi2SetRealInputDerivatives).
 * A communication point within 1e-9*h of a kink counts as on the kink. */
static double sig_rate(const Signal *s, double t, double h) {
    switch (s->kind) {
    case CONST: return 0;
    case SIN: return s->v[1] * 2 * M_PI * s->v[2] * cos(2 * M_PI * s->v[2] * t);
    case SCURVE: {
        double d = s->t[1] - s->t[0], x = (t - s->t[0]) / d;
        if (x <= 0 || x >= 1) return 0;
        return (s->v[1] - s->v[0]) * 0.5 * M_PI / d * sin(M_PI * x);
    }
    default: {
        double tt = t + 1e-9 * h;
        for (int i = 0; i + 1 < s->n; i++)
            if (tt >= s->t[i] && tt < s->t[i + 1]) return (s->v[i + 1] - s->v[i]) / (s->t[i + 1] - s->t[i]);
        return 0;
    }
    }
}

static void read_scene(const char *path, Scene *sc) {
    FILE *f = fopen(path, "r");
    if (!f) { perror(path); exit(2); }
    memset(sc, 0, sizeof *sc);
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        char *p = line, word[32];
        int used;
        if (sscanf(p, "%31s%n", word, &used) != 1) continue;
        p += used;
        if (!strcmp(word, "stop")) sc->stop = strtod(p, NULL);
        else if (!strcmp(word, "output")) sc->out[sc->n_out++] = (fmi2ValueReference)strtoul(p, NULL, 10);
        else if (!strcmp(word, "param")) {
            char kind[8], vr[32], value[32];
            sscanf(p, "%7s %31s %31s", kind, vr, value);
            snprintf(sc->par[sc->n_par++], 80, "%s:%s=%s", kind, vr, value);
        } else if (!strcmp(word, "input")) {
            Signal *s = &sc->in[sc->n_in++];
            char kind[16];
            sscanf(p, "%u %15s%n", &s->vr, kind, &used);
            p += used;
            double x[2 * MAX_PTS];
            int n = 0;
            char *end;
            for (double v = strtod(p, &end); end != p; v = strtod(p, &end)) { x[n++] = v; p = end; }
            if (!strcmp(kind, "const")) { s->kind = CONST; s->v[0] = x[0]; }
            else if (!strcmp(kind, "sin")) { s->kind = SIN; memcpy(s->v, x, 3 * sizeof(double)); }
            else if (!strcmp(kind, "scurve")) { s->kind = SCURVE; s->t[0] = x[0]; s->t[1] = x[1]; s->v[0] = x[2]; s->v[1] = x[3]; }
            else {
                s->kind = PWL; s->n = n / 2;
                for (int i = 0; i < s->n; i++) {
                    s->t[i] = x[2 * i]; s->v[i] = x[2 * i + 1];
                    if (sc->n_breaks < MAX_PTS && s->t[i] > 0) sc->breaks[sc->n_breaks++] = s->t[i];
                }
            }
            if (s->kind != CONST) sc->n_moving++;
        }
    }
    fclose(f);
    /* sort the breakpoints (a handful) */
    for (int i = 0; i < sc->n_breaks; i++)
        for (int j = i + 1; j < sc->n_breaks; j++)
            if (sc->breaks[j] < sc->breaks[i]) { double t = sc->breaks[i]; sc->breaks[i] = sc->breaks[j]; sc->breaks[j] = t; }
}

/* ---------------------------------------------------------------- FMU */

typedef struct {
    fmi2InstantiateTYPE *Instantiate; fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment; fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode; fmi2SetRealTYPE *SetReal; fmi2GetRealTYPE *GetReal;
    fmi2SetBooleanTYPE *SetBoolean; fmi2SetIntegerTYPE *SetInteger; fmi2DoStepTYPE *DoStep;
    fmi2SetRealInputDerivativesTYPE *SetRealInputDerivatives; fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate; fmi2NewDiscreteStatesTYPE *NewDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE *EnterContinuousTimeMode; fmi2SetTimeTYPE *SetTime;
    fmi2SetContinuousStatesTYPE *SetContinuousStates; fmi2GetContinuousStatesTYPE *GetContinuousStates;
    fmi2GetDerivativesTYPE *GetDerivatives; fmi2GetNominalsOfContinuousStatesTYPE *GetNominalsOfContinuousStates;
} Api;

static void *sym(Library lib, const char *name) {
    void *p = find_symbol(lib, name);
    if (!p) { fprintf(stderr, "no %s\n", name); exit(2); }
    return p;
}

static void load_api(const char *path, Api *a) {
    Library lib = open_library(path);
    if (!lib) { fprintf(stderr, "%s\n", library_error()); exit(2); }
#define L(n) a->n = (fmi2##n##TYPE *)sym(lib, "fmi2" #n)
    L(Instantiate); L(FreeInstance); L(SetupExperiment); L(EnterInitializationMode); L(ExitInitializationMode);
    L(SetReal); L(GetReal); L(SetBoolean); L(SetInteger); L(DoStep); L(SetRealInputDerivatives); L(GetFMUstate);
    L(SetFMUstate); L(NewDiscreteStates); L(EnterContinuousTimeMode); L(SetTime); L(SetContinuousStates);
    L(GetContinuousStates); L(GetDerivatives); L(GetNominalsOfContinuousStates);
#undef L
}

static void logger_impl(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String cat,
                        fmi2String message, ...) {
    (void)env; (void)name; (void)cat;
    if (status >= fmi2Discard) fprintf(stderr, "  [fmu %d] %s\n", status, message);
}

static fmi2Status set_param(Api *a, fmi2Component c, const char *spec) {
    char kind = spec[0];
    fmi2ValueReference vr = (fmi2ValueReference)strtoul(spec + 2, NULL, 10);
    const char *value = strchr(spec, '=') + 1;
    if (kind == 'b') { fmi2Boolean b = atoi(value); return a->SetBoolean(c, &vr, 1, &b); }
    if (kind == 'i') { fmi2Integer i = atoi(value); return a->SetInteger(c, &vr, 1, &i); }
    fmi2Real r = atof(value);
    return a->SetReal(c, &vr, 1, &r);
}

/* The thread's CPU time: time while other processes have the core does not count. */
static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e9 + ts.tv_nsec;
}

/* The cost of reading the clock twice (a system call for the thread's CPU
 * time), taken off every timed run: the runs at h = 0.1 s have 10 steps only. */
static double clock_cost;

static void calibrate_clock(void) {
    double best = 1e9;
    for (int i = 0; i < 2000; i++) {
        double a = now_ns(), b = now_ns();
        if (b - a < best) best = b - a;
    }
    clock_cost = best;
}

/* ---------------------------------------------------------------- jobs */

typedef struct {
    int is_me, derivs, n_par, status;
    char id[64];
    double h, rtol;
    char par[MAX_PARAMS][64];
    long steps;
    fmi2Component c;
    fmi2FMUstate start_state;
    /* ME */
    SUNContext ctx;
    void *cvode;
    N_Vector y;
    SUNMatrix A;
    SUNLinearSolver LS;
    double x0, t0;
    long nst, nfe, nsetups, netf;
    double *ns; /* per round */
} Job;

static Api api;
static Scene scene;
static fmi2CallbackFunctions callbacks = {logger_impl, calloc, free, NULL, NULL};

static void set_inputs(fmi2Component c, double t) {
    fmi2ValueReference vr[MAX_INPUTS];
    fmi2Real u[MAX_INPUTS];
    for (int i = 0; i < scene.n_in; i++) { vr[i] = scene.in[i].vr; u[i] = sig_value(&scene.in[i], t); }
    api.SetReal(c, vr, scene.n_in, u);
}

static void set_moving_inputs(fmi2Component c, double t) {
    fmi2ValueReference vr[MAX_INPUTS];
    fmi2Real u[MAX_INPUTS];
    int n = 0;
    for (int i = 0; i < scene.n_in; i++)
        if (scene.in[i].kind != CONST) { vr[n] = scene.in[i].vr; u[n++] = sig_value(&scene.in[i], t); }
    if (n) api.SetReal(c, vr, n, u);
}

static void set_rates(fmi2Component c, double t, double h) {
    fmi2ValueReference vr[MAX_INPUTS];
    fmi2Real d[MAX_INPUTS];
    fmi2Integer order[MAX_INPUTS];
    int n = 0;
    for (int i = 0; i < scene.n_in; i++)
        if (scene.in[i].kind != CONST) { vr[n] = scene.in[i].vr; d[n] = sig_rate(&scene.in[i], t, h); order[n++] = 1; }
    if (n) api.SetRealInputDerivatives(c, vr, n, order, d);
}

static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user) {
    Job *j = user;
    if (scene.n_moving) set_moving_inputs(j->c, t);
    api.SetTime(j->c, t);
    if (api.SetContinuousStates(j->c, NV_DATA_S(y), 1) > fmi2Warning) return 1; /* recoverable: smaller step */
    return api.GetDerivatives(j->c, NV_DATA_S(ydot), 1) > fmi2Warning ? -1 : 0;
}

static int setup(Job *j, const char *guid) {
    fmi2Component c = api.Instantiate(j->id, j->is_me ? fmi2ModelExchange : fmi2CoSimulation, guid, "", &callbacks,
                                      fmi2False, fmi2False);
    if (!c) return 3;
    j->c = c;
    if (api.SetupExperiment(c, j->is_me, j->rtol, 0.0, fmi2True, scene.stop) != fmi2OK) return 4;
    for (int i = 0; i < scene.n_par; i++) if (set_param(&api, c, scene.par[i]) != fmi2OK) return 4;
    for (int i = 0; i < j->n_par; i++) if (set_param(&api, c, j->par[i]) != fmi2OK) return 4;
    set_inputs(c, 0.0);
    if (api.EnterInitializationMode(c) != fmi2OK) return 5;
    if (api.ExitInitializationMode(c) != fmi2OK) return 5;
    if (!j->is_me) return api.GetFMUstate(c, &j->start_state) == fmi2OK ? 0 : 6;
    fmi2EventInfo info;
    memset(&info, 0, sizeof info);
    info.newDiscreteStatesNeeded = fmi2True;
    while (info.newDiscreteStatesNeeded) {
        if (api.NewDiscreteStates(c, &info) != fmi2OK) return 5;
    }
    if (api.EnterContinuousTimeMode(c) != fmi2OK) return 5;
    double nominal;
    api.GetContinuousStates(c, &j->x0, 1);
    api.GetNominalsOfContinuousStates(c, &nominal, 1);
    j->t0 = 0.0;
    if (SUNContext_Create(NULL, &j->ctx)) return 7;
    j->y = N_VNew_Serial(1, j->ctx);
    NV_Ith_S(j->y, 0) = j->x0;
    j->cvode = CVodeCreate(CV_BDF, j->ctx);
    if (CVodeInit(j->cvode, rhs, 0.0, j->y)) return 7;
    CVodeSetUserData(j->cvode, j);
    N_Vector atol = N_VNew_Serial(1, j->ctx);
    NV_Ith_S(atol, 0) = j->rtol * nominal;
    if (CVodeSVtolerances(j->cvode, j->rtol, atol)) return 7;
    N_VDestroy(atol);
    j->A = SUNDenseMatrix(1, 1, j->ctx);
    j->LS = SUNLinSol_Dense(j->y, j->A, j->ctx);
    if (CVodeSetLinearSolver(j->cvode, j->LS, j->A)) return 7;
    CVodeSetMaxStep(j->cvode, scene.stop / 50.0);
    CVodeSetMaxNumSteps(j->cvode, 10000000);
    return 0;
}

/* One run of the scene from the job's initial state; outputs into `rec` (n+1
 * rows) when given. Returns the stepping time in ns, or -status on failure. */
static double run_cs(Job *j, double *rec) {
    fmi2Component c = j->c;
    api.SetFMUstate(c, j->start_state);
    const double h = j->h;
    const long n = j->steps;
    const int no = scene.n_out;
    fmi2Real y[MAX_OUTPUTS];
    if (rec) { api.GetReal(c, scene.out, no, y); memcpy(rec, y, no * sizeof(double)); }
    double t0 = now_ns();
    for (long k = 0; k < n; k++) {
        double t = (double)k * h;
        set_inputs(c, t);
        if (j->derivs) set_rates(c, t, h);
        fmi2Status s = api.DoStep(c, t, h, fmi2True);
        if (s != fmi2OK) return -(double)s - 1;
        api.GetReal(c, scene.out, no, y);
        if (rec) memcpy(rec + (k + 1) * no, y, no * sizeof(double));
    }
    return now_ns() - t0 - clock_cost;
}

static double run_me(Job *j, double *rec) {
    fmi2Component c = j->c;
    const double h = j->h;
    const long n = j->steps;
    const int no = scene.n_out;
    fmi2Real out[MAX_OUTPUTS];
    /* back to the initial state: time, inputs, state; restart CVode */
    api.SetTime(c, j->t0);
    set_inputs(c, j->t0);
    api.SetContinuousStates(c, &j->x0, 1);
    NV_Ith_S(j->y, 0) = j->x0;
    CVodeReInit(j->cvode, j->t0, j->y);
    int b = 0;
    while (b < scene.n_breaks && scene.breaks[b] <= j->t0) b++;
    CVodeSetStopTime(j->cvode, b < scene.n_breaks ? scene.breaks[b] : scene.stop);
    if (rec) { api.GetReal(c, scene.out, no, out); memcpy(rec, out, no * sizeof(double)); }
    double t0 = now_ns();
    double tret = j->t0;
    for (long k = 1; k <= n; k++) {
        double tk = (double)k * h;
        /* restart at every kink of a piecewise-linear input before tk */
        while (b < scene.n_breaks && scene.breaks[b] <= tk * (1 + 1e-12)) {
            double bp = scene.breaks[b];
            if (bp - tret > 1e-9 * h) {
                int flag = CVode(j->cvode, bp, j->y, &tret, CV_NORMAL);
                if (flag < 0) return -10 + flag;
                CVodeReInit(j->cvode, tret, j->y);
            }
            b++;
            CVodeSetStopTime(j->cvode, b < scene.n_breaks ? scene.breaks[b] : scene.stop);
        }
        if (tk - tret > 1e-9 * h) { /* a kink within 1e-9*h of tk counts as on it */
            int flag = CVode(j->cvode, tk, j->y, &tret, CV_NORMAL);
            if (flag < 0) return -10 + flag;
        }
        /* outputs at tk: time, inputs, (interpolated) state */
        api.SetTime(c, tk);
        set_inputs(c, tk);
        api.SetContinuousStates(c, NV_DATA_S(j->y), 1);
        api.GetReal(c, scene.out, no, out);
        if (rec) memcpy(rec + k * no, out, no * sizeof(double));
    }
    double elapsed = now_ns() - t0 - clock_cost;
    if (rec) {
        CVodeGetNumSteps(j->cvode, &j->nst);
        CVodeGetNumRhsEvals(j->cvode, &j->nfe);
        CVodeGetNumLinSolvSetups(j->cvode, &j->nsetups);
        CVodeGetNumErrTestFails(j->cvode, &j->netf);
    }
    return elapsed;
}

static int read_jobs(const char *path, Job *jobs) {
    FILE *f = fopen(path, "r");
    if (!f) { perror(path); exit(2); }
    int n = 0;
    char line[4096];
    while (fgets(line, sizeof line, f) && n < MAX_JOBS) {
        Job *j = &jobs[n];
        memset(j, 0, sizeof *j);
        char kind[8];
        int used, np;
        if (sscanf(line, "%7s", kind) != 1) continue;
        if (!strcmp(kind, "cs")) {
            if (sscanf(line, "%7s %63s %lf %d %d%n", kind, j->id, &j->h, &j->derivs, &np, &used) != 5) continue;
        } else {
            j->is_me = 1;
            if (sscanf(line, "%7s %63s %lf %lf %d%n", kind, j->id, &j->h, &j->rtol, &np, &used) != 5) continue;
        }
        char *p = line + used;
        for (int i = 0; i < np; i++) {
            int u;
            sscanf(p, "%63s%n", j->par[i], &u);
            p += u;
        }
        j->n_par = np;
        n++;
    }
    fclose(f);
    return n;
}

int main(int argc, char **argv) {
    if (argc < 8) { fprintf(stderr, "usage: see the comment at the top of study_driver.c\n"); return 2; }
    load_api(argv[1], &api);
    read_scene(argv[3], &scene);
    calibrate_clock();
    static Job jobs[MAX_JOBS];
    int nj = read_jobs(argv[4], jobs);
    const char *dir = argv[5];
    int rounds = atoi(argv[6]);
    double min_ns = atof(argv[7]);
    int *reps = calloc(nj, sizeof(int));
    for (int i = 0; i < nj; i++) {
        Job *j = &jobs[i];
        j->steps = lround(scene.stop / j->h);
        j->ns = calloc(rounds, sizeof(double));
        j->status = setup(j, argv[2]);
        if (j->status) continue;
        double *rec = calloc((j->steps + 1) * scene.n_out, sizeof(double));
        double t = j->is_me ? run_me(j, rec) : run_cs(j, rec);
        if (t < 0) { j->status = (int)(-t); free(rec); continue; }
        char path[4200];
        snprintf(path, sizeof path, "%s/%s.bin", dir, j->id);
        FILE *f = fopen(path, "wb");
        fwrite(rec, sizeof(double), (j->steps + 1) * scene.n_out, f);
        fclose(f);
        free(rec);
        reps[i] = t >= min_ns ? 1 : (int)ceil(min_ns / (t > 1 ? t : 1));
    }
    for (int r = 0; r < rounds; r++)
        for (int i = 0; i < nj; i++) {
            Job *j = &jobs[i];
            if (j->status) continue;
            double total = 0;
            for (int k = 0; k < reps[i]; k++) total += j->is_me ? run_me(j, NULL) : run_cs(j, NULL);
            j->ns[r] = total / ((double)reps[i] * j->steps);
        }
    char path[4200];
    snprintf(path, sizeof path, "%s/results.txt", dir);
    FILE *f = fopen(path, "w");
    for (int i = 0; i < nj; i++) {
        Job *j = &jobs[i];
        fprintf(f, "%s %d %ld", j->id, j->status, j->steps);
        for (int r = 0; r < rounds; r++) fprintf(f, " %.3f", j->status ? 0.0 : j->ns[r]);
        if (j->is_me) fprintf(f, " me %ld %ld %ld %ld", j->nst, j->nfe, j->nsetups, j->netf);
        fprintf(f, "\n");
    }
    fclose(f);
    return 0;
}

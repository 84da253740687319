/* `host bench`: the cost of a communication step in a host's loop, FMI 2.0 and 3.0, co-simulation
 * and Model Exchange, on the paper's baseline (Omega = 1.75, V = 0.07) over tau <= 1000 with
 * h = 0.01. Each variant is one host loop:
 *   bare      the step alone (fmi2DoStep / fmi3DoStep; for Model Exchange an RK4 step: four
 *             derivative evaluations, the event indicators, fmi2CompletedIntegratorStep, event
 *             mode when an indicator changed sign or the FMU asks for it)
 *   get       the step, then Get(x, v)
 *   set       Set(z_in, zdot_in), then the step, in internal mode (the inputs are not used)
 *   sampled   the same Set, then the step, in external mode (the plate from the sampled
 *             inputs; co-simulation: Hermite reconstruction)
 * The inputs are the baseline sinusoid at the communication points, computed before the timing.
 * The variants run alternately, 7 rounds (BENCH_ROUNDS), and each reports its best round, so
 * that the ratios come from one run under the same machine load. */
#include "host.h"

enum { BARE, GET, SET, SAMPLED, NVARIANT };
static const char *variant_name[NVARIANT] = {"bare", "+ Get(x, v)", "+ Set(z_in, zdot_in), internal",
                                             "sampled inputs, external"};

#define OMEGA 1.75
#define VEL 0.07

static double *inputs; /* z_in, zdot_in at the start of step k: inputs[2k], inputs[2k + 1] */
static long nsteps;
static double step_h;

static void quiet2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String format, ...) {
    (void)env, (void)name, (void)status, (void)category, (void)format;
}
static fmi2CallbackFunctions quiet_callbacks = {quiet2, NULL, NULL, NULL, NULL};

static void fail(const char *what, double t) {
    fprintf(stderr, "bench: %s failed at t = %g\n", what, t);
    exit(1);
}

/* ---- FMI 2.0 ---- */

static fmi2Component start2(fmi2Type type, int variant) {
    fmi2Component c = F.fmi2Instantiate("bench", type, guid, NULL, &quiet_callbacks, fmi2False, fmi2False);
    fmi2ValueReference mode = vr("shaker_mode"), in[2] = {vr("z_in"), vr("zdot_in")};
    fmi2Integer m = variant == SAMPLED ? 2 : 1;
    if (!c || F.fmi2SetupExperiment(c, fmi2False, 0, 0.0, fmi2False, 0) != fmi2OK ||
        F.fmi2SetInteger(c, &mode, 1, &m) != fmi2OK || F.fmi2SetReal(c, in, 2, inputs) != fmi2OK ||
        F.fmi2EnterInitializationMode(c) != fmi2OK || F.fmi2ExitInitializationMode(c) != fmi2OK)
        fail("fmi2 start", 0);
    return c;
}

static double cs2(int variant) {
    fmi2Component c = start2(fmi2CoSimulation, variant);
    fmi2ValueReference xv[2] = {vr("x"), vr("v")}, in[2] = {vr("z_in"), vr("zdot_in")};
    fmi2Real out[2];
    int get = variant == GET, set = variant == SET || variant == SAMPLED;
    double t0 = now(), t = 0.0;
    for (long k = 0; k < nsteps; k++) {
        double next = (double)(k + 1) * step_h;
        if (set && F.fmi2SetReal(c, in, 2, inputs + 2 * k) != fmi2OK) fail("fmi2SetReal", t);
        if (F.fmi2DoStep(c, t, next - t, fmi2True) != fmi2OK) fail("fmi2DoStep", t);
        if (get && F.fmi2GetReal(c, xv, 2, out) != fmi2OK) fail("fmi2GetReal", t);
        t = next;
    }
    double dt = now() - t0;
    F.fmi2FreeInstance(c);
    return dt;
}

static int deriv2(fmi2Component c, double t, const double x[2], double d[2]) {
    return F.fmi2SetTime(c, t) != fmi2OK || F.fmi2SetContinuousStates(c, x, 2) != fmi2OK ||
           F.fmi2GetDerivatives(c, d, 2) != fmi2OK;
}

/* Event mode at the current time, back to continuous-time mode. */
static void event2(fmi2Component c, double t) {
    fmi2EventInfo info;
    if (F.fmi2EnterEventMode(c) != fmi2OK) fail("fmi2EnterEventMode", t);
    do {
        if (F.fmi2NewDiscreteStates(c, &info) != fmi2OK) fail("fmi2NewDiscreteStates", t);
    } while (info.newDiscreteStatesNeeded);
    if (F.fmi2EnterContinuousTimeMode(c) != fmi2OK) fail("fmi2EnterContinuousTimeMode", t);
}

static int crossed(const double a[2], const double b[2]) {
    return (a[0] > 0) != (b[0] > 0) || (a[1] > 0) != (b[1] > 0);
}

static double me2(int variant) {
    fmi2Component c = start2(fmi2ModelExchange, variant);
    fmi2ValueReference xv[2] = {vr("x"), vr("v")}, in[2] = {vr("z_in"), vr("zdot_in")};
    fmi2Real out[2];
    int get = variant == GET, set = variant == SET || variant == SAMPLED;
    double t0 = now(), t = 0.0, x[2], z0[2], z1[2];
    event2(c, 0.0);
    if (F.fmi2GetContinuousStates(c, x, 2) != fmi2OK || F.fmi2GetEventIndicators(c, z0, 2) != fmi2OK)
        fail("fmi2 ME start", t);
    for (long k = 0; k < nsteps; k++) {
        double h = step_h, next = (double)(k + 1) * h, k1[2], k2[2], k3[2], k4[2], a[2];
        if (set && F.fmi2SetReal(c, in, 2, inputs + 2 * k) != fmi2OK) fail("fmi2SetReal", t);
        int bad = deriv2(c, t, x, k1);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k1[i];
        bad |= deriv2(c, t + h / 2, a, k2);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k2[i];
        bad |= deriv2(c, t + h / 2, a, k3);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h * k3[i];
        bad |= deriv2(c, next, a, k4);
        for (int i = 0; i < 2; i++) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
        fmi2Boolean enter = fmi2False, terminate = fmi2False;
        bad |= F.fmi2SetTime(c, next) != fmi2OK || F.fmi2SetContinuousStates(c, x, 2) != fmi2OK ||
               F.fmi2GetEventIndicators(c, z1, 2) != fmi2OK ||
               F.fmi2CompletedIntegratorStep(c, fmi2True, &enter, &terminate) != fmi2OK;
        if (bad) fail("fmi2 ME step", t);
        t = next;
        if (enter || crossed(z0, z1)) {
            event2(c, t);
            if (F.fmi2GetContinuousStates(c, x, 2) != fmi2OK || F.fmi2GetEventIndicators(c, z1, 2) != fmi2OK)
                fail("fmi2 ME event", t);
        }
        z0[0] = z1[0], z0[1] = z1[1];
        if (get && F.fmi2GetReal(c, xv, 2, out) != fmi2OK) fail("fmi2GetReal", t);
    }
    double dt = now() - t0;
    F.fmi2FreeInstance(c);
    return dt;
}

/* ---- FMI 3.0 ---- */

static fmi3Instance start3(int me, int variant) {
    fmi3Instance c = me ? F.fmi3InstantiateModelExchange("bench", guid, NULL, false, false, NULL, NULL)
                        : F.fmi3InstantiateCoSimulation("bench", guid, NULL, false, false, false, false,
                                                        NULL, 0, NULL, NULL, NULL);
    fmi3ValueReference mode = vr("shaker_mode"), in[2] = {vr("z_in"), vr("zdot_in")};
    fmi3Int64 m = variant == SAMPLED ? 2 : 1;
    if (!c || F.fmi3SetInt64(c, &mode, 1, &m, 1) != fmi3OK || F.fmi3SetFloat64(c, in, 2, inputs, 2) != fmi3OK ||
        F.fmi3EnterInitializationMode(c, false, 0, 0.0, false, 0) != fmi3OK ||
        F.fmi3ExitInitializationMode(c) != fmi3OK)
        fail("fmi3 start", 0);
    return c;
}

static double cs3(int variant) {
    fmi3Instance c = start3(0, variant);
    fmi3ValueReference xv[2] = {vr("x"), vr("v")}, in[2] = {vr("z_in"), vr("zdot_in")};
    fmi3Float64 out[2], last = 0;
    bool need = false, term = false, ret = false;
    int get = variant == GET, set = variant == SET || variant == SAMPLED;
    double t0 = now(), t = 0.0;
    for (long k = 0; k < nsteps; k++) {
        double next = (double)(k + 1) * step_h;
        if (set && F.fmi3SetFloat64(c, in, 2, inputs + 2 * k, 2) != fmi3OK) fail("fmi3SetFloat64", t);
        if (F.fmi3DoStep(c, t, next - t, true, &need, &term, &ret, &last) != fmi3OK) fail("fmi3DoStep", t);
        if (get && F.fmi3GetFloat64(c, xv, 2, out, 2) != fmi3OK) fail("fmi3GetFloat64", t);
        t = next;
    }
    double dt = now() - t0;
    F.fmi3FreeInstance(c);
    return dt;
}

static int deriv3(fmi3Instance c, double t, const double x[2], double d[2]) {
    return F.fmi3SetTime(c, t) != fmi3OK || F.fmi3SetContinuousStates(c, x, 2) != fmi3OK ||
           F.fmi3GetContinuousStateDerivatives(c, d, 2) != fmi3OK;
}

static void event3(fmi3Instance c, double t) {
    bool need = true, term, changed, vchanged, defined;
    double next_event;
    if (F.fmi3EnterEventMode(c) != fmi3OK) fail("fmi3EnterEventMode", t);
    while (need)
        if (F.fmi3UpdateDiscreteStates(c, &need, &term, &changed, &vchanged, &defined, &next_event) != fmi3OK)
            fail("fmi3UpdateDiscreteStates", t);
    if (F.fmi3EnterContinuousTimeMode(c) != fmi3OK) fail("fmi3EnterContinuousTimeMode", t);
}

static double me3(int variant) {
    fmi3Instance c = start3(1, variant);
    fmi3ValueReference xv[2] = {vr("x"), vr("v")}, in[2] = {vr("z_in"), vr("zdot_in")};
    fmi3Float64 out[2];
    int get = variant == GET, set = variant == SET || variant == SAMPLED;
    double t0 = now(), t = 0.0, x[2], z0[2], z1[2];
    event3(c, 0.0);
    if (F.fmi3GetContinuousStates(c, x, 2) != fmi3OK || F.fmi3GetEventIndicators(c, z0, 2) != fmi3OK)
        fail("fmi3 ME start", t);
    for (long k = 0; k < nsteps; k++) {
        double h = step_h, next = (double)(k + 1) * h, k1[2], k2[2], k3[2], k4[2], a[2];
        if (set && F.fmi3SetFloat64(c, in, 2, inputs + 2 * k, 2) != fmi3OK) fail("fmi3SetFloat64", t);
        int bad = deriv3(c, t, x, k1);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k1[i];
        bad |= deriv3(c, t + h / 2, a, k2);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k2[i];
        bad |= deriv3(c, t + h / 2, a, k3);
        for (int i = 0; i < 2; i++) a[i] = x[i] + h * k3[i];
        bad |= deriv3(c, next, a, k4);
        for (int i = 0; i < 2; i++) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
        bool enter = false, terminate = false;
        bad |= F.fmi3SetTime(c, next) != fmi3OK || F.fmi3SetContinuousStates(c, x, 2) != fmi3OK ||
               F.fmi3GetEventIndicators(c, z1, 2) != fmi3OK ||
               F.fmi3CompletedIntegratorStep(c, true, &enter, &terminate) != fmi3OK;
        if (bad) fail("fmi3 ME step", t);
        t = next;
        if (enter || crossed(z0, z1)) {
            event3(c, t);
            if (F.fmi3GetContinuousStates(c, x, 2) != fmi3OK || F.fmi3GetEventIndicators(c, z1, 2) != fmi3OK)
                fail("fmi3 ME event", t);
        }
        z0[0] = z1[0], z0[1] = z1[1];
        if (get && F.fmi3GetFloat64(c, xv, 2, out, 2) != fmi3OK) fail("fmi3GetFloat64", t);
    }
    double dt = now() - t0;
    F.fmi3FreeInstance(c);
    return dt;
}

/* fmi3DoStep with earlyReturnAllowed and eventModeUsed: every event an early return followed by
 * event mode (fmi3EnterEventMode, fmi3UpdateDiscreteStates, fmi3EnterStepMode); `*returns`
 * counts the early returns. */
static double cs3_early(long *returns) {
    fmi3Instance c = F.fmi3InstantiateCoSimulation("bench", guid, NULL, false, false, true, true, NULL, 0,
                                                   NULL, NULL, NULL);
    bool need = false, term = false, ret = false, defined = false, changed = false;
    double last = 0.0, next_event = 0.0;
    if (!c || F.fmi3EnterInitializationMode(c, false, 0, 0.0, false, 0) != fmi3OK ||
        F.fmi3ExitInitializationMode(c) != fmi3OK ||
        F.fmi3UpdateDiscreteStates(c, &need, &term, &changed, &changed, &defined, &next_event) != fmi3OK ||
        F.fmi3EnterStepMode(c) != fmi3OK)
        fail("fmi3 start (early return)", 0);
    *returns = 0;
    double t0 = now(), t = 0.0;
    for (long k = 0; k < nsteps; k++) {
        double next = (double)(k + 1) * step_h;
        while (t < next) {
            if (F.fmi3DoStep(c, t, next - t, true, &need, &term, &ret, &last) != fmi3OK) fail("fmi3DoStep", t);
            t = ret ? last : next;
            *returns += ret;
            if (need && (F.fmi3EnterEventMode(c) != fmi3OK ||
                         F.fmi3UpdateDiscreteStates(c, &need, &term, &changed, &changed, &defined,
                                                    &next_event) != fmi3OK ||
                         F.fmi3EnterStepMode(c) != fmi3OK))
                fail("fmi3 event mode", t);
        }
    }
    double dt = now() - t0;
    F.fmi3FreeInstance(c);
    return dt;
}

/* One fmi2DoStep over [0, t_end] (bare, internal mode). */
static double cs2_one_step(double t_end) {
    fmi2Component c = start2(fmi2CoSimulation, BARE);
    double t0 = now();
    if (F.fmi2DoStep(c, 0.0, t_end, fmi2True) != fmi2OK) fail("fmi2DoStep", 0);
    double dt = now() - t0;
    F.fmi2FreeInstance(c);
    return dt;
}

/* ---- the table ---- */

enum { CS2, CS3, ME2, ME3, NLOOP };
static const char *loop_name[NLOOP] = {"FMI 2.0 co-simulation (fmi2DoStep)", "FMI 3.0 co-simulation (fmi3DoStep)",
                                       "FMI 2.0 Model Exchange (RK4 step)", "FMI 3.0 Model Exchange (RK4 step)"};
static double (*const loop_fn[NLOOP])(int) = {cs2, cs3, me2, me3};

void bench(void) {
    const double t_end = 1000.0, h = 0.01;
    /* BENCH_ROUNDS: more rounds for a busy machine (each variant keeps its best round). */
    const char *env_rounds = getenv("BENCH_ROUNDS");
    const int rounds = env_rounds && atoi(env_rounds) > 0 ? atoi(env_rounds) : 7;
    step_h = h;
    nsteps = (long)(t_end / h + 0.5);
    inputs = malloc(2 * (size_t)nsteps * sizeof *inputs);
    if (!inputs) fail("malloc", 0);
    for (long k = 0; k < nsteps; k++) {
        double t = (double)k * h;
        inputs[2 * k] = VEL / OMEGA * sin(OMEGA * t);
        inputs[2 * k + 1] = VEL * cos(OMEGA * t);
    }
    /* Only the loops named in BENCH_LOOPS (e.g. "cs2,me3"), and the variants in BENCH_VARIANTS
     * (e.g. "bare,get"), when set: for profiling one loop. */
    const char *loops = getenv("BENCH_LOOPS"), *variants = getenv("BENCH_VARIANTS");
    static const char *loop_key[NLOOP] = {"cs2", "cs3", "me2", "me3"};
    static const char *variant_key[NVARIANT] = {"bare", "get", "set", "sampled"};
    int on[NLOOP][NVARIANT];
    for (int l = 0; l < NLOOP; l++)
        for (int v = 0; v < NVARIANT; v++)
            on[l][v] = (!loops || strstr(loops, loop_key[l])) && (!variants || strstr(variants, variant_key[v]));
    double best[NLOOP][NVARIANT];
    for (int l = 0; l < NLOOP; l++)
        for (int v = 0; v < NVARIANT; v++) best[l][v] = INFINITY;
    for (int l = 0; l < NLOOP; l++) /* warm up */
        if (on[l][BARE]) loop_fn[l](BARE);
    for (int r = 0; r < rounds; r++)
        for (int l = 0; l < NLOOP; l++)
            for (int v = 0; v < NVARIANT; v++) {
                if (!on[l][v]) continue;
                double dt = loop_fn[l](v);
                best[l][v] = dt < best[l][v] ? dt : best[l][v];
            }
    double big = INFINITY;
    if (on[CS2][BARE])
        for (int r = 0; r < rounds; r++) {
            double dt = cs2_one_step(t_end);
            big = dt < big ? dt : big;
        }
    printf("bench: baseline Omega=%g V=%g, tau <= %g, h = %g (%ld steps), best of %d alternating rounds\n",
           OMEGA, VEL, t_end, h, nsteps, rounds);
    if (on[CS2][BARE])
        printf("bench: one fmi2DoStep of %g: %.3f ms; %ld of h = %g: %.3f ms, %.2f x one step\n", t_end,
               big * 1e3, nsteps, h, best[CS2][BARE] * 1e3, best[CS2][BARE] / big);
    if (on[CS3][BARE]) {
        double early = INFINITY;
        long returns = 0;
        for (int r = 0; r < rounds; r++) {
            double dt = cs3_early(&returns);
            early = dt < early ? dt : early;
        }
        printf("bench: fmi3DoStep with early return and event mode: %.1f ns per step (%ld early returns), "
               "%.2f x bare fmi3DoStep\n",
               early / (double)nsteps * 1e9, returns, early / best[CS3][BARE]);
    }
    printf("| host loop | per communication step | ns | x bare | x internal with Set |\n");
    printf("|---|---|---|---|---|\n");
    for (int l = 0; l < NLOOP; l++)
        for (int v = 0; v < NVARIANT; v++) {
            if (!on[l][v]) continue;
            double ns = best[l][v] / (double)nsteps * 1e9, bare = best[l][BARE] / (double)nsteps * 1e9;
            char internal[32] = "";
            if (v == SAMPLED && on[l][SET]) snprintf(internal, sizeof internal, "%.2f", best[l][SAMPLED] / best[l][SET]);
            printf("| %s | %s | %.1f | %.2f | %s |\n", loop_name[l], variant_name[v], ns, ns / bare, internal);
        }
    free(inputs);
}

/* A small FMI 2.0 host (co-simulation, and Model Exchange in me.c) for the bistable_impact FMU, compiled against the
 * cbindgen-generated header (fmu/include/bistable_impact.h) and loading the binary with dlopen.
 *
 *   host test  LIB.so modelDescription.xml   scenarios + scripted illegal calls; prints
 *                                            "N passed, M failed" and exits 1 on any failure
 *   host bench LIB.so modelDescription.xml   cost per communication step in FMI 2.0/3.0 host loops (bench.c)
 *   host fuzz  LIB.so modelDescription.xml SEEDS NCALLS
 *                                            random FMI call sequences with invariants (fuzz.c)
 *
 * Value references are looked up by name in modelDescription.xml (the single source of truth).
 */
#include "host.h"

struct fmi_table F;

int load(const char *path) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        return -1;
    }
    int missing = 0, count = 0;
#define LOAD(f)                                                      \
    F.f = (__typeof__(&f))dlsym(lib, #f);                            \
    if (!F.f) {                                                      \
        fprintf(stderr, "missing export %s\n", #f);                  \
        missing++;                                                   \
    }                                                                \
    count++;
    FMI_FUNCTIONS(LOAD)
    printf("loaded %d of %d fmi2 functions\n", count - missing, count);
    FMI3_BENCH_FUNCTIONS(LOAD)
#undef LOAD
    return missing ? -1 : 0;
}

/* ---- model description: guid and value references by name ---- */
char *xml;

/* The value reference of the variable `name` (exits if absent). */
fmi2ValueReference vr(const char *name) {
    char key[128];
    snprintf(key, sizeof key, "name=\"%s\"", name);
    const char *p = strstr(xml, key);
    const char *q = p ? strstr(p, "valueReference=\"") : NULL;
    if (!q) {
        fprintf(stderr, "variable %s not in modelDescription.xml\n", name);
        exit(2);
    }
    return (fmi2ValueReference)strtoul(q + strlen("valueReference=\""), NULL, 10);
}

char guid[64];

static void read_guid(void) {
    const char *p = strstr(xml, "guid=\"");
    if (p) sscanf(p + 6, "%63[^\"]", guid);
}

/* ---- logger: a real variadic function; keeps the last message ---- */
static char last_msg[2048];
static fmi2Status last_status = -1;
static int n_events;

double impact_t[MAX_IMPACTS];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String format, ...) {
    (void)env;
    (void)name;
    va_list ap;
    va_start(ap, format);
    vsnprintf(last_msg, sizeof last_msg, format, ap);
    va_end(ap);
    last_status = status;
    if (strcmp(category, "logEvents") == 0) {
        n_events++;
        long k;
        double t;
        if (sscanf(last_msg, "impact %ld at t=%lf", &k, &t) == 2 && k >= 0 && k < MAX_IMPACTS)
            impact_t[k] = t;
    }
    if (getenv("HOST_VERBOSE")) printf("  [%d %s] %s\n", status, category, last_msg);
}

fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};

/* ---- checks ---- */
static int passed, failed;

void hcheck(int ok, const char *what) {
    if (ok) {
        passed++;
    } else {
        failed++;
        printf("FAIL: %s (last log: %s)\n", what, last_msg);
    }
}

void hrefused(fmi2Status s, const char *needle, const char *what) {
    char buf[512];
    snprintf(buf, sizeof buf, "%s: refused with a message about \"%s\"", what, needle);
    hcheck(s == fmi2Error && last_status == fmi2Error && strstr(last_msg, needle) != NULL, buf);
    last_msg[0] = 0;
    last_status = -1;
}

static fmi2Component instantiate(int logging) {
    return F.fmi2Instantiate("host", fmi2CoSimulation, guid, NULL, &callbacks, fmi2False,
                             logging);
}

/* Instantiated, parameters set, initialized at t = 0 (stop time `stop` if > 0). */
static fmi2Component started(double omega, double v, double stop) {
    fmi2Component c = instantiate(fmi2False);
    if (!c) return NULL;
    fmi2ValueReference vrs[2] = {vr("Omega"), vr("V")};
    fmi2Real vals[2] = {omega, v};
    int ok = F.fmi2SetupExperiment(c, fmi2False, 0, 0.0, stop > 0, stop) == fmi2OK &&
             F.fmi2SetReal(c, vrs, 2, vals) == fmi2OK &&
             F.fmi2EnterInitializationMode(c) == fmi2OK &&
             F.fmi2ExitInitializationMode(c) == fmi2OK;
    if (!ok) {
        F.fmi2FreeInstance(c);
        return NULL;
    }
    return c;
}

static double real(fmi2Component c, const char *name) {
    fmi2ValueReference r = vr(name);
    fmi2Real x = NAN;
    F.fmi2GetReal(c, &r, 1, &x);
    return x;
}

static int integer(fmi2Component c, const char *name) {
    fmi2ValueReference r = vr(name);
    fmi2Integer x = -1;
    F.fmi2GetInteger(c, &r, 1, &x);
    return x;
}

/* Steps of size h from t0 to t_end (last one shortened), reading x and v after each step when
 * `read`; returns 0 if every step was OK. */
static int run_reading(fmi2Component c, double t0, double t_end, double h, int read) {
    long n = (long)ceil((t_end - t0) / h - 1e-9);
    double t = t0;
    fmi2ValueReference xv[2] = {vr("x"), vr("v")};
    fmi2Real out[2];
    for (long k = 1; k <= n; k++) {
        double next = k == n ? t_end : t0 + (double)k * h;
        if (F.fmi2DoStep(c, t, next - t, fmi2True) != fmi2OK) return -1;
        if (read && F.fmi2GetReal(c, xv, 2, out) != fmi2OK) return -1;
        t = next;
    }
    return 0;
}

static int run(fmi2Component c, double t0, double t_end, double h) {
    return run_reading(c, t0, t_end, h, 0);
}

/* ---- scenarios ---- */

static void step_size_independence(void) {
    const double hs[] = {1e-3, 0.01, 0.1, 1.0, 10.0};
    double x0 = 0, v0 = 0, t0 = 0;
    int n0 = 0;
    for (int i = 0; i < 5; i++) {
        fmi2Component c = started(1.75, 0.07, 0);
        hcheck(c != NULL, "instantiate and initialize the baseline");
        if (!c) return;
        hcheck(run(c, 0, 200, hs[i]) == 0, "baseline steps are all fmi2OK");
        double x = real(c, "x"), v = real(c, "v"), t = real(c, "last_impact_time");
        int n = integer(c, "impact_count");
        if (i == 0) {
            x0 = x, v0 = v, t0 = t, n0 = n;
            hcheck(n > 50, "baseline has impacts");
        } else {
            char what[128];
            snprintf(what, sizeof what, "h = %g agrees with h = 1e-3 to 1e-12 (x, v, impacts)", hs[i]);
            hcheck(fabs(x - x0) <= 1e-12 && fabs(v - v0) <= 1e-12 && fabs(t - t0) <= 1e-12 && n == n0,
                  what);
        }
        F.fmi2Terminate(c);
        F.fmi2FreeInstance(c);
    }
}

static void fmu_state_across_instances(void) {
    fmi2Component a = started(0.3, 0.05, 0), b = started(1.0, 0.01, 0);
    hcheck(a && b, "two instances");
    if (!a || !b) return;
    run(a, 0, 15, 0.25);
    fmi2FMUstate s = NULL, t = NULL;
    hcheck(F.fmi2GetFMUstate(a, &s) == fmi2OK && s, "fmi2GetFMUstate");
    size_t size = 0;
    hcheck(F.fmi2SerializedFMUstateSize(a, s, &size) == fmi2OK && size > 100, "state size");
    fmi2Byte *bytes = malloc(size);
    hcheck(F.fmi2SerializeFMUstate(a, s, bytes, size) == fmi2OK, "serialize");
    run(a, 15, 40, 0.25);
    double xa = real(a, "x"), va = real(a, "v");
    int na = integer(a, "impact_count");
    hcheck(F.fmi2DeSerializeFMUstate(b, bytes, size, &t) == fmi2OK && t, "deserialize in another instance");
    hcheck(F.fmi2SetFMUstate(b, t) == fmi2OK, "set the deserialized state");
    run(b, 15, 40, 0.25);
    hcheck(real(b, "x") == xa && real(b, "v") == va && integer(b, "impact_count") == na,
          "restored instance continues bit for bit");
    hcheck(F.fmi2SetFMUstate(a, s) == fmi2OK, "roll back");
    run(a, 15, 40, 0.25);
    hcheck(real(a, "x") == xa && real(a, "v") == va, "rollback reproduces the steps bit for bit");
    bytes[size / 2] ^= 1;
    fmi2FMUstate u = NULL;
    hrefused(F.fmi2DeSerializeFMUstate(b, bytes, size, &u), "checksum", "corrupt state bytes");
    hrefused(F.fmi2DeSerializeFMUstate(b, bytes, size - 8, &u), "bytes", "truncated state bytes");
    hrefused(F.fmi2DeSerializeFMUstate(b, bytes, 3, &u), "truncated", "three state bytes");
    hcheck(u == NULL, "no state from bad bytes");
    hcheck(F.fmi2FreeFMUstate(a, &s) == fmi2OK && s == NULL, "free state");
    hcheck(F.fmi2FreeFMUstate(b, &t) == fmi2OK, "free deserialized state");
    free(bytes);
    F.fmi2FreeInstance(a);
    F.fmi2FreeInstance(b);
}

/* The internal sinusoid fed through z_in, zdot_in and derivatives of order 2..5 reproduces the
 * internal shaker (the plate over a step is the degree-5 Taylor polynomial of the inputs). */
static void external_inputs(void) {
    const double omega = 1.75, v = 0.07, h = 0.01, t_end = 30.0;
    fmi2Component in = started(omega, v, 0), ex = instantiate(fmi2False);
    hcheck(in && ex, "two instances for the external-input scenario");
    if (!in || !ex) return;
    fmi2ValueReference mode = vr("shaker_mode"), zv[2] = {vr("z_in"), vr("zdot_in")};
    fmi2Integer external = 2;
    F.fmi2SetupExperiment(ex, fmi2False, 0, 0, fmi2False, 0);
    F.fmi2SetInteger(ex, &mode, 1, &external);
    F.fmi2EnterInitializationMode(ex);
    fmi2Real z0[2] = {0.0, v};
    F.fmi2SetReal(ex, zv, 2, z0);
    hcheck(F.fmi2ExitInitializationMode(ex) == fmi2OK, "external mode initializes");
    int ok = 1;
    long n = (long)(t_end / h + 0.5);
    for (long k = 0; k < n; k++) {
        double t = (double)k * h, d[6];
        for (int j = 0; j < 6; j++) d[j] = v / omega * pow(omega, j) * sin(omega * t + j * M_PI / 2);
        fmi2ValueReference dv[4] = {zv[0], zv[0], zv[0], zv[0]};
        fmi2Integer orders[4] = {2, 3, 4, 5};
        ok &= F.fmi2SetReal(ex, zv, 2, d) == fmi2OK;
        ok &= F.fmi2SetRealInputDerivatives(ex, dv, 4, orders, d + 2) == fmi2OK;
        ok &= F.fmi2DoStep(ex, t, (double)(k + 1) * h - t, fmi2True) == fmi2OK;
    }
    hcheck(ok, "external steps are all fmi2OK");
    run(in, 0, t_end, h);
    hcheck(fabs(real(ex, "x") - real(in, "x")) < 1e-9 && fabs(real(ex, "v") - real(in, "v")) < 1e-9 &&
              integer(ex, "impact_count") == integer(in, "impact_count"),
          "external inputs with derivatives reproduce the internal sinusoid within 1e-9");
    F.fmi2FreeInstance(in);
    F.fmi2FreeInstance(ex);
}

static void logging_of_events(void) {
    fmi2Component c = instantiate(fmi2True);
    hcheck(c != NULL, "instantiate with logging");
    if (!c) return;
    const char *cat = "logEvents";
    hcheck(F.fmi2SetDebugLogging(c, fmi2True, 1, &cat) == fmi2OK, "enable logEvents");
    F.fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
    F.fmi2EnterInitializationMode(c);
    F.fmi2ExitInitializationMode(c);
    n_events = 0;
    run(c, 0, 50, 50);
    int n = integer(c, "impact_count");
    hcheck(n_events >= n - 1 && n > 5, "every impact inside one big step is logged under logEvents");
    hcheck(strstr(last_msg, "impact") != NULL || strstr(last_msg, "snap") != NULL ||
              strstr(last_msg, "stick") != NULL,
          "event messages arrive through the variadic logger");
    F.fmi2FreeInstance(c);
}

/* The scripted sequence of illegal calls and bad values. */
static void illegal_calls(void) {
    fmi2Component none = NULL;
    int bogus = 42;
    hcheck(F.fmi2Instantiate("x", fmi2CoSimulation, "{wrong}", NULL, &callbacks, 0, 0) == NULL &&
              strstr(last_msg, "does not match") != NULL,
          "wrong GUID refused with a logged reason");
    hcheck(F.fmi2Instantiate("x", 7, guid, NULL, &callbacks, 0, 0) == NULL &&
              strstr(last_msg, "must be fmi2ModelExchange") != NULL,
          "unknown fmuType refused");
    hcheck(F.fmi2Instantiate("x", fmi2CoSimulation, guid, NULL, NULL, 0, 0) == NULL,
          "NULL callbacks refused");
    hcheck(F.fmi2Instantiate(NULL, fmi2CoSimulation, guid, NULL, &callbacks, 0, 0) == NULL,
          "NULL instance name refused");
    hcheck(F.fmi2Instantiate("x", fmi2CoSimulation, NULL, NULL, &callbacks, 0, 0) == NULL,
          "NULL GUID refused");

    fmi2Component c = instantiate(fmi2False);
    hcheck(c != NULL, "instantiate");
    if (!c) return;
    fmi2ValueReference zeta = vr("zeta"), e = vr("e"), x = vr("x"), z_in = vr("z_in");
    fmi2ValueReference mode = vr("shaker_mode"), unknown = 777;
    fmi2Real nan = NAN, two = 2.0, one = 1.0, out = 0;
    fmi2Integer three = 3, order = 9;
    fmi2Boolean b = 0;
    hrefused(F.fmi2DoStep(c, 0, 0.1, 0), "not allowed in state Instantiated", "step before initialization");
    hrefused(F.fmi2GetReal(c, &x, 1, &out), "not allowed", "get before initialization");
    hrefused(F.fmi2ExitInitializationMode(c), "not allowed", "exit before enter");
    hrefused(F.fmi2SetReal(c, &zeta, 1, &nan), "zeta = NaN", "NaN parameter");
    hrefused(F.fmi2SetReal(c, &e, 1, &two), "e = 2 is out of range", "out-of-range e");
    hrefused(F.fmi2SetInteger(c, &mode, 1, &three), "shaker_mode = 3", "unknown shaker mode");
    hrefused(F.fmi2SetReal(c, &unknown, 1, &one), "unknown value reference 777", "unknown vr");
    hrefused(F.fmi2SetReal(c, NULL, 1, &one), "vr is NULL", "NULL vr array");
    hrefused(F.fmi2SetReal(c, &zeta, 1, NULL), "value is NULL", "NULL value array");
    hrefused(F.fmi2SetReal(c, &x, 1, &one), "is an output", "setting an output");
    hrefused(F.fmi2SetBoolean(c, &zeta, 1, &b), "not Boolean", "wrong type");
    hrefused(F.fmi2SetString(c, &zeta, 1, (const fmi2String[]){"a"}), "not String", "no strings");
    hrefused(F.fmi2SetupExperiment(c, 0, 0, NAN, 0, 0), "startTime", "NaN start time");
    hrefused(F.fmi2SetupExperiment(c, 0, 0, 5, 1, 1), "stopTime", "stop before start");
    hrefused(F.fmi2SetRealInputDerivatives(c, &z_in, 1, &order, &one), "order 9", "derivative order");
    hrefused(F.fmi2SetRealInputDerivatives(c, &zeta, 1, &(fmi2Integer){1}, &one), "only z_in",
            "derivative of a parameter");
    hrefused(F.fmi2SetDebugLogging(c, 1, 1, (const fmi2String[]){"logNothing"}), "unknown log category",
            "unknown category");
    hrefused(F.fmi2SetDebugLogging(c, 1, 1, NULL), "categories is NULL", "NULL categories");
    fmi2FMUstate fake = &bogus;
    hrefused(F.fmi2SetFMUstate(c, fake), "not created by this instance", "foreign FMU state pointer");
    hrefused(F.fmi2FreeFMUstate(c, NULL), "FMUstate is NULL", "NULL state slot");
    hrefused(F.fmi2GetFMUstate(c, NULL), "FMUstate is NULL", "NULL state output");
    hrefused(F.fmi2DeSerializeFMUstate(c, (const fmi2Byte *)"garbage!garbage!garbage!", 24, &fake),
            "magic", "garbage state bytes");

    hcheck(F.fmi2SetupExperiment(c, 0, 0, 0, 1, 20) == fmi2OK, "setup with stop time 20");
    hcheck(F.fmi2EnterInitializationMode(c) == fmi2OK, "enter initialization");
    hrefused(F.fmi2EnterInitializationMode(c), "not allowed", "enter twice");
    fmi2ValueReference x0 = vr("x0");
    fmi2Real below = -1.0, zero = 0.0;
    hcheck(F.fmi2SetReal(c, &x0, 1, &below) == fmi2OK, "x0 = -1 accepted by range");
    hrefused(F.fmi2ExitInitializationMode(c), "below the plate", "mass below the plate");
    hcheck(F.fmi2SetReal(c, &x0, 1, &zero) == fmi2OK, "x0 = 0");
    hcheck(F.fmi2ExitInitializationMode(c) == fmi2OK, "exit initialization");
    hrefused(F.fmi2SetReal(c, &zeta, 1, &one), "fixed parameter", "fixed parameter after init");
    hrefused(F.fmi2DoStep(c, 0, 0, 0), "communicationStepSize = 0", "zero step");
    hrefused(F.fmi2DoStep(c, 0, -1, 0), "communicationStepSize = -1", "negative step");
    hrefused(F.fmi2DoStep(c, 0, INFINITY, 0), "communicationStepSize = inf", "infinite step");
    hrefused(F.fmi2DoStep(c, 3, 1, 0), "does not match", "wrong communication point");
    hrefused(F.fmi2DoStep(c, 0, 25, 0), "beyond stopTime", "step past the stop time");
    hrefused(F.fmi2CancelStep(c), "synchronous", "cancel without a pending step");
    hrefused(F.fmi2GetDirectionalDerivative(c, &x, 1, &zeta, 1, &one, &out), "not provided",
            "directional derivative");
    hrefused(F.fmi2GetRealOutputDerivatives(c, &x, 1, &(fmi2Integer){2}, &out), "only order 1",
            "second output derivative");
    hrefused(F.fmi2GetBooleanStatus(c, fmi2Terminated, NULL), "value is NULL", "NULL status output");
    hrefused(F.fmi2GetRealStatus(c, 99, &out), "unknown status kind", "unknown status kind");
    hrefused(F.fmi2GetString(c, &x, 1, &(fmi2String){NULL}), "not String", "get string");
    fmi2Status st = fmi2OK;
    hcheck(F.fmi2GetStatus(c, fmi2DoStepStatus, &st) == fmi2Discard, "fmi2DoStepStatus is not available");

    /* NULL component: every function refuses it without touching memory. */
    hcheck(F.fmi2DoStep(none, 0, 1, 0) == fmi2Error && F.fmi2GetReal(none, &x, 1, &out) == fmi2Error &&
              F.fmi2SetReal(none, &zeta, 1, &one) == fmi2Error && F.fmi2Reset(none) == fmi2Error &&
              F.fmi2Terminate(none) == fmi2Error && F.fmi2CancelStep(none) == fmi2Error,
          "NULL component refused");
    F.fmi2FreeInstance(none);

    /* The instance is intact after all the refusals. */
    hcheck(F.fmi2DoStep(c, 0, 20, 0) == fmi2OK && integer(c, "impact_count") > 2, "still steps after refusals");
    fmi2Integer der_order = 1;
    hcheck(F.fmi2GetRealOutputDerivatives(c, &x, 1, &der_order, &out) == fmi2OK && out == real(c, "v"),
          "dx/dt is v");
    hcheck(F.fmi2Terminate(c) == fmi2OK, "terminate");
    hrefused(F.fmi2DoStep(c, 20, 1, 0), "not allowed in state Terminated", "step after terminate");
    hcheck(F.fmi2Reset(c) == fmi2OK, "reset");
    hcheck(F.fmi2SetReal(c, &zeta, 1, &one) == fmi2OK, "parameters settable again after reset");
    F.fmi2FreeInstance(c);
}

double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    int fuzz = argc == 6 && strcmp(argv[1], "fuzz") == 0;
    if (!fuzz && (argc != 4 || (strcmp(argv[1], "test") != 0 && strcmp(argv[1], "bench") != 0))) {
        fprintf(stderr,
                "usage: %s test|bench LIB.so modelDescription.xml\n"
                "       %s fuzz LIB.so modelDescription.xml SEEDS NCALLS   (SEEDS: N or FIRST-LAST)\n",
                argv[0], argv[0]);
        return 2;
    }
    xml = read_text(argv[3]);
    if (!xml) {
        fprintf(stderr, "cannot read %s\n", argv[3]);
        return 2;
    }
    read_guid();
    if (load(argv[2]) != 0) return 1;
    if (fuzz) {
        int rc = fuzz_main(argv[4], argv[5]);
        free(xml);
        return rc;
    }
    if (strcmp(argv[1], "bench") == 0) {
        bench();
        free(xml);
        return 0;
    }
    hcheck(strcmp(F.fmi2GetVersion(), "2.0") == 0, "fmi2GetVersion is 2.0");
    hcheck(strcmp(F.fmi2GetTypesPlatform(), "default") == 0, "types platform is default");
    step_size_independence();
    fmu_state_across_instances();
    external_inputs();
    logging_of_events();
    illegal_calls();
    me_tests();
    printf("%d passed, %d failed\n", passed, failed);
    free(xml);
    return failed ? 1 : 0;
}

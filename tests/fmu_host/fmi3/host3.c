/* A small FMI 3.0 host for the bistable_impact FMU, compiled against the official FMI 3.0 headers
 * (fmi3Functions.h, fmi3FunctionTypes.h, fmi3PlatformTypes.h, shipped with fmpy) and loading the
 * binary with dlopen/dlsym, beside the FMI 2.0 host (tests/fmu_host/host.c).
 *
 *   host3 test LIB.so MD.xml              scenarios + scripted illegal calls; prints
 *                                         "N passed, M failed" and exits 1 on any failure
 *   host3 fuzz LIB.so MD.xml SEEDS NCALLS random FMI 3.0 call sequences with invariants (fuzz3.c)
 *
 * MD.xml is the FMI 3.0 modelDescription.xml (target/fmu/stage3/modelDescription.xml, printed by
 * target/release/fmi3-model-description); value references are looked up by name in it.
 *
 * Scenarios of `test`:
 *   (a) co-simulation with earlyReturnAllowed + eventModeUsed over the baseline (t <= 200,
 *       communication step 1): every early return at an impact is at last_impact_time, impacts
 *       come one per early return, the final count and the values at the communication points
 *       agree with a run without early return;
 *   (a') early return where the plate is rebuilt at the events (external shaker mode with the
 *       inputs sampled at every communication point; internal mode with Omega changed in event
 *       mode): every step fmi3OK, every FMU state accepted back by its instance, no two
 *       snap-throughs at one instant;
 *   (b) without early return, the outputs at every communication point equal those of the FMI 2.0
 *       functions of the same binary bit for bit; instances of one API are refused by the other;
 *   (c) Model Exchange (fixed-step RK4, indicator sign changes bisected to 1e-12 s) reaches the
 *       co-simulation impact count over t <= 50;
 *   (d) FMU state get/set/serialize/deserialize in the middle of an early-return run reproduces
 *       the following steps bit for bit; states of other interfaces or options are refused;
 *   (e) scripted illegal calls: fmi3Error (or NULL) with a logged message, never a crash.
 */
#include "host3.h"

struct fmi3_table F3;

int load3(const char *path) {
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        return -1;
    }
    int missing = 0, count = 0;
#define LOAD3(f)                                                     \
    *(void **)(&F3.f) = dlsym(lib, #f);                              \
    if (!F3.f) {                                                     \
        fprintf(stderr, "missing export %s\n", #f);                  \
        missing++;                                                   \
    }                                                                \
    count++;
    FMI3_FUNCTIONS(LOAD3)
    FMI2_FUNCTIONS(LOAD3)
#undef LOAD3
    if (!getenv("FUZZ_QUIET")) printf("loaded %d of %d fmi3 (+ fmi2) functions\n", count - missing, count);
    return missing ? -1 : 0;
}

double now3(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- model description ---- */
char *xml3;
char token[64];
Var3 vars3[MAXV3];
int nv3;

static void parse_md(void) {
    const char *p = strstr(xml3, "instantiationToken=\"");
    if (p) sscanf(p + strlen("instantiationToken=\""), "%63[^\"]", token);
    const char *mv = strstr(xml3, "<ModelVariables>");
    const char *mv_end = mv ? strstr(mv, "</ModelVariables>") : NULL;
    if (!mv || !mv_end) {
        fprintf(stderr, "no ModelVariables in the model description\n");
        exit(2);
    }
    double emin = INFINITY, emax = -INFINITY;
    for (const char *q = strstr(xml3, "<Item "); q && q < mv; q = strstr(q + 1, "<Item ")) {
        char b[64];
        if (attr(q, strchr(q, '>'), "value", b, sizeof b)) {
            emin = fmin(emin, atof(b));
            emax = fmax(emax, atof(b));
        }
    }
    static const struct {
        const char *tag;
        int type;
    } tags[] = {{"<Float64 ", T_F64}, {"<Int32 ", T_I32}, {"<Enumeration ", T_I64}, {"<Boolean ", T_BOOL}};
    for (const char *q = strchr(mv + 1, '<'); q && q < mv_end && nv3 < MAXV3; q = strchr(q + 1, '<')) {
        int type = -1;
        for (size_t k = 0; k < sizeof tags / sizeof tags[0]; k++)
            if (strncmp(q, tags[k].tag, strlen(tags[k].tag)) == 0) type = tags[k].type;
        if (type < 0) continue;
        const char *end = strchr(q, '>');
        Var3 *v = &vars3[nv3++];
        char b[64] = "";
        v->type = type;
        attr(q, end, "name", v->name, sizeof v->name);
        attr(q, end, "valueReference", b, sizeof b);
        v->vr = (fmi3ValueReference)strtoul(b, NULL, 10);
        b[0] = 0;
        attr(q, end, "causality", b, sizeof b);
        v->caus = strcmp(b, "parameter") == 0 ? C_PARAM
                  : strcmp(b, "input") == 0   ? C_INPUT
                  : strcmp(b, "output") == 0  ? C_OUTPUT
                  : strcmp(b, "independent") == 0 ? C_INDEPENDENT
                                                  : C_LOCAL;
        v->tunable = attr(q, end, "variability", b, sizeof b) && strcmp(b, "tunable") == 0;
        v->min = type == T_I64 ? emin : type == T_BOOL ? 0 : type == T_I32 ? INT32_MIN : -INFINITY;
        v->max = type == T_I64 ? emax : type == T_BOOL ? 1 : type == T_I32 ? INT32_MAX : INFINITY;
        if (attr(q, end, "min", b, sizeof b)) v->min = atof(b);
        if (attr(q, end, "max", b, sizeof b)) v->max = atof(b);
        v->start = attr(q, end, "start", b, sizeof b) ? (strcmp(b, "true") == 0 ? 1 : atof(b)) : 0;
    }
}

int var3_index(const char *name) {
    for (int i = 0; i < nv3; i++)
        if (strcmp(vars3[i].name, name) == 0) return i;
    fprintf(stderr, "variable %s not in the model description\n", name);
    exit(2);
}

int var3_of(fmi3ValueReference r) {
    for (int i = 0; i < nv3; i++)
        if (vars3[i].vr == r) return i;
    return -1;
}

fmi3ValueReference vr3(const char *name) { return vars3[var3_index(name)].vr; }

fmi3Status read_outputs3(fmi3Instance c, Outputs *o) {
    fmi3ValueReference fv[MAXOUT], iv[MAXOUT], bv[MAXOUT];
    o->nf = o->ni = o->nb = 0;
    for (int k = 0; k < nv3; k++) {
        if (vars3[k].caus != C_OUTPUT) continue;
        if (vars3[k].type == T_F64 && o->nf < MAXOUT) fv[o->nf++] = vars3[k].vr;
        if (vars3[k].type == T_I32 && o->ni < MAXOUT) iv[o->ni++] = vars3[k].vr;
        if (vars3[k].type == T_BOOL && o->nb < MAXOUT) bv[o->nb++] = vars3[k].vr;
    }
    fmi3Status s = F3.fmi3GetFloat64(c, fv, (size_t)o->nf, o->f, (size_t)o->nf);
    if (s != fmi3OK) return s;
    s = F3.fmi3GetInt32(c, iv, (size_t)o->ni, o->i, (size_t)o->ni);
    if (s != fmi3OK) return s;
    return F3.fmi3GetBoolean(c, bv, (size_t)o->nb, o->b, (size_t)o->nb);
}

/* The same outputs through the fmi2 functions (fmi2 instance). */
static fmi2Status read_outputs2(fmi2Component c, Outputs *o) {
    fmi2ValueReference fv[MAXOUT], iv[MAXOUT], bv[MAXOUT];
    fmi2Integer ii[MAXOUT];
    fmi2Boolean bb[MAXOUT];
    o->nf = o->ni = o->nb = 0;
    for (int k = 0; k < nv3; k++) {
        if (vars3[k].caus != C_OUTPUT) continue;
        if (vars3[k].type == T_F64 && o->nf < MAXOUT) fv[o->nf++] = vars3[k].vr;
        if (vars3[k].type == T_I32 && o->ni < MAXOUT) iv[o->ni++] = vars3[k].vr;
        if (vars3[k].type == T_BOOL && o->nb < MAXOUT) bv[o->nb++] = vars3[k].vr;
    }
    fmi2Status s = F3.fmi2GetReal(c, fv, (size_t)o->nf, o->f);
    if (s != fmi2OK) return s;
    s = F3.fmi2GetInteger(c, iv, (size_t)o->ni, ii);
    if (s != fmi2OK) return s;
    s = F3.fmi2GetBoolean(c, bv, (size_t)o->nb, bb);
    for (int k = 0; k < o->ni; k++) o->i[k] = ii[k];
    for (int k = 0; k < o->nb; k++) o->b[k] = bb[k] != 0;
    return s;
}

static int outputs_equal(const Outputs *a, const Outputs *b) {
    if (a->nf != b->nf || a->ni != b->ni || a->nb != b->nb) return 0;
    return memcmp(a->f, b->f, sizeof(double) * (size_t)a->nf) == 0 &&
           memcmp(a->i, b->i, sizeof(int32_t) * (size_t)a->ni) == 0 &&
           memcmp(a->b, b->b, sizeof(bool) * (size_t)a->nb) == 0;
}

/* ---- logger ---- */
char last_msg3[2048];
int last_status3 = -1;
long n_msgs3;

void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    snprintf(last_msg3, sizeof last_msg3, "%s", message ? message : "(NULL message)");
    last_status3 = (int)status;
    n_msgs3++;
    if (getenv("HOST_VERBOSE")) printf("  [%d %s] %s\n", (int)status, category ? category : "(NULL)", last_msg3);
}

/* fmi2 logger for the fmi2 instances of scenario (b). */
static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                    fmi2String format, ...) {
    (void)env;
    (void)name;
    (void)category;
    va_list ap;
    va_start(ap, format);
    vsnprintf(last_msg3, sizeof last_msg3, format, ap);
    va_end(ap);
    last_status3 = (int)status;
}
static fmi2CallbackFunctions callbacks2 = {logger2, NULL, NULL, NULL, NULL};

/* ---- checks ---- */
static int passed, failed;

static void check(int ok, const char *what) {
    if (ok) {
        passed++;
    } else {
        failed++;
        printf("FAIL: %s (last log: %s)\n", what, last_msg3);
    }
}

static void clear_log(void) {
    last_msg3[0] = 0;
    last_status3 = -1;
}

/* An expected refusal: fmi3Error and a logged fmi3Error message starting with `func` (when not
 * NULL) and containing `needle` (when not NULL). */
static void refused(fmi3Status s, const char *func, const char *needle, const char *what) {
    char buf[512];
    snprintf(buf, sizeof buf, "%s: refused (status %d) with a logged message \"%s...%s\"", what, (int)s,
             func ? func : "", needle ? needle : "");
    check(s == fmi3Error && last_status3 == fmi3Error && last_msg3[0] &&
              (!func || strncmp(last_msg3, func, strlen(func)) == 0) &&
              (!needle || strstr(last_msg3, needle) != NULL),
          buf);
    clear_log();
}

/* An expected NULL instance with a logged message containing `needle`. */
static void refused_null(fmi3Instance c, const char *needle, const char *what) {
    char buf[512];
    snprintf(buf, sizeof buf, "%s: NULL instance with a logged message about \"%s\"", what, needle);
    check(c == NULL && last_status3 == fmi3Error && strstr(last_msg3, needle) != NULL, buf);
    clear_log();
}

/* ---- instances ---- */
static fmi3Instance cs_new(int event_mode, int early, int logging) {
    return F3.fmi3InstantiateCoSimulation("host3", token, NULL, false, logging, event_mode, early, NULL, 0,
                                          NULL, logger3, NULL);
}

/* Leaves the event mode of an event-mode co-simulation instance: fmi3UpdateDiscreteStates until
 * no update is needed, then fmi3EnterStepMode; 0 on success. */
static int settle_cs(fmi3Instance c) {
    bool need = true, term, nom, val, def;
    double next;
    for (int k = 0; need && k < 100; k++)
        if (F3.fmi3UpdateDiscreteStates(c, &need, &term, &nom, &val, &def, &next) != fmi3OK) return -1;
    return need || F3.fmi3EnterStepMode(c) != fmi3OK ? -1 : 0;
}

/* A co-simulation instance with Omega, V set, initialized at t = 0 (stop time `stop` if > 0),
 * in step mode. */
static fmi3Instance cs_started(int event_mode, int early, double omega, double v, double stop) {
    fmi3Instance c = cs_new(event_mode, early, false);
    if (!c) return NULL;
    fmi3ValueReference vrs[2] = {vr3("Omega"), vr3("V")};
    double vals[2] = {omega, v};
    int ok = F3.fmi3SetFloat64(c, vrs, 2, vals, 2) == fmi3OK &&
             F3.fmi3EnterInitializationMode(c, false, 0, 0.0, stop > 0, stop) == fmi3OK &&
             F3.fmi3ExitInitializationMode(c) == fmi3OK && (!event_mode || settle_cs(c) == 0);
    if (!ok) {
        F3.fmi3FreeInstance(c);
        return NULL;
    }
    return c;
}

static double f64(fmi3Instance c, const char *name) {
    fmi3ValueReference r = vr3(name);
    double x = NAN;
    F3.fmi3GetFloat64(c, &r, 1, &x, 1);
    return x;
}

static int i32(fmi3Instance c, const char *name) {
    fmi3ValueReference r = vr3(name);
    int32_t x = -1;
    F3.fmi3GetInt32(c, &r, 1, &x, 1);
    return x;
}

/* One step record of an early-return run. */
typedef struct {
    fmi3Status status;
    bool handling, terminate, early;
    double last;
    Outputs out;
} StepRec;

/* One fmi3DoStep from t to t_end with the event mode handled when asked; fills `r`. */
static int step_rec(fmi3Instance c, double t, double t_end, StepRec *r) {
    memset(r, 0, sizeof *r);
    r->status = F3.fmi3DoStep(c, t, t_end - t, false, &r->handling, &r->terminate, &r->early, &r->last);
    if (r->status != fmi3OK) return -1;
    if (r->handling && (F3.fmi3EnterEventMode(c) != fmi3OK || settle_cs(c) != 0)) return -1;
    return read_outputs3(c, &r->out) == fmi3OK ? 0 : -1;
}

/* ---- (a) early return over the baseline ---- */
static void early_return_baseline(void) {
    const double t_end = 200, h = 1.0;
    fmi3Instance a = cs_started(true, true, 1.75, 0.07, t_end), b = cs_started(false, false, 1.75, 0.07, t_end);
    check(a && b, "(a) instances with and without early return");
    if (!a || !b) return;
    fmi3ValueReference xv[4] = {vr3("x"), vr3("v"), vr3("z"), vr3("zdot")};
    long early_returns = 0, at_impacts = 0, bad_time = 0, multi = 0, bad_last = 0, bad_flags = 0;
    double max_diff = 0;
    int prev = i32(a, "impact_count"), ok = 1;
    double t = 0;
    for (long k = 1; k <= (long)(t_end / h + 0.5) && ok; k++) {
        double next = (double)k * h;
        for (int guard = 0; t < next && ok; guard++) {
            if (guard > 100000) {
                ok = 0;
                break;
            }
            bool handling = false, term = false, early = false;
            double last = NAN;
            if (F3.fmi3DoStep(a, t, next - t, false, &handling, &term, &early, &last) != fmi3OK) {
                ok = 0;
                break;
            }
            if (!(last >= t && last <= next)) bad_last++;
            if (early) {
                early_returns++;
                if (!handling || !(last < next)) bad_flags++;
                int n = i32(a, "impact_count");
                if (n > prev) {
                    at_impacts++;
                    if (n != prev + 1) multi++;
                    if (f64(a, "last_impact_time") != last) {
                        if (bad_time < 3)
                            printf("(a) early return at %.17g, last_impact_time %.17g\n", last,
                                   f64(a, "last_impact_time"));
                        bad_time++;
                    }
                } else if (n < prev) {
                    multi++;
                }
                prev = n;
                t = last;
            } else {
                if (handling || last != next) bad_flags++;
                prev = i32(a, "impact_count");
                t = next;
            }
            if (handling && (F3.fmi3EnterEventMode(a) != fmi3OK || settle_cs(a) != 0)) ok = 0;
        }
        bool hb, tb, eb;
        double lb;
        if (F3.fmi3DoStep(b, next - h, h, false, &hb, &tb, &eb, &lb) != fmi3OK || eb || lb != next) ok = 0;
        double va[4], vb[4];
        F3.fmi3GetFloat64(a, xv, 4, va, 4);
        F3.fmi3GetFloat64(b, xv, 4, vb, 4);
        for (int j = 0; j < 4; j++) max_diff = fmax(max_diff, fabs(va[j] - vb[j]));
        if (!(max_diff <= 1e-9)) {
            static int shown;
            if (shown++ < 3) printf("(a) t = %g: x %.17g vs %.17g\n", next, va[0], vb[0]);
        }
    }
    int na = i32(a, "impact_count"), nb = i32(b, "impact_count");
    printf("(a) baseline t<=200 h=1: %ld early returns, %ld at impacts, impact count %d (without early "
           "return %d), max |difference| at the communication points %.2e\n",
           early_returns, at_impacts, na, nb, max_diff);
    check(ok, "(a) every fmi3DoStep / event mode call of the early-return run is fmi3OK");
    check(early_returns > 50 && at_impacts > 50, "(a) early returns happen at the impacts");
    check(bad_last == 0, "(a) lastSuccessfulTime within [currentCommunicationPoint, end of step]");
    check(bad_flags == 0, "(a) earlyReturn implies eventHandlingNeeded (eventModeUsed) and a time before the "
                          "step's end; no early return reaches the step's end");
    check(bad_time == 0, "(a) each early return at an impact is at last_impact_time exactly");
    check(multi == 0, "(a) impact_count increases by at most 1 per early return");
    check(na == nb, "(a) the final impact count equals the one without early return");
    check(max_diff <= 1e-9, "(a) x, v, z, zdot at the communication points agree with the run without early "
                            "return within 1e-9");
    F3.fmi3FreeInstance(a);
    F3.fmi3FreeInstance(b);
}

/* ---- (a') early return when the plate is rebuilt at an event ---- */
/* Runs with early return + event mode in which the FMU rebuilds the plate motion at the events:
 *   external (recon 1 or 2): the baseline sinusoid fed through z_in, zdot_in, sampled at every
 *     communication point (after an early return: lastSuccessfulTime);
 *   internal (recon 0): Omega = 1, V = 0.3 (frequent snap-throughs), and at every early return
 *     with a snap-through Omega changed in event mode by a factor 1 +- 1e-6 (a tunable change
 *     keeps the plate continuous).
 * Checks: every step fmi3OK; the FMU state taken after every step is accepted back by its
 * instance; the mass never snaps through twice at one instant (no two snap-throughs at the same
 * time). Early returns without progress (lastSuccessfulTime = currentCommunicationPoint) are
 * counted. */
static void early_return_rebuilt(int recon) {
    const int external = recon > 0;
    const double omega = external ? 1.75 : 1.0, v = external ? 0.07 : 0.3, t_end = 60, h = 1.0;
    char name[96], what[320];
    if (external) snprintf(name, sizeof name, "external mode, plate_reconstruction %d", recon);
    else snprintf(name, sizeof name, "internal mode Omega=1 V=0.3, Omega changed in event mode at snap-throughs");
    fmi3Instance c = cs_new(true, true, false);
    snprintf(what, sizeof what, "(a') %s: instance", name);
    check(c != NULL, what);
    if (!c) return;
    fmi3ValueReference mode = vr3("shaker_mode"), rec = vr3("plate_reconstruction"), om = vr3("Omega");
    fmi3ValueReference pv[2] = {om, vr3("V")}, in[2] = {vr3("z_in"), vr3("zdot_in")};
    int64_t ext = 2, r = recon;
    double p[2] = {omega, v}, z0[2] = {0, v};
    int ok = (!external || (F3.fmi3SetInt64(c, &mode, 1, &ext, 1) == fmi3OK &&
                            F3.fmi3SetInt64(c, &rec, 1, &r, 1) == fmi3OK &&
                            F3.fmi3SetFloat64(c, in, 2, z0, 2) == fmi3OK)) &&
             F3.fmi3SetFloat64(c, pv, 2, p, 2) == fmi3OK &&
             F3.fmi3EnterInitializationMode(c, false, 0, 0, false, 0) == fmi3OK &&
             F3.fmi3ExitInitializationMode(c) == fmi3OK && settle_cs(c) == 0;
    long steps = 0, early = 0, stuck = 0, state_refused = 0, double_snaps = 0, snaps = 0;
    double t = 0, fail_t = NAN, state_t = NAN, snap_t = NAN, double_t = NAN, w = omega;
    int n_snap = i32(c, "snap_through_count");
    while (ok && t < t_end && steps < 100000) {
        double next = (floor(t / h + 1e-9) + 1) * h;
        double z[2] = {v / omega * sin(omega * t), v * cos(omega * t)};
        bool hd, term, er;
        double last;
        if ((external && F3.fmi3SetFloat64(c, in, 2, z, 2) != fmi3OK) ||
            F3.fmi3DoStep(c, t, next - t, false, &hd, &term, &er, &last) != fmi3OK) {
            ok = 0, fail_t = t;
            break;
        }
        steps++;
        early += er;
        stuck += er && last == t;
        int n = i32(c, "snap_through_count");
        if (n > n_snap) {
            snaps += n - n_snap;
            if (n - n_snap > 1 || last == snap_t) {
                if (!double_snaps++) double_t = last;
            }
            snap_t = last;
        }
        if (hd) {
            ok = F3.fmi3EnterEventMode(c) == fmi3OK;
            if (ok && !external && n > n_snap) {
                w *= snaps % 2 ? 1 + 1e-6 : 1 - 1e-6;
                ok = F3.fmi3SetFloat64(c, &om, 1, &w, 1) == fmi3OK;
            }
            ok = ok && settle_cs(c) == 0;
        }
        n_snap = n;
        fmi3FMUState s = NULL;
        if (F3.fmi3GetFMUState(c, &s) != fmi3OK || F3.fmi3SetFMUState(c, s) != fmi3OK) {
            if (!state_refused++) state_t = last;
        }
        F3.fmi3FreeFMUState(c, &s);
        t = last;
    }
    printf("(a') %s, t<=%g h=%g: %ld steps, %ld early returns (%ld without progress), %ld snap-throughs, impact "
           "count %d%s\n",
           name, t_end, h, steps, early, stuck, snaps, i32(c, "impact_count"), ok ? "" : ", stopped by a refused step");
    snprintf(what, sizeof what, "(a') %s: every step fmi3OK (first refusal at t = %.17g)", name, fail_t);
    check(ok && t >= t_end, what);
    snprintf(what, sizeof what, "(a') %s: the FMU state of every step is accepted by its instance (%ld refused, first "
             "at t = %.17g)", name, state_refused, state_t);
    check(state_refused == 0, what);
    snprintf(what, sizeof what, "(a') %s: no two snap-throughs at one instant (%ld, first at t = %.17g)", name,
             double_snaps, double_t);
    check(double_snaps == 0, what);
    F3.fmi3FreeInstance(c);
}

/* ---- (b) without early return: bit for bit equal to the FMI 2.0 functions ---- */
static void fmi2_vs_fmi3(const char *name, double omega, double v, double t_end, double h) {
    fmi3Instance c3 = cs_started(false, false, omega, v, t_end);
    fmi2Component c2 = F3.fmi2Instantiate("host2", fmi2CoSimulation, token, NULL, &callbacks2, fmi2False, fmi2False);
    char what[256];
    snprintf(what, sizeof what, "(b) %s: an fmi3 and an fmi2 instance", name);
    check(c3 && c2, what);
    if (!c3 || !c2) return;
    fmi2ValueReference vrs[2] = {vr3("Omega"), vr3("V")};
    fmi2Real vals[2] = {omega, v};
    int ok = F3.fmi2SetupExperiment(c2, fmi2False, 0, 0.0, fmi2True, t_end) == fmi2OK &&
             F3.fmi2SetReal(c2, vrs, 2, vals) == fmi2OK && F3.fmi2EnterInitializationMode(c2) == fmi2OK &&
             F3.fmi2ExitInitializationMode(c2) == fmi2OK;
    long n = (long)ceil(t_end / h - 1e-9), same = 0, points = 0;
    double t = 0;
    Outputs o3, o2;
    ok = ok && read_outputs3(c3, &o3) == fmi3OK && read_outputs2(c2, &o2) == fmi2OK;
    same += ok && outputs_equal(&o3, &o2);
    points++;
    for (long k = 1; k <= n && ok; k++) {
        double next = k == n ? t_end : (double)k * h;
        bool hd, term, early;
        double last;
        ok = F3.fmi3DoStep(c3, t, next - t, false, &hd, &term, &early, &last) == fmi3OK && !early && !hd &&
             F3.fmi2DoStep(c2, t, next - t, fmi2True) == fmi2OK && read_outputs3(c3, &o3) == fmi3OK &&
             read_outputs2(c2, &o2) == fmi2OK;
        int eq = ok && outputs_equal(&o3, &o2);
        if (ok && !eq && points - same < 3)
            printf("(b) %s: t = %g: x %.17g (fmi3) vs %.17g (fmi2)\n", name, next, o3.f[0], o2.f[0]);
        same += eq;
        points++;
        t = next;
    }
    snprintf(what, sizeof what, "(b) %s: all steps fmi3OK / fmi2OK without early return", name);
    check(ok, what);
    snprintf(what, sizeof what, "(b) %s: all outputs equal bit for bit at %ld of %ld communication points", name,
             same, points);
    check(ok && same == points, what);
    printf("(b) %s: %ld communication points, %ld bit-for-bit equal (%d Float64, %d Int32, %d Boolean outputs), "
           "impact count %d\n",
           name, points, same, o3.nf, o3.ni, o3.nb, i32(c3, "impact_count"));

    /* Each API refuses the other's instances. */
    clear_log();
    check(F3.fmi2DoStep((fmi2Component)c3, t_end, 1, fmi2True) == fmi2Error && strstr(last_msg3, "fmi3"),
          "(b) fmi2DoStep on an fmi3 instance: fmi2Error, logged");
    clear_log();
    fmi2FMUstate s2 = NULL;
    check(F3.fmi2GetFMUstate((fmi2Component)c3, &s2) == fmi2Error && s2 == NULL,
          "(b) fmi2GetFMUstate on an fmi3 instance: fmi2Error");
    clear_log();
    bool hd, term, early;
    double last;
    refused(F3.fmi3DoStep((fmi3Instance)c2, t_end, 1, false, &hd, &term, &early, &last), "fmi3DoStep", "fmi2",
            "(b) fmi3DoStep on an fmi2 instance");
    double x = 0;
    fmi3ValueReference xr = vr3("x");
    refused(F3.fmi3GetFloat64((fmi3Instance)c2, &xr, 1, &x, 1), "fmi3GetFloat64", NULL,
            "(b) fmi3GetFloat64 on an fmi2 instance");
    F3.fmi3FreeInstance(c3);
    F3.fmi2FreeInstance(c2);
}

/* ---- (c) Model Exchange ---- */
static int me_settle(fmi3Instance c, double *next) {
    bool need = true, term, nom, val, def = false;
    double t_next = 0;
    for (int k = 0; need; k++) {
        if (k > 100 || F3.fmi3UpdateDiscreteStates(c, &need, &term, &nom, &val, &def, &t_next) != fmi3OK) return -1;
    }
    *next = def ? t_next : INFINITY;
    return F3.fmi3EnterContinuousTimeMode(c) == fmi3OK ? 0 : -1;
}

static int me_put(fmi3Instance c, double t, const double x[2]) {
    return F3.fmi3SetTime(c, t) == fmi3OK && F3.fmi3SetContinuousStates(c, x, 2) == fmi3OK ? 0 : -1;
}

static int me_deriv(fmi3Instance c, double t, const double x[2], double d[2]) {
    return me_put(c, t, x) || F3.fmi3GetContinuousStateDerivatives(c, d, 2) != fmi3OK ? -1 : 0;
}

static int me_rk4(fmi3Instance c, double t, const double x[2], double h, double y[2]) {
    double k1[2], k2[2], k3[2], k4[2], a[2];
    /* Stops at the first failing call (its outputs are not set). */
    if (me_deriv(c, t, x, k1)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k1[i];
    if (me_deriv(c, t + h / 2, a, k2)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k2[i];
    if (me_deriv(c, t + h / 2, a, k3)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h * k3[i];
    if (me_deriv(c, t + h, a, k4)) return -1;
    for (int i = 0; i < 2; i++) y[i] = x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    return 0;
}

static int me_ind(fmi3Instance c, double t, const double x[2], double z[2]) {
    return me_put(c, t, x) || F3.fmi3GetEventIndicators(c, z, 2) != fmi3OK ? -1 : 0;
}

static int crossed(const double a[2], const double b[2]) {
    return (a[0] > 0) != (b[0] > 0) || (a[1] > 0) != (b[1] > 0);
}

/* The ME driver of me.c with the fmi3 functions: RK4 steps h from t0 to t_end, indicator sign
 * changes bisected to 1e-12 s, time events honoured; 0 on success. */
static int me_run(fmi3Instance c, double t0, double t_end, double h, double next, long *events) {
    double t = t0, x[2], x1[2], z0[2], z1[2];
    while (t < t_end) {
        if (F3.fmi3GetContinuousStates(c, x, 2) != fmi3OK || me_ind(c, t, x, z0)) return -1;
        double step = fmin(h, fmin(t_end, next) - t);
        if (me_rk4(c, t, x, step, x1) || me_ind(c, t + step, x1, z1)) return -1;
        int event = crossed(z0, z1);
        if (event) {
            double lo = 0, hi = step;
            while (hi - lo > 1e-12) {
                double mid = 0.5 * (lo + hi);
                if (me_rk4(c, t, x, mid, x1) || me_ind(c, t + mid, x1, z1)) return -1;
                if (crossed(z0, z1)) hi = mid;
                else lo = mid;
            }
            step = hi;
            if (me_rk4(c, t, x, step, x1)) return -1;
        }
        t += step;
        bool enter = false, terminate = false;
        if (me_put(c, t, x1) || F3.fmi3CompletedIntegratorStep(c, true, &enter, &terminate) != fmi3OK) return -1;
        if (event || enter || t >= next) {
            if (F3.fmi3EnterEventMode(c) != fmi3OK || me_settle(c, &next)) return -1;
            (*events)++;
        }
    }
    return 0;
}

static void model_exchange(double omega, double v, double t_end, double h) {
    fmi3Instance cs = cs_started(false, false, omega, v, t_end);
    fmi3Instance me = F3.fmi3InstantiateModelExchange("me3", token, NULL, false, false, NULL, logger3);
    check(cs && me, "(c) co-simulation and Model Exchange instances");
    if (!cs || !me) return;
    size_t nx = 0, nz = 0;
    check(F3.fmi3GetNumberOfContinuousStates(me, &nx) == fmi3OK && nx == 2 &&
              F3.fmi3GetNumberOfEventIndicators(me, &nz) == fmi3OK && nz == 2,
          "(c) 2 continuous states, 2 event indicators");
    fmi3ValueReference vrs[2] = {vr3("Omega"), vr3("V")};
    double vals[2] = {omega, v}, next = INFINITY;
    long events = 0;
    int ok = F3.fmi3SetFloat64(me, vrs, 2, vals, 2) == fmi3OK &&
             F3.fmi3EnterInitializationMode(me, false, 0, 0, true, t_end) == fmi3OK &&
             F3.fmi3ExitInitializationMode(me) == fmi3OK && me_settle(me, &next) == 0 &&
             me_run(me, 0, t_end, h, next, &events) == 0;
    check(ok, "(c) the ME driver runs (every call fmi3OK)");
    bool hd, term, early;
    double last;
    check(F3.fmi3DoStep(cs, 0, t_end, false, &hd, &term, &early, &last) == fmi3OK, "(c) co-simulation in one step");
    int n_me = i32(me, "impact_count"), n_cs = i32(cs, "impact_count");
    char what[256];
    snprintf(what, sizeof what, "(c) Omega=%g V=%g t<=%g: ME (RK4 h=%g, %ld event modes) impact count %d = "
             "co-simulation's %d", omega, v, t_end, h, events, n_me, n_cs);
    printf("%s\n", what);
    check(ok && n_cs > 10 && n_me == n_cs, what);
    check(fabs(f64(me, "last_impact_time") - f64(cs, "last_impact_time")) < 1e-6,
          "(c) last impact time agrees within 1e-6 s");
    F3.fmi3FreeInstance(cs);
    F3.fmi3FreeInstance(me);
}

/* ---- (d) FMU state round trip in the middle of an early-return run ---- */
#define NREC 40
static int replay(fmi3Instance c, double t, StepRec *rec) {
    for (int k = 0; k < NREC; k++) {
        if (step_rec(c, t, t + 1.0, &rec[k])) return -1;
        t = rec[k].last;
    }
    return 0;
}

static int same_recs(const StepRec *a, const StepRec *b) {
    for (int k = 0; k < NREC; k++)
        if (a[k].status != b[k].status || a[k].early != b[k].early || a[k].handling != b[k].handling ||
            memcmp(&a[k].last, &b[k].last, sizeof(double)) != 0 || !outputs_equal(&a[k].out, &b[k].out))
            return 0;
    return 1;
}

static void fmu_state_round_trip(void) {
    static StepRec r0[NREC], r1[NREC], r2[NREC];
    fmi3Instance a = cs_started(true, true, 1.75, 0.07, 0), b = cs_started(true, true, 1.0, 0.01, 0);
    check(a && b, "(d) two early-return instances");
    if (!a || !b) return;
    /* Into the middle of the run: early returns up to t >= 37. */
    double t = 0;
    StepRec r;
    for (int k = 0; t < 37 && k < 10000; k++) {
        if (step_rec(a, t, t + 1.0, &r)) break;
        t = r.last;
    }
    check(t >= 37, "(d) early-return run to t >= 37");
    fmi3FMUState s = NULL, s2 = NULL, s3 = NULL;
    check(F3.fmi3GetFMUState(a, &s) == fmi3OK && s, "(d) fmi3GetFMUState");
    size_t size = 0;
    check(F3.fmi3SerializedFMUStateSize(a, s, &size) == fmi3OK && size > 100, "(d) serialized size");
    fmi3Byte *bytes = malloc(size);
    check(F3.fmi3SerializeFMUState(a, s, bytes, size) == fmi3OK, "(d) fmi3SerializeFMUState");
    check(replay(a, t, r0) == 0, "(d) 40 steps after the state");
    int n_early = 0;
    for (int k = 0; k < NREC; k++) n_early += r0[k].early;
    check(n_early > 5, "(d) the following steps return early");
    check(F3.fmi3SetFMUState(a, s) == fmi3OK && replay(a, t, r1) == 0 && same_recs(r0, r1),
          "(d) fmi3SetFMUState: the following steps repeat bit for bit (times, flags, all outputs)");
    check(F3.fmi3DeserializeFMUState(b, bytes, size, &s2) == fmi3OK && s2 &&
              F3.fmi3SetFMUState(b, s2) == fmi3OK && replay(b, t, r2) == 0 && same_recs(r0, r2),
          "(d) deserialized into another instance: the following steps repeat bit for bit");
    /* Overwriting an existing state in place, then restoring it. */
    check(F3.fmi3GetFMUState(b, &s2) == fmi3OK && F3.fmi3SetFMUState(a, s) == fmi3OK,
          "(d) fmi3GetFMUState into an existing state");

    /* Refusals: other interface, other options. */
    fmi3Instance me = F3.fmi3InstantiateModelExchange("me3", token, NULL, false, false, NULL, logger3);
    fmi3Instance plain = cs_new(false, false, false), em_only = cs_new(true, false, false);
    check(me && plain && em_only, "(d) ME, plain and event-mode-only instances");
    if (me && plain && em_only) {
        refused(F3.fmi3DeserializeFMUState(me, bytes, size, &s3), "fmi3DeserializeFMUState", "FMU state",
                "(d) a CS state deserialized in an ME instance");
        refused(F3.fmi3DeserializeFMUState(plain, bytes, size, &s3), "fmi3DeserializeFMUState", "FMU state",
                "(d) an early-return state deserialized in an instance without early return");
        refused(F3.fmi3DeserializeFMUState(em_only, bytes, size, &s3), "fmi3DeserializeFMUState", "FMU state",
                "(d) an early-return state deserialized in an event-mode instance without early return");
        check(s3 == NULL, "(d) no state from refused bytes");
        refused(F3.fmi3SetFMUState(me, s), "fmi3SetFMUState", NULL, "(d) another instance's state handle (ME)");
        refused(F3.fmi3SetFMUState(plain, s), "fmi3SetFMUState", NULL, "(d) another instance's state handle (CS)");
        fmi3FMUState sp = NULL;
        size_t psize = 0;
        check(F3.fmi3GetFMUState(me, &sp) == fmi3OK && F3.fmi3SerializedFMUStateSize(me, sp, &psize) == fmi3OK,
              "(d) ME state");
        fmi3Byte *pb = malloc(psize);
        check(F3.fmi3SerializeFMUState(me, sp, pb, psize) == fmi3OK, "(d) ME state serialized");
        refused(F3.fmi3DeserializeFMUState(a, pb, psize, &s3), "fmi3DeserializeFMUState", "FMU state",
                "(d) an ME state deserialized in a CS instance");
        free(pb);
        F3.fmi3FreeFMUState(me, &sp);
    }
    /* Corrupt, truncated bytes. */
    bytes[size / 2] ^= 1;
    refused(F3.fmi3DeserializeFMUState(b, bytes, size, &s3), "fmi3DeserializeFMUState", NULL,
            "(d) corrupt serialized state (one bit flipped)");
    bytes[size / 2] ^= 1;
    refused(F3.fmi3DeserializeFMUState(b, bytes, size - 8, &s3), "fmi3DeserializeFMUState", NULL,
            "(d) truncated serialized state");
    refused(F3.fmi3DeserializeFMUState(b, bytes, 3, &s3), "fmi3DeserializeFMUState", NULL,
            "(d) three bytes of serialized state");
    refused(F3.fmi3SerializeFMUState(a, s, bytes, size - 1), "fmi3SerializeFMUState", "too small",
            "(d) serialize into a buffer too small");
    check(s3 == NULL, "(d) no state from bad bytes");
    check(F3.fmi3FreeFMUState(a, &s) == fmi3OK && s == NULL, "(d) fmi3FreeFMUState sets the handle to NULL");
    check(F3.fmi3FreeFMUState(b, &s2) == fmi3OK && s2 == NULL, "(d) free the deserialized state");
    free(bytes);
    F3.fmi3FreeInstance(a);
    F3.fmi3FreeInstance(b);
    F3.fmi3FreeInstance(me);
    F3.fmi3FreeInstance(plain);
    F3.fmi3FreeInstance(em_only);
}

/* ---- (e) scripted illegal calls ---- */
static void illegal_calls(void) {
    fmi3ValueReference none_vr = 0;
    clear_log();
    refused_null(F3.fmi3InstantiateCoSimulation("x", "{wrong}", NULL, false, false, true, true, NULL, 0, NULL,
                                                logger3, NULL),
                 "does not match", "wrong instantiationToken (CS)");
    refused_null(F3.fmi3InstantiateModelExchange("x", "{wrong}", NULL, false, false, NULL, logger3),
                 "does not match", "wrong instantiationToken (ME)");
    refused_null(F3.fmi3InstantiateCoSimulation("", token, NULL, false, false, false, false, NULL, 0, NULL, logger3,
                                                NULL),
                 "instanceName", "empty instance name");
    refused_null(F3.fmi3InstantiateModelExchange("  ", token, NULL, false, false, NULL, logger3), "instanceName",
                 "blank instance name (ME)");
    refused_null(F3.fmi3InstantiateCoSimulation(NULL, token, NULL, false, false, false, false, NULL, 0, NULL,
                                                logger3, NULL),
                 "instanceName", "NULL instance name");
    refused_null(F3.fmi3InstantiateCoSimulation("x", NULL, NULL, false, false, false, false, NULL, 0, NULL, logger3,
                                                NULL),
                 "instantiationToken", "NULL instantiationToken");
    refused_null(F3.fmi3InstantiateCoSimulation("x", token, NULL, false, false, false, false, &none_vr, 1, NULL,
                                                logger3, NULL),
                 "nRequiredIntermediateVariables", "required intermediate variables");
    refused_null(F3.fmi3InstantiateScheduledExecution("x", token, NULL, false, false, NULL, logger3, NULL, NULL, NULL),
                 "Scheduled", "fmi3InstantiateScheduledExecution");
    check(F3.fmi3InstantiateCoSimulation("x", "{wrong}", NULL, false, false, false, false, NULL, 0, NULL, NULL,
                                         NULL) == NULL,
          "wrong token without a logger: NULL, no crash");
    check(strcmp(F3.fmi3GetVersion(), "3.0") == 0, "fmi3GetVersion is 3.0");

    fmi3Instance c = cs_new(false, false, false);
    check(c != NULL, "(e) instantiate co-simulation without event mode");
    if (!c) return;
    fmi3ValueReference x = vr3("x"), zeta = vr3("zeta"), omega = vr3("Omega"), count = vr3("impact_count");
    fmi3ValueReference mode = vr3("shaker_mode"), contact = vr3("in_contact"), unknown = 777;
    fmi3ValueReference two_vr[2] = {vr3("Omega"), vr3("V")};
    double one = 1.0, out = 0, two[2] = {1, 2};
    int32_t iout = 0, ione = 1;
    int64_t lout = 0;
    bool bout = false, hd, term, early, b1, b2, b3, b4, b5;
    double last, next;
    float fl = 1.0f;
    int8_t i8 = 1;
    const char *str = "a";
    const fmi3Byte bin[1] = {1};
    size_t binsz = 1;
    fmi3Binary binv = bin;
    fmi3Clock clk = false;

    refused(F3.fmi3DoStep(c, 0, 0.1, false, &hd, &term, &early, &last), "fmi3DoStep", "not allowed",
            "fmi3DoStep before initialization");
    refused(F3.fmi3GetFloat64(c, &x, 1, &out, 1), "fmi3GetFloat64", "not allowed", "get before initialization");
    refused(F3.fmi3ExitInitializationMode(c), "fmi3ExitInitializationMode", "not allowed", "exit before enter");
    refused(F3.fmi3SetFloat64(c, &unknown, 1, &one, 1), "fmi3SetFloat64", "777", "set with an unknown vr");
    refused(F3.fmi3SetFloat64(c, two_vr, 2, two, 1), "fmi3SetFloat64", "nValues", "nValues != nValueReferences (set)");
    refused(F3.fmi3SetFloat64(c, NULL, 1, &one, 1), "fmi3SetFloat64", NULL, "NULL valueReferences");
    refused(F3.fmi3SetFloat64(c, &zeta, 1, NULL, 1), "fmi3SetFloat64", NULL, "NULL values");
    refused(F3.fmi3SetFloat64(c, &x, 1, &one, 1), "fmi3SetFloat64", "output", "setting an output");
    refused(F3.fmi3SetInt32(c, &count, 1, &ione, 1), "fmi3SetInt32", NULL, "setting an Int32 output");
    refused(F3.fmi3SetBoolean(c, &contact, 1, &bout, 1), "fmi3SetBoolean", NULL, "setting a Boolean output");
    refused(F3.fmi3SetInt64(c, &mode, 1, &(int64_t){3}, 1), "fmi3SetInt64", NULL, "unknown enumeration value");
    refused(F3.fmi3SetInt32(c, &zeta, 1, &ione, 1), "fmi3SetInt32", NULL, "Int32 on a Float64 variable");
    refused(F3.fmi3SetFloat64(c, &zeta, 1, &(double){NAN}, 1), "fmi3SetFloat64", NULL, "NaN parameter");
    refused(F3.fmi3SetDebugLogging(c, true, 1, (const fmi3String[]){"logNothing"}), "fmi3SetDebugLogging",
            "unknown log category", "unknown log category");
    refused(F3.fmi3SetDebugLogging(c, true, 1, NULL), "fmi3SetDebugLogging", NULL, "NULL categories");
    refused(F3.fmi3EnterInitializationMode(c, false, 0, NAN, false, 0), "fmi3EnterInitializationMode", NULL,
            "NaN start time");
    refused(F3.fmi3EnterInitializationMode(c, false, 0, 5, true, 1), "fmi3EnterInitializationMode", NULL,
            "stop time before the start time");

    /* Types the model does not have: refused for any value reference. */
    for (int k = 0; k < 3; k++) {
        fmi3ValueReference r = k == 0 ? zeta : k == 1 ? x : unknown;
        refused(F3.fmi3GetFloat32(c, &r, 1, &fl, 1), "fmi3GetFloat32", NULL, "fmi3GetFloat32");
        refused(F3.fmi3SetFloat32(c, &r, 1, &fl, 1), "fmi3SetFloat32", NULL, "fmi3SetFloat32");
        refused(F3.fmi3GetInt8(c, &r, 1, &i8, 1), "fmi3GetInt8", NULL, "fmi3GetInt8");
        refused(F3.fmi3SetInt8(c, &r, 1, &i8, 1), "fmi3SetInt8", NULL, "fmi3SetInt8");
        refused(F3.fmi3GetUInt64(c, &r, 1, &(uint64_t){0}, 1), "fmi3GetUInt64", NULL, "fmi3GetUInt64");
        refused(F3.fmi3SetUInt16(c, &r, 1, &(uint16_t){0}, 1), "fmi3SetUInt16", NULL, "fmi3SetUInt16");
        refused(F3.fmi3GetString(c, &r, 1, &str, 1), "fmi3GetString", NULL, "fmi3GetString");
        refused(F3.fmi3SetString(c, &r, 1, &str, 1), "fmi3SetString", NULL, "fmi3SetString");
        refused(F3.fmi3GetBinary(c, &r, 1, &binsz, &binv, 1), "fmi3GetBinary", NULL, "fmi3GetBinary");
        refused(F3.fmi3SetBinary(c, &r, 1, &binsz, &binv, 1), "fmi3SetBinary", NULL, "fmi3SetBinary");
        refused(F3.fmi3GetClock(c, &r, 1, &clk), "fmi3GetClock", NULL, "fmi3GetClock");
        refused(F3.fmi3SetClock(c, &r, 1, &clk), "fmi3SetClock", NULL, "fmi3SetClock");
    }
    refused(F3.fmi3GetIntervalDecimal(c, &x, 1, &out, (fmi3IntervalQualifier[]){0}), "fmi3GetIntervalDecimal",
            NULL, "fmi3GetIntervalDecimal");
    refused(F3.fmi3EnterConfigurationMode(c), "fmi3EnterConfigurationMode", NULL, "configuration mode");
    refused(F3.fmi3EvaluateDiscreteStates(c), "fmi3EvaluateDiscreteStates", NULL, "fmi3EvaluateDiscreteStates");
    refused(F3.fmi3ActivateModelPartition(c, 0, 0), "fmi3ActivateModelPartition", NULL, "model partition");
    refused(F3.fmi3GetDirectionalDerivative(c, &x, 1, &zeta, 1, &one, 1, &out, 1), "fmi3GetDirectionalDerivative",
            NULL, "directional derivative");
    refused(F3.fmi3GetAdjointDerivative(c, &x, 1, &zeta, 1, &one, 1, &out, 1), "fmi3GetAdjointDerivative", NULL,
            "adjoint derivative");

    /* ME functions on a CS instance. */
    double xs[2];
    size_t nx;
    refused(F3.fmi3EnterContinuousTimeMode(c), "fmi3EnterContinuousTimeMode", "CoSimulation",
            "fmi3EnterContinuousTimeMode on CS");
    refused(F3.fmi3SetTime(c, 0), "fmi3SetTime", "CoSimulation", "fmi3SetTime on CS");
    refused(F3.fmi3GetContinuousStates(c, xs, 2), "fmi3GetContinuousStates", "CoSimulation",
            "fmi3GetContinuousStates on CS");
    refused(F3.fmi3SetContinuousStates(c, xs, 2), "fmi3SetContinuousStates", "CoSimulation",
            "fmi3SetContinuousStates on CS");
    refused(F3.fmi3GetNumberOfContinuousStates(c, &nx), "fmi3GetNumberOfContinuousStates", "CoSimulation",
            "fmi3GetNumberOfContinuousStates on CS");
    refused(F3.fmi3CompletedIntegratorStep(c, true, &b1, &b2), "fmi3CompletedIntegratorStep", "CoSimulation",
            "fmi3CompletedIntegratorStep on CS");
    refused(F3.fmi3GetEventIndicators(c, xs, 2), "fmi3GetEventIndicators", "CoSimulation",
            "fmi3GetEventIndicators on CS");

    check(F3.fmi3EnterInitializationMode(c, false, 0, 0, true, 20) == fmi3OK, "(e) enter initialization (stop 20)");
    refused(F3.fmi3EnterInitializationMode(c, false, 0, 0, true, 20), "fmi3EnterInitializationMode", "not allowed",
            "enter initialization twice");
    check(F3.fmi3ExitInitializationMode(c) == fmi3OK, "(e) exit initialization (step mode)");
    refused(F3.fmi3SetFloat64(c, &zeta, 1, &one, 1), "fmi3SetFloat64", "fixed", "fixed parameter after initialization");
    refused(F3.fmi3GetFloat64(c, two_vr, 2, &out, 1), "fmi3GetFloat64", "nValues", "nValues != nValueReferences (get)");
    refused(F3.fmi3GetFloat64(c, &unknown, 1, &out, 1), "fmi3GetFloat64", "777", "get with an unknown vr");
    refused(F3.fmi3GetFloat64(c, &x, 1, NULL, 1), "fmi3GetFloat64", NULL, "NULL values (get)");
    refused(F3.fmi3GetInt32(c, &x, 1, &iout, 1), "fmi3GetInt32", NULL, "Int32 get of a Float64");
    refused(F3.fmi3GetInt64(c, &x, 1, &lout, 1), "fmi3GetInt64", NULL, "Int64 get of a Float64");
    refused(F3.fmi3DoStep(c, 0, 1, false, NULL, &term, &early, &last), "fmi3DoStep", NULL,
            "NULL eventHandlingNeeded");
    refused(F3.fmi3DoStep(c, 0, 1, false, &hd, NULL, &early, &last), "fmi3DoStep", NULL, "NULL terminateSimulation");
    refused(F3.fmi3DoStep(c, 0, 1, false, &hd, &term, NULL, &last), "fmi3DoStep", NULL, "NULL earlyReturn");
    refused(F3.fmi3DoStep(c, 0, 1, false, &hd, &term, &early, NULL), "fmi3DoStep", NULL, "NULL lastSuccessfulTime");
    refused(F3.fmi3DoStep(c, 0, -1, false, &hd, &term, &early, &last), "fmi3DoStep", NULL, "negative step");
    refused(F3.fmi3DoStep(c, 0, NAN, false, &hd, &term, &early, &last), "fmi3DoStep", NULL, "NaN step");
    refused(F3.fmi3DoStep(c, 0, 0, false, &hd, &term, &early, &last), "fmi3DoStep", NULL, "zero step");
    refused(F3.fmi3DoStep(c, 0, INFINITY, false, &hd, &term, &early, &last), "fmi3DoStep", NULL, "infinite step");
    refused(F3.fmi3DoStep(c, 3, 1, false, &hd, &term, &early, &last), "fmi3DoStep", "does not match",
            "currentCommunicationPoint that does not match");
    refused(F3.fmi3DoStep(c, NAN, 1, false, &hd, &term, &early, &last), "fmi3DoStep", NULL,
            "NaN currentCommunicationPoint");
    refused(F3.fmi3DoStep(c, 0, 25, false, &hd, &term, &early, &last), "fmi3DoStep", NULL, "step past the stop time");
    refused(F3.fmi3EnterEventMode(c), "fmi3EnterEventMode", "eventModeUsed", "fmi3EnterEventMode in CS without "
            "eventModeUsed");
    refused(F3.fmi3UpdateDiscreteStates(c, &b1, &b2, &b3, &b4, &b5, &next), "fmi3UpdateDiscreteStates", "not allowed",
            "fmi3UpdateDiscreteStates in step mode");
    refused(F3.fmi3EnterStepMode(c), "fmi3EnterStepMode", "not allowed", "fmi3EnterStepMode in step mode");
    refused(F3.fmi3GetFMUState(c, NULL), "fmi3GetFMUState", NULL, "NULL FMUState output");
    refused(F3.fmi3FreeFMUState(c, NULL), "fmi3FreeFMUState", NULL, "NULL FMUState slot");
    refused(F3.fmi3SerializedFMUStateSize(c, NULL, &nx), "fmi3SerializedFMUStateSize", NULL, "NULL FMUState size");
    int bogus = 42;
    refused(F3.fmi3SetFMUState(c, &bogus), "fmi3SetFMUState", NULL, "foreign FMU state pointer");
    fmi3FMUState fake = NULL;
    refused(F3.fmi3DeserializeFMUState(c, (const fmi3Byte *)"garbage!garbage!garbage!", 24, &fake),
            "fmi3DeserializeFMUState", NULL, "garbage state bytes");
    refused(F3.fmi3DeserializeFMUState(c, NULL, 24, &fake), "fmi3DeserializeFMUState", NULL, "NULL state bytes");
    check(fake == NULL, "no state from garbage");
    refused(F3.fmi3GetOutputDerivatives(c, &x, 1, &(fmi3Int32){2}, &out, 1), "fmi3GetOutputDerivatives", NULL,
            "second output derivative");
    refused(F3.fmi3GetOutputDerivatives(c, &x, 1, &(fmi3Int32){1}, &out, 2), "fmi3GetOutputDerivatives", "nValues",
            "output derivative nValues != nValueReferences");
    refused(F3.fmi3GetNumberOfVariableDependencies(c, x, &nx), "fmi3GetNumberOfVariableDependencies", NULL,
            "variable dependencies");

    /* NULL instance: refused without a crash. */
    check(F3.fmi3DoStep(NULL, 0, 1, false, &hd, &term, &early, &last) == fmi3Error &&
              F3.fmi3GetFloat64(NULL, &x, 1, &out, 1) == fmi3Error && F3.fmi3Reset(NULL) == fmi3Error &&
              F3.fmi3EnterEventMode(NULL) == fmi3Error && F3.fmi3Terminate(NULL) == fmi3Error,
          "NULL instance refused");
    F3.fmi3FreeInstance(NULL);

    /* Still intact. */
    check(F3.fmi3DoStep(c, 0, 20, false, &hd, &term, &early, &last) == fmi3OK && !early && last == 20 &&
              i32(c, "impact_count") > 2,
          "(e) still steps after the refusals");
    fmi3Int32 order = 1;
    check(F3.fmi3GetOutputDerivatives(c, &x, 1, &order, &out, 1) == fmi3OK && out == f64(c, "v"), "(e) dx/dt is v");
    check(F3.fmi3SetFloat64(c, &omega, 1, &(double){2.0}, 1) == fmi3OK, "(e) tunable parameter in step mode");
    check(F3.fmi3Terminate(c) == fmi3OK, "(e) terminate");
    refused(F3.fmi3DoStep(c, 20, 1, false, &hd, &term, &early, &last), "fmi3DoStep", "not allowed",
            "step after terminate");
    check(F3.fmi3Reset(c) == fmi3OK, "(e) reset");
    check(F3.fmi3SetFloat64(c, &zeta, 1, &one, 1) == fmi3OK, "(e) fixed parameters settable again after reset");
    F3.fmi3FreeInstance(c);

    /* Event-mode instance: state machine of event mode in co-simulation. */
    fmi3Instance e = cs_new(true, true, false);
    check(e != NULL, "(e) event-mode instance");
    if (!e) return;
    F3.fmi3EnterInitializationMode(e, false, 0, 0, false, 0);
    check(F3.fmi3ExitInitializationMode(e) == fmi3OK, "(e) exit initialization into event mode");
    refused(F3.fmi3DoStep(e, 0, 1, false, &hd, &term, &early, &last), "fmi3DoStep", "not allowed",
            "fmi3DoStep in event mode");
    refused(F3.fmi3UpdateDiscreteStates(e, NULL, &b2, &b3, &b4, &b5, &next), "fmi3UpdateDiscreteStates", NULL,
            "NULL discreteStatesNeedUpdate");
    refused(F3.fmi3UpdateDiscreteStates(e, &b1, &b2, &b3, &b4, &b5, NULL), "fmi3UpdateDiscreteStates", NULL,
            "NULL nextEventTime");
    check(F3.fmi3SetFloat64(e, &omega, 1, &(double){1.5}, 1) == fmi3OK, "(e) tunable parameter in event mode");
    refused(F3.fmi3SetFloat64(e, &zeta, 1, &one, 1), "fmi3SetFloat64", NULL, "fixed parameter in event mode");
    check(settle_cs(e) == 0, "(e) update discrete states, enter step mode");
    refused(F3.fmi3EnterStepMode(e), "fmi3EnterStepMode", "not allowed", "fmi3EnterStepMode in step mode (event mode used)");
    refused(F3.fmi3UpdateDiscreteStates(e, &b1, &b2, &b3, &b4, &b5, &next), "fmi3UpdateDiscreteStates", "not allowed",
            "fmi3UpdateDiscreteStates in step mode (event mode used)");
    check(F3.fmi3DoStep(e, 0, 10, false, &hd, &term, &early, &last) == fmi3OK && early && hd && last > 0 && last < 10,
          "(e) the first step returns early");
    refused(F3.fmi3DoStep(e, 0, 10, false, &hd, &term, &early, &last), "fmi3DoStep", NULL,
            "restart the step at the old communication point after an early return");
    F3.fmi3FreeInstance(e);

    /* ME instance: CS functions refused. */
    fmi3Instance m = F3.fmi3InstantiateModelExchange("me3", token, NULL, false, false, NULL, logger3);
    check(m != NULL, "(e) ME instance");
    if (!m) return;
    F3.fmi3EnterInitializationMode(m, false, 0, 0, false, 0);
    F3.fmi3ExitInitializationMode(m);
    refused(F3.fmi3DoStep(m, 0, 1, false, &hd, &term, &early, &last), "fmi3DoStep", "ModelExchange",
            "fmi3DoStep on ME");
    refused(F3.fmi3EnterStepMode(m), "fmi3EnterStepMode", "ModelExchange", "fmi3EnterStepMode on ME");
    refused(F3.fmi3GetOutputDerivatives(m, &x, 1, &order, &out, 1), "fmi3GetOutputDerivatives", "ModelExchange",
            "fmi3GetOutputDerivatives on ME");
    refused(F3.fmi3SetContinuousStates(m, xs, 2), "fmi3SetContinuousStates", "not allowed",
            "continuous states in event mode");
    refused(F3.fmi3GetContinuousStates(m, xs, 3), "fmi3GetContinuousStates", NULL, "three continuous states");
    refused(F3.fmi3GetEventIndicators(m, NULL, 2), "fmi3GetEventIndicators", NULL, "NULL event indicators");
    refused(F3.fmi3GetNumberOfEventIndicators(m, NULL), "fmi3GetNumberOfEventIndicators", NULL,
            "NULL nEventIndicators");
    F3.fmi3FreeInstance(m);
}

int main(int argc, char **argv) {
    int fuzz = argc == 6 && strcmp(argv[1], "fuzz") == 0;
    if (!fuzz && (argc != 4 || strcmp(argv[1], "test") != 0)) {
        fprintf(stderr,
                "usage: %s test LIB.so modelDescription.xml   (the FMI 3.0 model description)\n"
                "       %s fuzz LIB.so modelDescription.xml SEEDS NCALLS   (SEEDS: N or FIRST-LAST)\n",
                argv[0], argv[0]);
        return 2;
    }
    xml3 = read_text(argv[3]);
    if (!xml3) {
        fprintf(stderr, "cannot read %s\n", argv[3]);
        return 2;
    }
    if (!strstr(xml3, "fmiVersion=\"3.0\"")) {
        fprintf(stderr, "%s is not an FMI 3.0 model description\n", argv[3]);
        free(xml3);
        return 2;
    }
    parse_md();
    if (load3(argv[2]) != 0) {
        free(xml3);
        return 1;
    }
    if (fuzz) {
        int rc = fuzz3_main(argv[4], argv[5]);
        free(xml3);
        return rc;
    }
    early_return_baseline();
    early_return_rebuilt(1);
    early_return_rebuilt(2);
    early_return_rebuilt(0);
    fmi2_vs_fmi3("baseline Omega=1.75 V=0.07 t<=200 h=1", 1.75, 0.07, 200, 1.0);
    fmi2_vs_fmi3("chatter Omega=0.2 V=0.05 t<=60 h=0.1", 0.2, 0.05, 60, 0.1);
    model_exchange(1.75, 0.07, 50, 1e-3);
    fmu_state_round_trip();
    illegal_calls();
    printf("%d passed, %d failed\n", passed, failed);
    free(xml3);
    return failed ? 1 : 0;
}

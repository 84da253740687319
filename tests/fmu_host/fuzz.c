/* `host fuzz LIB.so modelDescription.xml SEEDS NCALLS`: random sequences of FMI calls against the
 * bistable_impact FMU, deterministic per seed, with invariants checked after every call.
 *
 * The host keeps an oracle of the FMU: its FMI 2.0 co-simulation state, the values it set, the
 * time, the stop time, the FMU states it holds and what they contain. Every call is generated with
 * valid or invalid arguments (wrong value references and types, NaN and +-inf, out of range, NULL
 * pointers wherever the FMU can check them, wrong communication points, huge and tiny steps, calls
 * in the wrong state, foreign, freed and corrupted FMU states and byte buffers) and its status is
 * compared with the oracle's expectation:
 *   - an invalid argument or a call illegal in the current state returns fmi2Error with a logged
 *     reason and leaves the instance as it was (outputs read back bit for bit unchanged);
 *   - a valid call in a valid state returns fmi2OK; inside the "sane" domain (wild(): moderate
 *     parameters, mass above the plate at the start, external inputs following a reference
 *     sinusoid) a step never fails; a run that left it (extreme but in-range values, random input
 *     derivatives, crafted FMU states) may end a step in fmi2Discard (with fmi2Terminated true and
 *     LastSuccessfulTime within the step) or have it refused with a logged reason;
 *   - after every call the outputs (when readable) are finite and physical: the mass is never below
 *     the plate by more than GAP_BOUND (relative), energies are >= 0 and agree with v, the well
 *     agrees with x, counts never decrease along a run, the last impact is not in the future;
 *   - parameters and inputs read back equal what was set; dx/dt = v and dz/dt = zdot exactly;
 *     fmi2LastSuccessfulTime equals the end of the last step;
 *   - rollback is exact: fmi2SetFMUstate gives back the outputs seen when the state was taken, bit
 *     for bit, and a step from a restored state repeats the original step bit for bit (restored
 *     through the handle, through serialize/deserialize, and in the other instance);
 *   - a truncated, extended, bit-flipped or random byte buffer is refused; a buffer with a
 *     recomputed checksum ("crafted": one field mutated) is either refused or gives a state that
 *     satisfies all of the above.
 * Every generated call is timed (the summary names the slowest, with its seed and call; the ME
 * calls, driver runs included, are in the ring of recent calls too).
 * A per-call watchdog (FUZZ_CALL_TIMEOUT seconds, default 20) reports a hang; a crash is reported
 * with the seed and the last calls. FUZZ_TRACE=1 prints every call, FUZZ_QUIET=1 only failing
 * seeds, FUZZ_SAVE_DIR=DIR writes accepted crafted buffers and, on a failure, the serialized state
 * before the last step (for regression tests). Valid steps that would take long (more than 1e4
 * shaker radians) are not generated: their cost is linear in their length, not a fault.
 */
#include "host.h"
#include "fuzzkit.h"

#include <float.h>
#include <limits.h>

/* The mass may be below the plate by at most this much, relative to max(delta_x, |x|, |z|). */
#define GAP_BOUND 1e-12

/* ---- variables from modelDescription.xml ---- */
enum { K_REAL, K_INT, K_BOOL };
enum { C_PARAM, C_INPUT, C_OUTPUT };
#define MAXV 64

typedef struct {
    char name[48];
    fmi2ValueReference vr;
    int kind, caus, tunable;
    double start, min, max;
} Var;

static Var vars[MAXV];
static int nv;
/* Indexes of the variables the oracle needs. */
static int iZeta, iE, iOmega, iV, iOmega0, iDx, iMass, iX0, iV0, iTol, iMode, iZin, iZdin;
static int iX, iVel, iZ, iZdot, iKE, iPE, iCount, iLastT, iPhase, iVb, iVa, iDk, iWell, iSnap,
    iContact;
/* Outputs by type. */
static int out_real[MAXV], n_out_real, out_int[MAXV], n_out_int, out_bool[MAXV], n_out_bool;
static fmi2ValueReference vr_out_real[MAXV], vr_out_int[MAXV], vr_out_bool[MAXV];

static int index_of(const char *name) {
    for (int i = 0; i < nv; i++)
        if (strcmp(vars[i].name, name) == 0) return i;
    fprintf(stderr, "fuzz: variable %s not in modelDescription.xml\n", name);
    exit(2);
}

static void parse_vars(void) {
    double emin = INFINITY, emax = -INFINITY;
    for (const char *p = strstr(xml, "<Item "); p; p = strstr(p + 1, "<Item ")) {
        char b[64];
        if (attr(p, strchr(p, '>'), "value", b, sizeof b)) {
            emin = fmin(emin, atof(b));
            emax = fmax(emax, atof(b));
        }
    }
    for (const char *p = strstr(xml, "<ScalarVariable"); p && nv < MAXV;
         p = strstr(p + 1, "<ScalarVariable")) {
        const char *end = strstr(p, "</ScalarVariable>");
        Var *v = &vars[nv++];
        char b[64] = "";
        attr(p, end, "name", v->name, sizeof v->name);
        attr(p, end, "valueReference", b, sizeof b);
        v->vr = (fmi2ValueReference)strtoul(b, NULL, 10);
        attr(p, end, "causality", b, sizeof b);
        /* Local variables (state derivatives, event indicators) and the independent variable
           (time) are computed like outputs. */
        v->caus = strcmp(b, "output") == 0 || strcmp(b, "local") == 0 ||
                          strcmp(b, "independent") == 0
                      ? C_OUTPUT
                  : strcmp(b, "input") == 0                           ? C_INPUT
                                                                      : C_PARAM;
        v->tunable = attr(p, end, "variability", b, sizeof b) && strcmp(b, "tunable") == 0;
        const char *ty;
        if ((ty = strstr(p, "<Real")) && ty < end) {
            v->kind = K_REAL;
            v->min = -INFINITY, v->max = INFINITY;
        } else if ((ty = strstr(p, "<Enumeration")) && ty < end) {
            v->kind = K_INT;
            v->min = emin, v->max = emax;
        } else if ((ty = strstr(p, "<Integer")) && ty < end) {
            v->kind = K_INT;
            v->min = INT_MIN, v->max = INT_MAX;
        } else {
            ty = strstr(p, "<Boolean");
            v->kind = K_BOOL;
            v->min = 0, v->max = 1;
        }
        if (attr(ty, end, "min", b, sizeof b)) v->min = atof(b);
        if (attr(ty, end, "max", b, sizeof b)) v->max = atof(b);
        v->start = attr(ty, end, "start", b, sizeof b) ? (strcmp(b, "true") == 0 ? 1 : atof(b)) : 0;
    }
    iZeta = index_of("zeta"), iE = index_of("e"), iOmega = index_of("Omega"), iV = index_of("V");
    iOmega0 = index_of("omega0"), iDx = index_of("delta_x"), iMass = index_of("mass");
    iX0 = index_of("x0"), iV0 = index_of("v0"), iTol = index_of("tol");
    iMode = index_of("shaker_mode"), iZin = index_of("z_in"), iZdin = index_of("zdot_in");
    iX = index_of("x"), iVel = index_of("v"), iZ = index_of("z"), iZdot = index_of("zdot");
    iKE = index_of("kinetic_energy"), iPE = index_of("potential_energy");
    iCount = index_of("impact_count"), iLastT = index_of("last_impact_time");
    iPhase = index_of("last_impact_phase"), iVb = index_of("last_impact_v_before");
    iVa = index_of("last_impact_v_after"), iDk = index_of("last_impact_delta_k");
    iWell = index_of("well"), iSnap = index_of("snap_through_count");
    iContact = index_of("in_contact");
    for (int i = 0; i < nv; i++) {
        if (vars[i].caus != C_OUTPUT) continue;
        if (vars[i].kind == K_REAL) vr_out_real[n_out_real] = vars[i].vr, out_real[n_out_real++] = i;
        if (vars[i].kind == K_INT) vr_out_int[n_out_int] = vars[i].vr, out_int[n_out_int++] = i;
        if (vars[i].kind == K_BOOL) vr_out_bool[n_out_bool] = vars[i].vr, out_bool[n_out_bool++] = i;
    }
}

/* Variable index of a value reference, -1 if none. */
static int var_of(fmi2ValueReference r) {
    for (int i = 0; i < nv; i++)
        if (vars[i].vr == r) return i;
    return -1;
}

/* ---- the oracle ---- */
enum { L_NONE, L_INST, L_INIT, L_STEP, L_FAILED, L_TERM, L_ERROR };
static const char *life_name[] = {"none", "Instantiated", "InitializationMode", "StepComplete",
                                  "StepFailed", "Terminated", "Error"};

/* What the host knows about an instance, or about an FMU state it holds. */
typedef struct {
    int life;
    double t, start, stop, last_ok;
    int has_stop, terminated, has_model;
    double val[MAXV];   /* parameters and inputs as set */
    int derivs;         /* input derivatives for the next step: 0 none, 1 reference, 2 random */
    int ext_ok;         /* external mode: inputs follow the reference sinusoid at t */
    double ext_a, ext_w; /* reference sinusoid z = a sin(w t) (m, rad/s) */
    int crafted;        /* restored from a crafted buffer: values parsed, expectations relaxed */
    int wild_init;      /* run initialized or stepped outside the sane domain (e.g. x0 far above
                           the plate, random input derivatives): its state may be extreme */
    double out[MAXV];   /* outputs read at this point */
    int out_ok;
} Meta;

#define MAXST 8
typedef struct {
    fmi2FMUstate h;
    Meta m;
} Held;

typedef struct {
    fmi2Component c;
    Meta m;
    Held st[MAXST];
    int nst;
    fmi2FMUstate stale[MAXST]; /* freed handles (never dereferenced by the FMU: registry lookup) */
    int nstale;
    char name[80];
    int has_logger;
    double count_floor; /* impact count may not fall below this along the current run */
} Inst;

static Inst I[2];

typedef struct {
    unsigned char *b;
    size_t n;
    Meta m;
} Buf;
#define MAXBUF 4
static Buf bufs[MAXBUF];
static int nbuf;

/* A zero-filled block passed as a component that is not a live instance. */
static _Alignas(64) unsigned char bogus[8192];

/* ---- counters (failures, ring of calls, watchdog: fuzzkit.h) ---- */
enum {
    N_CALLS, N_CHECKS, N_INVARIANTS, N_INVALID, N_STATE, N_NANINF, N_NULL, N_BADVR, N_STEP_EXTREME,
    N_WRONG_TC, N_ROLLBACK, N_ROUNDTRIP, N_CROSS, N_CORRUPT, N_CRAFTED, N_CRAFTED_OK, N_REINST,
    N_STEPS_OK, N_DISCARD, N_STEP_REFUSED_WILD, N_COUNT
};
static const char *count_name[] = {
    "calls", "observation calls", "invariant checks", "invalid-argument calls",
    "wrong-state calls", "NaN/inf arguments", "NULL/bogus pointers", "bad value references",
    "huge/tiny/zero/negative steps", "wrong communication points", "rollbacks (handle)",
    "serialize round trips", "cross-instance restores", "corrupt buffers", "crafted buffers",
    "crafted accepted", "free + re-instantiate", "steps OK", "steps Discard",
    "valid steps refused (wild)"};
static long cnt[N_COUNT], total[N_COUNT];
/* Calls made on an instance in each lifecycle state (the oracle's view). */
static long by_life[7];
static double gap_min = INFINITY; /* smallest (x - z) / scale seen */

/* The step in progress (reported by the watchdog: kit.pending). */
static char pending[320];

/* The FMU's last log message (kit.last_log). */
static char log_msg[1024];

/* FUZZ_SAVE_DIR: the serialized state before the last step and its arguments, written on the
 * first failure of a seed and on a hang or crash (kit.save; for a regression test). */
static unsigned char *prestep;
static size_t prestep_n;
static double prestep_tc, prestep_h;

static void save_prestep(void) {
    const char *dir = getenv("FUZZ_SAVE_DIR");
    if (!dir || !prestep) return;
    char path[512];
    snprintf(path, sizeof path, "%s/prestep-%lu-%ld-tc%.17g-h%.17g.bin", dir, seed_now, call_now,
             prestep_tc, prestep_h);
    FILE *f = fopen(path, "wb");
    if (f) fwrite(prestep, 1, prestep_n, f), fclose(f);
}

/* ---- logger: checks its arguments, keeps the last message ---- */
static void *expected_env;
static const char *expected_name;
static long log_errors;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String format, ...) {
    va_list ap;
    va_start(ap, format);
    vsnprintf(log_msg, sizeof log_msg, format, ap);
    va_end(ap);
    if (status == fmi2Error || status == fmi2Fatal) log_errors++;
    cnt[N_INVARIANTS]++;
    if (env != expected_env || !name || !category || !format || strcmp(format, "%s") != 0 ||
        (expected_name && strcmp(name, expected_name) != 0))
        fail("logger called with env %p (expected %p), name \"%s\", format \"%s\"", env,
             expected_env, name ? name : "(null)", format ? format : "(null)");
}

static fmi2CallbackFunctions cb_with_logger[2], cb_without_logger[2];

/* ---- expectations ---- */
enum { E_OK, E_ERR, E_OK_ERR, E_ANY, E_DISCARD };
static const char *exp_name[] = {"OK", "Error", "OK or Error", "any", "Discard"};
static const char *st_name(fmi2Status s) {
    static const char *n[] = {"OK", "Warning", "Discard", "Error", "Fatal", "Pending"};
    return s >= 0 && s <= 5 ? n[s] : "?";
}

static Inst *cur;      /* instance of the call in progress (NULL: none/bogus component) */
static long errs_before;

static void begin(Inst *in) {
    cur = in;
    if (in) by_life[in->c ? in->m.life : L_NONE]++;
    expected_env = in;
    expected_name = in ? in->name : NULL;
    errs_before = log_errors;
    log_msg[0] = 0;
    cnt[N_CALLS]++;
}

/* Checks status `s` against expectation `e`; returns 1 if it matched. */
static int expect(fmi2Status s, int e, const char *what) {
    mix((uint64_t)s + 7);
    int ok;
    switch (e) {
    case E_OK: ok = s == fmi2OK || s == fmi2Warning; break;
    case E_ERR: ok = s == fmi2Error; break;
    case E_OK_ERR: ok = s == fmi2OK || s == fmi2Warning || s == fmi2Error; break;
    case E_DISCARD: ok = s == fmi2Discard; break;
    default: ok = s >= fmi2OK && s <= fmi2Error; break;
    }
    note("I%d %s -> %s (expected %s)", cur ? (int)(cur - I) : -1, what, st_name(s), exp_name[e]);
    check(ok, "%s returned %s, expected %s", what, st_name(s), exp_name[e]);
    if (s == fmi2Error && cur && cur->has_logger)
        check(log_errors > errs_before, "%s returned fmi2Error without logging a reason", what);
    return ok;
}

/* ---- sane domain: inside it the FMU must initialize and step without failing ---- */
static int is_external(const Meta *m) { return m->val[iMode] == 2; }

static int wild(const Meta *m) {
    const double *v = m->val;
    if (m->crafted || m->wild_init) return 1;
    double dx = v[iDx], w0 = v[iOmega0];
    int ok = v[iZeta] >= 0 && v[iZeta] <= 0.3 && v[iE] >= 0.4 && v[iE] <= 0.95 &&
             v[iOmega] >= 0.3 && v[iOmega] <= 4 && v[iV] >= 0.005 && v[iV] <= 0.3 &&
             w0 >= 0.2 && w0 <= 5 && dx >= 0.01 && dx <= 100 && v[iMass] >= 0.01 &&
             v[iMass] <= 100 && fabs(v[iV0]) <= 0.5 * w0 * dx && v[iTol] >= 1e-16 &&
             v[iTol] <= 1e-8 && (v[iMode] == 1 || v[iMode] == 2) && fabs(m->start) <= 1e6;
    if (!ok) return 1;
    if (m->life <= L_INIT) {
        double zs = is_external(m) ? v[iZin] : 0.0;
        if (!(v[iX0] >= zs && v[iX0] <= zs + 1.5 * dx)) return 1;
    }
    if (is_external(m) && (!m->ext_ok || m->derivs == 2)) return 1;
    return 0;
}

static double slack(double t) { return 1e-9 * fmax(fabs(t), 1.0); }

/* ---- reading and checking outputs ---- */
static int readable(int life) { return life >= L_INIT; }

/* Physical and consistency checks of a set of outputs of instance `in`. */
static void physical(Inst *in, const double *o) {
    const Meta *m = &in->m;
    for (int k = 0; k < n_out_real; k++)
        check(isfinite(o[out_real[k]]), "output %s = %g is not finite", vars[out_real[k]].name,
              o[out_real[k]]);
    double dx = m->val[iDx], x = o[iX], z = o[iZ];
    double scale = fmax(dx, fmax(fabs(x), fabs(z)));
    double gap = (x - z) / scale;
    if (gap < gap_min) gap_min = gap;
    check(gap >= -GAP_BOUND, "mass below the plate: x - z = %g m (x = %.17g, z = %.17g)", x - z,
          x, z);
    check(o[iKE] >= 0 && o[iPE] >= 0, "negative energy (%g, %g)", o[iKE], o[iPE]);
    double ke = 0.5 * m->val[iMass] * o[iVel] * o[iVel];
    check(fabs(o[iKE] - ke) <= 1e-12 * ke + 1e-300 || m->crafted,
          "kinetic_energy %.17g != mass v^2/2 = %.17g", o[iKE], ke);
    check(o[iWell] == 1 || o[iWell] == 2, "well = %g", o[iWell]);
    if (fabs(x - 0.5 * dx) > 1e-9 * dx)
        check(o[iWell] == (x < 0.5 * dx ? 1 : 2), "well %g does not match x = %.17g (delta_x %g)",
              o[iWell], x, dx);
    check(o[iContact] == 0 || o[iContact] == 1, "in_contact = %g", o[iContact]);
    if (o[iContact] == 1)
        check(x == z && o[iVel] == o[iZdot], "in contact but x != z or v != zdot");
    check(o[iCount] >= 0 && o[iSnap] >= 0, "negative counts");
    check(o[iPhase] >= 0 && o[iPhase] <= 1, "last_impact_phase = %g not in [0, 1]", o[iPhase]);
    if (o[iCount] > 0 && m->life >= L_STEP)
        check(o[iLastT] <= m->t + slack(m->t) + 1e-9 * fabs(m->t),
              "last impact at %.17g s is after the FMU time %.17g s", o[iLastT], m->t);
}

/* Reads every output of `in` into `o`; returns the status (OK only if all reads were OK). */
static fmi2Status read_outputs(Inst *in, double *o) {
    fmi2Real r[MAXV];
    fmi2Integer n[MAXV];
    fmi2Boolean b[MAXV];
    expected_env = in, expected_name = in->name;
    cnt[N_CHECKS] += 3;
    fmi2Status s1 = F.fmi2GetReal(in->c, vr_out_real, (size_t)n_out_real, r);
    fmi2Status s2 = F.fmi2GetInteger(in->c, vr_out_int, (size_t)n_out_int, n);
    fmi2Status s3 = F.fmi2GetBoolean(in->c, vr_out_bool, (size_t)n_out_bool, b);
    if (s1 != s2 || s2 != s3) {
        check(0, "output reads disagree: GetReal %s, GetInteger %s, GetBoolean %s", st_name(s1),
              st_name(s2), st_name(s3));
        return fmi2Error;
    }
    if (s1 != fmi2OK) return s1;
    for (int k = 0; k < n_out_real; k++) o[out_real[k]] = r[k];
    for (int k = 0; k < n_out_int; k++) o[out_int[k]] = n[k];
    for (int k = 0; k < n_out_bool; k++) {
        check(b[k] == fmi2True || b[k] == fmi2False, "Boolean output %d", b[k]);
        o[out_bool[k]] = b[k];
    }
    return fmi2OK;
}

static const char *differs = "";
static int same_outputs(const double *a, const double *b) {
    for (int k = 0; k < nv; k++)
        if (vars[k].caus == C_OUTPUT && bits(a[k]) != bits(b[k])) {
            differs = vars[k].name;
            return 0;
        }
    return 1;
}

/* Reads the outputs after a call. `unchanged`: the call was refused or only read, so the outputs
 * must be bit for bit those read before it. */
static void observe(Inst *in, int unchanged, const char *after) {
    Meta *m = &in->m;
    if (!in->c || !readable(m->life)) {
        m->out_ok = 0;
        return;
    }
    double o[MAXV];
    memcpy(o, m->out, sizeof o);
    fmi2Status s = read_outputs(in, o);
    int must = m->has_model || !wild(m);
    cnt[N_INVARIANTS]++;
    if (s != fmi2OK) {
        if (must || s != fmi2Error)
            fail("outputs not readable after %s in state %s: %s", after, life_name[m->life],
                 st_name(s));
        m->out_ok = 0;
        return;
    }
    physical(in, o);
    if (unchanged && m->out_ok)
        check(same_outputs(o, m->out), "outputs changed by %s (which was refused or read only): %s", after,
              differs);
    if (m->life >= L_STEP && o[iCount] < in->count_floor)
        check(0, "impact_count fell from %g to %g along a run", in->count_floor, o[iCount]);
    in->count_floor = o[iCount];
    for (int k = 0; k < nv; k++)
        if (vars[k].caus == C_OUTPUT) mix(bits(o[k]));
    memcpy(m->out, o, sizeof o);
    m->out_ok = 1;
}

/* ---- random arguments ---- */
static const double specials[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 1e-300, -1e-300, 0.0,
                                  -0.0, 5e-324, DBL_MAX, -DBL_MAX, 1e20, -1};

static double special(void) { return specials[pick((int)(sizeof specials / sizeof specials[0]))]; }

/* A sane value of variable i (relative to the other values in m). */
static double sane_value(const Meta *m, int i) {
    const double *v = m->val;
    if (i == iZeta) return chance(0.2) ? 0.0 : urange(0, 0.3);
    if (i == iE) return urange(0.4, 0.95);
    if (i == iOmega) return urange(0.3, 4);
    if (i == iV) return logu(0.005, 0.3);
    if (i == iOmega0) return chance(0.5) ? 1.0 : logu(0.2, 5);
    if (i == iDx) return chance(0.5) ? 1.0 : logu(0.01, 100);
    if (i == iMass) return chance(0.5) ? 1.0 : logu(0.01, 100);
    if (i == iX0) {
        double zs = is_external(m) ? v[iZin] : 0.0;
        return chance(0.4) ? zs : zs + urange(0, 1.4) * v[iDx];
    }
    if (i == iV0) return chance(0.4) ? 0.0 : urange(-0.45, 0.45) * v[iOmega0] * v[iDx];
    if (i == iTol) return chance(0.5) ? 1e-16 : logu(1e-16, 1e-8);
    if (i == iMode) return 1 + pick(2);
    return urange(-0.1, 0.1) * v[iDx];
}

/* A random value for variable i: sane, in range, boundary, out of range or special. */
static double any_value(const Meta *m, int i, int *naninf) {
    const Var *v = &vars[i];
    int r = pick(100);
    double x;
    if (r < 55) x = sane_value(m, i);
    else if (r < 70) {
        double lo = fmax(v->min, -1e12), hi = fmin(v->max, 1e12);
        x = chance(0.5) ? urange(lo, hi) : (lo > 0 ? logu(lo, hi) : urange(lo, hi) * pow(10, -pick(12)));
    } else if (r < 78) x = chance(0.5) ? v->min : v->max;
    else if (r < 88) x = chance(0.5) ? v->min - fmax(1, fabs(v->min)) : v->max * 2 + 1;
    else x = special();
    if (v->kind != K_REAL) x = isfinite(x) && fabs(x) < 3e9 ? floor(x) : (double)(pick(7) - 3);
    if (!isfinite(x)) *naninf = 1;
    return x;
}

/* Whether a Real/Integer value for variable i is accepted by a setter in state `life`. */
static int settable(int i, int kind, int life, double x) {
    const Var *v = &vars[i];
    if (v->kind != kind || v->caus == C_OUTPUT) return 0;
    if (v->caus == C_PARAM && !v->tunable && life == L_STEP) return 0;
    if (kind == K_BOOL) return 0;
    return isfinite(x) && x >= v->min && x <= v->max && (kind == K_REAL || x == floor(x));
}

/* A value reference: mostly of the wanted kind and causality, sometimes any, sometimes unknown. */
static fmi2ValueReference any_vr(int kind, int settable_only, int *bad) {
    int r = pick(100);
    if (r < 8) {
        *bad = 1;
        static const fmi2ValueReference unknown[] = {4096, 4097, 100000, 777777, 0x7fffffff, 0xffffffffu};
        return unknown[pick(6)];
    }
    if (r < 25) return vars[pick(nv)].vr;
    for (int tries = 0; tries < 50; tries++) {
        int i = pick(nv);
        if (vars[i].kind == kind && (!settable_only || vars[i].caus != C_OUTPUT)) return vars[i].vr;
    }
    return vars[pick(nv)].vr;
}

/* ---- instance lifecycle ---- */
static void meta_reset(Meta *m) {
    memset(m, 0, sizeof *m);
    m->life = L_INST;
    for (int i = 0; i < nv; i++) m->val[i] = vars[i].start;
}

static int held_index(Inst *in, fmi2FMUstate h) {
    for (int k = 0; k < in->nst; k++)
        if (in->st[k].h == h) return k;
    return -1;
}

static void forget_stale(Inst *in, fmi2FMUstate h) {
    for (int k = 0; k < in->nstale; k++)
        if (in->stale[k] == h) in->stale[k] = NULL;
}

static void add_stale(Inst *in, fmi2FMUstate h) {
    if (in->nstale < MAXST) in->stale[in->nstale++] = h;
    else in->stale[pick(MAXST)] = h;
}

static void hold(Inst *in, fmi2FMUstate h, const Meta *m) {
    int k = held_index(in, h);
    forget_stale(in, h);
    if (k < 0) k = in->nst++;
    in->st[k].h = h;
    in->st[k].m = *m;
}

static void unhold(Inst *in, int k) {
    add_stale(in, in->st[k].h);
    in->st[k] = in->st[--in->nst];
}

static int instantiate(int k, int valid) {
    Inst *in = &I[k];
    in->nst = 0; /* handles of a freed instance are only stale pointers now */
    in->has_logger = !valid || chance(0.9);
    int variant = valid ? -1 : pick(6);
    switch (pick(4)) {
    case 0: snprintf(in->name, sizeof in->name, "fuzz%d", k); break;
    case 1: snprintf(in->name, sizeof in->name, "%%s%%n%%d 100%% name %d", k); break;
    case 2: memset(in->name, 'n', sizeof in->name - 1), in->name[sizeof in->name - 1] = 0; break;
    default: snprintf(in->name, sizeof in->name, "inst\xc3\xa9%lu", seed_now); break;
    }
    const char *name = variant == 0 ? NULL : variant == 1 ? "" : in->name;
    const char *g = variant == 2 ? NULL : variant == 3 ? "{00000000-0000-0000-0000-000000000000}" : guid;
    /* variant 4: an unknown FMU type (Model Exchange instances are fuzzed by me_sequence) */
    fmi2Type type = variant == 4 ? 2 + pick(100) : fmi2CoSimulation;
    const fmi2CallbackFunctions *cb =
        variant == 5 ? NULL : in->has_logger ? &cb_with_logger[k] : &cb_without_logger[k];
    fmi2Boolean logging = chance(0.2);
    begin(in);
    expected_name = name ? name : "";
    fmi2Component c = F.fmi2Instantiate(name, type, g, NULL, cb, fmi2False, logging);
    note("I%d fmi2Instantiate(variant %d, logging %d) -> %p", k, variant, logging, c);
    if (!valid) {
        cnt[N_INVALID]++;
        if (variant == 0 || variant == 5) cnt[N_NULL]++;
        check(c == NULL, "invalid fmi2Instantiate (variant %d) returned an instance", variant);
        if (variant != 5 && in->has_logger)
            check(log_errors > errs_before, "refused fmi2Instantiate logged no reason");
        if (c) F.fmi2FreeInstance(c);
        return 0;
    }
    check(c != NULL, "valid fmi2Instantiate returned NULL");
    if (!c) return 0;
    in->c = c;
    meta_reset(&in->m);
    in->count_floor = 0;
    if (logging && chance(0.5)) {
        const char *cat = "logEvents";
        F.fmi2SetDebugLogging(c, fmi2False, 1, &cat);
    }
    return 1;
}

static void free_instance(int k) {
    Inst *in = &I[k];
    begin(in);
    F.fmi2FreeInstance(in->c);
    note("I%d fmi2FreeInstance", k);
    for (int j = 0; j < in->nst; j++) add_stale(in, in->st[j].h);
    in->nst = 0;
    in->c = NULL;
    in->m.life = L_NONE;
}

/* ---- actions ---- */

/* Sets every parameter to a sane value (Instantiated or initialization mode). */
static void act_sane_config(Inst *in) {
    Meta *m = &in->m;
    if (m->life != L_INST && m->life != L_INIT) return;
    Meta t = *m;
    int order[] = {iMode, iZeta, iE, iOmega, iV, iOmega0, iDx, iMass, iTol};
    for (int j = 0; j < 9; j++) t.val[order[j]] = sane_value(&t, order[j]);
    if (fabs(m->start) > 1e6) t.val[iMode] = 1; /* the reference sinusoid needs a moderate time */
    if (is_external(&t)) {
        t.ext_a = t.val[iDx] * t.val[iV] / t.val[iOmega];
        t.ext_w = t.val[iOmega] * t.val[iOmega0];
        t.val[iZin] = t.ext_a * sin(t.ext_w * m->start);
        t.val[iZdin] = t.ext_a * t.ext_w * cos(t.ext_w * m->start);
    }
    t.val[iX0] = sane_value(&t, iX0);
    t.val[iV0] = sane_value(&t, iV0);
    fmi2ValueReference rv[MAXV];
    fmi2Real rx[MAXV];
    int n = 0;
    for (int i = 0; i < nv; i++)
        if (vars[i].caus != C_OUTPUT && vars[i].kind == K_REAL) rv[n] = vars[i].vr, rx[n++] = t.val[i];
    fmi2ValueReference mv = vars[iMode].vr;
    fmi2Integer mode = (fmi2Integer)t.val[iMode];
    begin(in);
    int ok = expect(F.fmi2SetInteger(in->c, &mv, 1, &mode), E_OK, "fmi2SetInteger(shaker_mode)");
    begin(in);
    ok &= expect(F.fmi2SetReal(in->c, rv, (size_t)n, rx), E_OK, "fmi2SetReal(sane parameters)");
    if (ok) {
        t.ext_ok = is_external(&t); /* derivatives set earlier stay until overwritten below */
        *m = t;
    }
    if (ok && is_external(m) && chance(0.7)) {
        /* Derivatives at the start time for the first step. */
        fmi2ValueReference dv[4] = {vars[iZin].vr, vars[iZin].vr, vars[iZin].vr, vars[iZin].vr};
        fmi2Integer ord[4] = {2, 3, 4, 5};
        fmi2Real d[4];
        for (int j = 0; j < 4; j++)
            d[j] = m->ext_a * pow(m->ext_w, j + 2) * sin(m->ext_w * m->start + (j + 2) * M_PI / 2);
        begin(in);
        if (expect(F.fmi2SetRealInputDerivatives(in->c, dv, 4, ord, d), E_OK,
                   "fmi2SetRealInputDerivatives(reference)"))
            m->derivs = 1;
    }
    observe(in, 0, "sane configuration");
}

/* External mode: inputs and their derivatives from the reference sinusoid at the FMU time;
 * returns whether they were set. */
static int act_ext_inputs(Inst *in) {
    Meta *m = &in->m;
    if (!is_external(m) || m->ext_w == 0 || !(m->life >= L_INST && m->life <= L_STEP)) return 0;
    double t = m->life == L_STEP ? m->t : m->start, a = m->ext_a, w = m->ext_w;
    if (!(fabs(w * t) < 1e6)) return 0; /* the reference sinusoid is for moderate times */
    fmi2ValueReference zv[2] = {vars[iZin].vr, vars[iZdin].vr};
    fmi2Real z[2] = {a * sin(w * t), a * w * cos(w * t)};
    begin(in);
    if (!expect(F.fmi2SetReal(in->c, zv, 2, z), E_OK, "fmi2SetReal(z_in, zdot_in reference)")) return 0;
    m->val[iZin] = z[0], m->val[iZdin] = z[1];
    int use_zdot = chance(0.5);
    fmi2ValueReference dv[4];
    fmi2Integer ord[4];
    fmi2Real d[4];
    for (int j = 0; j < 4; j++) {
        dv[j] = use_zdot ? zv[1] : zv[0];
        ord[j] = use_zdot ? j + 1 : j + 2;
        d[j] = a * pow(w, j + 2) * sin(w * t + (j + 2) * M_PI / 2);
    }
    begin(in);
    if (expect(F.fmi2SetRealInputDerivatives(in->c, dv, 4, ord, d), E_OK,
               "fmi2SetRealInputDerivatives(reference)")) {
        m->derivs = 1;
        m->ext_ok = 1;
    }
    observe(in, 0, "reference inputs");
    return 1;
}

static void act_setup(Inst *in) {
    Meta *m = &in->m;
    int tol_def = chance(0.3), stop_def = chance(0.4), naninf = 0;
    double tol = chance(0.8) ? logu(1e-12, 1e-3) : special();
    double start = chance(0.6) ? 0.0 : chance(0.7) ? urange(-50, 100) : special();
    double stop = chance(0.85) ? start + logu(1, 1000) : chance(0.5) ? start - 1 : special();
    if (tol_def && !isfinite(tol)) naninf = 1;
    if (!isfinite(start) || (stop_def && !isfinite(stop))) naninf = 1;
    int valid = isfinite(start) && (!stop_def || (isfinite(stop) && stop >= start)) &&
                (!tol_def || (isfinite(tol) && tol > 0));
    int allowed = m->life == L_INST;
    cnt[N_NANINF] += naninf;
    cnt[N_INVALID] += !valid;
    cnt[N_STATE] += !allowed;
    char what[200];
    snprintf(what, sizeof what, "fmi2SetupExperiment(tol %d %g, start %.17g, stop %d %.17g)",
             tol_def, tol, start, stop_def, stop);
    begin(in);
    fmi2Status s = F.fmi2SetupExperiment(in->c, tol_def, tol, start, stop_def, stop);
    if (expect(s, valid && allowed ? E_OK : E_ERR, what) && s == fmi2OK) {
        m->start = start;
        m->has_stop = stop_def;
        m->stop = stop;
        if (is_external(m)) m->ext_ok = 0;
    }
    observe(in, s != fmi2OK, what);
}

static void act_enter(Inst *in) {
    Meta *m = &in->m;
    int allowed = m->life == L_INST;
    cnt[N_STATE] += !allowed;
    begin(in);
    fmi2Status s = F.fmi2EnterInitializationMode(in->c);
    if (expect(s, allowed ? E_OK : E_ERR, "fmi2EnterInitializationMode") && s == fmi2OK)
        m->life = L_INIT;
    observe(in, s != fmi2OK, "fmi2EnterInitializationMode");
}

static void act_exit(Inst *in) {
    Meta *m = &in->m;
    int allowed = m->life == L_INIT;
    cnt[N_STATE] += !allowed;
    begin(in);
    fmi2Status s = F.fmi2ExitInitializationMode(in->c);
    if (expect(s, !allowed ? E_ERR : wild(m) ? E_OK_ERR : E_OK, "fmi2ExitInitializationMode") &&
        s == fmi2OK) {
        m->wild_init = wild(m);
        m->life = L_STEP;
        m->t = m->last_ok = m->start;
        m->has_model = 1;
        in->count_floor = 0;
    }
    observe(in, s != fmi2OK, "fmi2ExitInitializationMode");
}

static void act_terminate(Inst *in) {
    Meta *m = &in->m;
    int allowed = m->life == L_STEP || m->life == L_FAILED;
    cnt[N_STATE] += !allowed;
    begin(in);
    fmi2Status s = F.fmi2Terminate(in->c);
    if (expect(s, allowed ? E_OK : E_ERR, "fmi2Terminate") && s == fmi2OK) m->life = L_TERM;
    observe(in, 1, "fmi2Terminate");
}

static void act_reset(Inst *in) {
    begin(in);
    fmi2Status s = F.fmi2Reset(in->c);
    if (expect(s, E_OK, "fmi2Reset") && s == fmi2OK) {
        meta_reset(&in->m);
        in->count_floor = 0;
    }
    observe(in, 0, "fmi2Reset");
}

/* fmi2SetReal / fmi2SetInteger / fmi2SetBoolean / fmi2SetString with random arguments. */
static void act_set(Inst *in, int kind) {
    Meta *m = &in->m;
    int n = chance(0.1) ? 0 : 1 + pick(4), bad = 0, naninf = 0, nul = 0;
    fmi2ValueReference rv[8];
    double x[8];
    int valid = 1;
    for (int j = 0; j < n; j++) {
        int badvr = 0;
        rv[j] = any_vr(kind == 3 ? K_REAL : kind, 1, &badvr);
        int i = var_of(rv[j]);
        x[j] = i >= 0 ? any_value(m, i, &naninf) : urange(-1, 1);
        bad |= badvr;
        valid &= i >= 0 && kind != 3 && settable(i, kind, m->life, x[j]);
    }
    fmi2Real r[8];
    fmi2Integer iv[8];
    fmi2Boolean bv[8];
    fmi2String sv[8];
    for (int j = 0; j < n; j++) {
        r[j] = x[j];
        iv[j] = (fmi2Integer)fmax(fmin(x[j], INT_MAX), INT_MIN);
        if (kind == K_INT && iv[j] != x[j]) valid = 0;
        bv[j] = chance(0.8) ? fmi2True : 2;
        sv[j] = chance(0.9) ? "text" : NULL;
    }
    const fmi2ValueReference *pv = rv;
    const void *px = kind == K_REAL ? (const void *)r : kind == K_INT ? (const void *)iv
                     : kind == K_BOOL ? (const void *)bv : (const void *)sv;
    if (n > 0 && chance(0.04)) pv = NULL, nul = 1;
    if (n > 0 && chance(0.04)) px = NULL, nul = 1;
    if (nul) valid = 0;
    int allowed = m->life >= L_INST && m->life <= L_STEP;
    cnt[N_STATE] += !allowed;
    cnt[N_BADVR] += bad;
    cnt[N_NANINF] += naninf;
    cnt[N_NULL] += nul;
    cnt[N_INVALID] += !valid;
    static const char *fn[] = {"fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean", "fmi2SetString"};
    char what[300];
    int w = snprintf(what, sizeof what, "%s(n %d%s%s:", fn[kind], n, pv ? "" : ", vr NULL",
                     px ? "" : ", value NULL");
    for (int j = 0; j < n && w < 260; j++) w += snprintf(what + w, sizeof what - (size_t)w, " %u=%.6g", rv[j], x[j]);
    snprintf(what + w, sizeof what - (size_t)w, ")");
    begin(in);
    fmi2Status s;
    switch (kind) {
    case K_REAL: s = F.fmi2SetReal(in->c, pv, (size_t)n, px); break;
    case K_INT: s = F.fmi2SetInteger(in->c, pv, (size_t)n, px); break;
    case K_BOOL: s = F.fmi2SetBoolean(in->c, pv, (size_t)n, px); break;
    default: s = F.fmi2SetString(in->c, pv, (size_t)n, px); break;
    }
    if (expect(s, valid && allowed ? E_OK : E_ERR, what) && s == fmi2OK) {
        for (int j = 0; j < n; j++) {
            int i = var_of(rv[j]);
            m->val[i] = x[j];
            if (i == iZin || i == iZdin) m->ext_ok = 0;
        }
    }
    observe(in, s != fmi2OK, what);
}

/* fmi2GetReal / fmi2GetInteger / fmi2GetBoolean / fmi2GetString with random arguments; values
 * read back must equal what was set, outputs what was observed. */
static void act_get(Inst *in, int kind) {
    Meta *m = &in->m;
    int n = chance(0.1) ? 0 : 1 + pick(5), bad = 0, nul = 0, valid = 1, outputs = 0;
    fmi2ValueReference rv[8];
    for (int j = 0; j < n; j++) {
        int badvr = 0;
        rv[j] = any_vr(kind == 3 ? K_REAL : kind, 0, &badvr);
        int i = var_of(rv[j]);
        bad |= badvr;
        valid &= i >= 0 && kind != 3 && vars[i].kind == kind;
        outputs |= i >= 0 && vars[i].caus == C_OUTPUT;
    }
    fmi2Real r[8];
    fmi2Integer iv[8];
    fmi2Boolean bv[8];
    fmi2String sv[8];
    const fmi2ValueReference *pv = rv;
    void *px = kind == K_REAL ? (void *)r : kind == K_INT ? (void *)iv : kind == K_BOOL ? (void *)bv : (void *)sv;
    if (n > 0 && chance(0.04)) pv = NULL, nul = 1;
    if (n > 0 && chance(0.04)) px = NULL, nul = 1;
    if (nul) valid = 0;
    int allowed = readable(m->life);
    cnt[N_STATE] += !allowed;
    cnt[N_BADVR] += bad;
    cnt[N_NULL] += nul;
    cnt[N_INVALID] += !valid;
    static const char *fn[] = {"fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString"};
    char what[200];
    int w = snprintf(what, sizeof what, "%s(n %d%s%s:", fn[kind], n, pv ? "" : ", vr NULL",
                     px ? "" : ", value NULL");
    for (int j = 0; j < n && w < 180; j++) w += snprintf(what + w, sizeof what - (size_t)w, " %u", rv[j]);
    snprintf(what + w, sizeof what - (size_t)w, ")");
    int e = !(valid && allowed) ? E_ERR : (outputs && !m->out_ok) ? E_OK_ERR : E_OK;
    begin(in);
    fmi2Status s;
    switch (kind) {
    case K_REAL: s = F.fmi2GetReal(in->c, pv, (size_t)n, px); break;
    case K_INT: s = F.fmi2GetInteger(in->c, pv, (size_t)n, px); break;
    case K_BOOL: s = F.fmi2GetBoolean(in->c, pv, (size_t)n, px); break;
    default: s = F.fmi2GetString(in->c, pv, (size_t)n, px); break;
    }
    if (expect(s, e, what) && s == fmi2OK) {
        for (int j = 0; j < n; j++) {
            int i = var_of(rv[j]);
            double got = kind == K_REAL ? r[j] : kind == K_INT ? iv[j] : bv[j];
            double want = vars[i].caus == C_OUTPUT ? m->out[i] : m->val[i];
            if (kind == K_INT && vars[i].caus != C_OUTPUT) want = (fmi2Integer)want;
            if (vars[i].caus != C_OUTPUT || m->out_ok)
                check(bits(got) == bits(want), "%s read %s = %.17g, expected %.17g", fn[kind],
                      vars[i].name, got, want);
        }
    }
    observe(in, 1, what);
}

/* One fmi2DoStep. `kind`: 0 sane, 1 anything. Returns the status. */
static fmi2Status do_step(Inst *in, int kind) {
    Meta *m = &in->m;
    double t = m->t, w0 = m->val[iOmega0];
    /* Work per step grows with the shaker periods it spans: sane steps span at most ~20 time
     * units (external: half a radian of the reference sinusoid). */
    double per_time = w0 * fmax(1.0, m->val[iOmega]);
    double hmax = is_external(m) && m->ext_w > 0 ? fmin(0.5 / m->ext_w, 20 / per_time) : 20 / per_time;
    if (!(hmax > 0 && isfinite(hmax)) || !m->has_model) hmax = 1;
    double h = logu(1e-4, 1) * hmax, tc = t;
    int extreme = 0, wrong_tc = 0;
    if (kind == 1) {
        int r = pick(100);
        if (r < 8) h = special(), extreme = 1;
        else if (r < 14) h = chance(0.5) ? 1e-300 : logu(1e-300, 1e-9), extreme = 1;
        else if (r < 18) h = chance(0.5) ? 0.0 : -logu(1e-6, 10), extreme = 1;
        else if (r < 22) h = logu(1e16, 1e300) / per_time, extreme = 1;
        else if (r < 28 && m->has_stop && (m->stop - t) * per_time < 1e3)
            h = m->stop - t + (chance(0.5) ? 0 : logu(1e-9, 10));
        r = pick(100);
        if (r < 4 && slack(t) * per_time < 1) tc = t * (1 + urange(-5e-10, 5e-10));
        else if (r < 10) tc = chance(0.5) ? special() : t + (chance(0.5) ? 1 : -1) * logu(1e-6, 1e3), wrong_tc = 1;
    }
    double t_end = tc + h;
    int valid = isfinite(h) && h > 0 && fabs(tc - t) <= slack(t) && t_end > t &&
                (!m->has_stop || t_end <= m->stop + slack(m->stop));
    /* The FMU refuses a step that spans more than 3e4 shaker radians (time units when Omega < 1)
     * or ends more than 2^52 of them after the start time (fmi2DoStep). */
    double step_span = fabs((t_end - t) * w0) * fmax(m->val[iOmega], 1.0);
    double clock_span = fabs((t_end - m->start) * w0) * fmax(m->val[iOmega], 1.0);
    if (!(step_span <= 3e4 && clock_span < 0x1p52)) valid = 0;
    if (valid && step_span > 1e4) {
        /* Valid, but a fraction of a second of work: kept for the steps that are meant to be
         * long, replaced by an ordinary step otherwise to keep the campaign fast. */
        if (!extreme || chance(0.9)) {
            h = hmax, tc = t, t_end = tc + h, extreme = 0;
            valid = !m->has_stop || t_end <= m->stop + slack(m->stop);
        }
    }
    int allowed = m->life == L_STEP;
    cnt[N_STATE] += !allowed;
    cnt[N_STEP_EXTREME] += extreme;
    cnt[N_WRONG_TC] += wrong_tc;
    cnt[N_NANINF] += !isfinite(h) || !isfinite(tc);
    cnt[N_INVALID] += !valid;
    char what[200];
    snprintf(what, sizeof what, "fmi2DoStep(tc %.17g, h %.17g) at t %.17g", tc, h, t);
    /* External mode: the plate over a step is the degree-5 Taylor polynomial of the inputs, far
     * from the reference sinusoid once the step spans more than half a radian of it. */
    int wild_step = is_external(m) && !(h * m->ext_w <= 0.5);
    int e = !(valid && allowed) ? E_ERR : wild(m) || wild_step ? E_ANY : E_OK;
    if (getenv("FUZZ_SAVE_DIR") && allowed) {
        fmi2FMUstate snap = NULL;
        size_t n = 0;
        free(prestep);
        prestep = NULL;
        if (F.fmi2GetFMUstate(in->c, &snap) == fmi2OK &&
            F.fmi2SerializedFMUstateSize(in->c, snap, &n) == fmi2OK) {
            prestep = malloc(n);
            prestep_n = n;
            prestep_tc = tc, prestep_h = h;
            if (F.fmi2SerializeFMUstate(in->c, snap, (fmi2Byte *)prestep, n) != fmi2OK)
                free(prestep), prestep = NULL;
        }
        F.fmi2FreeFMUstate(in->c, &snap);
    }
    begin(in);
    snprintf(pending, sizeof pending, "I%d %s", (int)(in - I), what);
    fmi2Status s = F.fmi2DoStep(in->c, tc, h, pick(2));
    pending[0] = 0;
    expect(s, e, what);
    if (s != fmi2Error && (wild(m) || wild_step)) m->wild_init = 1;
    if (s == fmi2OK) {
        cnt[N_STEPS_OK]++;
        m->t = t_end;
        m->last_ok = t_end;
        m->derivs = 0;
        if (is_external(m)) m->ext_ok = 0;
    } else if (s == fmi2Discard) {
        cnt[N_DISCARD]++;
        fmi2Real lst = NAN;
        fmi2Boolean term = 0;
        begin(in);
        expect(F.fmi2GetRealStatus(in->c, fmi2LastSuccessfulTime, &lst), E_OK,
               "fmi2GetRealStatus(LastSuccessfulTime) after Discard");
        begin(in);
        expect(F.fmi2GetBooleanStatus(in->c, fmi2Terminated, &term), E_OK,
               "fmi2GetBooleanStatus(Terminated) after Discard");
        check(term == fmi2True, "Discard without fmi2Terminated");
        check(lst >= t - slack(t) && lst <= t_end + slack(t_end),
              "LastSuccessfulTime %.17g after Discard not in [%.17g, %.17g]", lst, t, t_end);
        m->life = L_FAILED;
        m->terminated = 1;
        m->t = m->last_ok = lst;
    } else if (s == fmi2Error && valid && allowed) {
        cnt[N_STEP_REFUSED_WILD]++;
        note("  refused (wild state): %s", log_msg);
    }
    observe(in, s == fmi2Error, what);
    return s;
}

static void act_step(Inst *in, int kind) {
    if (is_external(&in->m) && in->m.life == L_STEP && chance(0.9)) act_ext_inputs(in);
    do_step(in, kind);
}

static void act_input_derivatives(Inst *in) {
    Meta *m = &in->m;
    int n = chance(0.1) ? 0 : 1 + pick(4), valid = 1, nul = 0, naninf = 0, bad = 0, stored = 0;
    fmi2ValueReference rv[8];
    fmi2Integer ord[8];
    fmi2Real x[8];
    for (int j = 0; j < n; j++) {
        int r = pick(10);
        rv[j] = r < 4 ? vars[iZin].vr : r < 8 ? vars[iZdin].vr : any_vr(K_REAL, 0, &bad);
        ord[j] = chance(0.85) ? 1 + pick(5) : (fmi2Integer[]){0, -1, 6, 99, INT_MIN}[pick(5)];
        x[j] = chance(0.8) ? urange(-1, 1) * pow(10, pick(6) - 2) : special();
        int i = var_of(rv[j]);
        int shift = i == iZdin;
        naninf |= !isfinite(x[j]);
        valid &= (i == iZin || i == iZdin) && ord[j] >= 1 && ord[j] <= 5 - shift && isfinite(x[j]);
        stored |= ord[j] + shift >= 2;
    }
    const fmi2ValueReference *pv = rv;
    const fmi2Integer *po = ord;
    const fmi2Real *px = x;
    int r = pick(100);
    if (n > 0 && r < 3) pv = NULL, nul = 1;
    else if (n > 0 && r < 6) po = NULL, nul = 1;
    else if (n > 0 && r < 9) px = NULL, nul = 1;
    if (nul) valid = 0;
    int allowed = m->life >= L_INST && m->life <= L_STEP;
    cnt[N_STATE] += !allowed;
    cnt[N_NULL] += nul;
    cnt[N_NANINF] += naninf;
    cnt[N_BADVR] += bad;
    cnt[N_INVALID] += !valid;
    char what[120];
    snprintf(what, sizeof what, "fmi2SetRealInputDerivatives(n %d%s)", n, nul ? ", NULL array" : "");
    begin(in);
    fmi2Status s = F.fmi2SetRealInputDerivatives(in->c, pv, (size_t)n, po, px);
    if (expect(s, valid && allowed ? E_OK : E_ERR, what) && s == fmi2OK && stored) m->derivs = 2;
    observe(in, s != fmi2OK, what);
}

static void act_output_derivatives(Inst *in) {
    Meta *m = &in->m;
    int n = chance(0.1) ? 0 : 1 + pick(4), valid = 1, nul = 0, bad = 0;
    fmi2ValueReference rv[8];
    fmi2Integer ord[8];
    fmi2Real x[8];
    int four[4] = {iX, iVel, iZ, iZdot};
    for (int j = 0; j < n; j++) {
        rv[j] = chance(0.8) ? vars[four[pick(4)]].vr : any_vr(K_REAL, 0, &bad);
        ord[j] = chance(0.85) ? 1 : pick(4) - 1;
        int i = var_of(rv[j]);
        valid &= (i == iX || i == iVel || i == iZ || i == iZdot) && ord[j] == 1;
    }
    const fmi2ValueReference *pv = rv;
    const fmi2Integer *po = ord;
    fmi2Real *px = x;
    int r = pick(100);
    if (n > 0 && r < 3) pv = NULL, nul = 1;
    else if (n > 0 && r < 6) po = NULL, nul = 1;
    else if (n > 0 && r < 9) px = NULL, nul = 1;
    if (nul) valid = 0;
    int allowed = m->life >= L_STEP;
    cnt[N_STATE] += !allowed;
    cnt[N_NULL] += nul;
    cnt[N_BADVR] += bad;
    cnt[N_INVALID] += !valid;
    begin(in);
    fmi2Status s = F.fmi2GetRealOutputDerivatives(in->c, pv, (size_t)n, po, px);
    int e = !(allowed && m->has_model) ? E_ERR : !valid ? E_ERR : E_OK;
    if (expect(s, e, "fmi2GetRealOutputDerivatives") && s == fmi2OK && m->out_ok) {
        for (int j = 0; j < n; j++) {
            int i = var_of(rv[j]);
            check(isfinite(x[j]), "output derivative of %s not finite", vars[i].name);
            if (i == iX) check(x[j] == m->out[iVel], "dx/dt %.17g != v %.17g", x[j], m->out[iVel]);
            if (i == iZ) check(x[j] == m->out[iZdot], "dz/dt %.17g != zdot %.17g", x[j], m->out[iZdot]);
        }
    }
    observe(in, 1, "fmi2GetRealOutputDerivatives");
}

static void act_status(Inst *in) {
    Meta *m = &in->m;
    int which = pick(5), nul = chance(0.05);
    fmi2StatusKind kind = chance(0.85) ? pick(4) : (fmi2StatusKind[]){-1, 4, 99, INT_MAX}[pick(4)];
    int allowed = m->life == L_STEP || m->life == L_FAILED || m->life == L_TERM;
    int known = kind >= 0 && kind <= 3;
    cnt[N_STATE] += !allowed;
    cnt[N_NULL] += nul;
    cnt[N_INVALID] += !known || nul;
    fmi2Status st = -1;
    fmi2Real r = NAN;
    fmi2Integer iv = -1;
    fmi2Boolean b = -1;
    fmi2String sv = NULL;
    int e = !allowed || nul || !known ? E_ERR : E_DISCARD;
    if (which == 1 && kind == fmi2LastSuccessfulTime && e == E_DISCARD) e = E_OK;
    if (which == 3 && kind == fmi2Terminated && e == E_DISCARD) e = E_OK;
    static const char *fn[] = {"fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
                               "fmi2GetBooleanStatus", "fmi2GetStringStatus"};
    char what[100];
    snprintf(what, sizeof what, "%s(kind %d%s)", fn[which], kind, nul ? ", value NULL" : "");
    begin(in);
    fmi2Status s;
    switch (which) {
    case 0: s = F.fmi2GetStatus(in->c, kind, nul ? NULL : &st); break;
    case 1: s = F.fmi2GetRealStatus(in->c, kind, nul ? NULL : &r); break;
    case 2: s = F.fmi2GetIntegerStatus(in->c, kind, nul ? NULL : &iv); break;
    case 3: s = F.fmi2GetBooleanStatus(in->c, kind, nul ? NULL : &b); break;
    default: s = F.fmi2GetStringStatus(in->c, kind, nul ? NULL : &sv); break;
    }
    if (expect(s, e, what) && s == fmi2OK) {
        if (which == 1)
            check(bits(r) == bits(m->last_ok), "LastSuccessfulTime %.17g, expected %.17g", r,
                  m->last_ok);
        if (which == 3)
            check(b == (m->terminated ? fmi2True : fmi2False), "Terminated %d, expected %d", b,
                  m->terminated);
    }
    observe(in, 1, what);
}

static void act_misc(Inst *in) {
    Meta *m = &in->m;
    int r = pick(4);
    fmi2Status s;
    if (r == 0) {
        begin(in);
        s = F.fmi2CancelStep(in->c);
        expect(s, E_ERR, "fmi2CancelStep");
    } else if (r == 1) {
        fmi2ValueReference a = vars[iX].vr, b = vars[iZeta].vr;
        fmi2Real dv = 1, out = 0;
        int nul = chance(0.3);
        begin(in);
        s = F.fmi2GetDirectionalDerivative(in->c, nul ? NULL : &a, 1, nul ? NULL : &b, 1,
                                           nul ? NULL : &dv, nul ? NULL : &out);
        expect(s, E_ERR, "fmi2GetDirectionalDerivative");
    } else {
        static const char *cats[] = {"logEvents", "logStatusWarning", "logStatusDiscard",
                                     "logStatusError", "logStatusFatal", "logAll", "logNothing", NULL};
        const char *list[4];
        int n = chance(0.2) ? 0 : 1 + pick(3), valid = 1, nul = 0;
        for (int j = 0; j < n; j++) {
            list[j] = cats[chance(0.9) ? pick(6) : 6 + pick(2)];
            valid &= list[j] != NULL && strcmp(list[j], "logNothing") != 0;
        }
        int null_entry = 0;
        for (int j = 0; j < n; j++) null_entry |= list[j] == NULL;
        if (n > 0 && chance(0.05)) nul = 1, valid = 0;
        cnt[N_NULL] += nul || null_entry;
        cnt[N_INVALID] += !valid;
        fmi2Boolean on = chance(0.3);
        begin(in);
        s = F.fmi2SetDebugLogging(in->c, on, (size_t)n, nul ? NULL : list);
        expect(s, valid ? E_OK : E_ERR, "fmi2SetDebugLogging");
    }
    (void)m;
    observe(in, 1, "misc");
}

/* A NULL or bogus component for a random function: refused without touching memory. */
static void act_null_component(void) {
    fmi2Component c = chance(0.5) ? NULL : (fmi2Component)bogus;
    fmi2ValueReference r = 0;
    fmi2Real x = 0;
    fmi2Integer n = 0;
    fmi2Boolean b = 0;
    fmi2FMUstate st = NULL;
    size_t size = 0;
    unsigned char bytes[8] = {0};
    cnt[N_NULL]++;
    cnt[N_INVALID]++;
    int which = pick(20);
    begin(NULL);
    fmi2Status s;
    switch (which) {
    case 0: s = F.fmi2SetDebugLogging(c, 1, 0, NULL); break;
    case 1: s = F.fmi2SetupExperiment(c, 0, 0, 0, 0, 0); break;
    case 2: s = F.fmi2EnterInitializationMode(c); break;
    case 3: s = F.fmi2ExitInitializationMode(c); break;
    case 4: s = F.fmi2Terminate(c); break;
    case 5: s = F.fmi2Reset(c); break;
    case 6: s = F.fmi2GetReal(c, &r, 1, &x); break;
    case 7: s = F.fmi2SetInteger(c, &r, 1, &n); break;
    case 8: s = F.fmi2GetBoolean(c, &r, 1, &b); break;
    case 9: s = F.fmi2GetFMUstate(c, &st); break;
    case 10: s = F.fmi2SetFMUstate(c, st); break;
    case 11: s = F.fmi2FreeFMUstate(c, &st); break;
    case 12: s = F.fmi2SerializedFMUstateSize(c, st, &size); break;
    case 13: s = F.fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, 8, &st); break;
    case 14: s = F.fmi2DoStep(c, 0, 1, 0); break;
    case 15: s = F.fmi2CancelStep(c); break;
    case 16: s = F.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &x); break;
    case 17: s = F.fmi2SetRealInputDerivatives(c, &r, 1, &n, &x); break;
    case 18: s = F.fmi2GetRealOutputDerivatives(c, &r, 1, &n, &x); break;
    default:
        F.fmi2FreeInstance(c);
        note("fmi2FreeInstance(%s component)", c ? "bogus" : "NULL");
        return;
    }
    char what[80];
    snprintf(what, sizeof what, "function %d with a %s component", which, c ? "bogus" : "NULL");
    expect(s, E_ERR, what);
    check(st == NULL, "a state handle came back from a call on a non-instance");
}

/* ---- FMU states ---- */

/* A handle to pass: own live (mostly), NULL, stale, foreign, or a host pointer. Sets *own. */
static fmi2FMUstate any_handle(Inst *in, int *own, int *nul) {
    static int host_thing;
    *own = 0, *nul = 0;
    int r = pick(100);
    if (r < 70 && in->nst > 0) {
        *own = 1;
        return in->st[pick(in->nst)].h;
    }
    if (r < 78) {
        *nul = 1;
        return NULL;
    }
    if (r < 88 && in->nstale > 0) {
        /* A freed handle. If the FMU reused its address for a new state the entry was dropped
         * (hold): a host pointer stands in, refused the same way, so that a seed's sequence
         * does not depend on the allocator. */
        fmi2FMUstate h = in->stale[pick(in->nstale)];
        return h && held_index(in, h) < 0 ? h : (fmi2FMUstate)&host_thing;
    }
    Inst *other = &I[in == &I[0]];
    if (r < 95 && other->nst > 0) return other->st[pick(other->nst)].h;
    return &host_thing;
}

static void act_get_state(Inst *in) {
    Meta *m = &in->m;
    int r = pick(100), own = 0, nul = 0;
    fmi2FMUstate h = NULL;
    int slot_null = r < 5;
    if (r >= 5 && r < 30) h = any_handle(in, &own, &nul);
    int valid = !slot_null && (h == NULL || own);
    if (in->nst >= MAXST && h == NULL) {
        /* keep the pool bounded: overwrite instead */
        h = in->st[pick(in->nst)].h, own = 1, valid = !slot_null;
    }
    cnt[N_NULL] += slot_null;
    cnt[N_INVALID] += !valid;
    begin(in);
    fmi2FMUstate before = h;
    fmi2Status s = F.fmi2GetFMUstate(in->c, slot_null ? NULL : &h);
    char what[100];
    snprintf(what, sizeof what, "fmi2GetFMUstate(%s) -> %p", slot_null ? "NULL slot" : before ? "overwrite" : "new", h);
    if (expect(s, valid ? E_OK : E_ERR, what) && s == fmi2OK) {
        check(h != NULL && (before == NULL || h == before), "fmi2GetFMUstate handle %p (was %p)", h, before);
        observe(in, 1, what);
        hold(in, h, m);
        return;
    }
    if (s != fmi2OK) check(h == before, "refused fmi2GetFMUstate changed the handle");
    observe(in, 1, what);
}

static void act_set_state(Inst *in) {
    Meta *m = &in->m;
    int own = 0, nul = 0;
    fmi2FMUstate h = any_handle(in, &own, &nul);
    cnt[N_NULL] += nul;
    cnt[N_INVALID] += !own;
    begin(in);
    fmi2Status s = F.fmi2SetFMUstate(in->c, h);
    char what[80];
    snprintf(what, sizeof what, "fmi2SetFMUstate(%p%s)", h, own ? "" : ", not ours");
    if (expect(s, own ? E_OK : E_ERR, what) && s == fmi2OK) {
        const Meta *saved = &in->st[held_index(in, h)].m;
        double out[MAXV];
        int had = saved->out_ok;
        memcpy(out, saved->out, sizeof out);
        *m = *saved;
        m->out_ok = 0;
        in->count_floor = 0;
        observe(in, 0, what);
        if (had && m->out_ok)
            check(same_outputs(out, m->out), "outputs after fmi2SetFMUstate differ from those when the state was taken");
        return;
    }
    observe(in, 1, what);
}

static void act_free_state(Inst *in) {
    int own = 0, nul = 0, slot_null = chance(0.05);
    fmi2FMUstate h = any_handle(in, &own, &nul);
    int valid = !slot_null && (own || h == NULL);
    cnt[N_NULL] += slot_null || nul;
    cnt[N_INVALID] += !valid;
    fmi2FMUstate before = h;
    begin(in);
    fmi2Status s = F.fmi2FreeFMUstate(in->c, slot_null ? NULL : &h);
    char what[80];
    snprintf(what, sizeof what, "fmi2FreeFMUstate(%p%s)", before, slot_null ? ", NULL slot" : "");
    if (expect(s, valid ? E_OK : E_ERR, what) && s == fmi2OK) {
        check(h == NULL, "fmi2FreeFMUstate did not clear the handle");
        int k = held_index(in, before);
        if (k >= 0) unhold(in, k);
    } else if (s != fmi2OK) {
        check(h == before, "refused fmi2FreeFMUstate changed the handle");
    }
    observe(in, 1, what);
}

/* fmi2SerializedFMUstateSize / fmi2SerializeFMUstate with a NULL, freed, foreign or host handle,
 * or a NULL size pointer: refused. */
static void act_serialize_bad(Inst *in) {
    int own = 0, nul = 0;
    fmi2FMUstate h = any_handle(in, &own, &nul);
    size_t size = 0;
    unsigned char buf[4096];
    int null_size = own && chance(0.5);
    cnt[N_NULL] += nul || null_size;
    cnt[N_INVALID] += !own || null_size;
    begin(in);
    fmi2Status s = F.fmi2SerializedFMUstateSize(in->c, h, null_size ? NULL : &size);
    expect(s, own && !null_size ? E_OK : E_ERR, "fmi2SerializedFMUstateSize(any handle)");
    if (!own) {
        begin(in);
        expect(F.fmi2SerializeFMUstate(in->c, h, (fmi2Byte *)buf, sizeof buf), E_ERR,
               "fmi2SerializeFMUstate(not our handle)");
    }
    observe(in, 1, "fmi2SerializedFMUstateSize");
}

/* Serializes a held state into a new buffer of the pool; returns its index or -1. */
static int serialize(Inst *in, int k) {
    size_t size = 0;
    begin(in);
    if (!expect(F.fmi2SerializedFMUstateSize(in->c, in->st[k].h, &size), E_OK,
                "fmi2SerializedFMUstateSize"))
        return -1;
    check(size > 100 && size < 100000, "serialized size %zu", size);
    unsigned char *b = malloc(size + 16);
    if (chance(0.2)) {
        /* too small, NULL buffer: refused */
        begin(in);
        expect(F.fmi2SerializeFMUstate(in->c, in->st[k].h, (fmi2Byte *)b, size - 1 - (size_t)pick(8)),
               E_ERR, "fmi2SerializeFMUstate(buffer too small)");
        begin(in);
        expect(F.fmi2SerializeFMUstate(in->c, in->st[k].h, NULL, size), E_ERR,
               "fmi2SerializeFMUstate(NULL buffer)");
        cnt[N_INVALID] += 2;
        cnt[N_NULL]++;
    }
    size_t given = chance(0.8) ? size : size + (size_t)pick(16);
    begin(in);
    if (!expect(F.fmi2SerializeFMUstate(in->c, in->st[k].h, (fmi2Byte *)b, given), E_OK,
                "fmi2SerializeFMUstate")) {
        free(b);
        return -1;
    }
    int j = nbuf < MAXBUF ? nbuf++ : pick(MAXBUF);
    free(bufs[j].b);
    bufs[j].b = b;
    bufs[j].n = size;
    bufs[j].m = in->st[k].m;
    return j;
}

/* Deserializes `n` bytes into instance `in` (new handle or overwriting one of ours), expecting
 * `e`; returns the handle or NULL. */
static fmi2FMUstate deserialize(Inst *in, const unsigned char *b, size_t n, int e, const char *what) {
    fmi2FMUstate h = NULL;
    int overwrite = in->nst > 0 && chance(0.2);
    if (overwrite) h = in->st[pick(in->nst)].h;
    if (!overwrite && in->nst >= MAXST) return NULL;
    fmi2FMUstate before = h;
    begin(in);
    fmi2Status s = F.fmi2DeSerializeFMUstate(in->c, (const fmi2Byte *)b, n, &h);
    if (!expect(s, e, what)) return NULL;
    if (s != fmi2OK) {
        check(h == before, "refused fmi2DeSerializeFMUstate changed the handle");
        observe(in, 1, what);
        return NULL;
    }
    check(h != NULL && (!before || h == before), "deserialized handle %p (was %p)", h, before);
    observe(in, 1, what);
    return h;
}

/* Rollback: take a state, step, restore (handle / bytes / other instance), step again: the two
 * steps must agree bit for bit. */
static void act_rollback(Inst *in) {
    Meta *m = &in->m;
    if (m->life != L_STEP || in->nst >= MAXST - 1) return;
    fmi2FMUstate h = NULL;
    begin(in);
    if (!expect(F.fmi2GetFMUstate(in->c, &h), wild(m) ? E_OK_ERR : E_OK, "fmi2GetFMUstate(rollback)") || !h)
        return;
    observe(in, 1, "fmi2GetFMUstate(rollback)");
    hold(in, h, m);
    Meta saved = *m;
    int ext = is_external(m) && chance(0.9) && act_ext_inputs(in);
    Meta pre = *m;
    fmi2Status s1 = do_step(in, 0);
    double out1[MAXV];
    memcpy(out1, m->out, sizeof out1);
    int ok1 = m->out_ok;
    Meta after1 = *m;

    int how = pick(3); /* 0 handle, 1 bytes into this instance, 2 bytes into the other one */
    Inst *target = in;
    fmi2FMUstate restore = h;
    int k = held_index(in, h);
    if (how > 0) {
        int j = serialize(in, k);
        if (j < 0) return;
        if (how == 2) {
            Inst *o = &I[in == &I[0]];
            if (o->c && o->nst < MAXST - 1) target = o;
        }
        restore = deserialize(target, bufs[j].b, bufs[j].n, E_OK, "fmi2DeSerializeFMUstate(round trip)");
        if (!restore) return;
        hold(target, restore, &saved);
        cnt[target == in ? N_ROUNDTRIP : N_CROSS]++;
    } else {
        cnt[N_ROLLBACK]++;
    }
    begin(target);
    if (!expect(F.fmi2SetFMUstate(target->c, restore), E_OK, "fmi2SetFMUstate(rollback)")) return;
    Meta *tm = &target->m;
    *tm = saved;
    tm->out_ok = 0;
    target->count_floor = 0;
    observe(target, 0, "fmi2SetFMUstate(rollback)");
    if (saved.out_ok && tm->out_ok)
        check(same_outputs(saved.out, tm->out), "outputs after restore differ from those when the state was taken");
    if (ext) {
        /* the same inputs as for the first step */
        fmi2ValueReference zv[2] = {vars[iZin].vr, vars[iZdin].vr};
        fmi2Real z[2] = {pre.val[iZin], pre.val[iZdin]};
        begin(target);
        expect(F.fmi2SetReal(target->c, zv, 2, z), E_OK, "fmi2SetReal(same inputs)");
        double a = pre.ext_a, w = pre.ext_w, t = pre.t;
        fmi2ValueReference dv[4] = {zv[0], zv[0], zv[0], zv[0]};
        fmi2Integer ord[4] = {2, 3, 4, 5};
        fmi2Real d[4];
        for (int j = 0; j < 4; j++) d[j] = a * pow(w, j + 2) * sin(w * t + (j + 2) * M_PI / 2);
        begin(target);
        expect(F.fmi2SetRealInputDerivatives(target->c, dv, 4, ord, d), E_OK, "fmi2SetRealInputDerivatives(same)");
        *tm = pre;
        tm->out_ok = 0;
    }
    double h1 = after1.t - pre.t;
    char what[160];
    snprintf(what, sizeof what, "fmi2DoStep(repeat, tc %.17g, h %.17g)", pre.t, h1);
    begin(target);
    fmi2Status s2 = F.fmi2DoStep(target->c, pre.t, h1, fmi2False);
    expect(s2, s1 == fmi2OK ? E_OK : E_ANY, what);
    check(s1 == s2 || s1 != fmi2OK, "repeated step returned %s, the first %s", st_name(s2), st_name(s1));
    if (s2 != fmi2Error && wild(tm)) tm->wild_init = 1;
    if (s2 == fmi2OK) {
        tm->t = tm->last_ok = after1.t;
        tm->derivs = 0;
        if (is_external(tm)) tm->ext_ok = 0;
    } else if (s2 == fmi2Discard) {
        tm->life = L_FAILED;
        tm->terminated = 1;
        fmi2Real lst = NAN;
        F.fmi2GetRealStatus(target->c, fmi2LastSuccessfulTime, &lst);
        tm->t = tm->last_ok = lst;
    }
    observe(target, 0, what);
    if (s1 == fmi2OK && s2 == fmi2OK && ok1 && tm->out_ok)
        check(same_outputs(out1, tm->out), "the step repeated after a restore differs from the first in %s (x %.17g vs %.17g)", differs,
              tm->out[iX], out1[iX]);
}

/* Serialized-state layout offsets (see fmu/src/state.rs). */
typedef struct {
    size_t life, vals, inputs[6], start, stop_tag, last, term, model_tag, model, end;
    int has_model, has_stop;
} Layout;

static double rdf(const unsigned char *p) {
    double v;
    memcpy(&v, p, 8);
    return v;
}
static void wrf(unsigned char *p, double v) { memcpy(p, &v, 8); }

static int layout(const unsigned char *b, size_t n, Layout *L) {
    if (n < 40) return 0;
    uint32_t g;
    memcpy(&g, b + 20, 4);
    size_t p = 24 + g;
    /* interface byte, FMI version byte (0: 2.0), lifecycle byte, u32 count, values */
    if (p + 7 + 8 * (size_t)nv >= n || b[p + 1] != 0) return 0;
    L->life = p + 2;
    L->vals = p + 7;
    p = L->vals + 8 * (size_t)nv;
    for (int k = 0; k < 6; k++) {
        if (p >= n) return 0;
        L->inputs[k] = p;
        p += b[p] ? 9 : 1;
    }
    L->start = p;
    p += 8;
    if (p >= n) return 0;
    L->stop_tag = p;
    L->has_stop = b[p];
    p += b[p] ? 9 : 1;
    L->last = p;
    p += 8;
    L->term = p++;
    L->model_tag = p;
    if (p >= n) return 0;
    L->has_model = b[p];
    L->model = p + 1;
    /* A co-simulation state ends with the model's at-event flag and the absent Model Exchange part
       (tag 0) before the checksum; `end` is the end of the model's time field. */
    L->end = n - 10;
    return L->model <= L->end && b[n - 9] == 0;
}

static uint64_t fnv(const unsigned char *b, size_t n) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t k = 0; k < n; k++) h = (h ^ b[k]) * 0x100000001b3ULL;
    return h;
}

/* Patches the declared length and the checksum of a buffer of n bytes. */
static void fix_up(unsigned char *b, size_t n) {
    uint64_t total = n;
    memcpy(b + 12, &total, 8);
    uint64_t sum = fnv(b, n - 8);
    memcpy(b + n - 8, &sum, 8);
}

/* What the host learns from an accepted crafted buffer. */
static void meta_from_bytes(const unsigned char *b, size_t n, Meta *m) {
    Layout L;
    meta_reset(m);
    m->crafted = 1;
    if (!layout(b, n, &L)) return;
    static const int lives[] = {L_INST, L_INIT, L_STEP, L_FAILED, L_TERM, L_ERROR};
    m->life = b[L.life] < 6 ? lives[b[L.life]] : L_ERROR;
    for (int i = 0; i < nv; i++) m->val[i] = rdf(b + L.vals + 8 * (size_t)i);
    for (int k = 0; k < 6; k++)
        if (b[L.inputs[k]]) m->derivs = 2;
    m->start = rdf(b + L.start);
    m->has_stop = L.has_stop;
    if (L.has_stop) m->stop = rdf(b + L.stop_tag + 1);
    m->last_ok = rdf(b + L.last);
    m->terminated = b[L.term] == 1;
    m->has_model = L.has_model;
    /* A running model is at the last successful time (the FMU checks it). */
    m->t = L.has_model ? m->last_ok : m->start;
}

static void act_buffers(Inst *in) {
    /* Make sure there is a buffer to work on. */
    if (nbuf == 0 || chance(0.2)) {
        if (in->nst == 0 || chance(0.3)) {
            fmi2FMUstate h = NULL;
            if (in->nst >= MAXST) return;
            begin(in);
            if (!expect(F.fmi2GetFMUstate(in->c, &h), wild(&in->m) ? E_OK_ERR : E_OK, "fmi2GetFMUstate(for bytes)") || !h)
                return;
            observe(in, 1, "fmi2GetFMUstate(for bytes)");
            hold(in, h, &in->m);
        }
        if (serialize(in, pick(in->nst)) < 0) return;
    }
    Buf *src = &bufs[pick(nbuf)];
    size_t n = src->n;
    unsigned char *b = malloc(2 * n + 64);
    memcpy(b, src->b, n);
    int r = pick(100), e = E_ERR, crafted = 0;
    char what[200];
    if (in->nst >= MAXST) {
        free(b);
        return;
    }
    if (r < 25) {
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(exact copy, %zu bytes)", n);
        e = E_OK;
    } else if (r < 35) {
        size_t cut = (size_t)pick((int)n);
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(truncated to %zu of %zu)", cut, n);
        n = cut;
        cnt[N_CORRUPT]++;
    } else if (r < 40) {
        size_t extra = 1 + (size_t)pick(32);
        for (size_t k = 0; k < extra; k++) b[n + k] = (unsigned char)rnd();
        n += extra;
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(%zu extra bytes)", extra);
        cnt[N_CORRUPT]++;
    } else if (r < 52) {
        int flips = 1 + pick(8);
        for (int k = 0; k < flips; k++) b[pick((int)n)] ^= (unsigned char)(1u << pick(8));
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(%d bit flips)", flips);
        if (memcmp(b, src->b, n) == 0) e = E_OK; /* the flips cancelled out */
        else cnt[N_CORRUPT]++;
    } else if (r < 57) {
        n = (size_t)pick(2 * (int)n);
        for (size_t k = 0; k < n; k++) b[k] = (unsigned char)rnd();
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(%zu random bytes)", n);
        cnt[N_CORRUPT]++;
    } else if (r < 60) {
        int z = pick(3);
        const unsigned char *p = z == 0 ? NULL : b;
        size_t len = z == 0 ? n : z == 1 ? 0 : (size_t)1 << 40;
        cnt[N_NULL] += z == 0;
        cnt[N_CORRUPT]++;
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(%s)", z == 0 ? "NULL bytes" : z == 1 ? "0 bytes" : "2^40 bytes");
        fmi2FMUstate h = NULL;
        begin(in);
        expect(F.fmi2DeSerializeFMUstate(in->c, (const fmi2Byte *)p, len, chance(0.2) ? NULL : &h), E_ERR, what);
        check(h == NULL, "a state came from refused bytes");
        observe(in, 1, what);
        free(b);
        return;
    } else {
        /* crafted: one field mutated, length and checksum recomputed */
        Layout L;
        crafted = 1;
        cnt[N_CRAFTED]++;
        e = E_OK_ERR;
        if (!layout(b, n, &L)) {
            free(b);
            return;
        }
        int kind = pick(12);
        double x = chance(0.5) ? special() : urange(-10, 10) * pow(10, pick(20) - 10);
        int must_fail = 0;
        const char *field = "?";
        switch (kind) {
        case 0: {
            int life = pick(10);
            b[L.life] = (unsigned char)life;
            /* 6, 7: Model Exchange states; 8, 9: unknown */
            must_fail = life >= 6 || (!L.has_model && life >= 2 && life <= 4);
            field = "lifecycle";
            break;
        }
        case 1: {
            int i = pick(nv);
            if (chance(0.5)) x = vars[i].caus == C_OUTPUT ? x : urange(vars[i].min, fmin(vars[i].max, 1e12));
            wrf(b + L.vals + 8 * (size_t)i, x);
            must_fail = !isfinite(x) || (vars[i].caus != C_OUTPUT && (x < vars[i].min || x > vars[i].max)) ||
                        (vars[i].kind != K_REAL && x != floor(x));
            field = vars[i].name;
            break;
        }
        case 2: wrf(b + L.start, x), must_fail = !isfinite(x), field = "start time"; break;
        case 3: wrf(b + L.last, x), must_fail = !isfinite(x), field = "last successful time"; break;
        case 4:
            if (!L.has_stop) { free(b); return; }
            wrf(b + L.stop_tag + 1, x), must_fail = !isfinite(x), field = "stop time";
            break;
        case 5: {
            unsigned v = (unsigned)pick(256);
            b[L.term] = (unsigned char)v;
            must_fail = v > 1;
            field = "terminated";
            break;
        }
        case 6: {
            int k = pick(6);
            if (b[L.inputs[k]]) wrf(b + L.inputs[k] + 1, x), must_fail = !isfinite(x);
            else b[L.inputs[k]] = (unsigned char)(2 + pick(254)), must_fail = 1;
            field = "input derivative";
            break;
        }
        case 7:
            if (!L.has_model) { free(b); return; }
            wrf(b + L.end - 8, x), must_fail = !isfinite(x), field = "model time";
            break;
        case 8: case 9: {
            if (!L.has_model || L.end - L.model < 16) { free(b); return; }
            size_t at = L.model + (size_t)pick((int)(L.end - L.model - 8));
            if (kind == 8) wrf(b + at, x);
            else b[at] = (unsigned char)rnd();
            field = kind == 8 ? "model f64" : "model byte";
            break;
        }
        case 10: {
            unsigned char v = (unsigned char)(chance(0.5) ? 0 : 2 + pick(254));
            if (!L.has_model && v == 0) { free(b); return; }
            b[L.model_tag] = v;
            must_fail = 1;
            field = "model tag";
            break;
        }
        default: {
            size_t from = L.life + (size_t)pick((int)(L.end - L.life));
            int len = 1 + pick(16);
            for (int k = 0; k < len && from + (size_t)k < L.end; k++) b[from + (size_t)k] = (unsigned char)rnd();
            field = "random body bytes";
            break;
        }
        }
        fix_up(b, n);
        if (must_fail) e = E_ERR;
        snprintf(what, sizeof what, "fmi2DeSerializeFMUstate(crafted %s = %.6g%s)", field, x,
                 must_fail ? ", invalid" : "");
    }
    Inst *target = chance(0.8) ? in : &I[in == &I[0]];
    if (!target->c || target->nst >= MAXST) target = in;
    fmi2FMUstate h = deserialize(target, b, n, e, what);
    if (h) {
        Meta m;
        if (crafted) {
            cnt[N_CRAFTED_OK]++;
            if (getenv("FUZZ_SAVE_DIR")) {
                /* accepted crafted buffers, for regression tests */
                char path[512];
                snprintf(path, sizeof path, "%s/crafted-%lu-%ld.bin", getenv("FUZZ_SAVE_DIR"), seed_now, call_now);
                FILE *f = fopen(path, "wb");
                if (f) fwrite(b, 1, n, f), fclose(f);
            }
            meta_from_bytes(b, n, &m);
        } else {
            m = src->m;
        }
        hold(target, h, &m);
        if (crafted || chance(0.5)) {
            /* use it: the restored instance must satisfy every invariant */
            begin(target);
            if (expect(F.fmi2SetFMUstate(target->c, h), E_OK, "fmi2SetFMUstate(deserialized)")) {
                Meta saved = target->st[held_index(target, h)].m;
                target->m = saved;
                target->m.out_ok = 0;
                target->count_floor = 0;
                observe(target, 0, "fmi2SetFMUstate(deserialized)");
                if (saved.out_ok && target->m.out_ok)
                    check(same_outputs(saved.out, target->m.out), "outputs after deserialize + set differ from those when the state was taken");
                if (crafted && target->m.life == L_STEP) do_step(target, 0);
            }
        }
    }
    free(b);
}

/* ---- the driver ---- */
static void act(void) {
    int k = chance(0.85) ? 0 : 1;
    Inst *in = &I[k];
    if (!in->c) {
        if (k == 1 && chance(0.7)) return;
        if (chance(0.1)) instantiate(k, 0);
        else instantiate(k, 1);
        return;
    }
    int life = in->m.life;
    if (chance(0.02)) {
        act_null_component();
        return;
    }
    if (chance(0.003)) {
        free_instance(k);
        cnt[N_REINST]++;
        return;
    }
    int r = pick(1000);
    /* mostly what the state calls for, sometimes anything */
    if (r < 850) {
        switch (life) {
        case L_INST:
            if (r < 300) act_sane_config(in);
            else if (r < 420) act_setup(in);
            else if (r < 650) act_enter(in);
            else if (r < 750) act_set(in, pick(4));
            else act_reset(in);
            return;
        case L_INIT:
            if (r < 250) act_sane_config(in);
            else if (r < 300) act_ext_inputs(in);
            else if (r < 650) act_exit(in);
            else if (r < 800) act_set(in, pick(4));
            else act_get(in, pick(4));
            return;
        case L_STEP:
            if (r < 450) act_step(in, r < 380 ? 0 : 1);
            else if (r < 520) act_rollback(in);
            else if (r < 570) act_set(in, pick(4));
            else if (r < 640) act_get(in, pick(4));
            else if (r < 700) act_buffers(in);
            else if (r < 720) act_get_state(in);
            else if (r < 740) act_set_state(in);
            else if (r < 755) act_free_state(in);
            else if (r < 760) act_serialize_bad(in);
            else if (r < 780) act_status(in);
            else if (r < 800) act_output_derivatives(in);
            else if (r < 815) act_input_derivatives(in);
            else if (r < 825) act_terminate(in);
            else act_reset(in);
            return;
        default:
            if (r < 300) act_reset(in);
            else if (r < 450) act_get(in, pick(4));
            else if (r < 550) act_status(in);
            else if (r < 650) act_set_state(in);
            else if (r < 750) act_buffers(in);
            else act_step(in, 1);
            return;
        }
    }
    switch (pick(22)) {
    case 0: act_setup(in); break;
    case 1: act_enter(in); break;
    case 2: act_exit(in); break;
    case 3: act_terminate(in); break;
    case 4: act_reset(in); break;
    case 5: act_set(in, pick(4)); break;
    case 6: act_get(in, pick(4)); break;
    case 7: act_step(in, 1); break;
    case 8: act_input_derivatives(in); break;
    case 9: act_output_derivatives(in); break;
    case 10: act_status(in); break;
    case 11: act_misc(in); break;
    case 12: act_get_state(in); break;
    case 13: act_set_state(in); break;
    case 14: act_free_state(in); break;
    case 15: act_buffers(in); break;
    case 16: act_rollback(in); break;
    case 17: act_sane_config(in); break;
    case 18: act_ext_inputs(in); break;
    case 19: act_null_component(); break;
    case 20: act_misc(in); break;
    default: act_step(in, 1); break;
    }
}

/* ---- Model Exchange sequences ----
 * One ME instance per seed driven through random legal and illegal calls: parameters (sane or
 * random, in or out of range), initialization, integration chunks by the host's ME driver (RK4 +
 * bisection, me.c) with random step sizes, random calls in any state with random arguments
 * (NaN/inf times and states, NULL pointers, wrong array lengths), event modes entered at random
 * times, FMU states taken, restored and serialized, terminate and reset. Oracle: the FMI 2.0 ME
 * table of allowed calls (an illegal call or bad argument is fmi2Error with a logged reason and
 * leaves the continuous states and counters bit for bit), and after every call in a readable state:
 * finite states, indicators and derivatives, impact and snap-through counts that never decrease
 * along a run, after an event mode the mass not below the plate (beyond 1e-9 relative) and the
 * well on the side of the barrier the mass is on, a restored FMU state giving back its states and
 * counts bit for bit. */
enum { M_NONE, M_INST, M_INIT, M_EVENT, M_CONT, M_TERM };
static const char *me_life[] = {"none", "Instantiated", "InitializationMode", "EventMode",
                                "ContinuousTimeMode", "Terminated"};

typedef struct {
    fmi2Component c;
    int life;
    double t, next;     /* time, next time event */
    double event_t;     /* time of the last event mode: SetTime may not go before it */
    int wild;           /* a random (possibly extreme) parameter value was accepted */
    int count, snaps;   /* counters seen last (never decrease along a run) */
    fmi2FMUstate held;  /* one FMU state and what it held */
    int held_life, held_wild;
    double held_x[2], held_t;
    int held_count;
} MeInst;

static MeInst M;

/* Expected status of an ME call: OK if allowed in the oracle's state and `valid`, else Error. */
static void me_expect(fmi2Status s, int allowed_mask, int valid, const char *what) {
    int allowed = (allowed_mask >> M.life) & 1;
    int want_ok = allowed && valid;
    if (!allowed) cnt[N_STATE]++;
    else if (!valid) cnt[N_INVALID]++;
    check(s == (want_ok ? fmi2OK : fmi2Error), "ME %s in %s: status %d, expected %s", what,
          me_life[M.life], s, want_ok ? "OK" : "Error");
}

#define ME_BIT(l) (1 << (l))
#define ME_RUN (ME_BIT(M_EVENT) | ME_BIT(M_CONT))
#define ME_READ (ME_BIT(M_INIT) | ME_RUN | ME_BIT(M_TERM))

static int me_int(const char *name) {
    fmi2ValueReference r = vr(name);
    fmi2Integer n = -1;
    F.fmi2GetInteger(M.c, &r, 1, &n);
    return n;
}

static double me_real(const char *name) {
    fmi2ValueReference r = vr(name);
    fmi2Real x = NAN;
    F.fmi2GetReal(M.c, &r, 1, &x);
    return x;
}

/* The invariants of a readable instance; `settled`: just after an event mode. */
static void me_observe(int settled) {
    /* Initialization mode: the readers build the model from the parameters and refuse invalid
     * ones (as the co-simulation outputs do). */
    if (!((ME_READ >> M.life) & 1) || M.life == M_INIT) return;
    double x[2] = {NAN, NAN}, z[2] = {NAN, NAN}, d[2] = {NAN, NAN};
    /* Extreme parameters may overflow the derivatives or indicators: then only the calls. */
    int sane = !M.wild;
    check(F.fmi2GetContinuousStates(M.c, x, 2) == fmi2OK && (!sane || (isfinite(x[0]) && isfinite(x[1]))),
          "ME states readable and finite");
    check(F.fmi2GetEventIndicators(M.c, z, 2) == fmi2OK && (!sane || (isfinite(z[0]) && isfinite(z[1]))),
          "ME event indicators readable and finite");
    check(F.fmi2GetDerivatives(M.c, d, 2) == fmi2OK && (!sane || (isfinite(d[0]) && isfinite(d[1]))),
          "ME derivatives readable and finite");
    int n = me_int("impact_count"), sn = me_int("snap_through_count");
    check(n >= M.count && sn >= M.snaps, "ME counts never decrease (%d after %d)", n, M.count);
    if (!sane) return;
    M.count = n, M.snaps = sn;
    if (settled && M.life != M_INIT) {
        double zp = me_real("z"), dx = me_real("delta_x");
        int contact = 0;
        fmi2ValueReference r = vr("in_contact");
        F.fmi2GetBoolean(M.c, &r, 1, &contact);
        double scale = fmax(dx, fmax(fabs(x[0]), fabs(zp)));
        check(contact || x[0] - zp >= -1e-9 * scale, "ME mass above the plate after an event "
              "(x - z = %g)", x[0] - zp);
        int well = me_int("well");
        check(fabs(x[0] - dx / 2) < 1e-9 * scale || well == (x[0] < dx / 2 ? 1 : 2),
              "ME well %d agrees with x = %g", well, x[0]);
    }
    mix(bits(x[0])), mix(bits(x[1])), mix((uint64_t)n);
}

/* Sane parameters (Instantiated or initialization mode): moderate shaker, the paper's start. */
static void me_sane(void) {
    fmi2ValueReference r[4] = {vr("Omega"), vr("V"), vr("e"), vr("zeta")};
    fmi2Real v[4] = {logu(0.2, 5), logu(0.01, 0.3), urange(0, 1), logu(1e-3, 0.5)};
    check(F.fmi2SetReal(M.c, r, 4, v) == fmi2OK, "ME sane parameters accepted");
}

static void me_start(void) {
    M = (MeInst){0};
    M.c = F.fmi2Instantiate("mefuzz", fmi2ModelExchange, guid, NULL, &cb_with_logger[0], fmi2False,
                            chance(0.5));
    check(M.c != NULL, "ME instantiate");
    M.life = M.c ? M_INST : M_NONE;
    M.next = INFINITY;
}

static void me_act(void) {
    cnt[N_CALLS]++;
    double x[2], z[2], before[2] = {NAN, NAN}, after[2] = {NAN, NAN};
    int readable = (ME_READ >> M.life) & 1;
    int count_before = readable ? me_int("impact_count") : -1;
    if (readable) F.fmi2GetContinuousStates(M.c, before, 2);
    int refusal = 0; /* the call is expected to be refused: states must not change */
    fmi2Status s;
    switch (pick(16)) {
    case 0: /* parameters */
        if (M.life <= M_INIT && chance(0.7)) {
            me_sane();
        } else {
            int naninf = 0, i = pick(nv);
            double val = any_value(&I[0].m, i, &naninf);
            fmi2ValueReference r = vars[i].vr;
            if (vars[i].kind == K_REAL) s = F.fmi2SetReal(M.c, &r, 1, &val);
            else { fmi2Integer iv = (fmi2Integer)val; s = F.fmi2SetInteger(M.c, &r, 1, &iv); }
            refusal = s != fmi2OK;
            if (naninf) cnt[N_NANINF]++;
            if (s == fmi2OK) M.wild = 1;
            check(s == fmi2OK || s == fmi2Error, "ME set: status %d", s);
        }
        break;
    case 1:
        s = F.fmi2SetupExperiment(M.c, fmi2False, 0, 0.0, fmi2False, 0);
        me_expect(s, ME_BIT(M_INST), 1, "fmi2SetupExperiment");
        refusal = s != fmi2OK;
        break;
    case 2:
        s = F.fmi2EnterInitializationMode(M.c);
        me_expect(s, ME_BIT(M_INST), 1, "fmi2EnterInitializationMode");
        if (s == fmi2OK) M.life = M_INIT;
        refusal = s != fmi2OK;
        break;
    case 3:
        if (M.life == M_INIT && chance(0.8)) me_sane();
        s = F.fmi2ExitInitializationMode(M.c);
        check(s == fmi2OK || s == fmi2Error, "ME exit initialization: status %d", s);
        if (M.life != M_INIT) check(s == fmi2Error, "ME exit initialization outside it refused");
        if (s == fmi2OK) {
            M.life = M_EVENT, M.t = M.event_t = 0;
            check(me_settle(M.c, &M.next) == 0, "ME first event update");
            M.life = M_CONT;
            me_observe(1);
        }
        break;
    case 4: case 5: case 6: /* integrate a chunk */
        if (M.life == M_CONT) {
            long events = 0;
            double h = logu(1e-4, 0.05), t_end = M.t + h * (1 + pick(40));
            snprintf(pending, sizeof pending,
                     "ME driver run from t %.17g to %.17g, h %.17g, next time event %.17g", M.t,
                     t_end, h, M.next);
            int rc = me_run(M.c, M.t, t_end, h, M.next, &events);
            pending[0] = 0;
            note("ME driver run from t %.17g to %.17g, h %.17g: %s, %ld event modes", M.t, t_end, h,
                 rc == 0 ? "OK" : "refused", events);
            /* Even with extreme parameters an event update must announce a later time event. */
            if (rc == ME_NO_PROGRESS)
                check(0, "ME driver: an event update at t = %.17g s announced a time event not "
                      "after it (the host would step by 0 for ever)", me_real("time"));
            int ok = rc == 0;
            check(ok || M.wild, "ME driver run to %g (sane parameters)", t_end);
            if (!ok) { /* extreme parameters: a refused call ends the run, the instance stays usable */
                double now_x[2];
                check(F.fmi2GetContinuousStates(M.c, now_x, 2) == fmi2OK, "ME usable after a refusal");
                F.fmi2SetTime(M.c, M.t); /* back to a time the oracle knows (or refused: stays) */
                break;
            }
            M.t = t_end;
            cnt[N_STEPS_OK]++;
            /* Settle at the end of the run (the driver's last event may lie before it). */
            if (F.fmi2EnterEventMode(M.c) == fmi2OK) {
                M.life = M_EVENT, M.event_t = M.t;
                check(me_settle(M.c, &M.next) == 0, "ME event update after a run");
                M.life = M_CONT;
            }
            me_observe(1);
        }
        break;
    case 7:
        s = F.fmi2EnterEventMode(M.c);
        me_expect(s, ME_RUN, 1, "fmi2EnterEventMode");
        if (s == fmi2OK) M.life = M_EVENT, M.event_t = M.t;
        refusal = s != fmi2OK;
        break;
    case 8: {
        fmi2EventInfo info;
        int null = chance(0.1);
        s = F.fmi2NewDiscreteStates(M.c, null ? NULL : &info);
        me_expect(s, ME_BIT(M_EVENT), !null, "fmi2NewDiscreteStates");
        if (s == fmi2OK) {
            check(!info.newDiscreteStatesNeeded && !info.terminateSimulation,
                  "ME one event update settles the instant");
            M.next = info.nextEventTimeDefined ? info.nextEventTime : INFINITY;
            me_observe(1);
        } else {
            refusal = 1;
        }
        break;
    }
    case 9:
        s = F.fmi2EnterContinuousTimeMode(M.c);
        me_expect(s, ME_BIT(M_EVENT), 1, "fmi2EnterContinuousTimeMode");
        if (s == fmi2OK) M.life = M_CONT;
        refusal = s != fmi2OK;
        break;
    case 10: { /* time: now, before the last event, not finite, or far ahead */
        int kind = pick(3);
        double t = kind == 0 ? M.t : kind == 1 ? M.event_t - logu(1e-3, 10) : special();
        if (kind == 2) cnt[N_NANINF]++;
        s = F.fmi2SetTime(M.c, t);
        if (((ME_RUN >> M.life) & 1) && (M.wild || (isfinite(t) && t >= M.event_t && t > M.t + 1e3)))
            check(s == fmi2OK || s == fmi2Error, "ME set time far ahead: status %d", s);
        else
            /* Times within rounding (1e-9 relative) before the last event are accepted. */
            me_expect(s, ME_RUN, isfinite(t) && t >= M.event_t - slack(M.event_t), "fmi2SetTime");
        if (s == fmi2OK) check(F.fmi2SetTime(M.c, M.t) == fmi2OK, "ME time back to the run's");
        refusal = 1; /* no state changes */
        break;
    }
    case 11: { /* states: bad length, NULL, non-finite; valid ones put back unchanged */
        int kind = pick(4);
        x[0] = before[0], x[1] = before[1];
        if (kind == 2) x[pick(2)] = special(), cnt[N_NANINF]++;
        s = F.fmi2SetContinuousStates(M.c, kind == 1 ? NULL : x, kind == 0 ? 3 : 2);
        if (kind == 1) cnt[N_NULL]++;
        int valid = kind == 3 || (kind == 2 && isfinite(x[0]) && isfinite(x[1]));
        if (kind == 2 && valid && M.life == M_CONT)
            check(s == fmi2OK || s == fmi2Error, "ME huge states: %d", s); /* may overflow scaling */
        else me_expect(s, ME_BIT(M_CONT), valid, "fmi2SetContinuousStates");
        if (s == fmi2OK && kind == 2) F.fmi2SetContinuousStates(M.c, before, 2);
        refusal = s != fmi2OK;
        break;
    }
    case 12: { /* readers with bad lengths or NULL */
        int kind = pick(3), n = kind == 0 ? 1 + 2 * pick(2) : 2;
        double *p = kind == 1 ? NULL : z;
        if (kind == 1) cnt[N_NULL]++;
        int which = pick(4);
        s = which == 0   ? F.fmi2GetEventIndicators(M.c, p, n)
            : which == 1 ? F.fmi2GetDerivatives(M.c, p, n)
            : which == 2 ? F.fmi2GetContinuousStates(M.c, p, n)
                         : F.fmi2GetNominalsOfContinuousStates(M.c, p, n);
        if (M.life == M_INIT && kind == 2 && which != 3)
            /* In initialization mode the states come from the parameters set so far, which the
             * ME oracle does not track: a start the FMU refuses (x0 below the plate, ...) makes
             * the readers refuse too. */
            check(s == fmi2OK || s == fmi2Error, "ME reader in InitializationMode: status %d", s);
        else
            me_expect(s, which == 3 ? (ME_READ | ME_BIT(M_INST)) : ME_READ, kind == 2, "ME reader");
        refusal = 1; /* readers never change the states */
        break;
    }
    case 13: { /* fmi2CompletedIntegratorStep, NULL outputs sometimes */
        fmi2Boolean enter, term;
        int null = chance(0.2);
        s = F.fmi2CompletedIntegratorStep(M.c, fmi2True, null ? NULL : &enter, &term);
        me_expect(s, ME_BIT(M_CONT), !null, "fmi2CompletedIntegratorStep");
        refusal = 1;
        break;
    }
    case 14: { /* FMU states: take, restore (round trip through bytes sometimes) */
        if (!M.held || chance(0.4)) {
            if (M.held) F.fmi2FreeFMUstate(M.c, &M.held);
            s = F.fmi2GetFMUstate(M.c, &M.held);
            check(s == fmi2OK && M.held, "ME fmi2GetFMUstate");
            M.held_life = M.life, M.held_count = me_int("impact_count"), M.held_t = M.t;
            M.held_wild = M.wild;
            memcpy(M.held_x, before, sizeof before);
            refusal = 1;
        } else {
            fmi2FMUstate use = M.held, fresh = NULL;
            unsigned char *b = NULL;
            if (chance(0.5)) {
                size_t n = 0;
                F.fmi2SerializedFMUstateSize(M.c, M.held, &n);
                b = malloc(n);
                check(b && F.fmi2SerializeFMUstate(M.c, M.held, (fmi2Byte *)b, n) == fmi2OK &&
                          F.fmi2DeSerializeFMUstate(M.c, (fmi2Byte *)b, n, &fresh) == fmi2OK,
                      "ME serialize round trip");
                if (fresh) use = fresh;
                cnt[N_ROUNDTRIP]++;
            }
            if (F.fmi2SetFMUstate(M.c, use) != fmi2OK) {
                check(0, "ME fmi2SetFMUstate of a held state");
                if (fresh) F.fmi2FreeFMUstate(M.c, &fresh);
                free(b);
                return;
            }
            cnt[N_ROLLBACK]++;
            M.life = M.held_life, M.wild = M.held_wild;
            M.count = 0, M.snaps = 0;
            if ((ME_READ >> M.life) & 1) {
                F.fmi2GetContinuousStates(M.c, after, 2);
                check(bits(after[0]) == bits(M.held_x[0]) && bits(after[1]) == bits(M.held_x[1]) &&
                          me_int("impact_count") == M.held_count,
                      "ME restored state gives back its states and counts bit for bit");
            }
            if (fresh) F.fmi2FreeFMUstate(M.c, &fresh);
            free(b);
            /* The restored time is that of the state; settle there. */
            M.next = INFINITY, M.t = M.event_t = M.held_t;
            if (M.life == M_CONT || M.life == M_EVENT) {
                if (F.fmi2EnterEventMode(M.c) == fmi2OK) {
                    M.life = M_EVENT;
                    check(me_settle(M.c, &M.next) == 0, "ME event update after a restore");
                    M.life = M_CONT;
                }
            }
            return;
        }
        break;
    }
    default: /* terminate, reset, free */
        if (chance(0.5)) {
            s = F.fmi2Terminate(M.c);
            me_expect(s, ME_RUN, 1, "fmi2Terminate");
            if (s == fmi2OK) M.life = M_TERM;
            refusal = s != fmi2OK;
        } else if (chance(0.7)) {
            check(F.fmi2Reset(M.c) == fmi2OK, "ME reset");
            M.life = M_INST, M.count = M.snaps = M.wild = 0, M.next = INFINITY, M.t = 0;
            return;
        } else {
            if (M.held) F.fmi2FreeFMUstate(M.c, &M.held);
            F.fmi2FreeInstance(M.c);
            cnt[N_REINST]++;
            me_start();
            return;
        }
    }
    if (refusal && readable && ((ME_READ >> M.life) & 1)) {
        F.fmi2GetContinuousStates(M.c, after, 2);
        check(bits(after[0]) == bits(before[0]) && bits(after[1]) == bits(before[1]) &&
                  me_int("impact_count") == count_before,
              "ME refused or reading call leaves states and counts");
    }
    me_observe(0);
}

/* An ME call sequence of `ncalls` calls on one instance (re-instantiated at times). */
static void me_sequence(long ncalls) {
    expected_env = &I[0];
    expected_name = "mefuzz";
    me_start();
    for (long k = 0; k < ncalls && M.c; k++, call_now++) {
        note("ME call %ld in %s", k, me_life[M.life]);
        timed_call(me_act);
    }
    if (M.c) {
        if (M.held) F.fmi2FreeFMUstate(M.c, &M.held);
        F.fmi2FreeInstance(M.c);
    }
    M.c = NULL;
}

static void run_seed(unsigned long seed, long ncalls) {
    seed_begin(seed, 0x5eedf00d5eedf00dULL);
    memset(I, 0, sizeof I);
    nbuf = 0;
    run_calls(ncalls, act);
    for (int k = 0; k < 2; k++)
        if (I[k].c) free_instance(k);
    for (int j = 0; j < nbuf; j++) free(bufs[j].b), bufs[j].b = NULL;
    me_sequence(ncalls / 4);
    disarm();
    if (!quiet || seed_failures)
        printf("seed %lu: %ld calls, %ld invariant checks, invalid %ld, wrong state %ld, NaN/inf %ld, "
               "NULL %ld, bad vr %ld, extreme steps %ld, wrong tc %ld, rollbacks %ld+%ld+%ld, corrupt %ld, "
               "crafted %ld (accepted %ld), re-instantiations %ld, steps OK %ld, Discard %ld, digest %016llx%s\n",
               seed, cnt[N_CALLS], cnt[N_INVARIANTS], cnt[N_INVALID], cnt[N_STATE], cnt[N_NANINF],
               cnt[N_NULL], cnt[N_BADVR], cnt[N_STEP_EXTREME], cnt[N_WRONG_TC], cnt[N_ROLLBACK],
               cnt[N_ROUNDTRIP], cnt[N_CROSS], cnt[N_CORRUPT], cnt[N_CRAFTED], cnt[N_CRAFTED_OK],
               cnt[N_REINST], cnt[N_STEPS_OK], cnt[N_DISCARD], (unsigned long long)digest,
               seed_failures ? "  FAILED" : "");
    seed_end();
}

/* Before the first seed: the variables and the callbacks. */
static void setup(void) {
    parse_vars();
    for (int k = 0; k < 2; k++) {
        cb_with_logger[k] = (fmi2CallbackFunctions){logger, NULL, NULL, NULL, &I[k]};
        cb_without_logger[k] = (fmi2CallbackFunctions){NULL, NULL, NULL, NULL, &I[k]};
    }
}

int fuzz_main(const char *seeds, const char *ncalls_text) {
    kit = (struct fuzzkit){.cnt = cnt, .total = total, .ncnt = N_COUNT, .calls = &cnt[N_CALLS],
                           .checks = &cnt[N_INVARIANTS], .last_log = log_msg, .pending = pending,
                           .save = save_prestep};
    if (!fuzz_run(seeds, ncalls_text, setup, run_seed, now)) return 2;
    print_totals(count_name, 32);
    printf("fuzz:   calls by state (oracle):");
    for (int k = 0; k < 7; k++) printf(" %s %ld%s", life_name[k], by_life[k], k < 6 ? "," : "\n");
    printf("fuzz:   smallest (x - z)/max(delta_x, |x|, |z|) seen: %.3g (bound -%g)\n", gap_min, GAP_BOUND);
    return verdict();
}

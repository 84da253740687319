/* `host3 fuzz LIB.so MD.xml SEEDS NCALLS`: random sequences of FMI 3.0 calls against the
 * bistable_impact FMU, deterministic per seed, with invariants checked after every call.
 *
 * Two instance slots, each (re-)instantiated at random as co-simulation (eventModeUsed and
 * earlyReturnAllowed random), Model Exchange, or scheduled execution (always NULL), sometimes
 * with a wrong instantiation token or an empty name (NULL expected). The host keeps an oracle of
 * each instance (its FMI 3.0 state, time, stop time, the values it set, the FMU states it holds
 * and serialized buffers) and generates every call with valid or invalid arguments: wrong and
 * unknown value references, nValues != nValueReferences, NULL pointers, NaN and +-inf, out of
 * range values, wrong communication points, negative/NaN/huge steps, calls in the wrong state or
 * of the wrong interface, the types the model does not have (Float32, Int8, ..., String, Binary,
 * Clock), foreign, freed and corrupted FMU states and byte buffers. Checks:
 *   - every status is in fmi3OK..fmi3Fatal, never fmi3Fatal;
 *   - a call the FMI 3.0 state machine (as the FMU declares it) forbids, or with an invalid
 *     argument, returns fmi3Error; every fmi3Error comes with a logged message;
 *   - a refused call leaves the instance as it was (outputs read back bit for bit unchanged);
 *   - a valid fmi3DoStep in the sane domain (moderate parameters, internal shaker or external
 *     inputs following a sinusoid) returns fmi3OK; elsewhere fmi3OK, fmi3Discard, or fmi3Error
 *     with a logged reason;
 *   - after every successful call the outputs (when readable) are finite; in co-simulation the
 *     mass is never below the plate beyond rounding: x - z >= -1e-9 max(1, |z|);
 *   - impact_count never decreases except after Reset, SetFMUState or a new initialization, and
 *     increases by at most 1 per early return;
 *   - fmi3DoStep: lastSuccessfulTime within [tc, tc + h], equal to tc + h unless it returned
 *     early; earlyReturn only with earlyReturnAllowed, eventHandlingNeeded only with
 *     eventModeUsed; no endless early returns at one time;
 *   - fmi3SetFMUState gives back the outputs seen when the state was taken, bit for bit;
 *     deserialized bytes are accepted only by an instance of the same interface and options;
 *   - fmi3UpdateDiscreteStates in co-simulation needs no further update; dx/dt (output
 *     derivative) equals v.
 * A per-call watchdog (FUZZ_CALL_TIMEOUT seconds, default 20) reports a hang; a crash is reported
 * with the seed and the last calls. FUZZ_TRACE=1 prints every call, FUZZ_QUIET=1 only failing
 * seeds and the summary.
 */
#include "host3.h"
#include "../fuzzkit.h"

/* ---- oracle ---- */
enum { L_NONE, L_INST, L_INIT, L_STEP, L_FAILED, L_TERM, L_ERROR, L_EVENT, L_CONT, N_LIFE };
static const char *life_name[] = {"none", "Instantiated", "InitializationMode", "StepMode", "StepFailed",
                                  "Terminated", "Error", "EventMode", "ContinuousTimeMode"};
#define B(l) (1u << (l))
/* The FMU's state masks (fmu/src/instance.rs, allowed::*). */
static const unsigned M_INSTANTIATED = B(L_INST);
static const unsigned M_INIT = B(L_INIT);
static const unsigned M_SET = B(L_INST) | B(L_INIT) | B(L_STEP) | B(L_EVENT) | B(L_CONT);
static const unsigned M_GET = B(L_INIT) | B(L_STEP) | B(L_FAILED) | B(L_EVENT) | B(L_CONT) | B(L_TERM) | B(L_ERROR);
static const unsigned M_TERMINATE = B(L_STEP) | B(L_FAILED) | B(L_EVENT) | B(L_CONT);
static const unsigned M_GET_DER = B(L_STEP) | B(L_FAILED) | B(L_TERM) | B(L_ERROR);
static const unsigned M_STEP = B(L_STEP);
static const unsigned M_ENTER_EVENT = B(L_EVENT) | B(L_CONT) | B(L_STEP);
static const unsigned M_EVENT = B(L_EVENT);
static const unsigned M_CONT = B(L_CONT);
static const unsigned M_SET_TIME = B(L_EVENT) | B(L_CONT);
static const unsigned M_ME_GET = B(L_INIT) | B(L_EVENT) | B(L_CONT) | B(L_TERM) | B(L_ERROR);
static const unsigned M_NOMINALS = B(L_INST) | B(L_INIT) | B(L_EVENT) | B(L_CONT) | B(L_TERM) | B(L_ERROR);

enum { K_CS, K_ME };

/* What the host knows about an instance's simulation (also kept with each FMU state). */
typedef struct {
    int life;
    double t, t_event, start, stop;
    int has_stop;
    int count;            /* impact_count last seen, -1 unknown */
    int wild;             /* parameters or inputs outside the sane domain */
    int ext;              /* external shaker mode */
    double ext_a, ext_w;  /* reference plate z = ext_a sin(ext_w t) for the external inputs */
    int ext_dirty;        /* inputs set off the reference since the last step */
    double val[MAXV3];    /* parameter and input values as set */
    int early_streak;     /* consecutive early returns without progress */
} Meta;

#define MAXST 4
typedef struct {
    fmi3FMUState h;
    Meta m;
    Outputs out;
    int out_ok;
} Held;

typedef struct {
    fmi3Instance c;
    int kind, em, er;
    Meta m;
    Held st[MAXST];
    int nst;
    fmi3FMUState stale; /* a freed handle (its value only) */
} Inst;

static Inst I[2];

/* Serialized states: bytes and who made them. */
#define MAXBUF 4
typedef struct {
    fmi3Byte *b;
    size_t n;
    int kind, em, er;
    Meta m;
    Outputs out;
    int out_ok;
} Buf;
static Buf bufs[MAXBUF];
static int nbuf;

/* ---- counters (failures, ring of calls, watchdog: fuzzkit.h) ---- */
enum {
    N_CALLS, N_FMI, N_INVARIANTS, N_STATE, N_INVALID, N_NULLI, N_STEPS_OK, N_EARLY, N_EVENTMODE, N_DISCARD,
    N_STEP_REFUSED, N_ROLLBACK, N_DESER, N_CORRUPT, N_REINST, N_ME_SEG, N_COUNT
};
static const char *count_name[] = {"calls (generated)", "FMI calls (incl. invariant reads)", "invariant checks",
                                   "refused: wrong state/interface", "refused: invalid argument",
                                   "NULL instances", "steps fmi3OK", "early returns", "event modes",
                                   "steps fmi3Discard", "valid steps refused (wild)", "rollbacks (SetFMUState)",
                                   "deserialized states", "corrupt/foreign buffers", "instantiations",
                                   "ME driver segments"};
static long cnt[N_COUNT], total[N_COUNT];
static long by_life[N_LIFE];
static double gap_min = INFINITY;

/* ---- status expectations ---- */
static long msgs_before;
/* A call of this turn changed the instance on purpose (reference inputs set before a step). */
static int mutated;

static void before_call(void) {
    msgs_before = n_msgs3;
    last_msg3[0] = 0;
    last_status3 = -1;
}

/* Checks a status: in range, never Fatal; Error logged; `must_fail` => Error;
 * `must_ok` => OK. Returns the status. */
static fmi3Status expect(fmi3Status s, int must_fail, int must_ok, const char *what) {
    cnt[N_FMI]++;
    mix((uint64_t)s);
    check((int)s >= 0 && (int)s <= 4, "%s: status %d out of range", what, (int)s);
    check(s != fmi3Fatal, "%s: fmi3Fatal", what);
    if (must_fail) check(s == fmi3Error, "%s: expected fmi3Error (forbidden), got %d", what, (int)s);
    else if (must_ok) check(s == fmi3OK, "%s: expected fmi3OK, got %d", what, (int)s);
    /* Refusals are always logged (logStatusError); a Discard only when its category is on. */
    if (s == fmi3Error)
        check(n_msgs3 > msgs_before && last_status3 == (int)s && last_msg3[0],
              "%s: status %d without a logged message of that status", what, (int)s);
    return s;
}

/* ---- variables ---- */
static int iZeta, iE, iOmega, iV, iOmega0, iDx, iMass, iX0, iV0, iTol, iMode, iZin, iZdin, iRecon;
static int oX, oV, oZ, oZdot, oCount; /* indexes into Outputs (f[] and i[]) */
static fmi3ValueReference vrX, vrV, vrZ, vrZdot;

static void find_vars(void) {
    iZeta = var3_index("zeta"), iE = var3_index("e"), iOmega = var3_index("Omega"), iV = var3_index("V");
    iOmega0 = var3_index("omega0"), iDx = var3_index("delta_x"), iMass = var3_index("mass");
    iX0 = var3_index("x0"), iV0 = var3_index("v0"), iTol = var3_index("tol"), iMode = var3_index("shaker_mode");
    iZin = var3_index("z_in"), iZdin = var3_index("zdot_in"), iRecon = var3_index("plate_reconstruction");
    vrX = vr3("x"), vrV = vr3("v"), vrZ = vr3("z"), vrZdot = vr3("zdot");
    /* Positions of x, v, z, zdot among the Float64 outputs and impact_count among the Int32. */
    int nf = 0, ni = 0;
    oX = oV = oZ = oZdot = oCount = -1;
    for (int k = 0; k < nv3; k++) {
        if (vars3[k].caus != C_OUTPUT) continue;
        if (vars3[k].type == T_F64) {
            if (!strcmp(vars3[k].name, "x")) oX = nf;
            if (!strcmp(vars3[k].name, "v")) oV = nf;
            if (!strcmp(vars3[k].name, "z")) oZ = nf;
            if (!strcmp(vars3[k].name, "zdot")) oZdot = nf;
            nf++;
        } else if (vars3[k].type == T_I32) {
            if (!strcmp(vars3[k].name, "impact_count")) oCount = ni;
            ni++;
        }
    }
    if (oX < 0 || oV < 0 || oZ < 0 || oZdot < 0 || oCount < 0) {
        fprintf(stderr, "fuzz: outputs x, v, z, zdot, impact_count not found\n");
        exit(2);
    }
}

static void meta_defaults(Meta *m) {
    memset(m, 0, sizeof *m);
    m->life = L_INST;
    m->count = -1;
    for (int k = 0; k < nv3; k++) m->val[k] = vars3[k].start;
}

/* Outputs readable in this state (fmi3Get* allowed). */
static int readable(const Inst *in) { return in->c && ((M_GET >> in->m.life) & 1); }

/* Reads the outputs for the invariants; 0 if not read. */
static int observe(Inst *in, Outputs *o, const char *after) {
    if (!readable(in)) return 0;
    before_call();
    cnt[N_FMI] += 3;
    fmi3Status s = read_outputs3(in->c, o);
    if (s != fmi3OK) {
        /* In initialization mode the model may not be buildable from the values set yet. */
        check(in->m.life == L_INIT || in->m.wild, "after %s: outputs not readable in %s (status %d)", after,
              life_name[in->m.life], (int)s);
        return 0;
    }
    for (int k = 0; k < o->nf; k++) {
        check(isfinite(o->f[k]), "after %s: output Float64 #%d = %g not finite", after, k, o->f[k]);
        mix(bits(o->f[k]));
    }
    for (int k = 0; k < o->ni; k++) mix((uint64_t)(uint32_t)o->i[k]);
    if (in->kind == K_CS && in->m.life != L_INIT && !in->m.ext_dirty) {
        double x = o->f[oX], z = o->f[oZ], scale = fmax(1.0, fabs(z));
        gap_min = fmin(gap_min, (x - z) / scale);
        check(x - z >= -1e-9 * scale, "after %s: mass below the plate: x = %.17g, z = %.17g", after, x, z);
    }
    int n = o->i[oCount];
    if (in->m.count >= 0 && in->m.life != L_INIT)
        check(n >= in->m.count, "after %s: impact_count decreased from %d to %d", after, in->m.count, n);
    if (in->m.life != L_INIT) in->m.count = n;
    return 1;
}

static int outputs_same(const Outputs *a, const Outputs *b) {
    return a->nf == b->nf && a->ni == b->ni && a->nb == b->nb &&
           memcmp(a->f, b->f, sizeof(double) * (size_t)a->nf) == 0 &&
           memcmp(a->i, b->i, sizeof(int32_t) * (size_t)a->ni) == 0 &&
           memcmp(a->b, b->b, sizeof(bool) * (size_t)a->nb) == 0;
}

/* ---- instances ---- */
static void free_instance(int k) {
    Inst *in = &I[k];
    if (!in->c) return;
    if (chance(0.5))
        for (int j = 0; j < in->nst; j++) F3.fmi3FreeFMUState(in->c, &in->st[j].h);
    note("fmi3FreeInstance(I%d)", k);
    F3.fmi3FreeInstance(in->c);
    cnt[N_FMI]++;
    memset(in, 0, sizeof *in);
}

static void instantiate(int k) {
    free_instance(k);
    Inst *in = &I[k];
    int kind = pick(10), bad = chance(0.08) ? 1 + pick(3) : 0;
    const char *tok = bad == 1 ? "{00000000-0000-0000-0000-000000000000}" : bad == 3 ? NULL : token;
    const char *name = bad == 2 ? (chance(0.5) ? "" : NULL) : (k ? "fuzzB" : "fuzzA");
    int em = chance(0.5), er = chance(0.5), logging = chance(0.3);
    fmi3Instance c;
    before_call();
    if (kind == 0) {
        note("fmi3InstantiateScheduledExecution(I%d)", k);
        c = F3.fmi3InstantiateScheduledExecution(name, tok, NULL, false, logging, &I[k], logger3, NULL, NULL, NULL);
        check(c == NULL, "fmi3InstantiateScheduledExecution returned an instance");
        check(n_msgs3 > msgs_before, "fmi3InstantiateScheduledExecution: NULL without a message");
        cnt[N_NULLI]++;
        return;
    }
    int me = kind <= 3;
    note("fmi3Instantiate%s(I%d, token %s, name %s, eventModeUsed %d, earlyReturnAllowed %d)",
         me ? "ModelExchange" : "CoSimulation", k, bad == 1 ? "wrong" : bad == 3 ? "NULL" : "ok",
         bad == 2 ? "bad" : "ok", em, er);
    if (me)
        c = F3.fmi3InstantiateModelExchange(name, tok, NULL, false, logging, &I[k], logger3);
    else
        c = F3.fmi3InstantiateCoSimulation(name, tok, NULL, false, logging, em, er, NULL, 0, &I[k], logger3, NULL);
    cnt[N_REINST]++;
    if (bad) {
        check(c == NULL, "instantiation with a bad token or name returned an instance");
        check(n_msgs3 > msgs_before && last_status3 == fmi3Error, "NULL instance without a logged message");
        if (c) F3.fmi3FreeInstance(c);
        cnt[N_NULLI]++;
        return;
    }
    check(c != NULL, "valid instantiation returned NULL");
    if (!c) return;
    in->c = c;
    in->kind = me ? K_ME : K_CS;
    in->em = me ? 0 : em;
    in->er = me ? 0 : er;
    meta_defaults(&in->m);
}

/* ---- value generation ---- */
/* A value for variable i: valid in the sane domain, valid but extreme (wild), or invalid. *how:
 * 0 sane, 1 wild, 2 invalid. */
static double gen_value(int i, int *how) {
    const Var3 *v = &vars3[i];
    int r = pick(10);
    if (r == 0) {
        *how = 2;
        int q = pick(4);
        if (v->type == T_F64) return q == 0 ? NAN : q == 1 ? INFINITY : q == 2 ? -INFINITY : v->max * 10 + 1;
        return q < 2 ? v->max + 1 + pick(5) : v->min - 1 - pick(5);
    }
    if (r == 1) {
        *how = 1;
        if (v->type != T_F64) return v->min + pick((int)(v->max - v->min) + 1);
        double lo = v->min, hi = v->max;
        if (!isfinite(lo)) lo = -1e6;
        if (!isfinite(hi)) hi = 1e6;
        return chance(0.5) ? (chance(0.5) ? lo : hi) : urange(lo, hi);
    }
    *how = 0;
    if (i == iZeta) return urange(0, 0.3);
    if (i == iE) return urange(0.3, 1);
    if (i == iOmega) return urange(0.3, 3);
    if (i == iV) return urange(0, 0.3);
    if (i == iOmega0) return urange(0.5, 2);
    if (i == iDx) return urange(0.5, 2);
    if (i == iMass) return logu(0.1, 10);
    if (i == iX0) return urange(0, 0.4);
    if (i == iV0) return urange(-0.3, 0.3);
    if (i == iTol) return logu(1e-16, 1e-10);
    if (i == iMode) return 1 + pick(2);
    if (i == iRecon) return 1 + pick(2);
    if (i == iZin || i == iZdin) return urange(-0.05, 0.05);
    if (v->type == T_BOOL) return pick(2);
    return v->start;
}

/* ---- one call ---- */
static void c_set(int k) {
    Inst *in = &I[k];
    int n = 1 + pick(3), mism = chance(0.05), nulls = chance(0.03) ? 1 + pick(2) : 0;
    int type = pick(10) < 7 ? T_F64 : pick(3) == 0 ? T_I32 : pick(2) ? T_I64 : T_BOOL;
    fmi3ValueReference vr[4];
    double vals[4];
    int invalid = mism || nulls, forbidden = !((M_SET >> in->m.life) & 1), wild = 0, idx[4];
    for (int j = 0; j < n; j++) {
        int i = pick(nv3), how = 0;
        if (chance(0.03)) {
            vr[j] = 900 + (fmi3ValueReference)pick(100);
            idx[j] = -1;
            invalid = 1;
            vals[j] = 1;
            continue;
        }
        /* Mostly parameters and inputs. */
        if (chance(0.8)) {
            for (int tries = 0; tries < 20 && (vars3[i].caus != C_PARAM && vars3[i].caus != C_INPUT); tries++)
                i = pick(nv3);
        }
        idx[j] = i;
        vr[j] = vars3[i].vr;
        vals[j] = gen_value(i, &how);
        /* The call's type: mostly the first variable's own. */
        if (j == 0 && chance(0.9)) type = vars3[i].type;
        if (vars3[i].caus != C_PARAM && vars3[i].caus != C_INPUT) invalid = 1;
        if (how == 2) invalid = 1;
        if (how == 1) wild = 1;
        /* The state machine of the variable: fixed parameters before initialization ends,
           tunable ones also in step and event mode, inputs also in continuous-time mode. */
        if (vars3[i].caus == C_PARAM && !vars3[i].tunable && in->m.life != L_INST && in->m.life != L_INIT)
            forbidden = 1;
        if (vars3[i].caus == C_PARAM && vars3[i].tunable && in->m.life == L_CONT) forbidden = 1;
    }
    /* Mixed types within one call: only vr[0]'s type is the call's. */
    for (int j = 0; j < n; j++)
        if (idx[j] >= 0 && vars3[idx[j]].type != type) invalid = 1;
    size_t nvals = (size_t)n + (mism ? 1 : 0);
    fmi3Status s;
    const char *fn = type == T_F64 ? "fmi3SetFloat64" : type == T_I32 ? "fmi3SetInt32" : type == T_I64 ? "fmi3SetInt64" : "fmi3SetBoolean";
    note("%s(I%d, vr %u %u %u, n %d, nValues %zu, values %.17g %.17g %.17g, null %d) in %s, expect %s", fn, k, vr[0],
         n > 1 ? vr[1] : 0, n > 2 ? vr[2] : 0, n, nvals, vals[0], n > 1 ? vals[1] : 0, n > 2 ? vals[2] : 0, nulls,
         life_name[in->m.life], forbidden ? "refusal (state)" : invalid ? "refusal (argument)" : "any");
    double fv[5];
    int32_t iv[5];
    int64_t lv[5];
    bool bv[5];
    for (int j = 0; j < n; j++) {
        fv[j] = vals[j];
        iv[j] = isfinite(vals[j]) && fabs(vals[j]) < 2e9 ? (int32_t)vals[j] : 0;
        lv[j] = isfinite(vals[j]) && fabs(vals[j]) < 9e18 ? (int64_t)vals[j] : 0;
        bv[j] = vals[j] != 0;
    }
    fv[n] = 0, iv[n] = 0, lv[n] = 0, bv[n] = 0;
    const fmi3ValueReference *pv = nulls == 1 ? NULL : vr;
    before_call();
    switch (type) {
    case T_F64: s = F3.fmi3SetFloat64(in->c, pv, (size_t)n, nulls == 2 ? NULL : fv, nvals); break;
    case T_I32: s = F3.fmi3SetInt32(in->c, pv, (size_t)n, nulls == 2 ? NULL : iv, nvals); break;
    case T_I64: s = F3.fmi3SetInt64(in->c, pv, (size_t)n, nulls == 2 ? NULL : lv, nvals); break;
    default: s = F3.fmi3SetBoolean(in->c, pv, (size_t)n, nulls == 2 ? NULL : bv, nvals); break;
    }
    /* Int32/Int64/Boolean conversions of a Float64 value are not the value checked above. */
    expect(s, forbidden || invalid, 0, fn);
    cnt[N_STATE] += forbidden;
    cnt[N_INVALID] += !forbidden && invalid;
    if (s == fmi3OK) {
        for (int j = 0; j < n; j++) {
            int i = idx[j];
            if (i < 0) continue;
            in->m.val[i] = type == T_F64 ? fv[j] : type == T_I32 ? iv[j] : type == T_I64 ? (double)lv[j] : bv[j];
            if (i == iZin || i == iZdin) in->m.ext_dirty = 1;
        }
        if (wild) in->m.wild = 1;
        in->m.ext = in->m.val[iMode] == 2;
    }
}

static void c_get(int k) {
    Inst *in = &I[k];
    int n = 1 + pick(4), mism = chance(0.05), nulls = chance(0.03) ? 1 + pick(2) : 0;
    int type = pick(4);
    fmi3ValueReference vr[5];
    int invalid = mism || nulls, forbidden = !((M_GET >> in->m.life) & 1);
    for (int j = 0; j < n; j++) {
        int i = pick(nv3);
        if (chance(0.03)) {
            vr[j] = 900 + (fmi3ValueReference)pick(100);
            invalid = 1;
            continue;
        }
        if (j == 0 && chance(0.9)) type = vars3[i].type;
        vr[j] = vars3[i].vr;
        if (vars3[i].type != type) invalid = 1;
    }
    size_t nvals = (size_t)n + (mism ? 1 : 0);
    double fv[6];
    int32_t iv[6];
    int64_t lv[6];
    bool bv[6];
    const char *fn = type == T_F64 ? "fmi3GetFloat64" : type == T_I32 ? "fmi3GetInt32" : type == T_I64 ? "fmi3GetInt64" : "fmi3GetBoolean";
    note("%s(I%d, vr %u.., n %d, nValues %zu, null %d) in %s", fn, k, vr[0], n, nvals, nulls, life_name[in->m.life]);
    const fmi3ValueReference *pv = nulls == 1 ? NULL : vr;
    fmi3Status s;
    before_call();
    switch (type) {
    case T_F64: s = F3.fmi3GetFloat64(in->c, pv, (size_t)n, nulls == 2 ? NULL : fv, nvals); break;
    case T_I32: s = F3.fmi3GetInt32(in->c, pv, (size_t)n, nulls == 2 ? NULL : iv, nvals); break;
    case T_I64: s = F3.fmi3GetInt64(in->c, pv, (size_t)n, nulls == 2 ? NULL : lv, nvals); break;
    default: s = F3.fmi3GetBoolean(in->c, pv, (size_t)n, nulls == 2 ? NULL : bv, nvals); break;
    }
    /* A valid get must succeed, except in initialization mode (values not yet consistent) and
       in wild runs. */
    expect(s, forbidden || invalid, !(forbidden || invalid) && in->m.life != L_INIT && !in->m.wild, fn);
    cnt[N_STATE] += forbidden;
    cnt[N_INVALID] += !forbidden && invalid;
    if (s == fmi3OK && type == T_F64)
        for (int j = 0; j < n; j++) check(isfinite(fv[j]), "%s: value %d = %g not finite", fn, j, fv[j]);
}

/* Calls of the types and features the model does not have: always fmi3Error. */
static void c_unsupported(int k) {
    Inst *in = &I[k];
    fmi3ValueReference vr = chance(0.5) ? vars3[pick(nv3)].vr : (fmi3ValueReference)pick(2000);
    float f32 = 1;
    int8_t i8 = 1;
    uint8_t u8 = 1;
    int16_t i16 = 1;
    uint16_t u16 = 1;
    uint32_t u32 = 1;
    uint64_t u64 = 1;
    fmi3String str = "s";
    const fmi3Byte byte = 1;
    fmi3Binary bin = &byte;
    size_t sz = 1;
    fmi3Clock clk = false;
    double d = 0;
    fmi3IntervalQualifier q;
    uint64_t cntr = 0, res = 0;
    int which = pick(30);
    fmi3Status s;
    static const char *names[] = {"GetFloat32", "SetFloat32", "GetInt8", "SetInt8", "GetUInt8", "SetUInt8",
                                  "GetInt16", "SetInt16", "GetUInt16", "SetUInt16", "GetUInt32", "SetUInt32",
                                  "GetUInt64", "SetUInt64", "GetString", "SetString", "GetBinary", "SetBinary",
                                  "GetClock", "SetClock", "GetIntervalDecimal", "GetIntervalFraction",
                                  "GetShiftDecimal", "SetIntervalDecimal", "EnterConfigurationMode",
                                  "ExitConfigurationMode", "EvaluateDiscreteStates", "ActivateModelPartition",
                                  "GetDirectionalDerivative", "GetAdjointDerivative"};
    note("fmi3%s(I%d, vr %u) in %s", names[which], k, vr, life_name[in->m.life]);
    before_call();
    switch (which) {
    case 0: s = F3.fmi3GetFloat32(in->c, &vr, 1, &f32, 1); break;
    case 1: s = F3.fmi3SetFloat32(in->c, &vr, 1, &f32, 1); break;
    case 2: s = F3.fmi3GetInt8(in->c, &vr, 1, &i8, 1); break;
    case 3: s = F3.fmi3SetInt8(in->c, &vr, 1, &i8, 1); break;
    case 4: s = F3.fmi3GetUInt8(in->c, &vr, 1, &u8, 1); break;
    case 5: s = F3.fmi3SetUInt8(in->c, &vr, 1, &u8, 1); break;
    case 6: s = F3.fmi3GetInt16(in->c, &vr, 1, &i16, 1); break;
    case 7: s = F3.fmi3SetInt16(in->c, &vr, 1, &i16, 1); break;
    case 8: s = F3.fmi3GetUInt16(in->c, &vr, 1, &u16, 1); break;
    case 9: s = F3.fmi3SetUInt16(in->c, &vr, 1, &u16, 1); break;
    case 10: s = F3.fmi3GetUInt32(in->c, &vr, 1, &u32, 1); break;
    case 11: s = F3.fmi3SetUInt32(in->c, &vr, 1, &u32, 1); break;
    case 12: s = F3.fmi3GetUInt64(in->c, &vr, 1, &u64, 1); break;
    case 13: s = F3.fmi3SetUInt64(in->c, &vr, 1, &u64, 1); break;
    case 14: s = F3.fmi3GetString(in->c, &vr, 1, &str, 1); break;
    case 15: s = F3.fmi3SetString(in->c, &vr, 1, &str, 1); break;
    case 16: s = F3.fmi3GetBinary(in->c, &vr, 1, &sz, &bin, 1); break;
    case 17: s = F3.fmi3SetBinary(in->c, &vr, 1, &sz, &bin, 1); break;
    case 18: s = F3.fmi3GetClock(in->c, &vr, 1, &clk); break;
    case 19: s = F3.fmi3SetClock(in->c, &vr, 1, &clk); break;
    case 20: s = F3.fmi3GetIntervalDecimal(in->c, &vr, 1, &d, &q); break;
    case 21: s = F3.fmi3GetIntervalFraction(in->c, &vr, 1, &cntr, &res, &q); break;
    case 22: s = F3.fmi3GetShiftDecimal(in->c, &vr, 1, &d); break;
    case 23: s = F3.fmi3SetIntervalDecimal(in->c, &vr, 1, &d); break;
    case 24: s = F3.fmi3EnterConfigurationMode(in->c); break;
    case 25: s = F3.fmi3ExitConfigurationMode(in->c); break;
    case 26: s = F3.fmi3EvaluateDiscreteStates(in->c); break;
    case 27: s = F3.fmi3ActivateModelPartition(in->c, vr, 0); break;
    case 28: s = F3.fmi3GetDirectionalDerivative(in->c, &vr, 1, &vr, 1, &d, 1, &d, 1); break;
    default: s = F3.fmi3GetAdjointDerivative(in->c, &vr, 1, &vr, 1, &d, 1, &d, 1); break;
    }
    char what[64];
    snprintf(what, sizeof what, "fmi3%s", names[which]);
    expect(s, 1, 0, what);
    cnt[N_INVALID]++;
}

static void c_enter_init(int k) {
    Inst *in = &I[k];
    int bad = chance(0.1);
    double start = chance(0.7) ? 0 : urange(-10, 100), stop = start + logu(1, 500);
    int has_stop = chance(0.5);
    if (bad) {
        if (chance(0.5)) start = chance(0.5) ? NAN : INFINITY;
        else has_stop = 1, stop = start - 1;
    }
    int forbidden = !((M_INSTANTIATED >> in->m.life) & 1);
    note("fmi3EnterInitializationMode(I%d, start %.17g, stop %d %.17g) in %s", k, start, has_stop, stop,
         life_name[in->m.life]);
    before_call();
    fmi3Status s = F3.fmi3EnterInitializationMode(in->c, chance(0.5), 1e-6, start, has_stop, stop);
    expect(s, forbidden || bad, 0, "fmi3EnterInitializationMode");
    cnt[N_STATE] += forbidden;
    if (s == fmi3OK) {
        in->m.life = L_INIT;
        in->m.start = in->m.t = in->m.t_event = start;
        in->m.has_stop = has_stop, in->m.stop = stop;
        in->m.count = -1;
    }
}

static void c_exit_init(int k) {
    Inst *in = &I[k];
    int forbidden = !((M_INIT >> in->m.life) & 1);
    /* External mode: inputs on a reference sinusoid through the plate at the start. */
    if (!forbidden && in->m.ext && chance(0.8)) {
        double w = in->m.val[iOmega] * in->m.val[iOmega0], a = in->m.val[iV] * in->m.val[iDx] / in->m.val[iOmega];
        if (!(isfinite(w) && isfinite(a) && w > 0)) w = 1, a = 0.05;
        in->m.ext_w = w, in->m.ext_a = a;
        fmi3ValueReference vr[2] = {vars3[iZin].vr, vars3[iZdin].vr};
        double z[2] = {a * sin(w * in->m.t), a * w * cos(w * in->m.t)};
        note("fmi3SetFloat64(I%d, z_in %.17g, zdot_in %.17g) reference", k, z[0], z[1]);
        before_call();
        if (expect(F3.fmi3SetFloat64(in->c, vr, 2, z, 2), 0, 0, "fmi3SetFloat64 reference inputs") == fmi3OK)
            in->m.ext_dirty = 0, mutated = 1;
    }
    note("fmi3ExitInitializationMode(I%d) in %s", k, life_name[in->m.life]);
    before_call();
    fmi3Status s = F3.fmi3ExitInitializationMode(in->c);
    expect(s, forbidden, 0, "fmi3ExitInitializationMode");
    cnt[N_STATE] += forbidden;
    if (s == fmi3OK) {
        in->m.life = in->kind == K_ME || in->em ? L_EVENT : L_STEP;
        in->m.t = in->m.t_event = in->m.start;
        in->m.count = -1;
        in->m.early_streak = 0;
        if (in->m.ext && in->m.ext_dirty) in->m.wild = 1;
    }
}

/* The communication point a valid step uses: the FMU's time. */
static void c_do_step(int k) {
    Inst *in = &I[k];
    Meta *m = &in->m;
    int forbidden = in->kind != K_CS || !((M_STEP >> m->life) & 1);
    int kind = pick(20), invalid = 0, maybe_refused = m->wild;
    double tc = m->t, h = chance(0.3) ? logu(1e-6, 0.1) : logu(0.01, 20);
    if (m->has_stop && tc + h > m->stop) h = m->stop - tc;
    int nulls = chance(0.02) ? 1 + pick(4) : 0;
    if (kind == 0) h = -logu(1e-6, 10), invalid = 1;
    else if (kind == 1) h = chance(0.5) ? NAN : INFINITY, invalid = 1;
    else if (kind == 2) h = 0, invalid = 1;
    else if (kind == 3) /* beyond the FMU's rounding allowance 1e-9 max(1, |t|) */
        tc = m->t + (chance(0.5) ? 1 : -1) * (urange(0.5, 10) + 1e-8 * fabs(m->t)), invalid = 1;
    else if (kind == 4) tc = NAN, invalid = 1;
    else if (kind == 5 && m->has_stop) h = m->stop - tc + urange(1, 10) + 1e-8 * fabs(m->stop), invalid = 1;
    else if (kind == 6) h = logu(1e6, 1e15), maybe_refused = 1; /* beyond the FMU's step span */
    if (!(h > 0) && !invalid) invalid = 1; /* at the stop time */
    invalid |= nulls != 0;
    /* External mode: the inputs at tc on the reference sinusoid, or random (wild). */
    if (!forbidden && !invalid && m->ext && chance(0.9)) {
        fmi3ValueReference vr[2] = {vars3[iZin].vr, vars3[iZdin].vr};
        double z[2] = {m->ext_a * sin(m->ext_w * tc), m->ext_a * m->ext_w * cos(m->ext_w * tc)};
        int off = chance(0.05);
        if (off) z[0] += urange(-0.1, 0.1), z[1] += urange(-0.1, 0.1);
        before_call();
        note("fmi3SetFloat64(I%d, z_in %.17g, zdot_in %.17g) %s", k, z[0], z[1], off ? "off the reference" : "reference");
        if (expect(F3.fmi3SetFloat64(in->c, vr, 2, z, 2), 0, 0, "fmi3SetFloat64 inputs") == fmi3OK) {
            m->ext_dirty = off;
            mutated = 1;
            if (off) m->wild = 1;
        }
    }
    bool hd = false, term = false, early = false;
    double last = NAN;
    int before_count = m->count;
    note("fmi3DoStep(I%d, tc %.17g, h %.17g, nulls %d) in %s, t %.17g, em %d, er %d", k, tc, h, nulls,
         life_name[m->life], m->t, in->em, in->er);
    before_call();
    fmi3Status s = F3.fmi3DoStep(in->c, tc, h, chance(0.5), nulls == 1 ? NULL : &hd, nulls == 2 ? NULL : &term,
                                 nulls == 3 ? NULL : &early, nulls == 4 ? NULL : &last);
    int valid = !forbidden && !invalid && !maybe_refused && !m->ext_dirty;
    expect(s, forbidden || invalid, 0, "fmi3DoStep");
    if (valid && !m->wild) check(s == fmi3OK, "fmi3DoStep: valid step in the sane domain returned %d", (int)s);
    cnt[N_STATE] += forbidden;
    cnt[N_INVALID] += !forbidden && invalid;
    if (s == fmi3Error && !forbidden && !invalid) cnt[N_STEP_REFUSED]++;
    if (s == fmi3OK || s == fmi3Discard) {
        mix(bits(last));
        check(last >= tc && last <= tc + h, "fmi3DoStep: lastSuccessfulTime %.17g outside [%.17g, %.17g]", last, tc,
              tc + h);
        check(!early || in->er, "fmi3DoStep: earlyReturn without earlyReturnAllowed");
        check(!hd || in->em, "fmi3DoStep: eventHandlingNeeded without eventModeUsed");
        if (s == fmi3OK) {
            cnt[N_STEPS_OK]++;
            check(early || last == tc + h, "fmi3DoStep: no early return but lastSuccessfulTime %.17g != tc + h %.17g",
                  last, tc + h);
            check(!early || last < tc + h, "fmi3DoStep: early return at the step's end");
            check(!early || !in->em || hd, "fmi3DoStep: early return at an event without eventHandlingNeeded");
            check(!term, "fmi3DoStep: terminateSimulation with fmi3OK");
            if (early) {
                cnt[N_EARLY]++;
                m->early_streak = last == tc ? m->early_streak + 1 : 0;
                check(m->early_streak < 1000, "fmi3DoStep: 1000 early returns without progress at t = %.17g", last);
            } else {
                m->early_streak = 0;
            }
        } else {
            cnt[N_DISCARD]++;
            check(term, "fmi3DoStep: fmi3Discard without terminateSimulation");
            m->life = L_FAILED;
        }
        m->t = last;
        m->ext_dirty = 0;
        Outputs o;
        if (observe(in, &o, "fmi3DoStep") && early && before_count >= 0)
            check(o.i[oCount] <= before_count + 1, "fmi3DoStep: early return after %d impacts (from %d to %d)",
                  o.i[oCount] - before_count, before_count, o.i[oCount]);
        /* Usually follow the FMU's request for event mode. */
        if (hd && s == fmi3OK && chance(0.9)) {
            note("fmi3EnterEventMode(I%d) after eventHandlingNeeded", k);
            before_call();
            if (expect(F3.fmi3EnterEventMode(in->c), 0, 1, "fmi3EnterEventMode after eventHandlingNeeded") == fmi3OK) {
                m->life = L_EVENT;
                cnt[N_EVENTMODE]++;
            }
        }
    }
}

static void c_event_calls(int k) {
    Inst *in = &I[k];
    Meta *m = &in->m;
    int which = pick(4);
    fmi3Status s;
    if (which == 0) {
        int forbidden = !((M_ENTER_EVENT >> m->life) & 1);
        int invalid = in->kind == K_CS && !in->em;
        note("fmi3EnterEventMode(I%d) in %s", k, life_name[m->life]);
        before_call();
        s = expect(F3.fmi3EnterEventMode(in->c), forbidden || invalid, !(forbidden || invalid),
                   "fmi3EnterEventMode");
        cnt[N_STATE] += forbidden || invalid;
        if (s == fmi3OK) {
            m->life = L_EVENT, m->t_event = m->t;
            cnt[N_EVENTMODE]++;
        }
    } else if (which == 1) {
        int forbidden = !((M_EVENT >> m->life) & 1), nulls = chance(0.05) ? 1 + pick(6) : 0;
        bool f[5] = {0};
        double next = 0;
        note("fmi3UpdateDiscreteStates(I%d, null %d) in %s", k, nulls, life_name[m->life]);
        before_call();
        s = F3.fmi3UpdateDiscreteStates(in->c, nulls == 1 ? NULL : &f[0], nulls == 2 ? NULL : &f[1],
                                        nulls == 3 ? NULL : &f[2], nulls == 4 ? NULL : &f[3],
                                        nulls == 5 ? NULL : &f[4], nulls == 6 ? NULL : &next);
        expect(s, forbidden || nulls, !(forbidden || nulls) && !m->wild, "fmi3UpdateDiscreteStates");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) {
            if (in->kind == K_CS) check(!f[0] && !f[1], "fmi3UpdateDiscreteStates (CS): further update or terminate asked");
            if (f[4]) check(isfinite(next) && next >= m->t, "fmi3UpdateDiscreteStates: next event time %.17g before t %.17g", next, m->t);
        }
    } else if (which == 2) {
        int forbidden = in->kind != K_CS || !((M_EVENT >> m->life) & 1);
        note("fmi3EnterStepMode(I%d) in %s", k, life_name[m->life]);
        before_call();
        s = expect(F3.fmi3EnterStepMode(in->c), forbidden, !forbidden, "fmi3EnterStepMode");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) m->life = L_STEP;
    } else {
        int forbidden = in->kind != K_ME || !((M_EVENT >> m->life) & 1);
        note("fmi3EnterContinuousTimeMode(I%d) in %s", k, life_name[m->life]);
        before_call();
        s = expect(F3.fmi3EnterContinuousTimeMode(in->c), forbidden, !forbidden, "fmi3EnterContinuousTimeMode");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) m->life = L_CONT;
    }
}

/* ---- Model Exchange ---- */
static int me_put(Inst *in, double t, const double x[2]) {
    cnt[N_FMI] += 2;
    return F3.fmi3SetTime(in->c, t) == fmi3OK && F3.fmi3SetContinuousStates(in->c, x, 2) == fmi3OK ? 0 : -1;
}
static int me_deriv(Inst *in, double t, const double x[2], double d[2]) {
    cnt[N_FMI]++;
    return me_put(in, t, x) || F3.fmi3GetContinuousStateDerivatives(in->c, d, 2) != fmi3OK ? -1 : 0;
}
static int me_rk4(Inst *in, double t, const double x[2], double h, double y[2]) {
    double k1[2], k2[2], k3[2], k4[2], a[2];
    /* Stops at the first failing call (its outputs are not set). */
    if (me_deriv(in, t, x, k1)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k1[i];
    if (me_deriv(in, t + h / 2, a, k2)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k2[i];
    if (me_deriv(in, t + h / 2, a, k3)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h * k3[i];
    if (me_deriv(in, t + h, a, k4)) return -1;
    for (int i = 0; i < 2; i++) y[i] = x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    return 0;
}
static int me_ind(Inst *in, double t, const double x[2], double z[2]) {
    cnt[N_FMI]++;
    return me_put(in, t, x) || F3.fmi3GetEventIndicators(in->c, z, 2) != fmi3OK ? -1 : 0;
}
static int crossed(const double a[2], const double b[2]) {
    return (a[0] > 0) != (b[0] > 0) || (a[1] > 0) != (b[1] > 0);
}

/* A valid ME segment from continuous-time mode: RK4 steps, indicator sign changes bisected,
 * event mode at every event (fmi3UpdateDiscreteStates until done, continuous-time mode). */
static void me_segment(int k) {
    Inst *in = &I[k];
    Meta *m = &in->m;
    double t = m->t, t_end = t + logu(0.01, 5), h = logu(1e-3, 2e-2), x[2], x1[2], z0[2], z1[2];
    note("ME driver segment (I%d) from t %.17g to %.17g, h %.3g", k, t, t_end, h);
    cnt[N_ME_SEG]++;
    int fails = 0;
    for (int steps = 0; t < t_end && steps < 5000 && !fails; steps++) {
        cnt[N_FMI]++;
        if (F3.fmi3GetContinuousStates(in->c, x, 2) != fmi3OK || me_ind(in, t, x, z0)) { fails = 1; break; }
        double step = fmin(h, t_end - t);
        if (me_rk4(in, t, x, step, x1) || me_ind(in, t + step, x1, z1)) { fails = 1; break; }
        int event = crossed(z0, z1);
        if (event) {
            double lo = 0, hi = step;
            while (hi - lo > 1e-12 && !fails) {
                double mid = 0.5 * (lo + hi);
                if (me_rk4(in, t, x, mid, x1) || me_ind(in, t + mid, x1, z1)) fails = 1;
                else if (crossed(z0, z1)) hi = mid;
                else lo = mid;
            }
            step = hi;
            if (fails || me_rk4(in, t, x, step, x1)) { fails = 1; break; }
        }
        t += step;
        m->t = t;
        bool enter = false, term = false;
        cnt[N_FMI]++;
        if (me_put(in, t, x1) || F3.fmi3CompletedIntegratorStep(in->c, true, &enter, &term) != fmi3OK) { fails = 1; break; }
        if (event || enter) {
            cnt[N_FMI] += 2;
            if (F3.fmi3EnterEventMode(in->c) != fmi3OK) { fails = 1; break; }
            m->life = L_EVENT, m->t_event = t;
            cnt[N_EVENTMODE]++;
            bool need = true, f2, f3, f4, def;
            double next;
            for (int j = 0; need && j < 10; j++) {
                cnt[N_FMI]++;
                if (F3.fmi3UpdateDiscreteStates(in->c, &need, &f2, &f3, &f4, &def, &next) != fmi3OK) { fails = 1; break; }
            }
            if (fails || F3.fmi3EnterContinuousTimeMode(in->c) != fmi3OK) { fails = 1; break; }
            m->life = L_CONT;
        }
        Outputs o;
        observe(in, &o, "ME driver step");
    }
    if (fails) {
        /* A valid ME sequence of a sane run never fails. */
        check(m->wild, "ME driver segment: a call failed at t = %.17g (in %s)", t, life_name[m->life]);
        /* Resynchronize the oracle with what the failing call left: unknown, so start anew. */
        note("ME driver failed; resetting I%d", k);
        cnt[N_FMI]++;
        check(F3.fmi3Reset(in->c) == fmi3OK, "fmi3Reset after a failed ME segment");
        meta_defaults(m);
    }
    mix(bits(m->t));
}

static void c_me_calls(int k) {
    Inst *in = &I[k];
    Meta *m = &in->m;
    int which = pick(9), me = in->kind == K_ME;
    fmi3Status s;
    double x[3] = {0, 0, 0};
    if (which == 0 && me && m->life == L_CONT) {
        me_segment(k);
        return;
    }
    switch (which) {
    case 0:
    case 1: { /* fmi3SetTime */
        int forbidden = !me || !((M_SET_TIME >> m->life) & 1), bad = chance(0.15);
        double t = m->t + (chance(0.3) ? 0 : logu(1e-9, 0.01));
        if (bad) t = chance(0.5) ? NAN : m->t_event - urange(0.01, 5);
        note("fmi3SetTime(I%d, %.17g) in %s, last event %.17g", k, t, life_name[m->life], m->t_event);
        before_call();
        s = expect(F3.fmi3SetTime(in->c, t), forbidden || bad, 0, "fmi3SetTime");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) {
            /* Time moved without the states: the mass may now be anywhere relative to the plate. */
            if (t != m->t) m->wild = 1;
            m->t = t;
        }
        break;
    }
    case 2: { /* fmi3SetContinuousStates */
        int forbidden = !me || !((M_CONT >> m->life) & 1), n = chance(0.1) ? 1 + 2 * pick(2) : 2, nul = chance(0.03);
        int bad = n != 2 || nul;
        cnt[N_FMI]++;
        if (F3.fmi3GetContinuousStates(in->c, x, 2) != fmi3OK) x[0] = x[1] = 0;
        x[0] += urange(-1e-6, 1e-5), x[1] += urange(-1e-5, 1e-5);
        if (chance(0.05)) x[pick(2)] = chance(0.5) ? NAN : INFINITY, bad = 1;
        note("fmi3SetContinuousStates(I%d, %.17g, %.17g, n %d, null %d) in %s", k, x[0], x[1], n, nul,
             life_name[m->life]);
        before_call();
        s = expect(F3.fmi3SetContinuousStates(in->c, nul ? NULL : x, (size_t)n), forbidden || bad, 0,
                   "fmi3SetContinuousStates");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) m->wild = 1;
        break;
    }
    case 3: { /* derivatives, indicators, states, nominals */
        int f = pick(4), n = chance(0.1) ? pick(4) : 2, nul = chance(0.03);
        unsigned mask = f == 3 ? M_NOMINALS : M_ME_GET;
        int forbidden = !me || !((mask >> m->life) & 1), bad = n != 2 || nul;
        static const char *fn[] = {"fmi3GetContinuousStateDerivatives", "fmi3GetEventIndicators",
                                   "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates"};
        note("%s(I%d, n %d, null %d) in %s", fn[f], k, n, nul, life_name[m->life]);
        before_call();
        double *p = nul ? NULL : x;
        s = f == 0 ? F3.fmi3GetContinuousStateDerivatives(in->c, p, (size_t)n)
            : f == 1 ? F3.fmi3GetEventIndicators(in->c, p, (size_t)n)
            : f == 2 ? F3.fmi3GetContinuousStates(in->c, p, (size_t)n)
                     : F3.fmi3GetNominalsOfContinuousStates(in->c, p, (size_t)n);
        expect(s, forbidden || bad, 0, fn[f]);
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK)
            for (int j = 0; j < n; j++) check(isfinite(x[j]), "%s: value %d = %g not finite", fn[f], j, x[j]);
        break;
    }
    case 4: { /* counts */
        int f = pick(2), nul = chance(0.1), forbidden = !me;
        size_t n = 99;
        note("fmi3GetNumberOf%s(I%d, null %d)", f ? "EventIndicators" : "ContinuousStates", k, nul);
        before_call();
        s = f ? F3.fmi3GetNumberOfEventIndicators(in->c, nul ? NULL : &n)
              : F3.fmi3GetNumberOfContinuousStates(in->c, nul ? NULL : &n);
        expect(s, forbidden || nul, !(forbidden || nul), "fmi3GetNumberOf*");
        if (s == fmi3OK) check(n == 2, "fmi3GetNumberOf*: %zu", n);
        break;
    }
    case 5: { /* fmi3CompletedIntegratorStep */
        int forbidden = !me || !((M_CONT >> m->life) & 1), nul = chance(0.05) ? 1 + pick(2) : 0;
        bool enter, term;
        note("fmi3CompletedIntegratorStep(I%d, null %d) in %s", k, nul, life_name[m->life]);
        before_call();
        s = F3.fmi3CompletedIntegratorStep(in->c, chance(0.5), nul == 1 ? NULL : &enter, nul == 2 ? NULL : &term);
        expect(s, forbidden || nul, 0, "fmi3CompletedIntegratorStep");
        if (s == fmi3OK) check(!term, "fmi3CompletedIntegratorStep: terminateSimulation");
        break;
    }
    default: { /* fmi3GetOutputDerivatives */
        int forbidden = me || !((M_GET_DER >> m->life) & 1);
        fmi3ValueReference vr[2];
        fmi3ValueReference cand[5] = {vrX, vrV, vrZ, vrZdot, vars3[iZeta].vr};
        int n = 1 + pick(2), bad = 0;
        fmi3Int32 ord[2];
        for (int j = 0; j < n; j++) {
            int c = pick(5);
            vr[j] = cand[c];
            ord[j] = chance(0.9) ? 1 : pick(4) - 1;
            bad |= c == 4 || ord[j] != 1;
        }
        double d[2] = {0, 0};
        note("fmi3GetOutputDerivatives(I%d, vr %u, order %d, n %d) in %s", k, vr[0], ord[0], n, life_name[m->life]);
        before_call();
        s = F3.fmi3GetOutputDerivatives(in->c, vr, (size_t)n, ord, d, (size_t)n);
        expect(s, forbidden || bad, 0, "fmi3GetOutputDerivatives");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK && n == 1 && vr[0] == vrX) {
            double v = NAN;
            cnt[N_FMI]++;
            F3.fmi3GetFloat64(in->c, &vrV, 1, &v, 1);
            check(bits(d[0]) == bits(v), "fmi3GetOutputDerivatives: dx/dt %.17g != v %.17g", d[0], v);
        }
        break;
    }
    }
}

/* ---- FMU states ---- */
static void c_states(int k) {
    Inst *in = &I[k];
    Inst *other = &I[1 - k];
    int which = pick(8);
    fmi3Status s;
    switch (which) {
    case 0:
    case 1: { /* get: new or overwrite */
        int j = in->nst < MAXST && (in->nst == 0 || chance(0.6)) ? in->nst : pick(in->nst ? in->nst : 1);
        int nul = chance(0.03);
        if (j >= MAXST) return;
        fmi3FMUState h = j < in->nst ? in->st[j].h : NULL;
        note("fmi3GetFMUState(I%d, slot %d %s, null %d) in %s", k, j, h ? "overwrite" : "new", nul, life_name[in->m.life]);
        before_call();
        s = expect(F3.fmi3GetFMUState(in->c, nul ? NULL : &h), nul, !nul, "fmi3GetFMUState");
        if (s == fmi3OK) {
            check(h != NULL, "fmi3GetFMUState: NULL state");
            if (!h) return;
            Held *st = &in->st[j];
            st->h = h;
            st->m = in->m;
            st->out_ok = observe(in, &st->out, "fmi3GetFMUState");
            if (j == in->nst) in->nst++;
        }
        break;
    }
    case 2:
    case 3: { /* set: own, other's, stale */
        int src = pick(10);
        fmi3FMUState h = NULL;
        Held *st = NULL;
        int bad = 0;
        if (src < 7 && in->nst) st = &in->st[pick(in->nst)], h = st->h;
        else if (src < 9 && other->c && other->nst) h = other->st[pick(other->nst)].h, bad = 1;
        else if (in->stale) h = in->stale, bad = 2;
        else return;
        /* A freed handle's address may have been reused for a live state (which depends on the
           allocator): then a handle the FMU never made stands in for it, so that a seed's calls
           do not depend on the allocator. */
        static int never_made;
        for (int j = 0; bad == 2 && j < MAXST; j++)
            if ((j < in->nst && in->st[j].h == h) || (other->c && j < other->nst && other->st[j].h == h))
                h = &never_made;

        note("fmi3SetFMUState(I%d, %s) in %s", k, bad ? "foreign/stale" : "own", life_name[in->m.life]);
        before_call();
        s = expect(F3.fmi3SetFMUState(in->c, h), bad, !bad, "fmi3SetFMUState");
        if (s == fmi3OK && st) {
            cnt[N_ROLLBACK]++;
            in->m = st->m;
            in->m.count = -1;
            Outputs o;
            int ok = observe(in, &o, "fmi3SetFMUState");
            if (ok && st->out_ok)
                check(outputs_same(&o, &st->out), "fmi3SetFMUState: outputs differ from those when it was taken");
        }
        break;
    }
    case 4: { /* free */
        if (!in->nst) return;
        int j = pick(in->nst);
        note("fmi3FreeFMUState(I%d, slot %d)", k, j);
        fmi3FMUState h = in->st[j].h;
        before_call();
        expect(F3.fmi3FreeFMUState(in->c, &in->st[j].h), 0, 1, "fmi3FreeFMUState");
        check(in->st[j].h == NULL, "fmi3FreeFMUState: handle not set to NULL");
        in->stale = h;
        in->st[j] = in->st[--in->nst];
        break;
    }
    case 5: { /* serialize */
        if (!in->nst) return;
        Held *st = &in->st[pick(in->nst)];
        size_t n = 0;
        note("fmi3SerializedFMUStateSize + fmi3SerializeFMUState(I%d)", k);
        before_call();
        if (expect(F3.fmi3SerializedFMUStateSize(in->c, st->h, &n), 0, 1, "fmi3SerializedFMUStateSize") != fmi3OK)
            return;
        check(n > 16 && n < 1 << 24, "serialized size %zu", n);
        fmi3Byte *b = malloc(n);
        int small = chance(0.05);
        before_call();
        s = expect(F3.fmi3SerializeFMUState(in->c, st->h, b, small ? n - 1 : n), small, !small, "fmi3SerializeFMUState");
        if (s != fmi3OK) {
            free(b);
            return;
        }
        int j = nbuf < MAXBUF ? nbuf++ : pick(MAXBUF);
        free(bufs[j].b);
        bufs[j] = (Buf){b, n, in->kind, in->em, in->er, st->m, st->out, st->out_ok};
        break;
    }
    default: { /* deserialize (maybe corrupt), then maybe set */
        if (!nbuf) return;
        Buf *bf = &bufs[pick(nbuf)];
        int corrupt = chance(0.2) ? 1 + pick(3) : 0;
        size_t n = corrupt == 2 ? bf->n - 1 - (size_t)pick((int)bf->n - 1) : bf->n;
        fmi3Byte *b = malloc(bf->n + 1);
        memcpy(b, bf->b, bf->n);
        if (corrupt == 1) b[pick((int)n)] ^= (fmi3Byte)(1u << pick(8));
        if (corrupt == 3) n = bf->n + 1, b[bf->n] = 0;
        int foreign = bf->kind != in->kind || bf->em != in->em || bf->er != in->er;
        fmi3FMUState h = NULL;
        note("fmi3DeserializeFMUState(I%d, corrupt %d, foreign %d, %zu bytes)", k, corrupt, foreign, n);
        before_call();
        s = expect(F3.fmi3DeserializeFMUState(in->c, b, n, &h), corrupt || foreign, 0, "fmi3DeserializeFMUState");
        free(b);
        cnt[N_CORRUPT] += corrupt || foreign;
        if (s != fmi3OK) {
            check(h == NULL, "fmi3DeserializeFMUState: refused but a state was made");
            return;
        }
        cnt[N_DESER]++;
        before_call();
        s = expect(F3.fmi3SetFMUState(in->c, h), 0, 1, "fmi3SetFMUState (deserialized)");
        if (s == fmi3OK) {
            cnt[N_ROLLBACK]++;
            in->m = bf->m;
            in->m.count = -1;
            Outputs o;
            if (observe(in, &o, "fmi3SetFMUState (deserialized)") && bf->out_ok)
                check(outputs_same(&o, &bf->out), "deserialized state: outputs differ from those when it was taken");
        }
        if (in->nst < MAXST && chance(0.5)) {
            in->st[in->nst].h = h;
            in->st[in->nst].m = bf->m;
            in->st[in->nst].out = bf->out;
            in->st[in->nst].out_ok = bf->out_ok;
            in->nst++;
        } else {
            before_call();
            expect(F3.fmi3FreeFMUState(in->c, &h), 0, 1, "fmi3FreeFMUState (deserialized)");
        }
        break;
    }
    }
}

static void c_lifecycle(int k) {
    Inst *in = &I[k];
    int which = pick(10);
    if (which < 5) {
        int forbidden = !((M_TERMINATE >> in->m.life) & 1);
        note("fmi3Terminate(I%d) in %s", k, life_name[in->m.life]);
        before_call();
        fmi3Status s = expect(F3.fmi3Terminate(in->c), forbidden, !forbidden, "fmi3Terminate");
        cnt[N_STATE] += forbidden;
        if (s == fmi3OK) in->m.life = L_TERM;
    } else if (which < 8) {
        note("fmi3Reset(I%d) in %s", k, life_name[in->m.life]);
        before_call();
        if (expect(F3.fmi3Reset(in->c), 0, 1, "fmi3Reset") == fmi3OK) meta_defaults(&in->m);
    } else {
        static const char *cats[] = {"logEvents", "logStatusWarning", "logStatusDiscard", "logStatusError",
                                     "logStatusFatal", "logAll", "logNothing"};
        int n = pick(3), nul = chance(0.05), bad = 0;
        fmi3String c[2];
        for (int j = 0; j < n; j++) {
            int q = pick(7);
            c[j] = cats[q];
            bad |= q == 6;
        }
        note("fmi3SetDebugLogging(I%d, n %d, null %d, bad %d)", k, n, nul, bad);
        before_call();
        expect(F3.fmi3SetDebugLogging(in->c, chance(0.5), (size_t)n, nul ? NULL : c), bad || (nul && n > 0),
               !(bad || (nul && n > 0)), "fmi3SetDebugLogging");
    }
}

/* A NULL instance: every function refuses it. */
static void c_null(void) {
    bool a, b, c, d;
    double t;
    fmi3ValueReference vr = 0;
    double x = 0;
    int which = pick(5);
    note("call with a NULL instance (%d)", which);
    cnt[N_FMI]++;
    fmi3Status s = which == 0   ? F3.fmi3DoStep(NULL, 0, 1, false, &a, &b, &c, &t)
                   : which == 1 ? F3.fmi3GetFloat64(NULL, &vr, 1, &x, 1)
                   : which == 2 ? F3.fmi3EnterEventMode(NULL)
                   : which == 3 ? F3.fmi3UpdateDiscreteStates(NULL, &a, &b, &c, &d, &a, &t)
                                : F3.fmi3Reset(NULL);
    check(s == fmi3Error, "NULL instance: status %d", (int)s);
    if (which == 4) F3.fmi3FreeInstance(NULL);
}

/* One generated call, weighted toward the valid progression of the instance's state. */
static void act(void) {
    int k = pick(2);
    Inst *in = &I[k];
    cnt[N_CALLS]++;
    if (!in->c || chance(0.003)) {
        if (chance(0.02)) c_null();
        else instantiate(k);
        return;
    }
    by_life[in->m.life]++;
    Outputs before;
    int had = in->m.life != L_INIT && readable(in) && !in->m.wild && read_outputs3(in->c, &before) == fmi3OK;
    if (had) cnt[N_FMI]++;
    long refused_before = cnt[N_STATE] + cnt[N_INVALID];
    mutated = 0;
    int r = pick(100), life = in->m.life;
    /* Valid progression first. */
    if (life == L_INST && r < 40) { if (chance(0.6)) c_set(k); else c_enter_init(k); }
    else if (life == L_INIT && r < 40) { if (chance(0.4)) c_set(k); else c_exit_init(k); }
    else if (life == L_STEP && r < 55) c_do_step(k);
    else if ((life == L_TERM || life == L_FAILED) && r < 20) {
        note("fmi3Reset(I%d) in %s", k, life_name[life]);
        before_call();
        if (expect(F3.fmi3Reset(in->c), 0, 1, "fmi3Reset") == fmi3OK) meta_defaults(&in->m);
    }
    else if (life == L_EVENT && r < 35) c_event_calls(k);
    else if (life == L_CONT && r < 40) c_me_calls(k);
    else if (r < 52) c_set(k);
    else if (r < 62) c_get(k);
    else if (r < 66) c_unsupported(k);
    else if (r < 70) c_enter_init(k);
    else if (r < 73) c_exit_init(k);
    else if (r < 78) c_do_step(k);
    else if (r < 83) c_event_calls(k);
    else if (r < 88) c_me_calls(k);
    else if (r < 95) c_states(k);
    else if (r < 99) c_lifecycle(k);
    else instantiate(k);
    if (!in->c) return;
    /* A refused call leaves the instance unchanged (outputs bit for bit). */
    if (had && !mutated && cnt[N_STATE] + cnt[N_INVALID] > refused_before && last_status3 == fmi3Error && readable(in)) {
        Outputs after;
        cnt[N_FMI]++;
        if (read_outputs3(in->c, &after) == fmi3OK)
            check(outputs_same(&before, &after), "a refused call changed the outputs");
    }
    Outputs o;
    observe(in, &o, "call");
}

static void run_seed(unsigned long seed, long ncalls) {
    seed_begin(seed, 0x3eedf00d5eedf00dULL);
    memset(I, 0, sizeof I);
    nbuf = 0;
    run_calls(ncalls, act);
    for (int k = 0; k < 2; k++) free_instance(k);
    for (int j = 0; j < nbuf; j++) free(bufs[j].b), bufs[j].b = NULL;
    disarm();
    if (!quiet || seed_failures)
        printf("seed %lu: %ld calls, %ld FMI calls, %ld invariant checks, wrong state %ld, invalid %ld, steps OK %ld, "
               "early returns %ld, event modes %ld, Discard %ld, rollbacks %ld, ME segments %ld, digest %016llx%s\n",
               seed, cnt[N_CALLS], cnt[N_FMI], cnt[N_INVARIANTS], cnt[N_STATE], cnt[N_INVALID], cnt[N_STEPS_OK],
               cnt[N_EARLY], cnt[N_EVENTMODE], cnt[N_DISCARD], cnt[N_ROLLBACK], cnt[N_ME_SEG],
               (unsigned long long)digest, seed_failures ? "  FAILED" : "");
    seed_end();
}

int fuzz3_main(const char *seeds, const char *ncalls_text) {
    kit = (struct fuzzkit){.cnt = cnt, .total = total, .ncnt = N_COUNT, .calls = &cnt[N_CALLS],
                           .checks = &cnt[N_INVARIANTS], .last_log = last_msg3};
    if (!fuzz_run(seeds, ncalls_text, find_vars, run_seed, now3)) return 2;
    print_totals(count_name, 36);
    printf("fuzz:   calls by state (oracle):");
    for (int k = 1; k < N_LIFE; k++) printf(" %s %ld%s", life_name[k], by_life[k], k < N_LIFE - 1 ? "," : "\n");
    printf("fuzz:   smallest (x - z)/max(1, |z|) seen in co-simulation: %.3g (bound -1e-9)\n", gap_min);
    return verdict();
}

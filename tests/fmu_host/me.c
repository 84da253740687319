/* `host test`, Model Exchange part: an ME driver with its own event loop (fixed-step RK4, every
 * sign change of an event indicator bisected to 1e-12 in τ, the time event of a chatter tail
 * honoured, fmi2EnterEventMode / fmi2NewDiscreteStates / fmi2EnterContinuousTimeMode), run
 * against the co-simulation interface's impacts; and scripted illegal Model Exchange calls. */
#include "host.h"

/* Settles an event (event mode to continuous-time mode); `*next` is the next time event or
 * INFINITY. 0 on success. */
int me_settle(fmi2Component c, double *next) {
    fmi2EventInfo info;
    do {
        if (F.fmi2NewDiscreteStates(c, &info) != fmi2OK) return -1;
    } while (info.newDiscreteStatesNeeded);
    *next = info.nextEventTimeDefined ? info.nextEventTime : INFINITY;
    return F.fmi2EnterContinuousTimeMode(c) == fmi2OK ? 0 : -1;
}

/* Sets time and states; 0 on success. */
static int put(fmi2Component c, double t, const double x[2]) {
    return F.fmi2SetTime(c, t) == fmi2OK && F.fmi2SetContinuousStates(c, x, 2) == fmi2OK ? 0 : -1;
}

static int deriv(fmi2Component c, double t, const double x[2], double d[2]) {
    return put(c, t, x) || F.fmi2GetDerivatives(c, d, 2) != fmi2OK ? -1 : 0;
}

/* One classical Runge-Kutta step of size h from (t, x) into y. A refused call ends it at once
 * (the derivatives it did not write are never passed on to the FMU). */
static int rk4(fmi2Component c, double t, const double x[2], double h, double y[2]) {
    double k1[2], k2[2], k3[2], k4[2], a[2];
    if (deriv(c, t, x, k1)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k1[i];
    if (deriv(c, t + h / 2, a, k2)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h / 2 * k2[i];
    if (deriv(c, t + h / 2, a, k3)) return -1;
    for (int i = 0; i < 2; i++) a[i] = x[i] + h * k3[i];
    if (deriv(c, t + h, a, k4)) return -1;
    for (int i = 0; i < 2; i++) y[i] = x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    return 0;
}

static int indicators(fmi2Component c, double t, const double x[2], double z[2]) {
    return put(c, t, x) || F.fmi2GetEventIndicators(c, z, 2) != fmi2OK ? -1 : 0;
}

static int crossed(const double a[2], const double b[2]) {
    return (a[0] > 0) != (b[0] > 0) || (a[1] > 0) != (b[1] > 0);
}

int me_run(fmi2Component c, double t0, double t_end, double h, double next, long *events) {
    double t = t0, x[2], x1[2], z0[2], z1[2];
    while (t < t_end) {
        if (F.fmi2GetContinuousStates(c, x, 2) != fmi2OK || indicators(c, t, x, z0)) return -1;
        double step = fmin(h, fmin(t_end, next) - t);
        /* A time event at or before t (announced by the last event update, or given by the
         * caller) would make every later step 0: the driver would loop at one instant. */
        if (!(step > 0)) return ME_NO_PROGRESS;
        if (rk4(c, t, x, step, x1) || indicators(c, t + step, x1, z1)) return -1;
        int event = crossed(z0, z1);
        if (event) {
            /* The earliest sign change: bisect, keeping `hi` on the far side. */
            double lo = 0, hi = step;
            while (hi - lo > 1e-12) {
                double mid = 0.5 * (lo + hi);
                if (rk4(c, t, x, mid, x1) || indicators(c, t + mid, x1, z1)) return -1;
                if (crossed(z0, z1)) hi = mid;
                else lo = mid;
            }
            step = hi;
            if (rk4(c, t, x, step, x1)) return -1;
        }
        t += step;
        fmi2Boolean enter = fmi2False, terminate = fmi2False;
        if (put(c, t, x1) ||
            F.fmi2CompletedIntegratorStep(c, fmi2True, &enter, &terminate) != fmi2OK)
            return -1;
        if (event || enter || t >= next) {
            if (F.fmi2EnterEventMode(c) != fmi2OK || me_settle(c, &next)) return -1;
            (*events)++;
        }
    }
    return 0;
}

/* A logging instance of `kind` with Omega, V set, initialized at t = 0 (ME: events settled). */
static fmi2Component start(fmi2Type kind, double omega, double v, double *next) {
    fmi2Component c = F.fmi2Instantiate("me", kind, guid, NULL, &callbacks, fmi2False, fmi2True);
    if (!c) return NULL;
    const char *cat = "logEvents";
    fmi2ValueReference vrs[2] = {vr("Omega"), vr("V")};
    fmi2Real vals[2] = {omega, v};
    int ok = F.fmi2SetDebugLogging(c, fmi2True, 1, &cat) == fmi2OK &&
             F.fmi2SetupExperiment(c, fmi2False, 0, 0.0, fmi2False, 0) == fmi2OK &&
             F.fmi2SetReal(c, vrs, 2, vals) == fmi2OK &&
             F.fmi2EnterInitializationMode(c) == fmi2OK &&
             F.fmi2ExitInitializationMode(c) == fmi2OK &&
             (kind == fmi2CoSimulation || me_settle(c, next) == 0);
    if (!ok) {
        F.fmi2FreeInstance(c);
        return NULL;
    }
    return c;
}

static int count(fmi2Component c) {
    fmi2ValueReference r = vr("impact_count");
    fmi2Integer n = -1;
    F.fmi2GetInteger(c, &r, 1, &n);
    return n;
}

/* Impact times (logged) of one run: co-simulation in one step, or the ME driver with step h. */
static int impacts(fmi2Type kind, double omega, double v, double t_end, double h, double *t) {
    double next = INFINITY;
    long events = 0;
    for (int k = 0; k < MAX_IMPACTS; k++) impact_t[k] = NAN;
    fmi2Component c = start(kind, omega, v, &next);
    if (!c) return -1;
    int ok = kind == fmi2CoSimulation ? F.fmi2DoStep(c, 0, t_end, fmi2True) == fmi2OK
                                      : me_run(c, 0, t_end, h, next, &events) == 0;
    int n = ok ? count(c) : -1;
    F.fmi2FreeInstance(c);
    for (int k = 0; k < n && k < MAX_IMPACTS; k++) t[k] = impact_t[k];
    return n;
}

/* The ME driver finds the co-simulation impacts. RK4's error is O(h^4): the error of each
 * impact time at step h is estimated from a run at h/2 as |t(h) - t(h/2)| * 16/15 (Richardson);
 * tolerance 2x that plus 2 % of the largest estimate (the finer run's own error, 1/16) plus
 * 1e-11 in τ (bisection to 1e-12 and the co-simulation's ~1e-13). */
static void me_against_cs(const char *name, double omega, double v, double t_end, double h) {
    static double cs[MAX_IMPACTS], me[MAX_IMPACTS], fine[MAX_IMPACTS];
    int n_cs = impacts(fmi2CoSimulation, omega, v, t_end, 0, cs);
    int n_me = impacts(fmi2ModelExchange, omega, v, t_end, h, me);
    int n_fine = impacts(fmi2ModelExchange, omega, v, t_end, h / 2, fine);
    char what[256];
    snprintf(what, sizeof what, "%s: ME driver (RK4 h=%g) impact count %d = co-simulation's %d",
             name, h, n_me, n_cs);
    hcheck(n_cs > 50 && n_cs < MAX_IMPACTS && n_me == n_cs && n_fine == n_cs, what);
    if (n_me != n_cs || n_fine != n_cs) return;
    double max_est = 0, max_err = 0, worst = 0;
    for (int k = 0; k < n_cs; k++) max_est = fmax(max_est, fabs(me[k] - fine[k]) * 16 / 15);
    int bad = -1;
    for (int k = 0; k < n_cs; k++) {
        double tol = 2 * fabs(me[k] - fine[k]) * 16 / 15 + 0.02 * max_est + 1e-11;
        double err = fabs(me[k] - cs[k]);
        max_err = fmax(max_err, err);
        if (err > tol && bad < 0) bad = k, worst = tol;
    }
    /* Times are the model's nondimensional τ = ω0·t (omega0 = 1 rad/s: the FMU's seconds are τ). */
    printf("me: %s: %d impacts, max |τ_ME - τ_CS| = %.2e, max error estimate %.2e (nondimensional "
           "time τ)\n", name, n_cs, max_err, max_est);
    snprintf(what, sizeof what, "%s: every ME impact time within its derived tolerance (first "
             "violation: impact %d, tolerance %.2e in τ)", name, bad, worst);
    hcheck(bad < 0, what);
}

/* Illegal Model Exchange calls: the other interface, the wrong state, bad arguments. */
static void me_illegal_calls(void) {
    double x[2] = {0, 0}, z[2];
    fmi2EventInfo info;
    fmi2Boolean enter, term;
    fmi2Component cs = F.fmi2Instantiate("cs", fmi2CoSimulation, guid, NULL, &callbacks, 0, 0);
    hrefused(F.fmi2EnterEventMode(cs), "not provided by a CoSimulation", "ME call on a CS instance");
    hrefused(F.fmi2GetNominalsOfContinuousStates(cs, x, 2), "not provided", "nominals on CS");
    F.fmi2FreeInstance(cs);

    fmi2Component c = F.fmi2Instantiate("me", fmi2ModelExchange, guid, NULL, &callbacks, 0, 0);
    hcheck(c != NULL, "instantiate Model Exchange");
    if (!c) return;
    hcheck(F.fmi2GetNominalsOfContinuousStates(c, x, 2) == fmi2OK && x[0] == 1 && x[1] == 1,
          "nominals delta_x, omega0*delta_x before initialization");
    hrefused(F.fmi2SetTime(c, 0), "not allowed in state Instantiated", "set time before init");
    hrefused(F.fmi2GetEventIndicators(c, z, 2), "not allowed", "indicators before init");
    F.fmi2SetupExperiment(c, fmi2False, 0, 0, fmi2False, 0);
    F.fmi2EnterInitializationMode(c);
    hcheck(F.fmi2GetContinuousStates(c, x, 2) == fmi2OK && x[0] == 0 && x[1] == 0,
          "states x0, v0 in initialization mode");
    hcheck(F.fmi2ExitInitializationMode(c) == fmi2OK, "exit initialization into event mode");
    hrefused(F.fmi2DoStep(c, 0, 1, 0), "not provided by a ModelExchange", "fmi2DoStep on ME");
    hrefused(F.fmi2SetContinuousStates(c, x, 2), "state EventMode", "states in event mode");
    hrefused(F.fmi2CompletedIntegratorStep(c, 0, &enter, &term), "state EventMode",
            "completed step in event mode");
    hrefused(F.fmi2NewDiscreteStates(c, NULL), "eventInfo is NULL", "NULL event info");
    hcheck(F.fmi2NewDiscreteStates(c, &info) == fmi2OK && info.valuesOfContinuousStatesChanged,
          "impact 0 at the start changes the states");
    hcheck(F.fmi2EnterContinuousTimeMode(c) == fmi2OK, "continuous-time mode");
    hrefused(F.fmi2NewDiscreteStates(c, &info), "state ContinuousTimeMode", "event update outside");
    hrefused(F.fmi2SetContinuousStates(c, x, 3), "nx = 3", "three states");
    hrefused(F.fmi2SetContinuousStates(c, NULL, 2), "x is NULL", "NULL states");
    hrefused(F.fmi2GetDerivatives(c, NULL, 2), "derivatives is NULL", "NULL derivatives");
    hrefused(F.fmi2GetEventIndicators(c, z, 1), "ni = 1", "one indicator");
    hrefused(F.fmi2SetTime(c, NAN), "must be finite", "NaN time");
    hrefused(F.fmi2SetTime(c, -1), "not before the last event", "time before the last event");
    double inf_state[2] = {INFINITY, 0};
    hrefused(F.fmi2SetContinuousStates(c, inf_state, 2), "must be finite", "infinite state");
    fmi2ValueReference omega = vr("Omega");
    fmi2Real two = 2;
    hrefused(F.fmi2SetReal(c, &omega, 1, &two), "only inputs", "parameter in continuous time");
    hcheck(F.fmi2GetContinuousStates(c, x, 2) == fmi2OK && x[0] == 0 && x[1] > 0.12,
          "refusals leave the states");
    hcheck(F.fmi2EnterEventMode(c) == fmi2OK && F.fmi2SetReal(c, &omega, 1, &two) == fmi2OK,
          "tunable parameter in event mode");
    hcheck(F.fmi2Terminate(c) == fmi2OK, "terminate from event mode");
    hrefused(F.fmi2EnterEventMode(c), "state Terminated", "event mode after terminate");
    F.fmi2FreeInstance(c);
}

/* With omega0 != 1 the time event of a chatter tail (start of sticking, announced as
 * until/omega0 s) must be due when the driver sets the time to it, also when t*omega0 comes back
 * an ulp before until; otherwise every event update announces the same time and this driver
 * steps by 0 for ever. From the paper's start with these parameters the run reaches t = 60 with
 * every time event after the time of its update (me_run returns ME_NO_PROGRESS otherwise, which
 * a tail never due causes with this h after 4 impacts), its work bounded by its steps of size h
 * (event modes: at most a tenth of them), and it counts the co-simulation's impacts (the tails
 * were applied). */
static void me_time_events_progress(void) {
    const char *names[5] = {"omega0", "Omega", "V", "e", "zeta"};
    const fmi2Real vals[5] = {1.2314973701554512, 0.31567602743490469, 0.016579423043057092,
                              0.18776913593613076, 0.17808901653899142};
    fmi2ValueReference vrs[5];
    for (int k = 0; k < 5; k++) vrs[k] = vr(names[k]);
    const double t_end = 60, h = 2.5e-3;
    int n[2] = {-1, -1};
    long events = 0, rc = -1;
    double next = INFINITY;
    for (int kind = 0; kind < 2; kind++) { /* fmi2ModelExchange, fmi2CoSimulation */
        fmi2Component c = F.fmi2Instantiate("me", kind, guid, NULL, &callbacks, fmi2False, fmi2False);
        int ok = c && F.fmi2SetupExperiment(c, fmi2False, 0, 0.0, fmi2False, 0) == fmi2OK &&
                 F.fmi2SetReal(c, vrs, 5, vals) == fmi2OK &&
                 F.fmi2EnterInitializationMode(c) == fmi2OK &&
                 F.fmi2ExitInitializationMode(c) == fmi2OK &&
                 (kind == fmi2CoSimulation || me_settle(c, &next) == 0);
        hcheck(ok, "time events: instantiate and initialize (omega0 = 1.2314973701554512)");
        if (ok && kind == fmi2ModelExchange) rc = me_run(c, 0, t_end, h, next, &events);
        if (ok && kind == fmi2CoSimulation) ok = F.fmi2DoStep(c, 0, t_end, fmi2True) == fmi2OK;
        if (ok) n[kind] = count(c);
        if (c) F.fmi2FreeInstance(c);
    }
    char what[256];
    snprintf(what, sizeof what, "time events: the ME driver reaches t = %g (status %ld; %d is a "
             "time event not after the current time)", t_end, rc, ME_NO_PROGRESS);
    hcheck(rc == 0, what);
    long bound = (long)(t_end / h) / 10;
    snprintf(what, sizeof what, "time events: %ld event modes <= %ld (a tenth of the %g steps)",
             events, bound, t_end / h);
    hcheck(events > 0 && events <= bound, what);
    snprintf(what, sizeof what, "time events: ME impact count %d = co-simulation's %d", n[0], n[1]);
    hcheck(n[0] > 0 && n[0] == n[1], what);
    printf("me: time events (omega0 = 1.2314973701554512, t <= %g): %ld event modes, %d impacts\n",
           t_end, events, n[0]);
}

void me_tests(void) {
    me_illegal_calls();
    me_time_events_progress();
    me_against_cs("baseline Omega=1.75 V=0.07 t<=200", 1.75, 0.07, 200, 1e-3);
    me_against_cs("chatter Omega=0.2 V=0.05 t<=60", 0.2, 0.05, 60, 1e-3);
}

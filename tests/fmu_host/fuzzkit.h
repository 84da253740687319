/* The harness shared by the fuzzers `host fuzz` (fuzz.c, FMI 2.0) and `host3 fuzz` (fmi3/fuzz3.c,
 * FMI 3.0): deterministic random numbers (splitmix64), the state of the seed in progress (seed,
 * call, failures, digest), the ring of recent calls, failure reports (at most 5 printed per seed),
 * the per-call watchdog and crash report, the wall time of every generated call (the slowest one
 * is reported in the summary: a benchmark figure, not checked), the arguments and FUZZ_* options,
 * the per-seed set-up and the summary. The fuzzer sets `kit` (its counters and hooks) before its first seed. All static
 * (inline: a fuzzer need not use every function). */
#ifndef BISTABLE_FUZZKIT_H
#define BISTABLE_FUZZKIT_H

#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <unistd.h>

/* What the harness needs from the fuzzer. */
struct fuzzkit {
    long *cnt, *total;    /* its counters of the seed and of all seeds, ncnt of them */
    int ncnt;
    long *calls;          /* counter of generated calls (the per-seed budget) */
    long *checks;         /* counter of invariant checks (check()) */
    const char *last_log; /* the FMU's last log message, printed with a failure */
    const char *pending;  /* the call in progress, printed by dump_ring if not empty (NULL: none) */
    void (*save)(void);   /* on the first failure of a seed and on a hang or crash (NULL: none) */
};
static struct fuzzkit kit;

/* ---- deterministic random numbers (splitmix64) ---- */
static uint64_t rng_state;

static inline uint64_t rnd(void) {
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
static inline double unif(void) { return (double)(rnd() >> 11) * 0x1.0p-53; }
static inline double urange(double a, double b) { return a + (b - a) * unif(); }
static inline double logu(double a, double b) { return exp(urange(log(a), log(b))); }
static inline int chance(double p) { return unif() < p; }
static inline int pick(int n) { return (int)(rnd() % (uint64_t)n); }

/* ---- the seed in progress, failures, trace ---- */
static unsigned long seed_now;
static long call_now;
static long failures, seed_failures;
static int trace, quiet;
static uint64_t digest;

#define RING 48
static char ring[RING][320];
static long ring_n;

/* Records a call in the ring (and prints it with FUZZ_TRACE). */
static inline void note(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(ring[ring_n % RING], sizeof ring[0], fmt, ap);
    va_end(ap);
    if (trace) printf("  %ld: %s\n", call_now, ring[ring_n % RING]);
    ring_n++;
}

static inline void dump_ring(void) {
    long first = ring_n > RING ? ring_n - RING : 0;
    printf("  last calls (seed %lu):\n", seed_now);
    for (long k = first; k < ring_n; k++) printf("    %s\n", ring[k % RING]);
    if (kit.pending && kit.pending[0]) printf("  in progress: %s\n", kit.pending);
}

static inline void fail(const char *fmt, ...) {
    failures++;
    seed_failures++;
    if (seed_failures == 1 && kit.save) kit.save();
    if (seed_failures > 5) return;
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    printf("FUZZ FAIL seed=%lu call=%ld: %s (last log: %s)\n", seed_now, call_now, buf, kit.last_log);
    dump_ring();
    fflush(stdout);
}

static inline void check(int ok, const char *fmt, ...) {
    (*kit.checks)++;
    if (ok) return;
    char buf[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fail("%s", buf);
}

/* The seed's digest of statuses and outputs (FNV-1a style). */
static inline void mix(uint64_t x) { digest = (digest ^ x) * 0x100000001b3ULL; }
static inline uint64_t bits(double x) {
    uint64_t u;
    memcpy(&u, &x, 8);
    return u;
}

/* ---- watchdog and crash report ---- */
static inline void on_signal(int sig) {
    char buf[160];
    int n = snprintf(buf, sizeof buf, "\nFUZZ %s seed=%lu call=%ld\n",
                     sig == SIGALRM ? "HANG (call timeout)" : "CRASH (signal)", seed_now, call_now);
    fflush(stdout);
    if (write(1, buf, (size_t)n) < 0) _exit(5);
    if (kit.save) kit.save();
    dump_ring();
    fflush(stdout);
    _exit(sig == SIGALRM ? 3 : 4);
}

static double call_timeout = 20;

static inline void arm(void) {
    struct itimerval it = {{0, 0}, {(time_t)call_timeout, 0}};
    setitimer(ITIMER_REAL, &it, NULL);
}

static inline void disarm(void) {
    struct itimerval off = {{0, 0}, {0, 0}};
    setitimer(ITIMER_REAL, &off, NULL);
}

/* ---- seeds and summary ---- */
/* Starts a seed: random numbers from `seed` and the fuzzer's `salt`, counters cleared. */
static inline void seed_begin(unsigned long seed, uint64_t salt) {
    rng_state = seed ^ salt;
    rng_state = rnd() ^ rnd(); /* decorrelate neighbouring seeds */
    seed_now = seed;
    seed_failures = 0;
    digest = 0xcbf29ce484222325ULL;
    ring_n = 0;
    memset(kit.cnt, 0, sizeof *kit.cnt * (size_t)kit.ncnt);
}

/* ---- wall time per generated call ---- */
static double slowest = -1;          /* wall time (s) of the slowest generated call so far */
static unsigned long slowest_seed;
static long slowest_call;
static char slowest_note[320];      /* the last call recorded in the ring before it ended */
static double calls_timed;
static double (*kit_clock)(void); /* the fuzzer's monotonic clock (s), given to fuzz_run */

/* One generated call under the watchdog, timed. */
static inline void timed_call(void (*act)(void)) {
    arm();
    double t0 = kit_clock();
    act();
    double dt = kit_clock() - t0;
    calls_timed++;
    if (dt > slowest) {
        slowest = dt, slowest_seed = seed_now, slowest_call = call_now;
        snprintf(slowest_note, sizeof slowest_note, "%s", ring_n ? ring[(ring_n - 1) % RING] : "");
    }
}

/* Calls `act` under the watchdog until the seed's budget of calls is spent. */
static inline void run_calls(long ncalls, void (*act)(void)) {
    for (call_now = 0; *kit.calls < ncalls; call_now++) timed_call(act);
}

/* Ends a seed (after its summary line): counters added to the totals. */
static inline void seed_end(void) {
    fflush(stdout);
    for (int k = 0; k < kit.ncnt; k++) kit.total[k] += kit.cnt[k];
}

/* The fuzz mode up to the totals: SEEDS ("N" or "A-B") and NCALLS, FUZZ_TRACE, FUZZ_QUIET,
 * FUZZ_CALL_TIMEOUT, `setup`, the watchdog, `run_seed` over the seeds (each call timed by
 * `wall`), the summary's first line (`wall`: monotonic wall time in s). 0 on bad arguments. */
static inline int fuzz_run(const char *seeds, const char *ncalls_text, void (*setup)(void),
                           void (*run_seed)(unsigned long, long), double (*wall)(void)) {
    unsigned long first = 0, last = 0;
    if (sscanf(seeds, "%lu-%lu", &first, &last) != 2) last = first = strtoul(seeds, NULL, 10);
    long ncalls = atol(ncalls_text);
    if (last < first || ncalls <= 0) {
        fprintf(stderr, "fuzz: bad SEEDS or NCALLS\n");
        return 0;
    }
    trace = getenv("FUZZ_TRACE") != NULL;
    quiet = getenv("FUZZ_QUIET") != NULL;
    if (getenv("FUZZ_CALL_TIMEOUT")) call_timeout = atof(getenv("FUZZ_CALL_TIMEOUT"));
    kit_clock = wall;
    setup();
    signal(SIGALRM, on_signal);
    signal(SIGSEGV, on_signal);
    signal(SIGBUS, on_signal);
    signal(SIGFPE, on_signal);
    signal(SIGABRT, on_signal);
    double t0 = wall();
    for (unsigned long s = first; s <= last; s++) run_seed(s, ncalls);
    double dt = wall() - t0;
    printf("fuzz: seeds %lu-%lu (%lu), %.2f s\n", first, last, last - first + 1, dt);
    return 1;
}

/* The totals of all seeds, one a line, names padded to `width`; then the slowest generated call
 * (wall time, with its seed, call number and last recorded FMI call). */
static inline void print_totals(const char **names, int width) {
    for (int k = 0; k < kit.ncnt; k++) printf("fuzz:   %-*s %ld\n", width, names[k], kit.total[k]);
    if (slowest >= 0)
        printf("fuzz:   %-*s %.3g s of %.0f calls (seed %lu call %ld, last recorded: %s)\n", width,
               "slowest call (wall)", slowest, calls_timed, slowest_seed, slowest_call,
               slowest_note);
}

/* The summary's last line; the exit code (1 if any invariant failed). */
static inline int verdict(void) {
    printf("fuzz: %ld invariant violations\n", failures);
    return failures ? 1 : 0;
}

#endif

/* bushenv FMU core: runs the model (model.h) at its own sample time whatever the master's step.

   Inputs: the MODEL_N_COORDS coordinates x (one deflection; or axial, radial, rotation), and
   an optional velocity of each. The model's velocity at sample n is the backward difference
   (x_n - x_(n-1)) / dt of the coordinates it was given (x_(-1) = 0: the bushing starts at
   rest), as bushenv's rigs feed their models; once the master connects a coordinate's velocity
   input (sets it after initialisation, or to other than its start value 0 during it), that
   input is used for that coordinate instead. Outputs: one force (N, or N m) per coordinate.

   Co-simulation: sample n lies at t0 + n * MODEL_DT_S. The core keeps the model state after
   every sample whose input is known ("committed"): at doStep(t, h) every sample at or before t
   is committed, its input interpolated linearly between the last two communication points.
   The outputs at time t_now are those of the latest sample at or before t_now when the input
   at t_now is known -- set by the master (a master that sets inputs, then reads outputs, gets
   the model's force) or extrapolated along the input derivative it set (FMI 2) -- computed on
   a scratch copy of the state ("pending", recomputed once the input is set, never committed
   on a guess). Read right after doStep, before any new input, they are those of the latest
   committed sample: the force lags the communication point by up to one step.

   Model exchange: no continuous states. Each sample is a time event (t0 + n dt, announced as
   the next event time) at which the sample is committed with the input at that time. Between
   samples n and n+1 the force is a direct function of the current input x: with a = (t -
   t_n) / dt, (1 - a) F_n(x) + a F_(n+1)(x), where F_n(x) is sample n recomputed with x (from
   the state before it) and F_(n+1)(x) the next sample taken with x (from the state after n),
   each with its own backward-difference velocity. At each sample the force is the model's, it
   is continuous across samples, and for an input linear between samples it is the linear
   interpolation of the model's forces when the model is linear in x and v. docs/export.md
   states the error of each case.

   Envelope (model.h, generated): a sample is outside when for a coordinate i |x_i| >
   ENV_STROKE[i], |x_i,n - x_i,(n-1)| / dt > ENV_VELOCITY[i], or x lies in a box the model's
   certificate flags (ENV_FLAGGED: per box its lower corner, then its upper one; a failing
   hold's cell). Such a sample also sets in_flagged_range; each entry into a box is logged, and
   a model that fails its certificate says so once, when initialisation ends. */
#include <stdio.h>
#include <string.h>

#define CORE_EPS (1e-6 * MODEL_DT_S) /* a time this close to a sample is on it */
#define NC MODEL_N_COORDS

typedef void (*core_log_fn)(void *env, int warning, const char *message);

typedef struct {
    double s[MODEL_N_STATE]; /* model state after the last counted sample */
    long n;                  /* samples counted */
    double x_last[NC];       /* input of the last counted sample */
    double force[NC];        /* its forces */
    int outside;             /* the last counted sample is outside the envelope */
    long n_outside;          /* counted samples outside */
    int flagged;             /* 1 + the flagged box the last counted sample is in, or 0 */
} CoreRun;

typedef struct {
    CoreRun done, pending, before; /* before: model exchange, the run before the latest sample */
    int pending_valid;
    double t0, t_known; /* last committed communication point */
    double x_known[NC], v_known[NC];
    int have_known;
    double t_now;                 /* current time */
    double x_now[NC], v_now[NC];  /* current inputs (set or extrapolated) */
    double dx_now[NC], dv_now[NC]; /* input derivatives set by the master (FMI 2) */
    int fresh;                    /* the input at t_now is known: set, or along a derivative */
    int has_derivative;           /* the master sets input derivatives (FMI 2) */
    int started;                  /* initialisation is over */
    int velocity_connected[NC];   /* the master connected that velocity (see the top) */
    int me;                       /* model exchange */
    core_log_fn log;
    void *log_env;
    char message[1024];
} Core;

static void core_reset(Core *c, double t0) {
    memset(&c->done, 0, sizeof c->done);
    model_reset(c->done.s);
    c->pending = c->before = c->done;
    c->pending_valid = 0;
    c->t0 = c->t_now = c->t_known = t0;
    c->have_known = 0;
    for (int i = 0; i < NC; i++) {
        c->x_now[i] = c->v_now[i] = c->x_known[i] = c->v_known[i] = 0.0;
        c->dx_now[i] = c->dv_now[i] = 0.0;
        c->velocity_connected[i] = 0;
    }
    c->fresh = 1;
    c->has_derivative = 0;
    c->started = 0;
}

/* A new start time, keeping the inputs set so far and the form (co-simulation or not). */
static void core_restart(Core *c, double t0) {
    double x[NC], v[NC];
    int me = c->me, connected[NC];
    for (int i = 0; i < NC; i++) {
        x[i] = c->x_now[i];
        v[i] = c->v_now[i];
        connected[i] = c->velocity_connected[i];
    }
    core_reset(c, t0);
    for (int i = 0; i < NC; i++) {
        c->x_now[i] = x[i];
        c->v_now[i] = v[i];
        c->velocity_connected[i] = connected[i];
    }
    c->me = me;
}

#define WHY_FLAGGED "in a range the certificate flags"

/* 1 + the first flagged box that holds x, or 0. */
static int core_in_flagged(const double *x) {
    for (int k = 0; k < ENV_N_FLAGGED; k++) {
        const double *lo = ENV_FLAGGED + 2 * NC * k, *hi = lo + NC;
        int in = 1;
        for (int i = 0; i < NC && in; i++) in = x[i] >= lo[i] && x[i] <= hi[i];
        if (in) return k + 1;
    }
    return 0;
}

/* Why a sample is outside the envelope (NULL: inside); *which: the coordinate. */
static const char *core_outside_why(const double *x, const double *x_prev, int first,
                                    int *which) {
    for (int i = 0; i < NC; i++) {
        *which = i;
        if (fabs(x[i]) > ENV_STROKE[i]) return "beyond the fitted stroke";
        if (!first && fabs(x[i] - x_prev[i]) / MODEL_DT_S > ENV_VELOCITY[i])
            return "rate beyond the fitted range";
    }
    *which = 0;
    if (core_in_flagged(x)) return WHY_FLAGGED;
    return NULL;
}

/* Count one sample at ts with inputs x (and velocity inputs v) into r. Returns 0, or -1 when
   a force is not finite. */
static int core_sample(Core *c, CoreRun *r, double ts, const double *x, const double *v) {
    double vv[NC];
    int which;
    for (int i = 0; i < NC; i++) /* backward difference; x_(-1) = 0 */
        vv[i] = c->velocity_connected[i] ? v[i] : (x[i] - r->x_last[i]) / MODEL_DT_S;
    model_step_n(r->s, x, vv, r->force);
    for (int i = 0; i < NC; i++) {
        if (!(r->force[i] == r->force[i]) || fabs(r->force[i]) > 1e300) {
            snprintf(c->message, sizeof c->message,
                     "the model's %s is not finite at t = %.6g s (%s = %.6g %s, rate %.6g %s/s)",
                     FORCE_NAMES[i], ts, COORD_NAMES[i], x[i], COORD_UNITS[i], vv[i],
                     COORD_UNITS[i]);
            return -1;
        }
    }
    r->outside = core_outside_why(x, r->x_last, r->n == 0, &which) != NULL;
    r->n_outside += r->outside;
    r->flagged = core_in_flagged(x);
    for (int i = 0; i < NC; i++) r->x_last[i] = x[i];
    r->n += 1;
    return 0;
}

/* Input at sample time ts: linear between the last committed point and (t_now, x_now). */
static void core_input(const Core *c, double ts, double *x, double *v) {
    double span = c->t_now - c->t_known;
    if (!c->have_known || span <= CORE_EPS || ts >= c->t_now - CORE_EPS) {
        for (int i = 0; i < NC; i++) {
            x[i] = c->x_now[i];
            v[i] = c->v_now[i];
        }
        return;
    }
    double a = (ts - c->t_known) / span;
    for (int i = 0; i < NC; i++) {
        x[i] = c->x_known[i] + a * (c->x_now[i] - c->x_known[i]);
        v[i] = c->v_known[i] + a * (c->v_now[i] - c->v_known[i]);
    }
}

/* Count every sample at or before t_now into c->pending (from the committed run). Returns 0,
   or -1 when the model's force is not finite (message set). */
static int core_pending(Core *c) {
    if (c->pending_valid) return 0;
    CoreRun r = c->done;
    for (;;) {
        double ts = c->t0 + (double)r.n * MODEL_DT_S;
        if (ts > c->t_now + CORE_EPS) break;
        double x[NC], v[NC];
        core_input(c, ts, x, v);
        if (core_sample(c, &r, ts, x, v)) return -1;
    }
    c->pending = r;
    c->pending_valid = 1;
    return 0;
}

/* Log an entry into the outside of the envelope at sample time ts (coordinate i). */
static void core_log_entry(Core *c, double ts, const char *why, int i, const double *x) {
    if (!c->log) return;
    snprintf(c->message, sizeof c->message,
             "t = %.6g s: input leaves the bushing's validity envelope: %s %s "
             "(%s = %.6g %s, stroke %.6g %s, rate limit %.6g %s/s; %s)",
             ts, COORD_NAMES[i], why, COORD_SYMBOLS[i], x[i], COORD_UNITS[i], ENV_STROKE[i],
             COORD_UNITS[i], ENV_VELOCITY[i], COORD_UNITS[i], ENV_SOURCE);
    c->log(c->log_env, 1, c->message);
}

/* Log an entry into flagged box k - 1 at sample time ts. */
static void core_log_flagged(Core *c, double ts, int k, const double *x) {
    if (!c->log || k <= 0) return;
    const double *lo = ENV_FLAGGED + 2 * NC * (k - 1), *hi = lo + NC;
    size_t used = (size_t)snprintf(c->message, sizeof c->message,
                                   "t = %.6g s: input enters a range where the model fails its "
                                   "certificate (%s):", ts, ENV_FLAGGED_WHY[k - 1]);
    for (int i = 0; i < NC && used < sizeof c->message; i++)
        used += (size_t)snprintf(c->message + used, sizeof c->message - used,
                                 "%s %s = %.6g %s in [%.6g, %.6g]", i ? "," : "", COORD_SYMBOLS[i],
                                 x[i], COORD_UNITS[i], lo[i], hi[i]);
    if (used < sizeof c->message)
        snprintf(c->message + used, sizeof c->message - used,
                 "; its force there is not to be trusted (card.certificate)");
    c->log(c->log_env, 1, c->message);
}

/* Log the entries of one sample: into the envelope's outside (not for a flagged box alone,
   which core_log_flagged says better), and into a flagged box. */
static void core_log_sample(Core *c, double ts, const double *x, const char *why, int which,
                            int was_outside, int flagged, int was_flagged) {
    if (why && !was_outside && why != WHY_FLAGGED) core_log_entry(c, ts, why, which, x);
    if (flagged && !was_flagged) core_log_flagged(c, ts, flagged, x);
}

/* Once, when initialisation ends: a model exported although it fails its certificate. */
static void core_log_certificate(Core *c) {
    if (!CERT_FAILS || !c->log) return;
    snprintf(c->message, sizeof c->message,
             "this model fails its certificate and was exported with --allow-failing: %s; "
             "in_flagged_range is true while the input lies in a flagged range (%d, listed in "
             "card.certificate_flagged)",
             CERT_VERDICT, ENV_N_FLAGGED);
    c->log(c->log_env, 1, c->message);
}

/* Commit the samples up to t_now and log each entry into the outside of the envelope. */
static int core_commit(Core *c) {
    CoreRun before = c->done;
    if (core_pending(c)) return -1;
    /* re-walk only to find entries (cheap: the envelope test, not the model) */
    int was_outside = before.outside, was_flagged = before.flagged, which;
    double x_prev[NC];
    for (int i = 0; i < NC; i++) x_prev[i] = before.x_last[i];
    for (long n = before.n; n < c->pending.n; n++) {
        double ts = c->t0 + (double)n * MODEL_DT_S, x[NC], v[NC];
        core_input(c, ts, x, v);
        const char *why = core_outside_why(x, x_prev, n == 0, &which);
        int flagged = core_in_flagged(x);
        core_log_sample(c, ts, x, why, which, was_outside, flagged, was_flagged);
        was_outside = why != NULL;
        was_flagged = flagged;
        for (int i = 0; i < NC; i++) x_prev[i] = x[i];
    }
    c->done = c->pending;
    return 0;
}

/* doStep(t, h): commit up to t, then move to t + h with the input extrapolated. */
static int core_do_step(Core *c, double t, double h) {
    c->t_now = t;
    if (core_commit(c)) return -1;
    c->t_known = t;
    for (int i = 0; i < NC; i++) {
        c->x_known[i] = c->x_now[i];
        c->v_known[i] = c->v_now[i];
        c->x_now[i] = c->x_known[i] + h * c->dx_now[i];
        c->v_now[i] = c->v_known[i] + h * c->dv_now[i];
    }
    c->have_known = 1;
    c->t_now = t + h;
    c->pending_valid = 0;
    c->fresh = c->has_derivative;
    return 0;
}

/* Model exchange, at an event: commit every sample due by t_now with the current input.
   Returns 0, or -1 when the force is not finite. */
static int core_me_event(Core *c) {
    int which;
    for (;;) {
        double ts = c->t0 + (double)c->done.n * MODEL_DT_S;
        if (ts > c->t_now + CORE_EPS) break;
        c->before = c->done;
        if (core_sample(c, &c->done, ts, c->x_now, c->v_now)) return -1;
        const char *why =
            core_outside_why(c->x_now, c->before.x_last, c->before.n == 0, &which);
        core_log_sample(c, ts, c->x_now, why, which, c->before.outside, c->done.flagged,
                        c->before.flagged);
    }
    c->pending_valid = 0;
    return 0;
}

/* Model exchange: the time of the next sample (the next time event). */
static double core_me_next_event(const Core *c) {
    return c->t0 + (double)c->done.n * MODEL_DT_S;
}

/* Model exchange: the forces at t_now between samples n and n+1 (see the top). */
static int core_me_pending(Core *c) {
    if (c->pending_valid) return 0;
    c->pending = c->done;
    if (c->done.n == 0) { /* before the first event: nothing counted yet */
        c->pending_valid = 1;
        return 0;
    }
    double t_latest = c->t0 + (double)(c->done.n - 1) * MODEL_DT_S;
    double a = (c->t_now - t_latest) / MODEL_DT_S;
    CoreRun latest = c->before, next = c->done;
    if (core_sample(c, &latest, c->t_now, c->x_now, c->v_now)) return -1;
    if (a > CORE_EPS / MODEL_DT_S) {
        if (a > 1.0) a = 1.0;
        if (core_sample(c, &next, c->t_now, c->x_now, c->v_now)) return -1;
        for (int i = 0; i < NC; i++)
            c->pending.force[i] = (1.0 - a) * latest.force[i] + a * next.force[i];
    } else { /* on the sample: the model's forces there */
        for (int i = 0; i < NC; i++) c->pending.force[i] = latest.force[i];
    }
    c->pending_valid = 1;
    return 0;
}

/* What the outputs show: the samples up to t_now when their input is known (set at t_now, or
   extrapolated along a derivative), else the committed ones (the input at t_now is unknown);
   in model exchange, the forces of the current input (core_me_pending). */
static const CoreRun *core_outputs(Core *c) {
    if (c->me) return core_me_pending(c) ? NULL : &c->pending;
    if (!c->fresh) return &c->done;
    if (core_pending(c)) return NULL;
    return &c->pending;
}

/* Set coordinate i's deflection (velocity 0) or velocity (1). */
static void core_set_input(Core *c, int velocity, int i, double value) {
    if (!velocity) c->x_now[i] = value;
    else {
        c->v_now[i] = value;
        /* connected: set after initialisation, or to other than its start value (0) during
           it; a master that only applies the start value has not connected it */
        if (c->started || value != 0.0) c->velocity_connected[i] = 1;
    }
    c->pending_valid = 0;
    c->fresh = 1;
}

static void core_set_derivative(Core *c, int velocity, int i, double value) {
    if (!velocity) c->dx_now[i] = value;
    else c->dv_now[i] = value;
    c->has_derivative = 1;
}

/* bushenv FMU core: runs the model (model.h) at its own sample time whatever the master's step.

   Inputs: the deflection, and an optional velocity. The model's velocity at sample n is the
   backward difference (x_n - x_(n-1)) / dt of the deflections it was given (x_(-1) = 0: the
   bushing starts at rest), as bushenv's rigs feed their models; once the master connects the
   `velocity` input (sets it after initialisation, or to other than its start value 0 during
   it), that input is used instead.

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

   Envelope (model.h, generated): a sample is outside when |x| > ENV_STROKE_M, |x_n -
   x_(n-1)| / dt > ENV_VELOCITY_M_PER_S, or x lies in a range the model's certificate flags. */
#include <stdio.h>
#include <string.h>

#define CORE_EPS (1e-6 * MODEL_DT_S) /* a time this close to a sample is on it */

typedef void (*core_log_fn)(void *env, int warning, const char *message);

typedef struct {
    double s[MODEL_N_STATE]; /* model state after the last counted sample */
    long n;                  /* samples counted */
    double x_last, force;    /* input and force of the last counted sample */
    int outside;             /* the last counted sample is outside the envelope */
    long n_outside;          /* counted samples outside */
} CoreRun;

typedef struct {
    CoreRun done, pending, before; /* before: model exchange, the run before the latest sample */
    int pending_valid;
    double t0, t_known, x_known, v_known; /* last committed communication point */
    int have_known;
    double t_now, x_now, v_now; /* current time and inputs (set or extrapolated) */
    double dx_now, dv_now;      /* input derivatives set by the master (FMI 2) */
    int fresh;                  /* the input at t_now is known: set, or along a derivative */
    int has_derivative;         /* the master sets input derivatives (FMI 2) */
    int started;                /* initialisation is over */
    int velocity_connected;     /* the master connected `velocity` (see the top) */
    int me;                     /* model exchange */
    core_log_fn log;
    void *log_env;
    char message[512];
} Core;

static void core_reset(Core *c, double t0) {
    memset(&c->done, 0, sizeof c->done);
    model_reset(c->done.s);
    c->pending = c->before = c->done;
    c->pending_valid = 0;
    c->t0 = c->t_now = c->t_known = t0;
    c->have_known = 0;
    c->x_now = c->v_now = c->x_known = c->v_known = c->dx_now = c->dv_now = 0.0;
    c->fresh = 1;
    c->has_derivative = 0;
    c->started = 0;
    c->velocity_connected = 0;
}

static int core_in_flagged(double x) {
    for (int i = 0; i < ENV_N_FLAGGED; i++)
        if (x >= ENV_FLAGGED[2 * i] && x <= ENV_FLAGGED[2 * i + 1]) return 1;
    return 0;
}

/* Why a sample is outside the envelope (NULL: inside). */
static const char *core_outside_why(double x, double speed) {
    if (fabs(x) > ENV_STROKE_M) return "deflection beyond the fitted stroke";
    if (speed > ENV_VELOCITY_M_PER_S) return "velocity beyond the fitted range";
    if (core_in_flagged(x)) return "deflection in a range the certificate flags";
    return NULL;
}

/* Count one sample at ts with input x (and velocity input v) into r. Returns 0, or -1 when
   the force is not finite. */
static int core_sample(Core *c, CoreRun *r, double ts, double x, double v) {
    double rate = (x - r->x_last) / MODEL_DT_S; /* backward difference; x_(-1) = 0 */
    double speed = r->n > 0 ? fabs(x - r->x_last) / MODEL_DT_S : 0.0;
    if (!c->velocity_connected) v = rate;
    r->force = model_step(r->s, x, v);
    if (!(r->force == r->force) || fabs(r->force) > 1e300) {
        snprintf(c->message, sizeof c->message,
                 "the model's force is not finite at t = %.6g s (x = %.6g m, v = %.6g m/s)",
                 ts, x, v);
        return -1;
    }
    r->outside = core_outside_why(x, speed) != NULL;
    r->n_outside += r->outside;
    r->x_last = x;
    r->n += 1;
    return 0;
}

/* Input at sample time ts: linear between the last committed point and (t_now, x_now). */
static void core_input(const Core *c, double ts, double *x, double *v) {
    double span = c->t_now - c->t_known;
    if (!c->have_known || span <= CORE_EPS || ts >= c->t_now - CORE_EPS) {
        *x = c->x_now;
        *v = c->v_now;
        return;
    }
    double a = (ts - c->t_known) / span;
    *x = c->x_known + a * (c->x_now - c->x_known);
    *v = c->v_known + a * (c->v_now - c->v_known);
}

/* Count every sample at or before t_now into c->pending (from the committed run). Returns 0,
   or -1 when the model's force is not finite (message set). */
static int core_pending(Core *c) {
    if (c->pending_valid) return 0;
    CoreRun r = c->done;
    for (;;) {
        double ts = c->t0 + (double)r.n * MODEL_DT_S;
        if (ts > c->t_now + CORE_EPS) break;
        double x, v;
        core_input(c, ts, &x, &v);
        if (core_sample(c, &r, ts, x, v)) return -1;
    }
    c->pending = r;
    c->pending_valid = 1;
    return 0;
}

/* Log an entry into the outside of the envelope at sample time ts. */
static void core_log_entry(Core *c, double ts, const char *why, double x) {
    if (!c->log) return;
    snprintf(c->message, sizeof c->message,
             "t = %.6g s: input leaves the bushing's validity envelope: %s "
             "(x = %.6g m, stroke %.6g m, velocity limit %.6g m/s; %s)",
             ts, why, x, ENV_STROKE_M, ENV_VELOCITY_M_PER_S, ENV_SOURCE);
    c->log(c->log_env, 1, c->message);
}

/* Commit the samples up to t_now and log each entry into the outside of the envelope. */
static int core_commit(Core *c) {
    CoreRun before = c->done;
    if (core_pending(c)) return -1;
    /* re-walk only to find entries (cheap: the envelope test, not the model) */
    int was_outside = before.outside;
    double x_prev = before.x_last;
    for (long n = before.n; n < c->pending.n; n++) {
        double ts = c->t0 + (double)n * MODEL_DT_S, x, v;
        core_input(c, ts, &x, &v);
        const char *why = core_outside_why(x, n > 0 ? fabs(x - x_prev) / MODEL_DT_S : 0.0);
        if (why && !was_outside) core_log_entry(c, ts, why, x);
        was_outside = why != NULL;
        x_prev = x;
    }
    c->done = c->pending;
    return 0;
}

/* doStep(t, h): commit up to t, then move to t + h with the input extrapolated. */
static int core_do_step(Core *c, double t, double h) {
    c->t_now = t;
    if (core_commit(c)) return -1;
    c->t_known = t;
    c->x_known = c->x_now;
    c->v_known = c->v_now;
    c->have_known = 1;
    c->t_now = t + h;
    c->x_now = c->x_known + h * c->dx_now;
    c->v_now = c->v_known + h * c->dv_now;
    c->pending_valid = 0;
    c->fresh = c->has_derivative;
    return 0;
}

/* Model exchange, at an event: commit every sample due by t_now with the current input.
   Returns 0, or -1 when the force is not finite. */
static int core_me_event(Core *c) {
    for (;;) {
        double ts = c->t0 + (double)c->done.n * MODEL_DT_S;
        if (ts > c->t_now + CORE_EPS) break;
        c->before = c->done;
        if (core_sample(c, &c->done, ts, c->x_now, c->v_now)) return -1;
        const char *why =
            core_outside_why(c->x_now, fabs(c->x_now - c->before.x_last) / MODEL_DT_S);
        if (why && !c->before.outside) core_log_entry(c, ts, why, c->x_now);
    }
    c->pending_valid = 0;
    return 0;
}

/* Model exchange: the time of the next sample (the next time event). */
static double core_me_next_event(const Core *c) {
    return c->t0 + (double)c->done.n * MODEL_DT_S;
}

/* Model exchange: the force at t_now between samples n and n+1 (see the top). */
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
        c->pending.force = (1.0 - a) * latest.force + a * next.force;
    } else {
        c->pending.force = latest.force; /* on the sample: the model's force there */
    }
    c->pending_valid = 1;
    return 0;
}

/* What the outputs show: the samples up to t_now when their input is known (set at t_now, or
   extrapolated along a derivative), else the committed ones (the input at t_now is unknown);
   in model exchange, the latest sample recomputed with the current input. */
static const CoreRun *core_outputs(Core *c) {
    if (c->me) return core_me_pending(c) ? NULL : &c->pending;
    if (!c->fresh) return &c->done;
    if (core_pending(c)) return NULL;
    return &c->pending;
}

static void core_set_inputs(Core *c, int which, double value) {
    if (which == 0) c->x_now = value;
    else {
        c->v_now = value;
        /* connected: set after initialisation, or to other than its start value (0) during
           it; a master that only applies the start value has not connected it */
        if (c->started || value != 0.0) c->velocity_connected = 1;
    }
    c->pending_valid = 0;
    c->fresh = 1;
}

static void core_set_derivative(Core *c, int which, double value) {
    if (which == 0) c->dx_now = value;
    else c->dv_now = value;
    c->has_derivative = 1;
}

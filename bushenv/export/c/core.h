/* bushenv FMU core: runs the model (model.h) at its own sample time whatever the master's step.

   Sample n lies at t0 + n * MODEL_DT_S. The core keeps the model state after every sample whose
   input is known ("committed"): at doStep(t, h) every sample at or before t is committed, its
   input interpolated linearly between the last two communication points. The outputs at time
   t_now are those of the latest sample at or before t_now when the input at t_now is known --
   set by the master (a master that sets inputs, then reads outputs, gets the model's force) or
   extrapolated along the input derivative it set (FMI 2) -- computed on a scratch copy of the
   state ("pending", recomputed once the input is set, never committed on a guess). Read right
   after doStep, before any new input, they are those of the latest committed sample: the force
   lags the communication point by up to one step. docs/export.md states the error of each case.

   Envelope (model.h, generated): a sample is outside when |x| > ENV_STROKE_M, |x_n -
   x_(n-1)| / dt > ENV_VELOCITY_M_PER_S, or x lies in a range the model's certificate flags. */
#include <stdio.h>
#include <string.h>

#define CORE_EPS (1e-6 * MODEL_DT_S) /* a communication point this close to a sample is on it */

typedef void (*core_log_fn)(void *env, int warning, const char *message);

typedef struct {
    double s[MODEL_N_STATE]; /* model state after the last counted sample */
    long n;                  /* samples counted */
    double x_last, force;    /* input and force of the last counted sample */
    int outside;             /* the last counted sample is outside the envelope */
    long n_outside;          /* counted samples outside */
} CoreRun;

typedef struct {
    CoreRun done, pending;
    int pending_valid;
    double t0, t_known, x_known, v_known; /* last committed communication point */
    int have_known;
    double t_now, x_now, v_now; /* current time and inputs (set or extrapolated) */
    double dx_now, dv_now;      /* input derivatives set by the master (FMI 2) */
    int fresh;                  /* the input at t_now is known: set, or along a derivative */
    int has_derivative;         /* the master sets input derivatives (FMI 2) */
    /* model exchange (ODE models): the importer integrates q = (y, w, z1, z2) */
    int me;
    double q[4], t_last_step, me_time_outside;
    int me_outside;
    core_log_fn log;
    void *log_env;
    char message[512];
} Core;

static void core_reset(Core *c, double t0) {
    memset(&c->done, 0, sizeof c->done);
    model_reset(c->done.s);
    c->pending = c->done;
    c->pending_valid = 0;
    c->t0 = c->t_now = c->t_known = t0;
    c->have_known = 0;
    c->x_now = c->v_now = c->x_known = c->v_known = c->dx_now = c->dv_now = 0.0;
    c->fresh = 1;
    c->has_derivative = 0;
    for (int i = 0; i < 4; i++) c->q[i] = 0.0;
    c->t_last_step = t0;
    c->me_time_outside = 0.0;
    c->me_outside = 0;
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
        double speed = r.n > 0 ? fabs(x - r.x_last) / MODEL_DT_S : 0.0;
        r.force = model_step(r.s, x, v);
        if (!(r.force == r.force) || fabs(r.force) > 1e300) {
            snprintf(c->message, sizeof c->message,
                     "the model's force is not finite at t = %.6g s (x = %.6g m, v = %.6g m/s)",
                     ts, x, v);
            return -1;
        }
        r.outside = core_outside_why(x, speed) != NULL;
        r.n_outside += r.outside;
        r.x_last = x;
        r.n += 1;
    }
    c->pending = r;
    c->pending_valid = 1;
    return 0;
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
        if (why && !was_outside && c->log) {
            snprintf(c->message, sizeof c->message,
                     "t = %.6g s: input leaves the bushing's validity envelope: %s "
                     "(x = %.6g m, stroke %.6g m, velocity limit %.6g m/s; %s)",
                     ts, why, x, ENV_STROKE_M, ENV_VELOCITY_M_PER_S, ENV_SOURCE);
            c->log(c->log_env, 1, c->message);
        }
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

/* What the outputs show: the samples up to t_now when their input is known (set at t_now, or
   extrapolated along a derivative), else the committed ones (the input at t_now is unknown). */
static const CoreRun *core_outputs(Core *c) {
    if (!c->fresh) return &c->done;
    if (core_pending(c)) return NULL;
    return &c->pending;
}

static void core_set_inputs(Core *c, int which, double value) {
    if (which == 0) c->x_now = value;
    else c->v_now = value;
    c->pending_valid = 0;
    c->fresh = 1;
}

static void core_set_derivative(Core *c, int which, double value) {
    if (which == 0) c->dx_now = value;
    else c->dv_now = value;
    c->has_derivative = 1;
}

/* Model exchange: after each completed integrator step, the time since the last one counts as
   outside when the input now is (velocity: the velocity input, there being no samples). */
static void core_me_completed(Core *c) {
    const char *why = core_outside_why(c->x_now, fabs(c->v_now));
    if (why) c->me_time_outside += c->t_now - c->t_last_step;
    if (why && !c->me_outside && c->log) {
        snprintf(c->message, sizeof c->message,
                 "t = %.6g s: input leaves the bushing's validity envelope: %s "
                 "(x = %.6g m, v = %.6g m/s, stroke %.6g m, velocity limit %.6g m/s; %s)",
                 c->t_now, why, c->x_now, c->v_now, ENV_STROKE_M, ENV_VELOCITY_M_PER_S,
                 ENV_SOURCE);
        c->log(c->log_env, 1, c->message);
    }
    c->me_outside = why != NULL;
    c->t_last_step = c->t_now;
}

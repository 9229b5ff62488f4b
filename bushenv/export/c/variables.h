/* The FMU's variables by value reference (the same in FMI 2 and 3; modelDescription.xml lists
   them): inputs, outputs, the envelope's constants and the model card's facts as strings. */
#define VR_TIME 0
#define VR_DEFLECTION 1
#define VR_VELOCITY 2
#define VR_FORCE 3
#define VR_OUTSIDE 4
#define VR_TIME_OUTSIDE 5
#define VR_STROKE 6
#define VR_VELOCITY_LIMIT 7
#define VR_SAMPLE_TIME 8
#define VR_STATES 10      /* model exchange: y, w, z1, z2 */
#define VR_DERIVATIVES 14 /* and their derivatives */
#define VR_INDICATORS 18  /* and where the right-hand side has a kink: d1, d2, z1, z2 = 0 */
#define N_INDICATORS (MODEL_HAS_RHS ? 4 : 0)
#define VR_FACTS 100

/* Event indicators of model exchange: the relative velocities d1, d2 and z1, z2, whose signs
   switch eqs. 1-2 (the right-hand side stays continuous, its slope does not). */
static void var_indicators(const Core *c, double *ind) {
    double dq[4];
    model_rhs(c->x_now, c->v_now, c->q, dq);
    ind[0] = c->v_now - dq[0];
    ind[1] = c->v_now - dq[1];
    ind[2] = c->q[2];
    ind[3] = c->q[3];
}

/* 0 ok, 1 unknown reference, -1 the model failed (c->message says why) */
static int var_get_real(Core *c, unsigned vr, double *out) {
    if (c->me && MODEL_HAS_RHS) {
        double dq[4];
        if (vr == VR_FORCE) { *out = model_force(c->q, c->x_now, c->v_now); return 0; }
        if (vr == VR_TIME_OUTSIDE) { *out = c->me_time_outside; return 0; }
        if (vr >= VR_STATES && vr < VR_STATES + 4) { *out = c->q[vr - VR_STATES]; return 0; }
        if (vr >= VR_DERIVATIVES && vr < VR_DERIVATIVES + 4) {
            model_rhs(c->x_now, c->v_now, c->q, dq);
            *out = dq[vr - VR_DERIVATIVES];
            return 0;
        }
        if (vr >= VR_INDICATORS && vr < VR_INDICATORS + 4) {
            var_indicators(c, dq);
            *out = dq[vr - VR_INDICATORS];
            return 0;
        }
    }
    switch (vr) {
    case VR_TIME: *out = c->t_now; return 0;
    case VR_DEFLECTION: *out = c->x_now; return 0;
    case VR_VELOCITY: if (!HAS_VELOCITY) return 1; *out = c->v_now; return 0;
    case VR_FORCE:
    case VR_TIME_OUTSIDE: {
        const CoreRun *r = core_outputs(c);
        if (!r) return -1;
        *out = vr == VR_FORCE ? r->force : (double)r->n_outside * MODEL_DT_S;
        return 0;
    }
    case VR_STROKE: *out = ENV_STROKE_M; return 0;
    case VR_VELOCITY_LIMIT: *out = ENV_VELOCITY_M_PER_S; return 0;
    case VR_SAMPLE_TIME: *out = MODEL_DT_S; return 0;
    default: return 1;
    }
}

static int var_get_boolean(Core *c, unsigned vr, int *out) {
    if (vr != VR_OUTSIDE) return 1;
    if (c->me) {
        *out = core_outside_why(c->x_now, fabs(c->v_now)) != NULL;
        return 0;
    }
    const CoreRun *r = core_outputs(c);
    if (!r) return -1;
    *out = r->outside;
    return 0;
}

static const char *var_get_string(unsigned vr) {
    if (vr < VR_FACTS || vr >= VR_FACTS + N_FACTS) return NULL;
    return FACTS[vr - VR_FACTS];
}

static int var_set_real(Core *c, unsigned vr, double value) {
    if (vr == VR_DEFLECTION) core_set_inputs(c, 0, value);
    else if (HAS_VELOCITY && vr == VR_VELOCITY) core_set_inputs(c, 1, value);
    else return 1;
    return 0;
}

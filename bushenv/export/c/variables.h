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
#define VR_FACTS 100

/* 0 ok, 1 unknown reference, -1 the model failed (c->message says why) */
static int var_get_real(Core *c, unsigned vr, double *out) {
    switch (vr) {
    case VR_TIME: *out = c->t_now; return 0;
    case VR_DEFLECTION: *out = c->x_now; return 0;
    case VR_VELOCITY: *out = c->v_now; return 0;
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
    else if (vr == VR_VELOCITY) core_set_inputs(c, 1, value);
    else return 1;
    return 0;
}

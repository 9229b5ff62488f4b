/* The FMU's variables by value reference (the same in FMI 2 and 3; modelDescription.xml lists
   them): inputs, outputs, the envelope's constants and the model card's facts as strings. The
   references of the per-coordinate variables are generated (model.h: VR_X, VR_V, VR_F,
   VR_STROKE_OF, VR_RATE_OF, one per coordinate); the others are fixed. */
#define VR_TIME 0
#define VR_OUTSIDE 4
#define VR_TIME_OUTSIDE 5
#define VR_SAMPLE_TIME 8
#define VR_IN_FLAGGED 9
#define VR_FACTS 100

/* The coordinate whose variable in ``table`` is ``vr``, or -1. */
static int var_coordinate(const unsigned *table, unsigned vr) {
    for (int i = 0; i < NC; i++)
        if (table[i] == vr) return i;
    return -1;
}

/* 0 ok, 1 unknown reference, -1 the model failed (c->message says why) */
static int var_get_real(Core *c, unsigned vr, double *out) {
    int i;
    if ((i = var_coordinate(VR_X, vr)) >= 0) { *out = c->x_now[i]; return 0; }
    if ((i = var_coordinate(VR_V, vr)) >= 0) { *out = c->v_now[i]; return 0; }
    if ((i = var_coordinate(VR_STROKE_OF, vr)) >= 0) { *out = ENV_STROKE[i]; return 0; }
    if ((i = var_coordinate(VR_RATE_OF, vr)) >= 0) { *out = ENV_VELOCITY[i]; return 0; }
    i = var_coordinate(VR_F, vr);
    if (i >= 0 || vr == VR_TIME_OUTSIDE) {
        const CoreRun *r = core_outputs(c);
        if (!r) return -1;
        *out = i >= 0 ? r->force[i] : (double)r->n_outside * MODEL_DT_S;
        return 0;
    }
    if (vr == VR_TIME) { *out = c->t_now; return 0; }
    if (vr == VR_SAMPLE_TIME) { *out = MODEL_DT_S; return 0; }
    return 1;
}

static int var_get_boolean(Core *c, unsigned vr, int *out) {
    if (vr != VR_OUTSIDE && vr != VR_IN_FLAGGED) return 1;
    const CoreRun *r = core_outputs(c);
    if (!r) return -1;
    *out = vr == VR_OUTSIDE ? r->outside : r->flagged != 0;
    return 0;
}

static const char *var_get_string(unsigned vr) {
    if (vr < VR_FACTS || vr >= VR_FACTS + N_FACTS) return NULL;
    return FACTS[vr - VR_FACTS];
}

/* Which input ``vr`` is: *velocity 0 (a coordinate) or 1 (its velocity), *i the coordinate.
   Returns 0, or 1 when ``vr`` is no input. */
static int var_input(unsigned vr, int *velocity, int *i) {
    if ((*i = var_coordinate(VR_X, vr)) >= 0) { *velocity = 0; return 0; }
    if ((*i = var_coordinate(VR_V, vr)) >= 0) { *velocity = 1; return 0; }
    return 1;
}

static int var_set_real(Core *c, unsigned vr, double value) {
    int velocity, i;
    if (var_input(vr, &velocity, &i)) return 1;
    core_set_input(c, velocity, i, value);
    return 0;
}

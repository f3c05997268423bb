// The model in memory: definitions with defaults, validation of every field (each rule its
// own status and a message naming the element), accessors, per-strain constants, enabling
// springs, cloning, and "no partial state after a failed call".
#include "springmass/model.h"
#include "test_harness.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// The message must name the element and the rule: it contains both substrings.
#define ENSURE_MESSAGE(model, part1, part2)                                                                  \
	do {                                                                                                     \
		const char* msg_ = sm_model_last_error(model);                                                       \
		if (strstr(msg_, part1) == NULL || strstr(msg_, part2) == NULL) {                                    \
			printf("  %s:%d: message \"%s\" lacks \"%s\" or \"%s\"\n", __FILE__, __LINE__, msg_, part1,      \
			       part2);                                                                                   \
			return 1;                                                                                        \
		}                                                                                                    \
	} while (0)

static sm_model* three_particles(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* m = sm_model_create(&md, NULL);
	for (int i = 0; i < 3; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.position[0] = 0.5 * i;  // 0, 0.5, 1 m
		if (sm_model_add_particle(m, &p, NULL) != SM_OK)
			return NULL;
	}
	return m;
}

static int test_defaults(void)
{
	const sm_particle_def p = sm_default_particle_def();
	ENSURE(p.mass == 1.0 && p.motion == SM_PARTICLE_FREE && p.position[0] == 0.0 && p.velocity[2] == 0.0);
	const sm_spring_def s = sm_default_spring_def();
	ENSURE(s.kind == SM_SPRING_REST_LENGTH && s.rest_length == SM_REST_LENGTH_INITIAL);
	ENSURE(s.stiffness == 0.0 && s.damping == 0.0 && isinf(s.break_strain) && s.break_strain > 0);
	ENSURE(s.stiffness_scaling == SM_ABSOLUTE && s.damping_scaling == SM_ABSOLUTE);
	const sm_model_def md = sm_default_model_def();
	ENSURE(md.gravity[0] == 0.0 && md.gravity[1] == 0.0 && md.gravity[2] == -9.81 && md.mass_damping == 0.0);
	sm_model_destroy(NULL);
	// The limits are written in decimal (C++ before C++17 has no hexadecimal floating literals),
	// to the bits of the powers of two they are.
	ENSURE(SM_MIN_MASS == DBL_MIN && SM_MIN_BREAK_STRAIN == ldexp(1.0, -53));
	return 0;
}

static int test_invalid_model_definitions(void)
{
	sm_error err;
	sm_model_def md = sm_default_model_def();
	md.gravity[1] = NAN;
	ENSURE(sm_model_create(&md, &err) == NULL);
	ENSURE(err.status == SM_ERROR_NOT_FINITE && strstr(err.message, "gravity y") != NULL);
	md = sm_default_model_def();
	md.mass_damping = -0.1;
	ENSURE(sm_model_create(&md, &err) == NULL);
	ENSURE(err.status == SM_ERROR_NEGATIVE && strstr(err.message, "mass damping") != NULL);
	md = sm_default_model_def();
	md.mass_damping = INFINITY;
	ENSURE(sm_model_create(&md, &err) == NULL && err.status == SM_ERROR_NOT_FINITE);
	md = sm_default_model_def();
	md.spring_capacity = -1;
	ENSURE(sm_model_create(&md, &err) == NULL && err.status == SM_ERROR_NEGATIVE);
	md = sm_default_model_def();
	md.particle_capacity = -1;
	ENSURE(sm_model_create(&md, &err) == NULL && err.status == SM_ERROR_NEGATIVE);
	ENSURE(strstr(err.message, "particle capacity") != NULL);
	// A capacity beyond the most a model holds (2^29 - 1) is an invalid hint, not a lack of memory:
	// nothing is allocated for it.
	md = sm_default_model_def();
	md.spring_capacity = INT32_MAX;
	ENSURE(sm_model_create(&md, &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);
	ENSURE(strstr(err.message, "spring capacity = 2147483647") != NULL && strstr(err.message, "536870911"));
	md = sm_default_model_def();
	md.particle_capacity = (1 << 29);
	ENSURE(sm_model_create(&md, &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);
	ENSURE(strstr(err.message, "particle capacity = 536870912") != NULL);
	ENSURE(sm_model_create(NULL, &err) == NULL && err.status == SM_ERROR_INVALID_ARGUMENT);
	md = sm_default_model_def();
	md.particle_capacity = 100;
	sm_model* m = sm_model_create(&md, &err);
	ENSURE(m != NULL && err.status == SM_OK && err.message[0] == '\0');
	// sm_model_set_def validates the same way and leaves the model unchanged on error.
	md.mass_damping = -1.0;
	ENSURE_STATUS(sm_model_set_def(m, &md), SM_ERROR_NEGATIVE);
	ENSURE(sm_model_get_def(m).mass_damping == 0.0);
	md.mass_damping = 0.5;
	md.gravity[2] = -1.62;
	ENSURE_STATUS(sm_model_set_def(m, &md), SM_OK);
	ENSURE(sm_model_get_def(m).mass_damping == 0.5 && sm_model_get_def(m).gravity[2] == -1.62);
	sm_model_destroy(m);
	return 0;
}

static int test_invalid_particles(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	struct {
		sm_particle_def def;
		sm_status status;
		const char* rule;
	} cases[9];
	for (int i = 0; i < 9; i++)
		cases[i].def = sm_default_particle_def();
	cases[0].def.mass = 0.0, cases[0].status = SM_ERROR_NONPOSITIVE_MASS,
	cases[0].rule = "mass = 0 must be > 0";
	cases[1].def.mass = -2.0, cases[1].status = SM_ERROR_NONPOSITIVE_MASS, cases[1].rule = "must be > 0";
	cases[2].def.mass = NAN, cases[2].status = SM_ERROR_NOT_FINITE, cases[2].rule = "mass";
	cases[3].def.position[2] = INFINITY, cases[3].status = SM_ERROR_NOT_FINITE, cases[3].rule = "position z";
	cases[4].def.velocity[0] = NAN, cases[4].status = SM_ERROR_NOT_FINITE, cases[4].rule = "velocity x";
	cases[5].def.motion = (sm_particle_motion)7, cases[5].status = SM_ERROR_INVALID_ARGUMENT,
	cases[5].rule = "motion";
	cases[6].def.mass = INFINITY, cases[6].status = SM_ERROR_NOT_FINITE, cases[6].rule = "not finite";
	cases[7].def.position[1] = -INFINITY, cases[7].status = SM_ERROR_NOT_FINITE, cases[7].rule = "position y";
	cases[8].def.load[2] = NAN, cases[8].status = SM_ERROR_NOT_FINITE, cases[8].rule = "load z = nan N";
	for (int i = 0; i < 9; i++) {
		int32_t index = -5;
		ENSURE_STATUS(sm_model_add_particle(m, &cases[i].def, &index), cases[i].status);
		ENSURE(index == -1);  // no particle's index, whatever the caller does with it
		ENSURE(sm_model_particle_count(m) == 3);
		ENSURE_MESSAGE(m, "particle 3", cases[i].rule);
		// Replacing particle 1 with the same bad definition fails the same way, changing nothing.
		ENSURE_STATUS(sm_model_set_particle(m, 1, &cases[i].def), cases[i].status);
		ENSURE_MESSAGE(m, "particle 1", cases[i].rule);
		sm_particle_def now;
		ENSURE_STATUS(sm_model_get_particle(m, 1, &now), SM_OK);
		ENSURE(now.mass == 1.0 && now.position[0] == 0.5 && now.motion == SM_PARTICLE_FREE &&
		       now.load[2] == 0.0);
	}
	ENSURE_STATUS(sm_model_add_particle(m, NULL, NULL), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_set_particle(m, 3, &cases[0].def), SM_ERROR_PARTICLE_INDEX);
	ENSURE_MESSAGE(m, "particle 3", "out of range (model has 3 particles)");
	ENSURE_STATUS(sm_model_set_particle_motion(m, -1, SM_PARTICLE_FIXED), SM_ERROR_PARTICLE_INDEX);
	ENSURE_STATUS(sm_model_set_particle_motion(m, 0, (sm_particle_motion)-3), SM_ERROR_INVALID_ARGUMENT);
	// An index out of range gives a definition of zeros, not what the caller's memory held.
	sm_particle_def out = cases[0].def;
	out.mass = NAN;
	ENSURE_STATUS(sm_model_get_particle(m, 3, &out), SM_ERROR_PARTICLE_INDEX);
	ENSURE(out.mass == 0.0 && out.position[0] == 0.0 && out.velocity[2] == 0.0 && out.load[1] == 0.0 &&
	       out.motion == SM_PARTICLE_FREE);
	sm_model_destroy(m);
	return 0;
}

static int test_invalid_springs(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def good = sm_default_spring_def();
	good.a = 0;
	good.b = 1;
	good.stiffness = 10.0;
	ENSURE_STATUS(sm_model_add_spring(m, &good, NULL), SM_OK);
	enum { CASES = 21 };
	struct {
		sm_spring_def def;
		sm_status status;
		const char* rule;
	} c[CASES];
	for (int i = 0; i < CASES; i++)
		c[i].def = good;
	c[0].def.b = 7, c[0].status = SM_ERROR_PARTICLE_INDEX,
	c[0].rule = "particle b = 7 out of range (model has 3 particles)";
	c[1].def.a = -1, c[1].status = SM_ERROR_PARTICLE_INDEX, c[1].rule = "particle a = -1 out of range";
	c[2].def.b = 0, c[2].status = SM_ERROR_SELF_SPRING, c[2].rule = "to itself";
	c[3].def.stiffness = -1.0, c[3].status = SM_ERROR_NEGATIVE, c[3].rule = "stiffness = -1 must be >= 0";
	c[4].def.stiffness = NAN, c[4].status = SM_ERROR_NOT_FINITE, c[4].rule = "stiffness";
	c[5].def.damping = -0.5, c[5].status = SM_ERROR_NEGATIVE, c[5].rule = "damping = -0.5 must be >= 0";
	c[6].def.damping = INFINITY, c[6].status = SM_ERROR_NOT_FINITE, c[6].rule = "damping";
	c[7].def.rest_length = -0.25, c[7].status = SM_ERROR_NEGATIVE, c[7].rule = "rest length = -0.25";
	c[8].def.rest_length = NAN, c[8].status = SM_ERROR_NOT_FINITE, c[8].rule = "rest length";
	c[9].def.rest_length = 0.0, c[9].def.stiffness_scaling = SM_PER_STRAIN,
	c[9].status = SM_ERROR_ZERO_REST_LENGTH, c[9].rule = "per-strain stiffness needs a rest length > 0";
	c[10].def.kind = SM_SPRING_ZERO_LENGTH, c[10].def.damping_scaling = SM_PER_STRAIN,
	c[10].status = SM_ERROR_ZERO_REST_LENGTH, c[10].rule = "per-strain damping";
	c[11].def.break_strain = 0.0, c[11].status = SM_ERROR_NEGATIVE,
	c[11].rule = "break strain = 0 must be > 0";
	c[12].def.break_strain = NAN, c[12].status = SM_ERROR_NOT_FINITE, c[12].rule = "break strain";
	c[13].def.rest_length = 0.0, c[13].def.break_strain = 0.1, c[13].status = SM_ERROR_ZERO_REST_LENGTH,
	c[13].rule = "break strain needs a rest length > 0";
	c[14].def.kind = (sm_spring_kind)9, c[14].status = SM_ERROR_INVALID_ARGUMENT, c[14].rule = "kind";
	c[15].def.stiffness_scaling = (sm_scaling)4, c[15].status = SM_ERROR_INVALID_ARGUMENT,
	c[15].rule = "scaling";
	c[16].def.kind = SM_SPRING_ZERO_LENGTH, c[16].def.rest_length = 0.3,
	c[16].status = SM_ERROR_INVALID_ARGUMENT, c[16].rule = "zero-length spring must have rest length 0";
	// Indices are 0 .. n - 1: n itself is out of range.
	c[17].def.a = 3, c[17].status = SM_ERROR_PARTICLE_INDEX,
	c[17].rule = "particle a = 3 out of range (model has 3 particles)";
	c[18].def.b = 3, c[18].status = SM_ERROR_PARTICLE_INDEX,
	c[18].rule = "particle b = 3 out of range (model has 3 particles)";
	c[19].def.damping_scaling = (sm_scaling)4, c[19].status = SM_ERROR_INVALID_ARGUMENT,
	c[19].rule = "damping scaling";
	// kd = c / l0 = 1e308 / 1e-10 overflows.
	c[20].def.rest_length = 1e-10, c[20].def.damping = 1e308, c[20].def.damping_scaling = SM_PER_STRAIN,
	c[20].status = SM_ERROR_NOT_FINITE, c[20].rule = "damping c / l0 = 1e+308 / 1e-10 is not finite";
	for (int i = 0; i < CASES; i++) {
		int32_t index = -5;
		ENSURE_STATUS(sm_model_add_spring(m, &c[i].def, &index), c[i].status);
		ENSURE(index == -1 && sm_model_spring_count(m) == 1);
		ENSURE_MESSAGE(m, "spring 1", c[i].rule);
		ENSURE_STATUS(sm_model_set_spring(m, 0, &c[i].def), c[i].status);
		ENSURE_MESSAGE(m, "spring 0", c[i].rule);
		sm_spring_def now;
		ENSURE_STATUS(sm_model_get_spring(m, 0, &now), SM_OK);
		ENSURE(now.a == 0 && now.b == 1 && now.stiffness == 10.0 && now.rest_length == 0.5);
	}
	// Two particles at the same place: the initial rest length is 0, which per-strain forbids.
	sm_particle_def p = sm_default_particle_def();
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 3 at the origin, like 0
	sm_spring_def coincident = good;
	coincident.b = 3;
	coincident.stiffness_scaling = SM_PER_STRAIN;
	ENSURE_STATUS(sm_model_add_spring(m, &coincident, NULL), SM_ERROR_ZERO_REST_LENGTH);
	ENSURE_MESSAGE(m, "spring 1", "rest length is 0");
	// Particles 1e308 m on either side of the origin: their distance, the initial rest length,
	// overflows. Refused for a zero-length spring too, whose force ks d the model evaluates as
	// ks L u (law_zero_length.h): not a number where L overflows.
	p.position[0] = 1e308;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 4
	p.position[0] = -1e308;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 5
	sm_spring_def far = good;
	far.a = 4;
	far.b = 5;
	// The message gives the distance where a double holds it, as it does for one too small.
	ENSURE_STATUS(sm_model_add_spring(m, &far, NULL), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(
	    m, "spring 1",
	    "initial distance between particles 4 and 5, more than 1.8e+308 m, is too large (its square "
	    "overflows");
	far.kind = SM_SPRING_ZERO_LENGTH;
	ENSURE_STATUS(sm_model_add_spring(m, &far, NULL), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(
	    m, "spring 1",
	    "initial distance between particles 4 and 5, more than 1.8e+308 m, is too large (its square "
	    "overflows");
	// 9e153 m along each axis: each square is finite, their sum is not; the distance is 1.56e154 m.
	p.position[0] = p.position[1] = p.position[2] = 9e153;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 6
	far.a = 3;
	far.b = 6;
	ENSURE_STATUS(sm_model_add_spring(m, &far, NULL), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(m, "spring 1", "initial distance between particles 3 and 6, 1.56e+154 m, is too large");
	p.position[1] = p.position[2] = 0.0;
	// Particles 1e-170 m apart, whose squared distance underflows to 0: the initial rest length
	// would be 0, not their distance, and per-strain constants refused as "rest length is 0".
	// Refused for what it is, as a structure's spring of that length, also with absolute
	// stiffness; so is 1e-155 m, whose square is subnormal (its root imprecise, the more so below).
	p.position[0] = 1e-170;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 7
	p.position[0] = 1e-155;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);  // particle 8
	sm_spring_def close = good;
	close.a = 3;
	for (int k = 7; k <= 8; k++) {
		close.b = k;
		for (int scaling = SM_ABSOLUTE; scaling <= SM_PER_STRAIN; scaling++) {
			close.stiffness_scaling = (sm_scaling)scaling;
			ENSURE_STATUS(sm_model_add_spring(m, &close, NULL), SM_ERROR_INVALID_ARGUMENT);
			ENSURE_MESSAGE(m, "spring 1",
			               k == 7 ? "initial distance between particles 3 and 7, 1e-170 m, is too small"
			                      : "initial distance between particles 3 and 8, 1e-155 m, is too small");
		}
	}
	ENSURE(sm_model_spring_count(m) == 1);
	ENSURE_STATUS(sm_model_add_spring(m, NULL, NULL), SM_ERROR_INVALID_ARGUMENT);
	ENSURE_STATUS(sm_model_set_spring(m, 1, &good), SM_ERROR_SPRING_INDEX);
	ENSURE_MESSAGE(m, "spring 1", "out of range (model has 1 spring)");
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 5, false), SM_ERROR_SPRING_INDEX);
	ENSURE(!sm_model_spring_enabled(m, 5));
	// A failed addition gives no spring's index; an index out of range a definition of zeros.
	int32_t index = 7;
	sm_spring_def out = good;
	out.stiffness = NAN;
	ENSURE_STATUS(sm_model_add_spring(m, &close, &index), SM_ERROR_INVALID_ARGUMENT);
	ENSURE(index == -1);
	ENSURE_STATUS(sm_model_get_spring(m, 1, &out), SM_ERROR_SPRING_INDEX);
	ENSURE(out.a == 0 && out.b == 0 && out.stiffness == 0.0 && out.rest_length == 0.0 &&
	       out.break_strain == 0.0);
	double constants[3] = {1.0, 2.0, 3.0};
	ENSURE_STATUS(sm_model_spring_constants(m, -1, &constants[0], &constants[1], &constants[2]),
	              SM_ERROR_SPRING_INDEX);
	ENSURE(constants[0] == 0.0 && constants[1] == 0.0 && constants[2] == 0.0);
	sm_model_destroy(m);
	return 0;
}

// Stored definitions: rest length resolved to the initial distance; per-strain constants
// ks = E / l0 and kd = c / l0 (exact divisions); fixed particles store zero velocity.
static int test_accessors_and_per_strain_constants(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 2;
	d.stiffness = 300.0;
	d.stiffness_scaling = SM_PER_STRAIN;
	d.damping = 2.0;
	d.damping_scaling = SM_PER_STRAIN;
	d.break_strain = 0.2;
	int32_t index = -1;
	ENSURE_STATUS(sm_model_add_spring(m, &d, &index), SM_OK);
	ENSURE(index == 0);
	sm_spring_def stored;
	ENSURE_STATUS(sm_model_get_spring(m, 0, &stored), SM_OK);
	ENSURE(stored.rest_length == 1.0 && stored.stiffness == 300.0 && stored.break_strain == 0.2);
	double l0, ks, kd;
	ENSURE_STATUS(sm_model_spring_constants(m, 0, &l0, &ks, &kd), SM_OK);
	ENSURE(l0 == 1.0 && ks == 300.0 && kd == 2.0);
	// An explicit rest length changes the constants: ks = 300 / 0.25, kd = 2 / 0.25.
	d.rest_length = 0.25;
	ENSURE_STATUS(sm_model_set_spring(m, 0, &d), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(m, 0, &l0, &ks, &kd), SM_OK);
	ENSURE(l0 == 0.25 && ks == 1200.0 && kd == 8.0);
	// SM_REST_LENGTH_INITIAL in set_spring keeps the current rest length.
	d.rest_length = SM_REST_LENGTH_INITIAL;
	d.stiffness = 600.0;
	ENSURE_STATUS(sm_model_set_spring(m, 0, &d), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(m, 0, &l0, &ks, NULL), SM_OK);
	ENSURE(l0 == 0.25 && ks == 2400.0);
	// Disabled: constants still reported; forces zero (checked in test_forces).
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(m, 0, &l0, &ks, NULL), SM_OK);
	ENSURE(ks == 2400.0);
	// Particles: fixed ones store zero velocity, motion changes renumber the free particles.
	sm_particle_def p = sm_default_particle_def();
	p.mass = 2.5;
	p.velocity[1] = 3.0;
	p.motion = SM_PARTICLE_FIXED;
	ENSURE_STATUS(sm_model_set_particle(m, 1, &p), SM_OK);
	sm_particle_def q;
	ENSURE_STATUS(sm_model_get_particle(m, 1, &q), SM_OK);
	ENSURE(q.mass == 2.5 && q.velocity[1] == 0.0 && q.motion == SM_PARTICLE_FIXED);
	ENSURE(sm_model_free_count(m) == 2);
	ENSURE(sm_model_free_index(m, 0) == 0 && sm_model_free_index(m, 1) == -1 &&
	       sm_model_free_index(m, 2) == 1);
	ENSURE(sm_model_free_index(m, 3) == -1);
	ENSURE_STATUS(sm_model_set_particle_motion(m, 0, SM_PARTICLE_DRIVEN), SM_OK);
	ENSURE(sm_model_free_count(m) == 1 && sm_model_free_index(m, 2) == 0);
	ENSURE_NEAR(sm_model_total_mass(m), 4.5, 1e-15);
	double x[9], v[9];
	sm_model_initial_state(m, x, v);
	ENSURE(x[3] == 0.0 && x[6] == 1.0 && v[4] == 0.0);  // particle 1 was replaced at the origin
	sm_model_initial_state(m, NULL, NULL);
	// A rest-length spring of rest length 0 between particles 1 m apart keeps it when replaced
	// with SM_REST_LENGTH_INITIAL ("keeps the current one").
	sm_spring_def z = sm_default_spring_def();
	z.a = 0;
	z.b = 2;
	z.rest_length = 0.0;
	z.stiffness = 5.0;
	ENSURE_STATUS(sm_model_add_spring(m, &z, &index), SM_OK);
	ENSURE(index == 1);
	z.rest_length = SM_REST_LENGTH_INITIAL;
	z.stiffness = 6.0;
	ENSURE_STATUS(sm_model_set_spring(m, 1, &z), SM_OK);
	ENSURE_STATUS(sm_model_spring_constants(m, 1, &l0, &ks, NULL), SM_OK);
	ENSURE(l0 == 0.0 && ks == 6.0);
	// An added driven particle is constrained (free index -1); the next free one follows the
	// free particle 2.
	p = sm_default_particle_def();
	p.motion = SM_PARTICLE_DRIVEN;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	p.motion = SM_PARTICLE_FREE;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	ENSURE(sm_model_free_count(m) == 2 && sm_model_free_index(m, 3) == -1 && sm_model_free_index(m, 4) == 1);
	sm_model_destroy(m);
	return 0;
}

// A clone is deep: changing it leaves the original as it was.
static int test_clone_is_independent(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 1;
	d.b = 2;
	d.stiffness = 5.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	sm_model* c = sm_model_clone(m);
	ENSURE(c != NULL);
	ENSURE(sm_model_particle_count(c) == 3 && sm_model_spring_count(c) == 1);
	d.stiffness = 7.0;
	ENSURE_STATUS(sm_model_set_spring(c, 0, &d), SM_OK);
	sm_particle_def p = sm_default_particle_def();
	ENSURE_STATUS(sm_model_add_particle(c, &p, NULL), SM_OK);
	ENSURE_STATUS(sm_model_add_spring(c, &d, NULL), SM_OK);
	sm_spring_def orig;
	ENSURE_STATUS(sm_model_get_spring(m, 0, &orig), SM_OK);
	ENSURE(orig.stiffness == 5.0 && sm_model_particle_count(m) == 3 && sm_model_spring_count(m) == 1);
	ENSURE(sm_model_clone(NULL) == NULL);
	sm_model_destroy(c);
	// Clone of an empty model.
	sm_model_def md = sm_default_model_def();
	sm_model* e = sm_model_create(&md, NULL);
	sm_model* ec = sm_model_clone(e);
	ENSURE(ec != NULL && sm_model_particle_count(ec) == 0);
	sm_model_destroy(ec);
	sm_model_destroy(e);
	sm_model_destroy(m);
	return 0;
}

// Many particles and springs (several reallocations) keep every stored value.
static int test_growth_keeps_values(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* m = sm_model_create(&md, NULL);
	for (int i = 0; i < 1000; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.mass = 1.0 + i;
		p.position[0] = i;
		ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
		if (i > 0) {
			sm_spring_def d = sm_default_spring_def();
			d.a = i - 1;
			d.b = i;
			d.stiffness = i;
			ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		}
	}
	for (int i = 0; i < 1000; i += 97) {
		sm_particle_def p;
		ENSURE_STATUS(sm_model_get_particle(m, i, &p), SM_OK);
		ENSURE(p.mass == 1.0 + i && p.position[0] == i);
	}
	for (int s = 0; s < 999; s += 101) {
		sm_spring_def d;
		ENSURE_STATUS(sm_model_get_spring(m, s, &d), SM_OK);
		ENSURE(d.a == s && d.b == s + 1 && d.stiffness == s + 1 && d.rest_length == 1.0);
	}
	sm_model_destroy(m);
	return 0;
}

// Each constant is scaled as its own definition says: per-strain stiffness with absolute damping
// and the reverse. Particles 0 and 1 are 0.5 m apart (l0 = 0.5 m); at x_b - x_a = 0.6 m along x
// and v_b - v_a = 0.3 m/s, f_a,x = ks (L - l0) + kd (v_b - v_a) (model.h). E = 300 N per strain
// gives ks = 600 N/m, c = 2 N s per strain gives kd = 4 N s/m; the absolute constants are
// 300 N/m and 2 N s/m. Rounding of 0.6 - 0.5 is ~1e-17 m, so 1e-12 N is ample.
static int test_each_constant_scaled_as_given(void)
{
	const double x[9] = {0, 0, 0, 0.6, 0, 0, 1, 0, 0}, v[9] = {0, 0, 0, 0.3, 0, 0, 0, 0, 0};
	const double expected[2] = {600.0 * 0.1 + 2.0 * 0.3, 300.0 * 0.1 + 4.0 * 0.3};
	for (int k = 0; k < 2; k++) {
		sm_model* m = three_particles();
		ENSURE(m != NULL);
		sm_spring_def d = sm_default_spring_def();
		d.a = 0;
		d.b = 1;
		d.stiffness = 300.0;
		d.damping = 2.0;
		d.stiffness_scaling = k == 0 ? SM_PER_STRAIN : SM_ABSOLUTE;
		d.damping_scaling = k == 0 ? SM_ABSOLUTE : SM_PER_STRAIN;
		ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
		double f[9];
		sm_model_forces(m, x, v, NULL, f);
		ENSURE_NEAR(f[0], expected[k], 1e-12);
		ENSURE_NEAR(f[3], -expected[k], 1e-12);
		sm_model_destroy(m);
	}
	return 0;
}

// A disabled spring exerts no force, also after its definition is replaced: it stays disabled
// and its new constants act once it is enabled again (particles 0 and 1, 0.5 m apart, at
// x_b - x_a = 0.6 m: f_a,x = ks 0.1 m).
static int test_replacing_a_disabled_spring_keeps_it_disabled(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0;
	d.b = 1;
	d.stiffness = 10.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
	d.stiffness = 50.0;
	ENSURE_STATUS(sm_model_set_spring(m, 0, &d), SM_OK);
	ENSURE(!sm_model_spring_enabled(m, 0));
	const double x[9] = {0, 0, 0, 0.6, 0, 0, 1, 0, 0};
	double f[9];
	sm_model_forces(m, x, NULL, NULL, f);
	ENSURE(f[0] == 0.0 && f[3] == 0.0);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, true), SM_OK);
	sm_model_forces(m, x, NULL, NULL, f);
	ENSURE_NEAR(f[0], 5.0, 1e-12);  // 50 N/m x 0.1 m, rounding of 0.6 - 0.5 aside
	sm_model_destroy(m);
	return 0;
}

// The library reports the version of the headers it was built with (the consumer test compiles
// against the installed headers of the same build).
static int test_version(void)
{
	char expected[64];
	snprintf(expected, sizeof expected, "%d.%d.%d", SM_VERSION_MAJOR, SM_VERSION_MINOR, SM_VERSION_PATCH);
	ENSURE(strcmp(sm_version(), expected) == 0);
	return 0;
}

// sm_format_number: exact round trip, and the fewest of 15, 16 and 17 digits that give it. Random
// bit patterns cover every exponent, subnormals included; the shorter forms are checked to fail
// (so the text is the shortest of the three, not merely one that reads back).
static int test_format_number(void)
{
	char text[SM_NUMBER_TEXT_CAPACITY];
	sm_format_number(0.03, text);
	ENSURE(strcmp(text, "0.03") == 0);
	sm_format_number(0.1 + 0.2, text);
	ENSURE(strcmp(text, "0.30000000000000004") == 0);
	sm_format_number(1e-6, text);
	ENSURE(strcmp(text, "1e-06") == 0);
	sm_format_number(-1500.0, text);
	ENSURE(strcmp(text, "-1500") == 0);
	sm_format_number(-0.0, text);
	ENSURE(strcmp(text, "-0") == 0);
	uint64_t state = 0x9e3779b97f4a7c15u;
	for (int k = 0; k < 200000; k++) {
		state ^= state << 13, state ^= state >> 7, state ^= state << 17;
		double value;
		memcpy(&value, &state, sizeof value);
		if (!isfinite(value))
			continue;
		sm_format_number(value, text);
		ENSURE(strlen(text) < SM_NUMBER_TEXT_CAPACITY);
		ENSURE(strtod(text, NULL) == value);
		char shorter[SM_NUMBER_TEXT_CAPACITY];
		snprintf(shorter, sizeof shorter, "%.15g", value);
		if (strcmp(shorter, text) != 0) {
			ENSURE(strtod(shorter, NULL) != value);
			snprintf(shorter, sizeof shorter, "%.16g", value);
			ENSURE(strcmp(shorter, text) == 0 || strtod(shorter, NULL) != value);
		}
	}
	return 0;
}

// From mutation testing, bugs planted in model.c (each test catches one that passed).

// A clone has the original's settings, free numbering and springs: the same definition, free
// count and indices, spring constants, and forces bit for bit (also where the zero-length
// spring's particles coincide, which a rest-length spring of l0 = 0 does not handle the same).
static int test_clone_copies_every_field(void)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[0] = 1.0, md.gravity[1] = 2.0, md.gravity[2] = -3.0;
	md.mass_damping = 0.5;
	sm_model* m = sm_model_create(&md, NULL);
	ENSURE(m != NULL);
	for (int i = 0; i < 3; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.position[0] = 0.5 * i;
		p.motion = i == 1 ? SM_PARTICLE_FIXED : SM_PARTICLE_FREE;
		p.load[1] = i == 2 ? 4.0 : 0.0;
		ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_OK);
	}
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.stiffness = 5.0, d.rest_length = 0.4, d.damping = 1.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	d = sm_default_spring_def();
	d.a = 1, d.b = 2, d.kind = SM_SPRING_ZERO_LENGTH, d.stiffness = 3.0, d.damping = 2.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	sm_model* c = sm_model_clone(m);
	ENSURE(c != NULL);
	const sm_model_def cd = sm_model_get_def(c);
	ENSURE(cd.gravity[0] == 1.0 && cd.gravity[1] == 2.0 && cd.gravity[2] == -3.0 && cd.mass_damping == 0.5);
	ENSURE(sm_model_free_count(c) == 2 && sm_model_free_count(m) == 2);
	for (int32_t i = 0; i < 3; i++)
		ENSURE(sm_model_free_index(c, i) == sm_model_free_index(m, i));
	for (int32_t k = 0; k < 2; k++) {
		double l0[2], ks[2], kd[2];
		ENSURE_STATUS(sm_model_spring_constants(m, k, &l0[0], &ks[0], &kd[0]), SM_OK);
		ENSURE_STATUS(sm_model_spring_constants(c, k, &l0[1], &ks[1], &kd[1]), SM_OK);
		ENSURE(l0[0] == l0[1] && ks[0] == ks[1] && kd[0] == kd[1]);
	}
	// Two states: stretched and moving; particles 1 and 2 coinciding (zero-length spring at L = 0).
	const double xs[2][9] = {{0, 0, 0, 1, 0, 0, 1, 2, 0}, {0, 0, 0, 1, 0, 0, 1, 0, 0}};
	const double v[9] = {0, 0, 1, 0, 0, 0, 0.5, -1, 0};
	for (int s = 0; s < 2; s++) {
		double f[9], fc[9];
		sm_model_forces(m, xs[s], v, NULL, f);
		sm_model_forces(c, xs[s], v, NULL, fc);
		for (int k = 0; k < 9; k++)
			ENSURE(f[k] == fc[k]);
		ENSURE(sm_model_energies(m, xs[s], v).gravity == sm_model_energies(c, xs[s], v).gravity);
	}
	sm_particle_def loaded;
	ENSURE_STATUS(sm_model_get_particle(c, 2, &loaded), SM_OK);
	ENSURE(loaded.load[0] == 0.0 && loaded.load[1] == 4.0 && loaded.load[2] == 0.0);
	sm_model_destroy(c);
	sm_model_destroy(m);
	return 0;
}

// Disabling and enabling restores the damping too, and replacing the definition of a disabled
// spring leaves its damping off. Spring (0, 1), l0 = 0.5 m along x, kd = 4 N s/m (absolute),
// particle 1 moving at 1 m/s along x: f_0 = kd (u . (v_1 - v_0)) u = (4, 0, 0) N, exact.
static int test_enabling_restores_damping(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.damping = 3.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
	d.damping = 4.0;
	ENSURE_STATUS(sm_model_set_spring(m, 0, &d), SM_OK);
	sm_model_def md = sm_model_get_def(m);
	md.gravity[2] = 0.0;
	ENSURE_STATUS(sm_model_set_def(m, &md), SM_OK);
	const double x[9] = {0, 0, 0, 0.5, 0, 0, 1, 0, 0};
	const double v[9] = {0, 0, 0, 1, 0, 0, 0, 0, 0};
	double f[9];
	sm_model_forces(m, x, v, NULL, f);
	ENSURE(f[0] == 0.0 && f[3] == 0.0);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, true), SM_OK);
	sm_model_forces(m, x, v, NULL, f);
	ENSURE_NEAR(f[0], 4.0, 1e-12);
	ENSURE_NEAR(f[3], -4.0, 1e-12);
	sm_model_destroy(m);
	return 0;
}

// Per-section damping alone requires a section > 0 (as per-section stiffness does).
static int test_damping_per_section_needs_a_section(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.damping = 1.0, d.damping_scaling = SM_PER_SECTION, d.section = 0.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_ERROR_NEGATIVE);
	ENSURE(strstr(sm_model_last_error(m), "section") != NULL);
	ENSURE(sm_model_spring_count(m) == 0);
	sm_model_destroy(m);
	return 0;
}

// The smallest mass accepted is SM_MIN_MASS = DBL_MIN itself (model.h: mass ">= SM_MIN_MASS"),
// whose reciprocal 1 / DBL_MIN = 4.5e307 kg^-1 is finite; the double just below it, subnormal, is
// refused with the rule.
static int test_the_smallest_normal_mass_is_accepted(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_particle_def p = sm_default_particle_def();
	p.mass = SM_MIN_MASS;
	ENSURE(isfinite(1.0 / p.mass));
	int32_t index = -1;
	ENSURE_STATUS(sm_model_add_particle(m, &p, &index), SM_OK);
	ENSURE(index == 3);
	ENSURE_STATUS(sm_model_set_particle(m, 0, &p), SM_OK);
	p.mass = nextafter(SM_MIN_MASS, 0.0);
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_ERROR_NONPOSITIVE_MASS);
	ENSURE_MESSAGE(m, "particle 4", "must be at least 2.2250738585072014e-308 kg");
	ENSURE(sm_model_particle_count(m) == 4);
	sm_model_destroy(m);
	return 0;
}

// Per-section damping, kd = damping section / l0, needs l0 > 0 (model.h, SM_PER_SECTION) as
// per-section stiffness does: on a spring of rest length 0 it is refused for that rule
// (SM_ERROR_ZERO_REST_LENGTH), not as the infinite constant the division would give.
static int test_per_section_damping_needs_a_rest_length(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.rest_length = 0.0, d.stiffness = 10.0, d.damping = 1.0;
	d.damping_scaling = SM_PER_SECTION, d.section = 0.01;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_ERROR_ZERO_REST_LENGTH);
	ENSURE_MESSAGE(m, "spring 0", "per-section damping needs a rest length > 0");
	d.kind = SM_SPRING_ZERO_LENGTH;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_ERROR_ZERO_REST_LENGTH);
	ENSURE_MESSAGE(m, "spring 0", "per-section damping needs a rest length > 0");
	ENSURE(sm_model_spring_count(m) == 0);
	sm_model_destroy(m);
	return 0;
}

// Gravity and initial velocities must be finite along every axis (model.h), z included: a
// non-finite z component is refused with its axis named, and sm_model_set_def leaves the model
// as it was.
static int test_every_axis_of_gravity_and_velocity_is_checked(void)
{
	sm_error err;
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = -INFINITY;
	ENSURE(sm_model_create(&md, &err) == NULL);
	ENSURE(err.status == SM_ERROR_NOT_FINITE && strstr(err.message, "gravity z") != NULL);
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	md.gravity[2] = NAN;
	ENSURE_STATUS(sm_model_set_def(m, &md), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(m, "model", "gravity z");
	ENSURE(sm_model_get_def(m).gravity[2] == -9.81);
	sm_particle_def p = sm_default_particle_def();
	p.velocity[2] = NAN;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(m, "particle 3", "velocity z");
	ENSURE_STATUS(sm_model_set_particle(m, 0, &p), SM_ERROR_NOT_FINITE);
	ENSURE_MESSAGE(m, "particle 0", "velocity z");
	ENSURE(sm_model_particle_count(m) == 3);
	sm_model_destroy(m);
	return 0;
}

// An infinite velocity is refused like a NaN one (model.h: "must be finite").
static int test_infinite_velocity_refused(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_particle_def p = sm_default_particle_def();
	p.velocity[1] = INFINITY;
	ENSURE_STATUS(sm_model_add_particle(m, &p, NULL), SM_ERROR_NOT_FINITE);
	ENSURE(sm_model_particle_count(m) == 3);
	ENSURE_STATUS(sm_model_set_particle(m, 0, &p), SM_ERROR_NOT_FINITE);
	sm_model_destroy(m);
	return 0;
}

// get_spring gives the rest length resolved to metres: 0 for a zero-length spring added with
// SM_REST_LENGTH_INITIAL (not the -1 marker).
static int test_zero_length_spring_rest_length_resolved(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 2, d.kind = SM_SPRING_ZERO_LENGTH, d.stiffness = 1.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	sm_spring_def stored;
	ENSURE_STATUS(sm_model_get_spring(m, 0, &stored), SM_OK);
	ENSURE(stored.rest_length == 0.0);
	sm_model_destroy(m);
	return 0;
}

// The last error belongs to the calls that modify the model: a successful one clears it, a const
// call leaves it (its status tells), and a clone starts without it.
static int test_last_error_follows_the_modifying_calls(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.stiffness = 4.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 7, false), SM_ERROR_SPRING_INDEX);
	ENSURE(strstr(sm_model_last_error(m), "spring 7") != NULL);
	sm_model* copy = sm_model_clone(m);
	ENSURE(copy != NULL && sm_model_last_error(copy)[0] == '\0');
	sm_particle_def p;
	ENSURE_STATUS(sm_model_get_particle(m, 99, &p), SM_ERROR_PARTICLE_INDEX);
	ENSURE(strstr(sm_model_last_error(m), "spring 7") != NULL);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
	ENSURE(sm_model_last_error(m)[0] == '\0');
	sm_model_destroy(copy);
	sm_model_destroy(m);
	return 0;
}

// From mutation testing: a clone keeps a disabled spring disabled (a broken spring stays broken in
// a copy): it reports the spring so and exerts nothing with it, enabling it in the clone brings
// back its constants, and the original's spring stays off. Particles at x = 0, 0.5 and 1 m, springs
// (0, 1) with ks = 4 N/m, disabled, and (1, 2) with ks = 2 N/m, both l0 = 0.25 m: the forces along
// x are ks (L - l0) = 1 N and 0.5 N, exact in binary. A clone that marked spring 0 enabled whatever
// it was, its zero constants kept, passed the tests of the model and of the physics core.
static int test_clone_keeps_a_disabled_spring_disabled(void)
{
	sm_model* m = three_particles();
	ENSURE(m != NULL);
	sm_spring_def d = sm_default_spring_def();
	d.a = 0, d.b = 1, d.stiffness = 4.0, d.rest_length = 0.25;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	d.a = 1, d.b = 2, d.stiffness = 2.0;
	ENSURE_STATUS(sm_model_add_spring(m, &d, NULL), SM_OK);
	ENSURE_STATUS(sm_model_set_spring_enabled(m, 0, false), SM_OK);
	sm_model* c = sm_model_clone(m);
	ENSURE(c != NULL);
	ENSURE(!sm_model_spring_enabled(c, 0) && sm_model_spring_enabled(c, 1));
	const double x[9] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0};
	double f[9];
	sm_model_forces(c, x, NULL, NULL, f);
	ENSURE(f[0] == 0.0 && f[3] == 0.5 && f[6] == -0.5);
	ENSURE_STATUS(sm_model_set_spring_enabled(c, 0, true), SM_OK);
	sm_model_forces(c, x, NULL, NULL, f);
	ENSURE(f[0] == 1.0 && f[3] == -0.5 && f[6] == -0.5);
	ENSURE(!sm_model_spring_enabled(m, 0));
	sm_model_forces(m, x, NULL, NULL, f);
	ENSURE(f[0] == 0.0 && f[3] == 0.5 && f[6] == -0.5);
	sm_model_destroy(c);
	sm_model_destroy(m);
	return 0;
}

int main(int argc, char** argv)
{
	TEST_INIT(argc, argv);
	RUN_TEST(test_defaults);
	RUN_TEST(test_invalid_model_definitions);
	RUN_TEST(test_invalid_particles);
	RUN_TEST(test_invalid_springs);
	RUN_TEST(test_accessors_and_per_strain_constants);
	RUN_TEST(test_clone_is_independent);
	RUN_TEST(test_each_constant_scaled_as_given);
	RUN_TEST(test_replacing_a_disabled_spring_keeps_it_disabled);
	RUN_TEST(test_growth_keeps_values);
	RUN_TEST(test_version);
	RUN_TEST(test_format_number);
	RUN_TEST(test_clone_copies_every_field);
	RUN_TEST(test_enabling_restores_damping);
	RUN_TEST(test_damping_per_section_needs_a_section);
	RUN_TEST(test_infinite_velocity_refused);
	RUN_TEST(test_zero_length_spring_rest_length_resolved);
	RUN_TEST(test_last_error_follows_the_modifying_calls);
	RUN_TEST(test_the_smallest_normal_mass_is_accepted);
	RUN_TEST(test_per_section_damping_needs_a_rest_length);
	RUN_TEST(test_every_axis_of_gravity_and_velocity_is_checked);
	RUN_TEST(test_clone_keeps_a_disabled_spring_disabled);
	return TEST_SUMMARY();
}

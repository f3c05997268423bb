// Shared fixtures of the simulation tests: small models with closed-form motion.
#pragma once

#include "springmass/model.h"
#include "springmass/simulation.h"
#include "springmass/structures.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

// Tight tolerances (rtol 1e-10, atol 1e-12 m and m/s) with the given linear solver: the closed forms
// and conservation laws the tests check are then met far below what they assert.
static inline sm_simulation_def tight_def(sm_linear_solver solver)
{
	sm_simulation_def d = sm_default_simulation_def();
	d.solver = solver;
	d.relative_tolerance = 1e-10;
	d.absolute_tolerance_position = 1e-12;
	d.absolute_tolerance_velocity = 1e-12;
	return d;
}

// Oscillator along x: an anchor at the origin (fixed, or driven: still until the test moves it)
// and a bob of mass m [kg] at x = l0 + u0 on a rest-length spring (stiffness k [N/m], rest length
// l0 = 1 m, spring damping kd [N s/m]), no gravity. The spring stays stretched or mildly
// compressed (|u| <= u0 = 0.2 m < l0), so the motion is the linear m u'' = -k u - kd u'.
static inline sm_model* oscillator_anchored(double m, double k, double kd, double u0,
                                            sm_particle_motion anchor_motion)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = 0.0;
	sm_model* model = sm_model_create(&md, NULL);
	sm_particle_def anchor = sm_default_particle_def();
	anchor.motion = anchor_motion;
	sm_particle_def bob = sm_default_particle_def();
	bob.mass = m;
	bob.position[0] = 1.0 + u0;
	sm_spring_def s = sm_default_spring_def();
	s.a = 0;
	s.b = 1;
	s.rest_length = 1.0;
	s.stiffness = k;
	s.damping = kd;
	if (!model || sm_model_add_particle(model, &anchor, NULL) != SM_OK ||
	    sm_model_add_particle(model, &bob, NULL) != SM_OK || sm_model_add_spring(model, &s, NULL) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

static inline sm_model* oscillator(double m, double k, double kd, double u0)
{
	return oscillator_anchored(m, k, kd, u0, SM_PARTICLE_FIXED);
}

// An n x n sheet of sm_add_sheet's defaults (1 m x 1 m, 1 kg) with mass damping alpha [1/s],
// corner (n-1, 0) fixed and corner (n-1, n-1) of the given motion.
static inline sm_model* sheet_held_at_corners(int32_t n, double alpha, sm_particle_motion far_corner,
                                              sm_structure* st)
{
	sm_model_def md = sm_default_model_def();
	md.mass_damping = alpha;
	sm_model* model = sm_model_create(&md, NULL);
	sm_sheet_def sd = sm_default_sheet_def();
	sd.nu = sd.nv = n;
	if (!model || sm_add_sheet(model, &sd, st) != SM_OK ||
	    sm_set_motion_at(model, st, n - 1, 0, 0, SM_PARTICLE_FIXED) != SM_OK ||
	    sm_set_motion_at(model, st, n - 1, n - 1, 0, far_corner) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// A spring to be pulled apart: spring 0 (100 N/m, rest length the initial 1 m, break strain 0.1)
// from a fixed particle 0 at the origin to a driven
// particle 1 at (1, 0, 0) m, which the test sets moving along x; spring 1 (damped, unbreakable)
// from particle 0 to a free particle 2 at (0, 0, -0.5) m, so that the model has a state to
// integrate. Driven at speed V from x = 1 m at t = 0, spring 0 breaks at 0.1 / V s.
static inline sm_model* pulled_spring(void)
{
	sm_model_def md = sm_default_model_def();
	sm_model* model = sm_model_create(&md, NULL);
	sm_particle_def p = sm_default_particle_def();
	p.motion = SM_PARTICLE_FIXED;
	sm_particle_def driven = sm_default_particle_def();
	driven.motion = SM_PARTICLE_DRIVEN;
	driven.position[0] = 1.0;
	sm_particle_def free_particle = sm_default_particle_def();
	free_particle.position[2] = -0.5;
	sm_spring_def pulled = sm_default_spring_def();
	pulled.a = 0;
	pulled.b = 1;
	pulled.stiffness = 100.0;
	pulled.break_strain = 0.1;
	sm_spring_def hanging = pulled;
	hanging.b = 2;
	hanging.break_strain = INFINITY;
	hanging.damping = 1.0;
	if (!model || sm_model_add_particle(model, &p, NULL) != SM_OK ||
	    sm_model_add_particle(model, &driven, NULL) != SM_OK ||
	    sm_model_add_particle(model, &free_particle, NULL) != SM_OK ||
	    sm_model_add_spring(model, &pulled, NULL) != SM_OK ||
	    sm_model_add_spring(model, &hanging, NULL) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

// Makes a serialised simulation state's last 8 bytes the FNV-1a checksum of the rest, as the
// format has it, so that a state changed on purpose is judged by its content, not by its checksum.
static inline void fix_checksum(unsigned char* bytes, size_t size)
{
	uint64_t h = 14695981039346656037ull;
	for (size_t k = 0; k + 8 < size; k++)
		h = (h ^ bytes[k]) * 1099511628211ull;
	memcpy(bytes + size - 8, &h, 8);
}

// A copy of a saved state whose time is `time` [s] (the serialised header's last field, 40 bytes
// in), its checksum made to match: a state as if saved then, for what restoring it checks. NULL if
// the state cannot be serialised or the copy is refused.
static inline sm_simulation_state* state_at_time(const sm_simulation_state* saved, double time)
{
	const size_t size = sm_simulation_state_size(saved);
	unsigned char* bytes = malloc(size);
	sm_simulation_state* copy = NULL;
	if (bytes != NULL && sm_simulation_state_serialize(saved, bytes, size) == SM_OK) {
		memcpy(bytes + 40, &time, sizeof time);
		fix_checksum(bytes, size);
		copy = sm_simulation_state_deserialize(bytes, size, NULL);
	}
	free(bytes);
	return copy;
}

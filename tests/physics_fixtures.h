// Shared fixtures of the physics-core tests: a deterministic random generator and small
// random models whose springs are stretched, compressed and nearly collinear, with damping.
#pragma once

#include "springmass/model.h"
#include "springmass/structures.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

// xorshift64*: deterministic, the same sequence on every machine.
typedef struct rng {
	uint64_t state;
} rng;

static inline double rng_uniform(rng* r, double lo, double hi)
{
	r->state ^= r->state >> 12;
	r->state ^= r->state << 25;
	r->state ^= r->state >> 27;
	const uint64_t bits = r->state * 2685821657736338717ull;
	return lo + (hi - lo) * (double)(bits >> 11) * (1.0 / 9007199254740992.0);
}

// A model of `n` particles at random positions in a unit box (one of them fixed when
// `with_fixed`), random velocities in the state arrays, springs of both kinds between random
// pairs plus a nearly collinear triple, with rest lengths from 0.5 to 1.5 times the distance
// (so both stretched and compressed springs), random stiffness and damping, mass damping.
// x, v receive a configuration (3n each). Returns NULL on failure.
static inline sm_model* random_model(rng* r, int32_t n, int32_t springs, int with_fixed, double* x, double* v)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[0] = 0.3;
	md.gravity[2] = -9.81;
	md.mass_damping = 0.7;
	sm_model* m = sm_model_create(&md, NULL);
	if (m == NULL)
		return NULL;
	for (int32_t i = 0; i < n; i++) {
		sm_particle_def p = sm_default_particle_def();
		p.mass = rng_uniform(r, 0.2, 2.0);
		for (int k = 0; k < 3; k++) {
			p.position[k] = rng_uniform(r, 0.0, 1.0);
			p.velocity[k] = rng_uniform(r, -1.0, 1.0);
		}
		// The first three particles are nearly collinear: the middle one 1e-4 m off the line.
		if (i < 3 && n >= 3) {
			p.position[0] = 0.5 * i;
			p.position[1] = i == 1 ? 1e-4 : 0.0;
			p.position[2] = 0.0;
		}
		if (with_fixed && i == n - 1)
			p.motion = SM_PARTICLE_FIXED;
		if (sm_model_add_particle(m, &p, NULL) != SM_OK) {
			sm_model_destroy(m);
			return NULL;
		}
		for (int k = 0; k < 3; k++) {
			x[3 * i + k] = p.position[k];
			v[3 * i + k] = p.motion == SM_PARTICLE_FIXED ? 0.0 : p.velocity[k];
		}
	}
	for (int32_t s = 0; s < springs; s++) {
		sm_spring_def d = sm_default_spring_def();
		if (s < 2 && n >= 3) {  // the nearly collinear pair 0-1, 1-2
			d.a = s;
			d.b = s + 1;
		} else {
			d.a = (int32_t)rng_uniform(r, 0.0, (double)n - 1e-9);
			do
				d.b = (int32_t)rng_uniform(r, 0.0, (double)n - 1e-9);
			while (d.b == d.a);
		}
		const double* xa = x + 3 * d.a;
		const double* xb = x + 3 * d.b;
		const double L = sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[1] - xa[1]) * (xb[1] - xa[1]) +
		                      (xb[2] - xa[2]) * (xb[2] - xa[2]));
		if (s % 4 == 3) {
			d.kind = SM_SPRING_ZERO_LENGTH;
			d.rest_length = 0.0;
		} else {
			d.rest_length = L * (s % 2 == 0 ? rng_uniform(r, 0.5, 0.9) : rng_uniform(r, 1.1, 1.5));
		}
		d.stiffness = rng_uniform(r, 10.0, 200.0);
		d.damping = rng_uniform(r, 0.5, 3.0);
		if (sm_model_add_spring(m, &d, NULL) != SM_OK) {
			sm_model_destroy(m);
			return NULL;
		}
	}
	return m;
}

// The special cases of the spring loop added to a random_model of at least 6 particles and 8
// springs: particles 4 and 5 made to coincide in x and a rest-length spring between them (the
// degenerate point), and spring 7 disabled. Returns SM_OK or the failing call's status.
static inline sm_status add_degenerate_and_disabled_springs(sm_model* m, double* x)
{
	memcpy(x + 3 * 4, x + 3 * 5, 3 * sizeof(double));
	sm_spring_def d = sm_default_spring_def();
	d.a = 4;
	d.b = 5;
	d.rest_length = 0.3;
	d.stiffness = 50.0;
	d.damping = 1.0;
	const sm_status status = sm_model_add_spring(m, &d, NULL);
	return status != SM_OK ? status : sm_model_set_spring_enabled(m, 7, false);
}

// A model under gravity (0, 0, gz) [m/s^2] with mass damping alpha [1/s], holding one straight
// rope from the origin along x: n segments over `length` [m], `mass` [kg] lumped at its particles
// 0 .. n, structural stiffness E [N] and damping c [N s] per strain. NULL on failure.
static inline sm_model* lumped_rope_model(double gz, double alpha, double length, int32_t n, double mass,
                                          double E, double c)
{
	sm_model_def md = sm_default_model_def();
	md.gravity[2] = gz;
	md.mass_damping = alpha;
	sm_model* model = sm_model_create(&md, NULL);
	sm_rope_def rd = sm_default_rope_def();
	rd.end[0] = length;
	rd.segments = n;
	rd.mass = mass;
	rd.mass_distribution = SM_MASS_LUMPED;
	rd.structural.stiffness = E;
	rd.structural.damping = c;
	if (model != NULL && sm_add_rope(model, &rd, NULL) != SM_OK) {
		sm_model_destroy(model);
		return NULL;
	}
	return model;
}

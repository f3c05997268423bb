// An integrator independent of CVODE for the tests: GSL's explicit Runge-Kutta-Prince-Dormand
// (8, 9) over a model's forces, y = [x of the free particles; v of the free particles], from the
// model's initial state, constrained particles held where they start (no driven motion).
#pragma once

#include "springmass/model.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <stdlib.h>

typedef struct gsl_reference {
	const sm_model* model;
	int32_t free_count;
	int32_t* free_particles;
	double* mass;       // of each free particle [kg]
	double *x, *v, *f;  // every particle's position [m], velocity [m/s] and force [N]
	double* y;
	double t;          // [s]
	long evaluations;  // right-hand sides so far
	gsl_odeiv2_system system;
	gsl_odeiv2_driver* driver;
} gsl_reference;

static inline void gsl_reference_unpack(gsl_reference* g, const double* y)
{
	const size_t nd = 3 * (size_t)g->free_count;
	for (int32_t k = 0; k < g->free_count; k++)
		for (int c = 0; c < 3; c++) {
			g->x[3 * g->free_particles[k] + c] = y[3 * k + c];
			g->v[3 * g->free_particles[k] + c] = y[nd + 3 * (size_t)k + (size_t)c];
		}
}

static inline int gsl_reference_rhs(double t, const double y[], double dydt[], void* params)
{
	(void)t;
	gsl_reference* g = params;
	const size_t nd = 3 * (size_t)g->free_count;
	gsl_reference_unpack(g, y);
	sm_model_forces(g->model, g->x, g->v, NULL, g->f);
	for (int32_t k = 0; k < g->free_count; k++)
		for (int c = 0; c < 3; c++) {
			dydt[3 * k + c] = y[nd + 3 * (size_t)k + (size_t)c];
			dydt[nd + 3 * (size_t)k + (size_t)c] = g->f[3 * g->free_particles[k] + c] / g->mass[k];
		}
	g->evaluations++;
	return GSL_SUCCESS;
}

static inline void gsl_reference_free(gsl_reference* g)
{
	if (g->driver != NULL)
		gsl_odeiv2_driver_free(g->driver);
	free(g->free_particles);
	free(g->mass);
	free(g->x);
	free(g->v);
	free(g->f);
	free(g->y);
}

// Starts at t = 0 with relative and absolute tolerance eps. Returns false if out of memory.
static inline bool gsl_reference_init(gsl_reference* g, const sm_model* model, double eps)
{
	const int32_t n = sm_model_particle_count(model);
	*g = (gsl_reference){.model = model, .free_count = sm_model_free_count(model)};
	const size_t nd = 3 * (size_t)g->free_count;
	g->free_particles = malloc(sizeof(int32_t) * ((size_t)g->free_count + 1));
	g->mass = malloc(sizeof(double) * ((size_t)g->free_count + 1));
	g->x = malloc(sizeof(double) * 3 * ((size_t)n + 1));
	g->v = malloc(sizeof(double) * 3 * ((size_t)n + 1));
	g->f = malloc(sizeof(double) * 3 * ((size_t)n + 1));
	g->y = malloc(sizeof(double) * (2 * nd + 1));
	if (!g->free_particles || !g->mass || !g->x || !g->v || !g->f || !g->y) {
		gsl_reference_free(g);
		return false;
	}
	sm_model_initial_state(model, g->x, g->v);
	for (int32_t i = 0, k = 0; i < n; i++) {
		if (sm_model_free_index(model, i) < 0) {
			g->v[3 * i] = g->v[3 * i + 1] = g->v[3 * i + 2] = 0.0;
			continue;
		}
		sm_particle_def p;
		sm_model_get_particle(model, i, &p);
		g->free_particles[k] = i;
		g->mass[k] = p.mass;
		for (int c = 0; c < 3; c++) {
			g->y[3 * k + c] = g->x[3 * i + c];
			g->y[nd + 3 * (size_t)k + (size_t)c] = g->v[3 * i + c];
		}
		k++;
	}
	g->system = (gsl_odeiv2_system){gsl_reference_rhs, NULL, 2 * nd, g};
	g->driver = gsl_odeiv2_driver_alloc_y_new(&g->system, gsl_odeiv2_step_rk8pd, 1e-6, eps, eps);
	if (g->driver == NULL) {
		gsl_reference_free(g);
		return false;
	}
	return true;
}

// Integrates to t_end [s] (>= g->t); g->x and g->v then hold every particle's state there.
// Returns GSL's status.
static inline int gsl_reference_advance(gsl_reference* g, double t_end)
{
	const int status = t_end > g->t ? gsl_odeiv2_driver_apply(g->driver, &g->t, t_end, g->y) : GSL_SUCCESS;
	gsl_reference_unpack(g, g->y);
	return status;
}

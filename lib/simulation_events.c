// Spring breaks: the root functions CVODE watches, and the breaks themselves.
//
// A spring with a break strain breaks when its length L rises through l0 (1 + break_strain): one
// root function g = L - l0 (1 + break_strain) per breakable spring, rising roots only.
#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

// g_i = L - l0 (1 + break_strain) for each breakable spring still intact; -1 once broken.
static int roots(sunrealtype t, N_Vector yv, sunrealtype* g, void* user_data)
{
	sm_simulation* sim = user_data;
	double* x = sim->work_position;
	double* v = sim->work_velocity;
	sm_simulation_unpack(sim, t, N_VGetArrayPointer(yv), x, v);
	for (int32_t r = 0; r < sim->root_count; r++) {
		const int32_t s = sim->root_spring[r];
		if (!sim->model->enabled[s]) {
			g[r] = -1.0;
			continue;
		}
		const double* a = x + 3 * (size_t)sim->model->spring_a[s];
		const double* b = x + 3 * (size_t)sim->model->spring_b[s];
		const double d0 = b[0] - a[0], d1 = b[1] - a[1], d2 = b[2] - a[2];
		g[r] = sqrt(d0 * d0 + d1 * d1 + d2 * d2) - sim->root_limit[r];
	}
	return 0;
}

sm_status sm_simulation_build_events(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	int32_t count = 0;
	for (int32_t s = 0; s < m->spring_count; s++)
		if (isfinite(m->spring_def[s].break_strain))
			count++;
	int32_t* spring = NULL;
	double *limit = NULL, *values = NULL;
	int *found = NULL, *direction = NULL;
	if (count > 0) {
		spring = malloc((size_t)count * sizeof(int32_t));
		limit = malloc((size_t)count * sizeof(double));
		values = malloc((size_t)count * sizeof(double));
		found = malloc((size_t)count * sizeof(int));
		direction = malloc((size_t)count * sizeof(int));
		if (!spring || !limit || !values || !found || !direction) {
			free(spring);
			free(limit);
			free(values);
			free(found);
			free(direction);
			return SM_ERROR_OUT_OF_MEMORY;
		}
		for (int32_t s = 0, r = 0; s < m->spring_count; s++) {
			if (!isfinite(m->spring_def[s].break_strain))
				continue;
			spring[r] = s;
			limit[r] = m->rest_length[s] * (1.0 + m->spring_def[s].break_strain);
			direction[r] = 1;  // only a strain rising through the limit breaks a spring
			r++;
		}
	}
	free(sim->root_spring);
	free(sim->root_limit);
	free(sim->root_values);
	free(sim->roots_found);
	sim->root_spring = spring;
	sim->root_limit = limit;
	sim->root_values = values;
	sim->roots_found = found;
	sim->root_count = count;
	sm_status st = SM_OK;
	if (sim->cvode != NULL) {
		if (CVodeRootInit(sim->cvode, count, count > 0 ? roots : NULL) != CV_SUCCESS ||
		    (count > 0 && CVodeSetRootDirection(sim->cvode, direction) != CV_SUCCESS))
			st = SM_ERROR_SOLVER;
		else if (count > 0)
			CVodeSetNoInactiveRootWarn(sim->cvode);
	}
	free(direction);
	return st;
}

sm_status sm_simulation_record_break(sm_simulation* sim, double t, int32_t spring)
{
	if (sim->break_count == sim->break_capacity) {
		int32_t cap = sim->break_capacity ? 2 * sim->break_capacity : 16;
		sm_break_event* b = realloc(sim->breaks, (size_t)cap * sizeof *b);
		if (!b)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->breaks = b;
		sim->break_capacity = cap;
	}
	sim->breaks[sim->break_count].time = t;
	sim->breaks[sim->break_count].spring = spring;
	sim->break_count++;
	return sm_model_set_spring_enabled(sim->model, spring, false);
}

// A broken spring takes its elastic energy with it, out of the mechanical system: it is added to
// the dissipated energy, so that kinetic + elastic + gravitational + dissipated energy stays
// constant across breaks as between them.
sm_status sm_simulation_break_springs(sm_simulation* sim)
{
	sm_simulation_unpack(sim, sim->time, N_VGetArrayPointer(sim->y), sim->position, sim->velocity);
	const double elastic_before = sm_model_energies(sim->model, sim->position, NULL).elastic;
	bool broke = false, out_of_memory = false;
	for (int32_t r = 0; r < sim->root_count && !out_of_memory; r++) {
		if (sim->roots_found[r] <= 0 || !sim->model->enabled[sim->root_spring[r]])
			continue;
		out_of_memory = sm_simulation_record_break(sim, sim->time, sim->root_spring[r]) != SM_OK;
		broke = broke || !out_of_memory;
	}
	if (broke) {
		const double elastic_after = sm_model_energies(sim->model, sim->position, NULL).elastic;
		N_VGetArrayPointer(sim->y)[2 * sim->dofs] += elastic_before - elastic_after;
	}
	// After a failure too: the springs not yet broken are beyond their limit at this time, and
	// the next advance, starting afresh here, breaks them first.
	sim->need_restart = sim->need_restart || broke || out_of_memory;
	if (out_of_memory) {
		snprintf(sim->last_error, sizeof sim->last_error, "out of memory recording a spring break");
		return SM_ERROR_OUT_OF_MEMORY;
	}
	return SM_OK;
}

sm_status sm_simulation_break_overstretched_springs(sm_simulation* sim)
{
	if (sim->root_count == 0)
		return SM_OK;
	roots(sim->time, sim->y, sim->root_values, sim);
	bool any = false;
	for (int32_t r = 0; r < sim->root_count; r++) {
		// At the limit counts as beyond: CVODE would not report a root function that starts at 0
		// as crossing when it rises. Broken springs give -1.
		sim->roots_found[r] = sim->root_values[r] >= 0.0;
		any = any || sim->roots_found[r];
	}
	return any ? sm_simulation_break_springs(sim) : SM_OK;
}

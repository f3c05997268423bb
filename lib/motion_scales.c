// The scales of a model's motion, against which its absolute tolerances are judged
// (simulation.h).
//
// CVODE's error weight of a component is 1 / (rtol |y| + atol): where the motion itself is
// smaller than atol, rtol no longer acts and the motion is resolved only to atol. The shortest
// spring with a free end sets the smallest length the model's shape resolves (one between held
// particles is no part of CVODE's state: its ends stay put or follow their prescribed motion); a
// motion of that length at the highest frequency the model can ring at (its Gershgorin bound, to
// which such a spring adds nothing either) sets the speed. Tolerances at
// or below SM_COARSE_TOLERANCE of both resolve it; above both, even its largest motion is held
// to little more than a ten-thousandth of its size.
#include "springmass/analysis.h"
#include "springmass/simulation.h"

#include <math.h>
#include <stdlib.h>

sm_status sm_model_motion_scales(const sm_model* model, sm_motion_scales* scales)
{
	if (model == NULL || scales == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	sm_explicit_limit limit;
	const sm_status st = sm_model_explicit_limit(model, &limit);
	if (st != SM_OK)
		return st;
	const int32_t n = sm_model_particle_count(model);
	double* x = malloc((3 * (size_t)n + 1) * sizeof(double));
	if (x == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	sm_model_initial_state(model, x, NULL);
	double shortest = INFINITY;
	for (int32_t k = 0; k < sm_model_spring_count(model); k++) {
		if (!sm_model_spring_enabled(model, k))
			continue;
		sm_spring_def s;
		double l0 = 0.0, ks = 0.0, kd = 0.0;
		sm_model_get_spring(model, k, &s);
		if (sm_model_free_index(model, s.a) < 0 && sm_model_free_index(model, s.b) < 0)
			continue;
		sm_model_spring_constants(model, k, &l0, &ks, &kd);
		const double* a = x + 3 * (size_t)s.a;
		const double* b = x + 3 * (size_t)s.b;
		const double length = l0 > 0.0 ? l0 : hypot(hypot(b[0] - a[0], b[1] - a[1]), b[2] - a[2]);
		if (length > 0.0)
			shortest = fmin(shortest, length);
	}
	free(x);
	scales->length = shortest;
	scales->speed = isfinite(shortest) ? shortest * limit.omega_max : INFINITY;
	return SM_OK;
}

bool sm_tolerances_coarse(const sm_simulation_def* def, const sm_motion_scales* scales)
{
	if (def == NULL || scales == NULL)
		return false;
	const double length = scales->length, speed = scales->speed;
	if (!(length > 0.0) || !isfinite(length) || !(speed > 0.0) || !isfinite(speed))
		return false;
	return def->absolute_tolerance_position > SM_COARSE_TOLERANCE * length &&
	       def->absolute_tolerance_velocity > SM_COARSE_TOLERANCE * speed;
}

// The scales of a model's motion, and the round-off of its forces, against which its absolute
// tolerances are judged (simulation.h).
//
// CVODE's error weight of a component is 1 / (rtol |y| + atol): where the motion itself is
// smaller than atol, rtol no longer acts and the motion is resolved only to atol. The shortest
// spring with a free end sets the smallest length the model's shape resolves (one between held
// particles is no part of CVODE's state: its ends stay put or follow their prescribed motion; one
// of neither stiffness nor damping, as a group's whose parameters are 0, exerts no force); a
// motion of that length at the highest frequency the model can ring at (its Gershgorin bound, to
// which such a spring adds nothing either) sets the speed. Tolerances at
// or below SM_COARSE_TOLERANCE of both resolve it; above both, even its largest motion is held
// to little more than a ten-thousandth of its size.
#include "springmass/analysis.h"
#include "springmass/simulation.h"

#include <float.h>
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
		if (ks == 0.0 && kd == 0.0)
			continue;  // no force: nothing of the shape turns on its length
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

// The round-off of a spring's force, against which the velocities' absolute tolerance is judged.
// A coordinate of size |x| is held to its ulp, at most DBL_EPSILON |x|, so the length of a spring
// between particles there is known to about that, and its force k (L - l0) only to
//   dF = k DBL_EPSILON |x|,
// whatever its length and strain: a noise that no step size removes. A step of CVODE's BDF
// solves for the change of velocity of an end of mass m (gamma about the step [s], c the
// spring's damping)
//   (m + gamma c + gamma^2 k) dv = gamma dF,
// which is largest without damping (c >= 0 only lowers it) at gamma = sqrt(m / k):
//   dv_max = dF / (2 sqrt(k m)) = DBL_EPSILON |x| sqrt(k / m) / 2,
// the speed of a motion of the coordinates' own rounding at the spring's frequency. Between two
// free particles the relative motion has the reduced mass, below either, and each end moves by
// its share: the lighter end's mass bounds both; other springs on an end only add to the matrix.
// Positions need no such bound: the same noise moves them by gamma dv <= dF / k = DBL_EPSILON
// |x|, their own rounding (atol_position down to 1e-20 m changed no step below). A velocity at
// rest, or a component passing through 0, is held to atol_velocity alone; CVODE's error test and
// its Newton iteration's convergence test see a part of dv_max (its error constants, 1/2 to 1/6,
// and the root mean square over the components), and below about a tenth of it
// (SM_TIGHT_TOLERANCE) fail over and over: with 1e9 N/m at 1 m, 1e-13 m/s took 83 521 steps and
// 69 036 failed Newton iterations to 2 s, 1e-14 m/s 922 587 steps, nearly all failing the error
// test. A 1 kg bob hanging at rest on a critically damped rest-length rod of 1 m for 2 s (rtol
// 1e-6, at most 20 000 steps per 0.5 s, "stop" when reached; the default solver, dense), the rod
// along z at |x| = 1 m and 1000 m from the origin:
//   k [N/m]  |x| [m]  dv_max [m/s]   steps at atol_velocity 1e-8 1e-10 1e-12 1e-13 1e-14 1e-15 m/s
//   1e5      1        3.5e-14                               141    195   256   241   309   324
//   1e5      1000     3.5e-11                               146    173   646  1832 10953  stop
//   1e7      1        3.5e-13                                97    150   180   767 13518 32407
//   1e7      1000     3.5e-10                                89    153 44962  stop  stop  stop
//   1e9      1        3.5e-12                                89    113   154  stop  stop  stop
//   1e9      1000     3.5e-9                                 94   stop  stop  stop  stop  stop
//   1e11     1        3.5e-11                                47    104  stop  stop  stop  stop
//   1e11     1000     3.5e-8                                 50   stop  stop  stop  stop  stop
// Below a tenth of dv_max every run slows down or stops but one (1e5 N/m at 1 m, 1e-15 m/s);
// above it one slows down (1e7 N/m at 1 m, 1e-13 m/s: 767 steps against 180), none stops.
sm_status sm_model_round_off(const sm_model* model, sm_round_off* round_off)
{
	if (model == NULL || round_off == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	const int32_t n = sm_model_particle_count(model);
	double* x = malloc((3 * (size_t)n + 1) * sizeof(double));
	if (x == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	sm_model_initial_state(model, x, NULL);
	*round_off = (sm_round_off){.spring = -1, .stiffness = 0.0, .velocity = 0.0};
	for (int32_t k = 0; k < sm_model_spring_count(model); k++) {
		if (!sm_model_spring_enabled(model, k))
			continue;
		sm_spring_def s;
		sm_particle_def a, b;
		double ks = 0.0;
		sm_model_get_spring(model, k, &s);
		sm_model_get_particle(model, s.a, &a);
		sm_model_get_particle(model, s.b, &b);
		double mass = INFINITY;
		if (a.motion == SM_PARTICLE_FREE)
			mass = a.mass;
		if (b.motion == SM_PARTICLE_FREE)
			mass = fmin(mass, b.mass);
		if (!isfinite(mass))
			continue;
		sm_model_spring_constants(model, k, NULL, &ks, NULL);
		double size = 0.0;
		for (int c = 0; c < 3; c++)
			size = fmax(size, fmax(fabs(x[3 * (size_t)s.a + c]), fabs(x[3 * (size_t)s.b + c])));
		const double velocity = DBL_EPSILON * size * sqrt(ks / mass) / 2.0;
		if (round_off->spring < 0 || velocity > round_off->velocity)
			*round_off = (sm_round_off){.spring = k, .stiffness = ks, .velocity = velocity};
	}
	free(x);
	return SM_OK;
}

bool sm_tolerances_tight(const sm_simulation_def* def, const sm_round_off* round_off)
{
	if (def == NULL || round_off == NULL)
		return false;
	const double velocity = round_off->velocity;
	if (!(velocity > 0.0) || !isfinite(velocity))
		return false;
	return def->absolute_tolerance_velocity < SM_TIGHT_TOLERANCE * velocity;
}

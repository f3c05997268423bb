// Spring breaks: the root functions CVODE watches, and the breaks themselves.
//
// A spring with a break strain breaks when its length L rises through l0 (1 + break_strain): one
// root function g = L - l0 (1 + break_strain) per breakable spring, rising roots only.
#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

// CVODE's largest orders, which the simulation leaves at their defaults (CVodeSetMaxOrd): 5 for
// BDF, 12 for Adams.
#define BDF_MAX_ORDER 5
#define ADAMS_MAX_ORDER 12

static int max_order(const sm_simulation* sim)
{
	return sim->def.method == SM_METHOD_ADAMS ? ADAMS_MAX_ORDER : BDF_MAX_ORDER;
}

sm_status sm_simulation_build_events(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	int32_t count = 0;
	for (int32_t s = 0; s < m->spring_count; s++)
		if (isfinite(m->spring_def[s].break_strain))
			count++;
	// What the search of each step needs and keeps for the simulation's life: its size depends on
	// the particles and the method only.
	if (count > 0 && sim->taylor_position == NULL) {
		const size_t n = (size_t)sim->particle_count;
		sim->taylor_position = malloc((((size_t)max_order(sim) + 1) * 3 * n + n + 1) * sizeof(double));
		if (sim->taylor_position == NULL)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->reach = sim->taylor_position + ((size_t)max_order(sim) + 1) * 3 * n;
	}
	if (count > 0 && sim->interpolated == NULL && (sim->interpolated = N_VClone(sim->y)) == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	int32_t* spring = NULL;
	double *limit = NULL, *values = NULL, *crossing = NULL;
	int *found = NULL, *direction = NULL;
	if (count > 0) {
		spring = malloc((size_t)count * sizeof(int32_t));
		limit = malloc((size_t)count * sizeof(double));
		values = malloc((size_t)count * sizeof(double));
		crossing = malloc((size_t)count * sizeof(double));
		found = malloc((size_t)count * sizeof(int));
		direction = malloc((size_t)count * sizeof(int));
		if (!spring || !limit || !values || !crossing || !found || !direction) {
			free(spring);
			free(limit);
			free(values);
			free(crossing);
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
	free(sim->crossing_time);
	free(sim->roots_found);
	sim->root_spring = spring;
	sim->root_limit = limit;
	sim->root_values = values;
	sim->crossing_time = crossing;
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
	sm_simulation_refresh_outputs(sim);
	// The springs' own energies, not the model's elastic energy before and after: that would cost
	// two passes over every spring per event (a tear of many events over a large model).
	double released = 0.0;
	bool broke = false, out_of_memory = false;
	for (int32_t r = 0; r < sim->root_count && !out_of_memory; r++) {
		if (sim->roots_found[r] <= 0 || !sim->model->enabled[sim->root_spring[r]])
			continue;
		const int32_t s = sim->root_spring[r];
		const double energy =
		    sm_model_spring_energy(sim->model, s, sim->position + 3 * (size_t)sim->model->spring_a[s],
			                       sim->position + 3 * (size_t)sim->model->spring_b[s]);
		out_of_memory = sm_simulation_record_break(sim, sim->time, s) != SM_OK;
		if (!out_of_memory)
			released += energy;
		broke = broke || !out_of_memory;
	}
	// An energy beyond a double (ks (L - l0)^2 / 2 above 1.8e308 J) is not handed on: the
	// dissipated energy is part of CVODE's state, and an infinite or NaN one would fail every step
	// after. The balance is lost with it, as the energies themselves were.
	if (isfinite(released))
		N_VGetArrayPointer(sim->y)[sm_simulation_dissipated_index(sim)] += released;
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
	roots(sm_simulation_cvode_time(sim, sim->time), sim->y, sim->root_values, sim);
	bool any = false;
	for (int32_t r = 0; r < sim->root_count; r++) {
		// At the limit counts as beyond: CVODE would not report a root function that starts at 0
		// as crossing when it rises. Broken springs give -1.
		sim->roots_found[r] = sim->root_values[r] >= 0.0;
		any = any || sim->roots_found[r];
	}
	return any ? sm_simulation_break_springs(sim) : SM_OK;
}

void sm_simulation_free_events(sm_simulation* sim)
{
	free(sim->root_spring);
	free(sim->root_limit);
	free(sim->root_values);
	free(sim->crossing_time);
	free(sim->roots_found);
	free(sim->taylor_position);  // reach too
	N_VDestroy(sim->interpolated);
}

// ---------------------------------------------------------------------------------------------
// Excursions between the ends of a step
// ---------------------------------------------------------------------------------------------
//
// CVODE compares the root functions at the ends of its steps only (and between the points of its
// own search once it has found a sign change): a strain that rises through its limit and falls
// back within one step goes unseen, and with steps of w h ~ 0.3 on a strain A cos(w t) peaks up
// to about 1 % above the limit are missed. So after every step the strain is followed on CVODE's
// interpolating polynomial of that step, over the whole step, and not only at its ends.
//
// Over the part [t_lo, t_hi] of a step searched, s = (t - t_lo) / H in [0, 1], H = t_hi - t_lo,
// the polynomial of order q gives each particle x(s) = sum_k X_k s^k with X_k = x^(k)(t_lo) H^k / k!
// (CVodeGetDky; a driven particle's path is its own, of degree 2 at most, and q is taken as 2 at
// least while one accelerates; a fixed particle's is constant). A spring's vector
// d(s) = x_b(s) - x_a(s) = sum_k D_k s^k, and its length reaches the limit l where
//   P(s) = |d(s)|^2 - l^2 = sum_j e_j s^j,  e_j = sum_{k + m = j} D_k . D_m  (minus l^2 for j = 0),
// a polynomial of degree n = 2q (at most 24, with Adams) of the same sign as L - l.
// How many points to sample it at? P may have up to n - 1 extrema in the step, anywhere, so no
// fixed number of samples can rule out an excursion between them. A bound can: in the Bernstein
// basis P(s) = sum_i b_i C(n, i) s^i (1 - s)^(n - i), with b_i = sum_{j <= i} C(i, j) / C(n, j) e_j,
// P lies between the least and the greatest b_i on [0, 1], and b_0 = P(0), b_n = P(1). So:
// - all b_i < 0: the spring stays below its limit over the whole interval;
// - otherwise halve the interval (de Casteljau's algorithm gives both halves' coefficients) and
//   look at the left half first, until the first half of CVODE's time resolution that ends with
//   P >= 0, its right end being the crossing, as CVODE's own root search returns it. A half whose
//   coefficients bound P below 0 is done with; one that reaches the resolution with P < 0 at both
//   ends touches the limit to round-off only and breaks nothing.
// The halves' coefficients approach P's values quadratically in their width, so an excursion is
// isolated in a few halvings, and a crossing located to the resolution in about 45 (bisection:
// each halving keeps a bracket of the first sign change). Before all this the triangle inequality
// rules out a spring far below its limit: |d(s)| <= |D_0| + sum_{k >= 1} (|X_k,a|_1 + |X_k,b|_1),
// the sums (how far each end may move over the step) formed once per particle. Most springs of a
// tearing model are ruled out so, at most steps.

// CVODE's root resolution (cvRcheck3 in cvode.c): 100 unit round-offs of |t_n| + |h|.
#define ROOT_RESOLUTION (100.0 * DBL_EPSILON)
// The most halvings of [0, 1]: the resolution is at least 100 eps = 2.2e-14 of the step, above
// 2^-46 = 1.4e-14; the search holds one pending half per level.
#define MAX_HALVINGS 47
#define MAX_DEGREE (2 * ADAMS_MAX_ORDER)

// The halvings of one spring's polynomial, depth first, left half first (simulation_internal.h).
double sm_simulation_first_rise(const double* b, int n, double resolution)
{
	double pending[MAX_HALVINGS + 2][MAX_DEGREE + 1];
	double start[MAX_HALVINGS + 2], width[MAX_HALVINGS + 2];
	memcpy(pending[0], b, (size_t)(n + 1) * sizeof(double));
	start[0] = 0.0;
	width[0] = 1.0;
	int depth = 1;  // intervals on the stack
	while (depth > 0) {
		depth--;
		const double* c = pending[depth];
		const double u = start[depth], w = width[depth];
		if (c[0] >= 0.0)
			return u;
		double greatest = c[0];
		for (int i = 1; i <= n; i++)
			greatest = fmax(greatest, c[i]);
		if (greatest < 0.0)
			continue;
		if (w <= resolution || depth >= MAX_HALVINGS) {
			if (c[n] >= 0.0)
				return u + w;
			continue;
		}
		// de Casteljau at 1/2: the left half's coefficients are the first of each level of
		// averages, the right half's the last. Each average is taken as a sum of halves: that of
		// two finite numbers is finite, where their sum may overflow (coefficients beyond
		// DBL_MAX / 2, for lengths near 1e154 m); +inf and -inf in one level then made NaN, whose
		// bounds compare false, and the search descended the whole tree of halvings. Halving is
		// exact above the subnormals, so the averages are the same bits as (a + b) / 2.
		double left[MAX_DEGREE + 1], right[MAX_DEGREE + 1], work[MAX_DEGREE + 1];
		memcpy(work, c, (size_t)(n + 1) * sizeof(double));
		left[0] = work[0];
		right[n] = work[n];
		for (int level = 1; level <= n; level++) {
			for (int i = 0; i <= n - level; i++)
				work[i] = 0.5 * work[i] + 0.5 * work[i + 1];
			left[level] = work[0];
			right[n - level] = work[n - level];
		}
		// The right half below the left one on the stack: the left is searched first.
		memcpy(pending[depth], right, (size_t)(n + 1) * sizeof(double));
		start[depth] = u + 0.5 * w;
		width[depth] = 0.5 * w;
		memcpy(pending[depth + 1], left, (size_t)(n + 1) * sizeof(double));
		start[depth + 1] = u;
		width[depth + 1] = 0.5 * w;
		depth += 2;
	}
	return -1.0;
}

// taylor_position row k (3 per particle) = X_k = x^(k)(t_lo) H^k / k!, k = 0..order, from CVODE's
// polynomial of its last step (of order q <= order: the free particles' rows beyond q are 0), and
// reach = sum_{k >= 1} |X_k|_1 >= |x(s) - x(0)| for s in [0, 1]. A CVODE flag.
static int fill_taylor_positions(sm_simulation* sim, double t_lo, double H, int q, int order)
{
	const size_t n3 = 3 * (size_t)sim->particle_count;
	for (int32_t i = 0; i < sim->particle_count; i++)
		sim->reach[i] = 0.0;
	double scale = 1.0;  // H^k / k!
	for (int k = 0; k <= order; k++) {
		scale *= k > 0 ? H / k : 1.0;
		double* X = sim->taylor_position + (size_t)k * n3;
		const double* y = NULL;
		if (k <= q) {
			const int flag = CVodeGetDky(sim->cvode, t_lo, k, sim->interpolated);
			if (flag != CV_SUCCESS)
				return flag;
			y = N_VGetArrayPointer(sim->interpolated);
		}
		if (k == 0) {  // every particle's position at t_lo, the constrained ones' from their motion
			sm_simulation_unpack(sim, t_lo, y, X, sim->work_velocity);
			continue;
		}
		for (int32_t f = 0; f < sim->free_count; f++) {
			const int32_t i = sim->free_particles[f];
			double* x = X + 3 * (size_t)i;
			for (int c = 0; c < 3; c++)
				x[c] = y != NULL ? scale * y[3 * (size_t)f + (size_t)c] : 0.0;
			sim->reach[i] += fabs(x[0]) + fabs(x[1]) + fabs(x[2]);
		}
		// A driven particle's path x0 + v0 s + a s^2 / 2 has the scaled derivatives H (v0 + a s) and
		// H^2 a / 2 at s = (time_origin - drive_time) + t_lo, and none beyond: its own, exact, whatever
		// CVODE's order (the search asks for order 2 at least when a driven particle accelerates; a
		// first-order step cut to H (v0 + a s) alone overshot a decelerating particle's path and broke
		// springs that never reached their limits).
		for (int32_t j = 0; j < sim->constrained_count; j++) {
			const int32_t i = sim->constrained[j];
			const bool driven = sim->model->motion[i] == SM_PARTICLE_DRIVEN;
			const double s = (sim->time_origin - sim->drive_time[i]) + t_lo;
			double* x = X + 3 * (size_t)i;
			for (int c = 0; c < 3; c++) {
				const double v0 = sim->drive_velocity[3 * (size_t)i + c];
				const double a = sim->drive_acceleration[3 * (size_t)i + c];
				x[c] = !driven ? 0.0 : k == 1 ? H * (v0 + s * a) : k == 2 ? scale * a : 0.0;
				sim->reach[i] += fabs(x[c]);
			}
		}
	}
	return CV_SUCCESS;
}

// Where breakable spring r first reaches its limit on the polynomial, as s in [0, 1] (see above),
// or -1. weights[i * (n + 1) + j] = C(i, j) / C(n, j) for the degree n = 2q.
static double spring_first_crossing(const sm_simulation* sim, int32_t r, int q, const double* weights,
                                    double resolution)
{
	const sm_model* m = sim->model;
	const int32_t s = sim->root_spring[r];
	const size_t n3 = 3 * (size_t)sim->particle_count;
	const int32_t ia = m->spring_a[s], ib = m->spring_b[s];
	const size_t a = 3 * (size_t)ia, b = 3 * (size_t)ib;
	const double limit = sim->root_limit[r];
	// |d(s)| <= |D_0| + sum_{k >= 1} |D_k| <= |D_0| + reach_a + reach_b: a spring that cannot reach
	// its limit within the step, compared squared.
	const double* X0 = sim->taylor_position;
	const double d0 = X0[b] - X0[a], d1 = X0[b + 1] - X0[a + 1], d2 = X0[b + 2] - X0[a + 2];
	const double margin = limit - sim->reach[ia] - sim->reach[ib];
	if (margin > 0.0 && d0 * d0 + d1 * d1 + d2 * d2 < margin * margin)
		return -1.0;
	double D[ADAMS_MAX_ORDER + 1][3];
	for (int k = 0; k <= q; k++) {
		const double* X = sim->taylor_position + (size_t)k * n3;
		for (int c = 0; c < 3; c++)
			D[k][c] = X[b + c] - X[a + c];
	}
	const int n = 2 * q;
	double e[MAX_DEGREE + 1], bernstein[MAX_DEGREE + 1];
	for (int j = 0; j <= n; j++) {
		double sum = 0.0;
		for (int k = j > q ? j - q : 0; k <= j && k <= q; k++)
			sum += D[k][0] * D[j - k][0] + D[k][1] * D[j - k][1] + D[k][2] * D[j - k][2];
		e[j] = sum;
	}
	e[0] -= limit * limit;
	for (int i = 0; i <= n; i++) {
		double sum = 0.0;
		for (int j = 0; j <= i; j++)
			sum += weights[i * (n + 1) + j] * e[j];
		bernstein[i] = sum;
		// A polynomial that overflows (the derivatives of a state flying apart, 1e64 m/s, come out
		// infinite or NaN) bounds nothing, and NaN fails every comparison of the search: such a step
		// is left to CVODE's comparison of its ends.
		if (!isfinite(sum))
			return -1.0;
	}
	return sm_simulation_first_rise(bernstein, n, resolution);
}

// The round-off of breakable spring r's root function at the positions x [m]: its length is formed
// from coordinate differences, each rounded to eps of the coordinates, and its limit from its
// rest length, rounded to eps of it; a few of each.
#define LENGTH_ROUNDOFF (8.0 * DBL_EPSILON)
static double length_roundoff(const sm_simulation* sim, int32_t r, const double* x)
{
	const int32_t s = sim->root_spring[r];
	const double* a = x + 3 * (size_t)sim->model->spring_a[s];
	const double* b = x + 3 * (size_t)sim->model->spring_b[s];
	const double extent = fmax(fmax(fabs(a[0]), fabs(a[1])), fabs(a[2])) +
	                      fmax(fmax(fabs(b[0]), fabs(b[1])), fabs(b[2])) + sim->root_limit[r];
	return LENGTH_ROUNDOFF * extent;
}

// Whether a driven particle moves with an acceleration (sm_simulation_set_driven_accelerating).
static bool drives_accelerate(const sm_simulation* sim)
{
	for (int32_t j = 0; j < sim->constrained_count; j++) {
		const int32_t i = sim->constrained[j];
		const double* a = sim->drive_acceleration + 3 * (size_t)i;
		if (sim->model->motion[i] == SM_PARTICLE_DRIVEN && (a[0] != 0.0 || a[1] != 0.0 || a[2] != 0.0))
			return true;
	}
	return false;
}

int sm_simulation_search_step(sm_simulation* sim, int flag, bool new_step, double* reached)
{
	if (sim->root_count == 0 || flag < 0)
		return flag;
	double tn = 0.0, hu = 0.0;
	int q = 0;
	CVodeGetCurrentTime(sim->cvode, &tn);
	CVodeGetLastStep(sim->cvode, &hu);
	CVodeGetLastOrder(sim->cvode, &q);
	const double t_hi = *reached;
	const double t_lo = new_step ? tn - hu : sim->searched_until;
	sim->searched_until = t_hi;
	const bool cvode_root = flag == CV_ROOT_RETURN;
	if (cvode_root)
		CVodeGetRootInfo(sim->cvode, sim->roots_found);
	const double resolution = ROOT_RESOLUTION * (fabs(tn) + fabs(hu));
	double first = INFINITY;
	for (int32_t r = 0; r < sim->root_count; r++)
		sim->crossing_time[r] = INFINITY;
	if (t_hi > t_lo && q >= 1 && q <= max_order(sim)) {
		const double H = t_hi - t_lo;
		// The polynomials' order: CVODE's, and at least a driven particle's quadratic path.
		const int order = q < 2 && drives_accelerate(sim) ? 2 : q;
		const int status = fill_taylor_positions(sim, t_lo, H, q, order);
		if (status != CV_SUCCESS)
			return status;
		const int n = 2 * order;
		double weights[(MAX_DEGREE + 1) * (MAX_DEGREE + 1)];
		for (int i = 0; i <= n; i++) {
			double ratio = 1.0;  // C(i, j) / C(n, j) = prod_{m < j} (i - m) / (n - m)
			for (int j = 0; j <= i; j++) {
				weights[i * (n + 1) + j] = ratio;
				ratio *= (double)(i - j) / (double)(n - j);
			}
		}
		for (int32_t r = 0; r < sim->root_count; r++) {
			if (!sim->model->enabled[sim->root_spring[r]])
				continue;
			const double u = spring_first_crossing(sim, r, order, weights, resolution / H);
			if (u < 0.0)
				continue;
			sim->crossing_time[r] = u >= 1.0 ? t_hi : fmin(t_lo + u * H, t_hi);
			first = fmin(first, sim->crossing_time[r]);
		}
	}
	// CVODE's root stands unless an excursion crossed before it by more than the resolution both
	// searches locate crossings to.
	const bool cvode_root_stands = cvode_root && !(first < t_hi - resolution);
	double t_event = t_hi;
	if (!cvode_root_stands) {
		if (!isfinite(first))
			return flag;
		t_event = first;
		const int status = CVodeGetDky(sim->cvode, t_event, 0, sim->y);
		if (status != CV_SUCCESS)
			return status;
		*reached = t_event;
		for (int32_t r = 0; r < sim->root_count; r++)
			sim->roots_found[r] = 0;
	}
	// Every spring that crossed within the resolution of the event breaks with it, as CVODE breaks
	// every root function whose sign changed in its last bracket, and so does every intact one at
	// or beyond its limit in the state there, to the round-off of its length, so that CVODE
	// restarts with all of them below. Springs that reach their limits together by symmetry (a
	// ring expanding evenly) differ by the round-off of their coordinates and rest lengths, which
	// spreads their crossings over a few 1e-15 s: one event, not one per few. (The round-off of a
	// long integration, or pcg's iterations, can set them further apart: docs/simulation.md.)
	roots(t_event, sim->y, sim->root_values, sim);
	for (int32_t r = 0; r < sim->root_count; r++)
		if (sim->crossing_time[r] <= t_event + resolution ||
		    sim->root_values[r] >= -length_roundoff(sim, r, sim->work_position))
			sim->roots_found[r] = 1;
	return CV_ROOT_RETURN;
}

// Evaluation of forces, energies and dissipated power (the laws are in law_*.h).
//
// The spring loop is the hot path of every simulation. It fuses the rest-length law
// (law_rest_length.h, which covers zero-length springs with l0 = 0) and spring damping
// (law_spring_damping.h) into one magnitude along u:
//
//   f_a = [ks (L - l0) + kd r] u,   f_b = -f_a,
//
// streams through the structure-of-arrays springs with no branch (disabled springs have zero
// constants; the degenerate point is a select, not a branch) and accumulates into f.
#include "law_body_forces.h"
#include "law_rest_length.h"
#include "law_spring_damping.h"
#include "model_internal.h"

#include <math.h>
#include <string.h>

static inline void spring_loop(int32_t count, const int32_t* restrict first, const int32_t* restrict second,
                               const double* restrict rest_length, const double* restrict stiffness,
                               const double* restrict damping, const double* restrict x,
                               const double* restrict v, double* restrict f, const int with_velocity)
{
	for (int32_t s = 0; s < count; s++) {
		const size_t a = 3 * (size_t)first[s], b = 3 * (size_t)second[s];
		const double dx = x[b] - x[a], dy = x[b + 1] - x[a + 1], dz = x[b + 2] - x[a + 2];
		const double l0 = rest_length[s];
		const double length = sqrt(dx * dx + dy * dy + dz * dz);
		// Regular unless L = 0 or L < ratio * l0 (see model_internal.h, spring_geometry).
		const int regular = length > 0.0 && length >= SM_DEGENERATE_LENGTH_RATIO * l0;
		const double inv = 1.0 / (regular ? length : 1.0);
		const double inv_length = regular ? inv : 0.0;
		const double ux = dx * inv_length, uy = dy * inv_length, uz = dz * inv_length;
		double magnitude = stiffness[s] * (length - l0);
		if (with_velocity) {
			const double rate = ux * (v[b] - v[a]) + uy * (v[b + 1] - v[a + 1]) + uz * (v[b + 2] - v[a + 2]);
			magnitude += damping[s] * rate;
		}
		const double fx = magnitude * ux, fy = magnitude * uy, fz = magnitude * uz;
		f[a] += fx;
		f[a + 1] += fy;
		f[a + 2] += fz;
		f[b] -= fx;
		f[b + 1] -= fy;
		f[b + 2] -= fz;
	}
}

void sm_model_forces(const sm_model* model, const double* x, const double* v, const double* f_external,
                     double* f)
{
	if (model == NULL || x == NULL || f == NULL)
		return;
	const int32_t n = model->particle_count;
	static const double zero[3] = {0.0, 0.0, 0.0};
	for (int32_t i = 0; i < n; i++) {
		const double* vi = v != NULL ? v + 3 * (size_t)i : zero;
		body_force(model->mass[i], model->def.gravity, model->def.mass_damping, vi, f + 3 * (size_t)i);
	}
	if (f_external != NULL)
		for (size_t k = 0; k < 3 * (size_t)n; k++)
			f[k] += f_external[k];
	if (v != NULL)
		spring_loop(model->spring_count, model->spring_a, model->spring_b, model->rest_length,
		            model->stiffness, model->damping, x, v, f, 1);
	else
		spring_loop(model->spring_count, model->spring_a, model->spring_b, model->rest_length,
		            model->stiffness, model->damping, x, NULL, f, 0);
}

sm_energies sm_model_energies(const sm_model* model, const double* x, const double* v)
{
	sm_energies e = {0.0, 0.0, 0.0};
	if (model == NULL)
		return e;
	const double* g = model->def.gravity;
	for (int32_t i = 0; i < model->particle_count; i++) {
		const double m = model->mass[i];
		if (v != NULL) {
			const double* vi = v + 3 * (size_t)i;
			e.kinetic += 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
		}
		if (x != NULL) {
			const double* xi = x + 3 * (size_t)i;
			e.gravity -= m * (g[0] * xi[0] + g[1] * xi[1] + g[2] * xi[2]);
		}
	}
	if (x != NULL)
		for (int32_t s = 0; s < model->spring_count; s++) {
			spring_geometry geo;
			spring_geometry_eval(x, NULL, model->spring_a[s], model->spring_b[s], model->rest_length[s], &geo);
			// Zero-length springs have l0 = 0: ks (L - 0)^2 / 2 = ks L^2 / 2 (law_zero_length.h).
			e.elastic += rest_length_energy(model->stiffness[s], model->rest_length[s], geo.length);
		}
	return e;
}

double sm_model_dissipated_power(const sm_model* model, const double* x, const double* v)
{
	if (model == NULL || x == NULL || v == NULL)
		return 0.0;
	double power = 0.0;
	const double alpha = model->def.mass_damping;
	for (int32_t i = 0; i < model->particle_count; i++) {
		const double* vi = v + 3 * (size_t)i;
		power += alpha * model->mass[i] * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
	}
	for (int32_t s = 0; s < model->spring_count; s++) {
		spring_geometry geo;
		spring_geometry_eval(x, v, model->spring_a[s], model->spring_b[s], model->rest_length[s], &geo);
		power += spring_damping_dissipation(model->damping[s], geo.rate);
	}
	return power;
}

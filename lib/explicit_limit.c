// Gershgorin bounds of a model's highest frequency and damping rate, and the largest stable step
// of symplectic Euler they give (analysis.h, sm_explicit_limit). Apart from the modes: a bound
// needs no eigensolver, and the FMU and the command-line tool use it without linking one in.
#include "model_internal.h"
#include "springmass/analysis.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

// h <= 2 / (gamma/2 + sqrt(gamma^2/4 + omega^2)), the condition on the determinant 1 - h gamma
// (>= -1) and the trace 2 - h gamma - h^2 omega^2 (>= -1 - determinant) of symplectic Euler's map
// (Jury's criterion; analysis.h). A negative gamma makes the determinant exceed 1 at every h > 0:
// no step is stable. NaN stays NaN (hypot(NaN, inf) is inf, so it is tested first).
double sm_symplectic_euler_step(double omega, double gamma)
{
	if (isnan(omega) || isnan(gamma))
		return NAN;
	if (gamma < 0.0)
		return 0.0;
	const double denominator = 0.5 * gamma + hypot(0.5 * gamma, omega);
	return denominator > 0.0 ? 2.0 / denominator : INFINITY;
}

// A spring's term in a Gershgorin row: constant x (1/m_i + between). 0 for a zero constant even
// where 1/m_i overflows (a subnormal mass), where the product would be NaN, which fmax would
// then drop from the maximum.
static double row_term(double constant, double inverse_mass, double between)
{
	return constant > 0.0 ? constant * (inverse_mass + between) : 0.0;
}

sm_status sm_model_explicit_limit(const sm_model* model, sm_explicit_limit* limit)
{
	if (model == NULL || limit == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	const int32_t n = model->particle_count;
	double* row = calloc(2 * (size_t)n + 1, sizeof(double));  // [1/s^2] then [1/s], per particle
	if (row == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	double* damping_row = row + n;
	for (int32_t k = 0; k < model->spring_count; k++) {
		if (!model->enabled[k])
			continue;
		const int32_t a = model->spring_a[k], b = model->spring_b[k];
		const bool free_a = model->free_index[a] >= 0, free_b = model->free_index[b] >= 0;
		// 1/sqrt(m_a m_b) as the product of the roots' reciprocals, each within 7e-155 to 7e153 for
		// the masses a model holds: m_a m_b itself underflows below 1e-154 kg and overflows above
		// 1e154 kg, and the bound would be infinite or leave the term out.
		const double between =
		    free_a && free_b ? (1.0 / sqrt(model->mass[a])) * (1.0 / sqrt(model->mass[b])) : 0.0;
		const double ks = fabs(model->stiffness[k]), kd = fabs(model->damping[k]);
		if (free_a) {
			row[a] += row_term(ks, 1.0 / model->mass[a], between);
			damping_row[a] += row_term(kd, 1.0 / model->mass[a], between);
		}
		if (free_b) {
			row[b] += row_term(ks, 1.0 / model->mass[b], between);
			damping_row[b] += row_term(kd, 1.0 / model->mass[b], between);
		}
	}
	double omega2 = 0.0, gamma = 0.0;
	bool any_free = false;
	for (int32_t i = 0; i < n; i++) {
		if (model->free_index[i] < 0)
			continue;
		any_free = true;
		omega2 = fmax(omega2, row[i]);
		gamma = fmax(gamma, damping_row[i]);
	}
	free(row);
	limit->omega_max = sqrt(omega2);
	limit->damping_rate = any_free ? gamma + fabs(model->def.mass_damping) : 0.0;
	limit->step = sm_symplectic_euler_step(limit->omega_max, limit->damping_rate);
	return SM_OK;
}

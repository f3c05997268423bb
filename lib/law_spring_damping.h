// Force law: spring damping, a dashpot along the spring.
//
// Derivation. With u = d / L, dv = v_b - v_a and the rate of change of the length
// r = dL/dt = u . dv:
//
//   force    f_a = kd r u,   f_b = -f_a                                        [N]
//   power    f_a . v_a + f_b . v_b = -f_a . dv = -kd r^2 <= 0                  [W]
//
// A rigid motion (v_i = w + omega x x_i) has dv = omega x d, so r = u . (omega x d) = 0:
// spring damping never slows a rigid translation or rotation of the pair.
//
//   D = d f_a / d v_b = kd u (d r / d v_b) = kd u u^T                          [N s/m]
//
// The force also depends on the positions through u. With du/dx_b = P / L (law_rest_length.h)
// and dr/dx_b = dv^T du/dx_b = (P dv)^T / L (P is symmetric):
//
//   d f_a / d x_b = kd [u (dr/dx_b) + r du/dx_b] = (kd / L) [r P + u (P dv)^T]  [N/m]
//
// This term is not symmetric; the definiteness-preserving variant leaves it out.
// At L = 0 (or a degenerate rest-length spring) the geometry sets u = 0 and 1/L = 0: the
// damping force and both blocks are zero, which keeps everything finite.
#pragma once

#include "model_internal.h"

// Magnitude of the damping force along u, kd r: f_a = spring_damping_magnitude(...) u [N].
static inline double spring_damping_magnitude(double damping, double rate)
{
	return damping * rate;
}

// Adds the damping blocks: kd u u^T to D and, for the exact variant, (kd/L)[r P + u (P dv)^T]
// to K.
static inline void spring_damping_add_blocks(double damping, const spring_geometry* g,
                                             sm_jacobian_variant variant, double K[9], double D[9])
{
	const double* u = g->u;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			D[3 * i + j] += damping * u[i] * u[j];
	if (variant == SM_JACOBIAN_EXACT) {
		// P dv = dv - u (u . dv) = dv - r u.
		double pdv[3];
		for (int k = 0; k < 3; k++)
			pdv[k] = g->dv[k] - g->rate * u[k];
		const double c = damping * g->inv_length;
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				const double p = (i == j ? 1.0 : 0.0) - u[i] * u[j];
				K[3 * i + j] += c * (g->rate * p + u[i] * pdv[j]);
			}
	}
}

// Power dissipated by the dashpot, kd r^2 >= 0 [W].
static inline double spring_damping_dissipation(double damping, double rate)
{
	return damping * rate * rate;
}

// Force law: the rest-length spring (and, with l0 = 0, the zero-length spring).
//
// Derivation. With d = x_b - x_a, L = |d|, u = d / L and P = I - u u^T (the projector onto the
// plane normal to the spring):
//
//   energy   E = ks (L - l0)^2 / 2                                            [J]
//   force    f_a = -dE/dx_a = ks (L - l0) u,   f_b = -f_a                      [N]
//
// because dL/dx_b = u^T and dL/dx_a = -u^T. For the Jacobian we need du/dx_b:
//
//   du/dx_b = d(d / L)/dx_b = I / L - d u^T / L^2 = (I - u u^T) / L = P / L,
//
// so, by the product rule,
//
//   K = d f_a / d x_b = ks [u u^T + (L - l0) P / L] = ks [u u^T + (1 - l0/L) P]   [N/m]
//   d f_a / d v_b = 0.
//
// u u^T is the axial stiffness, ks (1 - l0/L) P the geometric (transverse) stiffness, which is
// negative for a compressed spring (L < l0): a compressed spring buckles sideways. The
// definiteness-preserving variant clamps the factor (1 - l0/L) at zero, which makes K
// symmetric positive semi-definite (so df/dx = -K on the diagonal blocks is negative
// semi-definite) and leaves it exact for stretched springs.
//
// Singular point: when L < SM_DEGENERATE_LENGTH_RATIO * l0 the direction u is undefined. The
// geometry then has u = 0 and inv_length = 0 (model_internal.h), so the force ks (L - l0) u is
// zero and the block is ks [0 + (1 - 0) I] = ks I, as model.h documents.
#pragma once

#include "model_internal.h"

// Magnitude of the elastic force along u, ks (L - l0): f_a = rest_length_magnitude(...) u [N].
static inline double rest_length_magnitude(double stiffness, double rest_length, double length)
{
	return stiffness * (length - rest_length);
}

// Adds the elastic block K = ks [u u^T + (1 - l0/L) P] (row-major) for the variant.
static inline void rest_length_add_block(double stiffness, double rest_length, const spring_geometry* g,
                                         sm_jacobian_variant variant, double K[9])
{
	double geometric = 1.0 - rest_length * g->inv_length;
	if (variant == SM_JACOBIAN_DEFINITE && geometric < 0.0)
		geometric = 0.0;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) {
			const double uu = g->u[i] * g->u[j];
			const double p = (i == j ? 1.0 : 0.0) - uu;
			K[3 * i + j] += stiffness * (uu + geometric * p);
		}
}

// Elastic energy ks (L - l0)^2 / 2 [J].
static inline double rest_length_energy(double stiffness, double rest_length, double length)
{
	const double e = length - rest_length;
	return 0.5 * stiffness * e * e;
}

// Force law: the ideal zero-length spring.
//
// Derivation. With d = x_b - x_a:
//
//   energy   E = ks |d|^2 / 2                                                 [J]
//   force    f_a = -dE/dx_a = ks d,   f_b = -f_a                               [N]
//   K = d f_a / d x_b = ks I                                                   [N/m]
//   d f_a / d v_b = 0 (its damping is the spring damping of law_spring_damping.h).
//
// The law is linear in the positions and defined everywhere, L = 0 included. It is exactly
// the rest-length law of law_rest_length.h with l0 = 0: ks (L - 0) u = ks d, and
// ks [u u^T + (1 - 0/L) P] = ks (u u^T + I - u u^T) = ks I, including at L = 0 where the
// geometry sets u = 0 and the block is again ks I. The model therefore stores l0 = 0 for
// zero-length springs and evaluates both kinds with the same branch-free code; the functions
// below state the law on its own, and test_forces (test_zero_length_spring_is_linear) checks
// that both forms agree.
#pragma once

#include "model_internal.h"

// Force on a: f_a = ks d [N].
static inline void zero_length_force(double stiffness, const double d[3], double f_a[3])
{
	for (int k = 0; k < 3; k++)
		f_a[k] = stiffness * d[k];
}

// Adds K = ks I.
static inline void zero_length_add_block(double stiffness, double K[9])
{
	K[0] += stiffness;
	K[4] += stiffness;
	K[8] += stiffness;
}

// Elastic energy ks L^2 / 2 [J].
static inline double zero_length_energy(double stiffness, double length)
{
	return 0.5 * stiffness * length * length;
}

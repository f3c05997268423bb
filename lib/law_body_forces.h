// Force laws on single particles: gravity, loads and mass-proportional damping.
//
// Derivation. For a particle of mass m, velocity v and position x:
//
//   gravity        f = m g,         energy -m g . x (zero at the origin),  df/dx = 0
//   load           f = F,           energy -F . x (zero at the origin),    df/dx = 0
//   mass damping   f = -alpha m v,  power  -alpha m |v|^2 <= 0,            df/dv = -alpha m I
//
// Mass damping acts on the absolute velocity, so unlike spring damping it also slows down a
// rigid motion of the whole structure, like drag in a still medium. Both act on every
// particle, constrained ones included (for those the force is reported, not applied).
#pragma once

#include "model_internal.h"

// Gravity plus mass damping on one particle: f = m (g - alpha v) [N].
static inline void body_force(double mass, const double gravity[3], double mass_damping, const double v[3],
                              double f[3])
{
	for (int k = 0; k < 3; k++)
		f[k] = mass * (gravity[k] - mass_damping * v[k]);
}

// Potential energy of the constant forces on one particle, gravity and its load F:
// -(m g + F) . x [J], zero at the origin.
static inline double constant_force_potential(double mass, const double gravity[3], const double load[3],
                                              const double x[3])
{
	return -(mass * (gravity[0] * x[0] + gravity[1] * x[1] + gravity[2] * x[2]) +
	         (load[0] * x[0] + load[1] * x[1] + load[2] * x[2]));
}

// Power dissipated by mass damping on one particle, alpha m |v|^2 >= 0 [W].
static inline double mass_damping_dissipation(double mass, double mass_damping, const double v[3])
{
	return mass_damping * mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

// Diagonal of d f / d v from mass damping, -alpha m [N s/m].
static inline double mass_damping_derivative(double mass, double mass_damping)
{
	return -mass_damping * mass;
}

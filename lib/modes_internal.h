// Modes: what the dense path (modes.c) and the sparse path (modes_lanczos.c) share.
#pragma once

#include "springmass/analysis.h"

#include <gsl/gsl_eigen.h>
#include <stddef.h>
#include <stdint.h>

// The fraction of the largest |omega^2| within which two omega^2 count as one repeated frequency
// (the eigensolvers' round-off is about 1e-15 of it) [1]: modes.c groups the modes by it, and the
// sparse path keeps a later run's mode that lies this far below the highest kept one.
#define SM_MODES_REPEATED_TOLERANCE 1e-12

// What both eigensolvers share: the configuration, the free map and the results' shape.
typedef struct modes_problem {
	const sm_model* model;
	const sm_modes_def* def;
	const double* x0;           // 3 n
	const int32_t* free_index;  // n
	const double* dof_mass;     // dof
	int32_t particle_count;
	size_t dof;
	size_t kept;
	double stiffness_norm;      // ||K||: its bound by sm_block_row_bound [N/m]
	double next_omega_squared;  // of the lowest mode not kept; NAN if unknown [1/s^2]
} modes_problem;

// Helpers of modes.c that the sparse path uses too.

// GSL's workspace for the symmetric eigenproblem of size n, allocated so that running out of
// memory returns NULL (GSL's own allocator would abort the process); destroyed by
// sm_modes_symmv_workspace_destroy, which accepts NULL.
gsl_eigen_symmv_workspace* sm_modes_symmv_workspace_create(size_t n);
void sm_modes_symmv_workspace_destroy(gsl_eigen_symmv_workspace* w);
// Writes the free-dof vector y (entry r at y[r * stride], scaled by scale[r], or 1 if scale is
// NULL) as a shape over all particles (constrained particles untouched, 0 in a zeroed shape).
void sm_modes_scatter_shape(const modes_problem* p, const double* y, size_t stride, const double* scale,
                            double* shape);
// The error for an omega^2 beyond the doubles: row r of M^(-1/2) K M^(-1/2) overflowed.
sm_status sm_modes_overflow_error(const modes_problem* p, size_t r, sm_error* err);
// ||r|| / (norm ||phi||) over n entries, the residual r of a mode phi relative to the bound norm
// on ||K||, without overflow or underflow; 0 if norm or phi is 0.
double sm_modes_relative_residual(const double* r, const double* phi, size_t n, double norm);
// Sets eigenvalues within zero_level of 0 to exactly 0 and counts the zero and unstable ones.
void sm_modes_classify(double* omega_squared, size_t count, double zero_level, sm_modes* modes);

#ifdef SPRINGMASS_HAVE_CHOLMOD
// The sparse path (modes_lanczos.c): the lowest p->kept modes by shift-invert Lanczos, their
// omega^2 [1/s^2] and mass-normalised shapes into modes (with the zero and unstable counts,
// omega_max and the shift), p->stiffness_norm and p->next_omega_squared set.
sm_status sm_modes_sparse(modes_problem* p, sm_modes* modes, sm_error* err);
#endif

// The sparse path's re-orthogonalisation (modes_lanczos.c, built with CHOLMOD): M-orthogonalises
// v (dof entries; M = diag(mass)) against the `locked_count` locked vectors and the `count` basis
// vectors (stride dof; each set M-orthonormal, the two M-orthogonal to round-off) by classical
// Gram-Schmidt twice (CGS2: each pass takes every coefficient q_i^T M v from the same v, then
// subtracts them all), both sets in every pass, so that v leaves orthogonal to both to round-off.
// Adds the basis coefficients of both passes to coefficients[] (count entries) if not NULL.
// scratch: dof + locked_count + count doubles.
void sm_modes_orthogonalise(const double* mass, size_t dof, double* v, const double* locked,
                            size_t locked_count, const double* basis, size_t count, double* coefficients,
                            double* scratch);

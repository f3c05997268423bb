// Helpers shared by the static equilibrium (statics.c) and the modal analysis (modes.c,
// modes_lanczos.c), defined in analysis_shared.c.
#pragma once

#include "springmass/analysis.h"

#include <stddef.h>
#include <stdint.h>

// Dense symmetric stiffness K = -df/dx at (x, zero velocity) over the free degrees of freedom,
// row-major dof x dof, assembled from the per-spring blocks of the given variant (constrained
// particles dropped). free_index[p] is the free index of particle p or -1. Adds nothing for disabled
// springs (their blocks are zero).
void sm_analysis_dense_stiffness(const sm_model* model, const int32_t* free_index, const double* x,
                                 size_t dof, sm_jacobian_variant variant, double* K);

// Free index of every particle (-1 for constrained ones) and the mass of every free degree of
// freedom; returns the number of free particles. free_index has particle_count entries,
// dof_mass 3 * free count (may be NULL).
int32_t sm_analysis_free_map(const sm_model* model, int32_t* free_index, double* dof_mass);

// The first intact rest-length spring (l0 > 0, ks > 0) with a free end whose two particles coincide
// at x (its degenerate point, L < SM_DEGENERATE_LENGTH_RATIO l0), or -1 if there is none. Its energy
// ks (L - l0)^2 / 2 is a maximum there, falling as the particles part in any direction with a force
// of about ks l0 that has no derivative at the point: the model.h convention (no force, K = ks I)
// makes it a force balance, never a stable one, and it has no linearisation. One without stiffness
// has no force and no energy anywhere (its damping is sm_analysis_coincident_damper's).
int32_t sm_analysis_coincident_spring(const sm_model* model, const double* x);

// The first intact spring with damping and a free end whose two particles coincide at x (a spring of rest
// length 0, or a rest-length spring at its degenerate point), or -1. Its damping force
// kd (u . dv) u has no derivative there: a motion straight through the point is damped by
// kd dv in full, while the model.h convention (no damping at L = 0, df/dv = 0) has none, so the
// configuration has no linearisation of its damping.
int32_t sm_analysis_coincident_damper(const sm_model* model, const double* x);

// The first intact rest-length or damped spring with a free end whose length at x is not a double (its square
// overflows: particles about 1e154 m apart or more), or -1. Its direction u = d / L comes out 0
// there, so its Jacobian blocks (the u u^T parts) are not those of the configuration.
int32_t sm_analysis_overflowing_spring(const sm_model* model, const double* x);

// One block row p of a symmetric matrix A of 3x3 blocks over the free degrees of freedom: the
// entry (i, j) of its k-th block at values[i * stride + 3 k + j], as both the sparse Jacobian
// (CSR: stride 3 blocks) and a dense row-major matrix (stride dof) hold it.
typedef struct sm_block_row {
	const double* values;  // entry (0, 0) of the row's first block
	size_t stride;         // from one scalar row of the blocks to the next
	size_t blocks;         // blocks in the row
	size_t diagonal;       // which of them is A_pp
	// The column of entry (0, j) at columns[j] (CSR), or NULL: block k is column block k.
	const int64_t* columns;
} sm_block_row;

// An upper bound that block row p gives on |lambda| over the eigenvalues lambda of
// M^(-1/2) A M^(-1/2), dof_mass the mass of every degree of freedom [kg], or of A itself if
// dof_mass is NULL: with A_pp's symmetric part and the magnitudes of the other blocks (|S| + |w| I
// for an off-diagonal block S + W, W x = w x x) added in T_p and subtracted in L_p,
// max(lambda_max(T_p), -lambda_min(L_p)), the derivation in block_bound.c. The largest over the
// block rows bounds |lambda| and so the spectral norm; it does not change when the model is
// turned, and it is attained by the highest mode of a uniform chain or square lattice of springs
// at rest (in the limit of many particles). INFINITY where an entry or the bound is not finite.
double sm_block_row_bound(const sm_block_row* row, const double* dof_mass);

// True if all count values are finite.
int sm_analysis_all_finite(const double* values, size_t count);

#ifdef SPRINGMASS_HAVE_CHOLMOD
#include <cholmod.h>

// A CHOLMOD view (no copy) of the symmetric dof x dof matrix with the pattern of a sparse
// Jacobian and the given values: the CSR arrays of a symmetric pattern are also its CSC arrays,
// and stype = 1 reads one half.
cholmod_sparse sm_analysis_cholmod_view(const sm_sparse_jacobian* pattern, size_t dof, double* values);

// Factors A, the symbolic analysis done once into *factor: 1 if A is positive definite, 0 if not,
// -1 on failure.
int sm_analysis_cholmod_factor(cholmod_sparse* A, cholmod_factor** factor, cholmod_common* common);

// out = A^-1 rhs with the factor of A (dof entries each). Returns 0, or -1 on failure.
int sm_analysis_cholmod_solve(cholmod_factor* factor, cholmod_common* common, size_t dof, const double* rhs,
                              double* out);
#endif

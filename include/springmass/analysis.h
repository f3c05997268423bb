// springmass: static equilibrium and natural frequencies (GSL, and CHOLMOD for large models).
//
// Both analyses look at the model at rest (zero velocity): velocities and damping play no part
// in the equilibrium, and the modes are those of the undamped system, with modal damping
// ratios computed afterwards from the damping matrix. Fixed and driven particles are held at
// their positions; only the free particles' degrees of freedom are unknowns. See
// docs/analysis.md for the methods and their limits.
//
// GSL's error handler. The functions below check their inputs and read GSL's return codes, so a
// failure inside GSL (out of memory, a factorisation of a reduced matrix that round-off made
// indefinite) comes back as an sm_status with a message. GSL's default handler, however, aborts
// the program before the code is returned, and the handler is GSL's process-wide setting, which
// the library leaves to the program: call gsl_set_error_handler_off() once at start-up (as the
// `springmass` tool does) to get the status instead of the abort.
//
// BLAS threads. CHOLMOD factorises large sparse matrices supernodally, with BLAS, whose sums
// may be split differently for another number of BLAS threads (another process-wide setting,
// e.g. OPENBLAS_NUM_THREADS): the sparse paths give the same bits run after run and in
// concurrent threads for a given BLAS thread count, and may differ in the last bits between
// counts (measured on a 40 x 40 hanging cloth, statics and modes, 1 and 2 threads). CHOLMOD
// would run its supernodal factorisation's loops in an OpenMP team of 4 threads; springmass keeps
// them to the calling thread (see "Threads" in simulation.h).
#pragma once

#include "springmass/model.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---------------------------------------------------------------------------------------------
// Static equilibrium: the free particles' positions x where the force balance
// f(x) = springs + gravity + loads + external forces = 0 holds, found by Newton's method on f with
// the exact Jacobian and a line search on the total potential energy
//   U(x) = elastic energy - sum (m g + load) . x - sum f_ext . x   [J].
// ---------------------------------------------------------------------------------------------

/// Linear algebra used by the Newton iteration.
typedef enum sm_statics_solver {
	SM_STATICS_AUTO = 0,  ///< dense up to SM_STATICS_DENSE_LIMIT degrees of freedom, sparse above
	SM_STATICS_DENSE,     ///< dense modified Cholesky (GSL); cost grows with the cube of the size
	SM_STATICS_SPARSE,    ///< sparse Cholesky (CHOLMOD) of the sparse Jacobian
} sm_statics_solver;

/// Degrees of freedom (3 per free particle) up to which SM_STATICS_AUTO solves densely.
#define SM_STATICS_DENSE_LIMIT 300

/// Factor of the round-off floor of the residual tolerance [1].
#define SM_STATICS_ROUNDOFF_FACTOR 8.0

/// The default residual tolerance [N], for loads of 1e-3 N and more (SM_STATICS_LOAD_FRACTION).
#define SM_STATICS_DEFAULT_TOLERANCE 1e-9

/// The default residual tolerance at a free particle is never above this fraction of its own
/// constant force (weight, load and external force) [1]: the loads of a micromechanical model, and
/// of a light part beside heavy ones, far below 1e-9 N, are balanced to this fraction of themselves.
#define SM_STATICS_LOAD_FRACTION 1e-6

/// Options of sm_statics_solve(); get them from sm_default_statics_def().
typedef struct sm_statics_def {
	/// Starting positions of all particles, 3 per particle [m]; NULL (default) = the model's
	/// initial positions. Fixed and driven particles are held where this puts them.
	const double* start;
	/// Constant external forces, 3 per particle [N]; NULL (default) = none. Entries of
	/// constrained particles add to the force their supports must take.
	const double* external_forces;
	/// Convergence, particle by particle: every free particle's largest force component must be
	/// at most its own tolerance [N]. Given (> 0), the same at every free particle, and below the
	/// largest constant force on a free particle (a tolerance at or above it is refused: any shape
	/// would pass). Default 0: at each free particle SM_STATICS_DEFAULT_TOLERANCE (1e-9 N), or
	/// SM_STATICS_LOAD_FRACTION times its own constant force (weight, load, external force) where
	/// that is smaller (a particle with none: the largest among the free particles joined to it by
	/// springs, or the largest of all). A particle's tolerance is never below its round-off floor,
	/// SM_STATICS_ROUNDOFF_FACTOR machine epsilons times the sum, over its springs, of
	/// ks max(L, l0, |x_a| + |x_b|), plus its constant force (docs/analysis.md).
	double residual_tolerance;
	/// Newton iterations allowed in all, >= 1; default 500. From 100 on, the stiffness
	/// continuation takes over after 50 (docs/analysis.md); below, Newton alone takes them all.
	int32_t max_iterations;
	sm_statics_solver solver;  ///< default SM_STATICS_AUTO
	/// Called after every Newton iteration with the iterations taken so far, the largest force
	/// component on a free particle at the new positions [N] (during the stiffness continuation,
	/// that of the softened model the stage solves) and `on_iteration_context` (default NULL: not
	/// called), e.g. to show progress during a long solve or to bound its wall time. The
	/// iterations and results are the same with or without it. Returning false stops the solve
	/// with SM_ERROR_NOT_CONVERGED (x and reactions not touched). It must not modify the model.
	bool (*on_iteration)(void* context, int32_t iterations, double residual);
	void* on_iteration_context;
} sm_statics_def;

/// What sm_statics_solve() found. Filled on success and, as far as it got, on failure.
typedef struct sm_statics_result {
	int32_t iterations;  ///< Newton iterations taken
	double residual;     ///< largest force component on a free particle at the end [N]
	/// The largest of the free particles' tolerances (the loosest; see residual_tolerance) [N]:
	/// the tolerance of every particle when all take the same. residual <= tolerance on success;
	/// critical_particle below tells whether each particle is within its own.
	double tolerance;
	double potential_energy;   ///< U at the end, as defined above [J]
	double reaction_total[3];  ///< sum of the reactions at the constrained particles [N]
	/// True if the exact stiffness -df/dx over the free degrees of freedom is positive definite
	/// at the equilibrium beyond round-off (a local minimum of U, not a saddle or a mechanism: its
	/// smallest eigenvalue exceeds k eps times its largest row sum, k the longest inner product of
	/// its Cholesky factorisation: dof on the dense path, the longest row of the factor on the
	/// sparse one, plus the stiffness the round-off of the positions, relative to the origin, can
	/// give it through the springs' tensions: docs/analysis.md). False for a group of particles
	/// held by no constrained particle (gravity 0:
	/// at rest anywhere, never stable).
	/// False also where the two particles of a rest-length spring of rest length > 0 and stiffness
	/// > 0 coincide: a force balance by convention there (model.h), but a maximum of that spring's
	/// energy.
	bool stable;
	/// The first such spring, whose two particles coincide at the rest shape, or -1.
	int32_t coincident_spring;
	sm_statics_solver solver;  ///< the linear algebra actually used (AUTO resolved)
	/// The free particle whose largest force component is the largest fraction of its own
	/// tolerance (see residual_tolerance): the one that decides convergence, which holds when
	/// critical_residual <= critical_tolerance. -1 without free particles, and when the solve
	/// stopped before judging any balance (an invalid argument, a free body under a net force).
	int32_t critical_particle;
	double critical_residual;   ///< its largest force component at the end [N]
	double critical_tolerance;  ///< its tolerance [N]
} sm_statics_result;

/// The default options (the values documented in sm_statics_def).
SM_API sm_statics_def sm_default_statics_def(void);

/// Finds the static equilibrium of the model (def NULL means the defaults). On success writes the positions
/// of all particles to x (3 per particle [m]; constrained particles stay at their start) and, if `reactions`
/// is not NULL, the reaction force on every particle (3 per particle [N]): for a constrained particle the
/// force its support exerts on it, minus the force the model exerts there; zero for free particles. The
/// reactions and the model's forces then balance exactly.
///
/// Errors (x and reactions are not touched, err says which element and rule):
/// - SM_ERROR_INVALID_ARGUMENT: NULL model or x, bad options;
/// - SM_ERROR_NOT_FINITE: non-finite start positions or external forces, forces that overflow
///   along the way, or spring forces whose round-off scale (stiffness x distance) does;
/// - SM_ERROR_NOT_CONVERGED: no equilibrium exists (a group of free particles not held by any
///   constrained particle, with a non-zero net force on it, such as a free body under gravity),
///   the iteration limit was reached, on_iteration returned false, or the round-off floor of the loosest
///   tolerance exceeds the largest constant force on a free particle where the iteration ended (no computed
///   balance resolves the loads there); the message names the particles or gives the residual (and the
///   particle above its own tolerance, when the largest force is within the loosest) or the floor;
/// - SM_ERROR_SOLVER: the sparse factorisation failed;
/// - SM_ERROR_OUT_OF_MEMORY.
SM_API sm_status sm_statics_solve(const sm_model* model, const sm_statics_def* def, double* x,
                                  double* reactions, sm_statics_result* result, sm_error* err);

// ---------------------------------------------------------------------------------------------
// Natural frequencies and mode shapes: the model linearised about a configuration x0 at zero
// velocity, M u'' + C u' + K u = 0 over the free degrees of freedom, with K = -df/dx (exact,
// symmetric at zero velocity) [N/m], C = -df/dv [N s/m] and M the lumped masses [kg].
// The undamped problem K phi = omega^2 M phi is solved either densely (GSL, after mass scaling:
// all modes, cost growing with the cube of the degrees of freedom, a few thousand at most) or,
// for the lowest mode_count modes of a large model, by shift-invert Lanczos on the sparse
// matrices (one CHOLMOD factorisation of K - sigma M, sigma < 0, then about two hundred
// sparse solves: seconds for a cloth of 16 000 particles). See docs/analysis.md.
// ---------------------------------------------------------------------------------------------

/// Eigensolver of sm_modes_compute().
typedef enum sm_modes_solver {
	/// dense up to SM_MODES_DENSE_LIMIT degrees of freedom or when all modes (mode_count = 0) or
	/// too many of them are asked for; sparse otherwise (if the build has CHOLMOD)
	SM_MODES_AUTO = 0,
	SM_MODES_DENSE,  ///< all eigenpairs, dense (GSL); O(dof^3) time, 2 dof^2 doubles of memory
	/// lowest mode_count eigenpairs by shift-invert Lanczos (CHOLMOD); needs
	/// 1 <= mode_count <= (dof - SM_MODES_SPARSE_MARGIN) / 4 (or no free particle: no modes)
	SM_MODES_SPARSE,
} sm_modes_solver;

/// Degrees of freedom (3 per free particle) up to which SM_MODES_AUTO solves densely.
#define SM_MODES_DENSE_LIMIT 300

/// Degrees of freedom the sparse path needs beyond 4 per mode (Krylov space and its margin).
#define SM_MODES_SPARSE_MARGIN 40

/// Options of sm_modes_compute(); get them from sm_default_modes_def().
typedef struct sm_modes_def {
	/// Configuration to linearise about, 3 per particle [m]; NULL (default) = the model's
	/// initial positions (pass a static equilibrium from sm_statics_solve() to get the
	/// vibrations about the rest shape).
	const double* configuration;
	/// Number of modes kept, lowest first; 0 (default) = all.
	int32_t mode_count;
	/// An eigenvalue omega^2 with |omega^2| <= zero_tolerance * max |omega^2| is a rigid-body
	/// mode and is set to exactly 0 [1]; default 1e-12. Round-off leaves rigid-body modes at
	/// about 1e-15 of the largest; physical modes can be far below 1e-9 of it (a hanging rope of N
	/// segments swings at about 3.5e-9 of its axial omega^2 for N = 500, 9e-10 for N = 1000:
	/// as N^-2).
	double zero_tolerance;
	/// Damping counts as proportional if every off-diagonal entry of Phi^T C Phi, divided by
	/// the geometric mean of its two diagonal entries, is below this [1]; default 1e-6.
	double proportional_tolerance;
	sm_modes_solver solver;  ///< default SM_MODES_AUTO
	/// Sparse path: every kept mode must satisfy ||K phi - omega^2 M phi|| <= residual_tolerance
	/// ||K|| ||phi|| (2-norms over the free degrees of freedom, ||K|| bounded from above as
	/// omega_max^2 is, over whole 3x3 blocks, without the masses) or the call fails with
	/// SM_ERROR_NOT_CONVERGED [1]; default 1e-9. The dense path reports the same residual without
	/// a test (it is at round-off, about 1e-14).
	double residual_tolerance;
	/// Sparse path: called after every cycle of the Lanczos iteration (a full Krylov space, whose
	/// Ritz pairs are then tested and kept for a thick restart) with the Lanczos steps taken so
	/// far (one sparse solve each), how many of the modes sought the current Lanczos run has
	/// converged (a later run, which looks for further modes of a repeated frequency, starts again
	/// from 0), the modes sought (those kept and, where the Krylov space has room, the next one),
	/// and `on_iteration_context` (default NULL: not called), e.g. to show progress or to bound
	/// the wall time of a large model. The modes are the same with or without it. Returning
	/// false stops the computation with SM_ERROR_NOT_CONVERGED (*modes zeroed). The dense path,
	/// one call of GSL's eigensolver, does not call it. It must not modify the model.
	bool (*on_iteration)(void* context, int64_t steps, int32_t converged, int32_t sought);
	void* on_iteration_context;
} sm_modes_def;

/// Modes found by sm_modes_compute(); the arrays are owned by it until sm_modes_release().
typedef struct sm_modes {
	int32_t dof;             ///< degrees of freedom: 3 * free particles
	int32_t particle_count;  ///< particles of the model (length of a shape / 3)
	int32_t count;           ///< modes kept (lowest first)
	double* omega_squared;   ///< count eigenvalues omega^2, ascending; < 0 = unstable [1/s^2]
	double* frequency;       ///< natural frequencies omega / (2 pi), 0 for rigid or unstable modes [Hz]
	/// phi^T C phi = 2 zeta omega for mass-normalised phi [1/s]. The modes of a repeated
	/// frequency are the basis of its eigenspace that makes their damping block diagonal, with
	/// these values ascending (docs/analysis.md).
	double* modal_damping;
	/// zeta = phi^T C phi / (2 omega) [1]; INFINITY for a damped zero-frequency mode, 0 for an
	/// undamped one, NAN for an unstable one (omega^2 < 0), which has none.
	double* damping_ratio;
	/// count shapes, each 3 per particle (constrained particles 0), mass-normalised:
	/// phi^T M phi = 1 [1/sqrt(kg)]. Shape i starts at shapes + i * 3 * particle_count.
	double* shapes;
	/// Rigid-body (zero-frequency) modes: among all dof modes (dense), among the kept ones
	/// (sparse: a count below the true one if mode_count cut them off).
	int32_t zero_count;
	/// Modes with omega^2 < 0 beyond the tolerance (not at a stable rest): among all modes
	/// (dense), among the kept ones (sparse; the unstable modes are the lowest, so they are all
	/// counted whenever mode_count exceeds their number).
	int32_t unstable_count;
	/// Highest angular frequency over all modes [rad/s]: exact (dense) or an upper bound, the
	/// square root of a Gershgorin bound on M^(-1/2) K M^(-1/2) over whole 3x3 blocks (sparse;
	/// the same however the model is turned, and exact for a uniform chain or square lattice of
	/// springs at rest in the limit of many particles: docs/analysis.md).
	double omega_max;
	/// Upper bound on every mode's damping rate phi^T C phi (2 zeta omega) [1/s]: the Gershgorin
	/// bound of sm_model_explicit_limit.
	double damping_rate_max;
	/// Largest stable step of symplectic Euler [s] (sm_explicit_limit): with every mode kept
	/// (dense path), the smallest of the modes' own limits (each omega with its modal_damping),
	/// otherwise the one of omega_max with damping_rate_max; exact or safe for proportional
	/// damping, an estimate otherwise; INFINITY when nothing limits it.
	double explicit_step;
	/// Largest normalised off-diagonal entry of Phi^T C Phi over the kept modes, |c_ij| /
	/// sqrt(c_ii c_jj); modes alike in frequency and damping count as one block, whose entries are
	/// taken together (docs/analysis.md) [1].
	double damping_coupling;
	bool proportional;       ///< damping_coupling <= proportional_tolerance
	sm_modes_solver solver;  ///< the eigensolver actually used (AUTO resolved)
	/// Largest ||K phi - omega^2 M phi|| / (||K|| ||phi||) over the kept modes, ||K|| bounded
	/// from above as omega_max^2 is on the sparse path, without the masses [1].
	double residual;
	/// Sparse path: the shift sigma < 0 of the factorisation K - sigma M that gave the modes,
	/// -1e-6 of the Gershgorin bound G or, when the wanted modes lie far below that, nearer to
	/// them; in an unstable configuration lowered a hundredfold at a time, at the latest to -2 G
	/// (docs/analysis.md); 0 on the dense path [1/s^2].
	double shift;
	/// omega^2 of the lowest mode beyond the kept ones [1/s^2]; NAN when every mode is kept, or on
	/// the sparse path when one more mode than mode_count would not fit (see mode_count's limit).
	double next_omega_squared;
	/// mode_count ended inside a group of repeated frequencies: next_omega_squared is the
	/// highest kept mode's (within the tolerance of docs/analysis.md). The group's kept modes are
	/// then an arbitrary part of its eigenspace; ask for more modes to get all of it.
	bool group_cut;
} sm_modes;

/// The default options (the values documented in sm_modes_def).
SM_API sm_modes_def sm_default_modes_def(void);

/// Computes the natural frequencies, damping ratios and mode shapes (def NULL means the
/// defaults). On success fills *modes,
/// which the caller releases with sm_modes_release(). On error *modes is zeroed and err says
/// why (SM_ERROR_INVALID_ARGUMENT, also for a configuration in which a rest-length spring's two
/// particles coincide, or those of a damped spring of rest length 0 (one of them free): its force,
/// or its damping force, has no derivative there; SM_ERROR_NOT_FINITE for a non-finite configuration or
/// stiffness, a configuration in which a rest-length or damped spring (one of its particles free) is
/// too long for its squared length to be a double (about 1e154 m), or an omega^2 beyond the range of a
/// double; SM_ERROR_OUT_OF_MEMORY;
/// SM_ERROR_SOLVER; and on the sparse path SM_ERROR_NOT_CONVERGED when the residual test fails
/// or on_iteration returned false).
/// A model with no free particle has no modes: success with count = 0, under every solver
/// and mode_count (the sparse solver's limits apply only when there is something to solve).
/// Deterministic: the same
/// model and options give the same numbers (the Lanczos start vectors are fixed; on the sparse
/// path, for a given BLAS thread count: see "BLAS threads" above).
SM_API sm_status sm_modes_compute(const sm_model* model, const sm_modes_def* def, sm_modes* modes,
                                  sm_error* err);

/// Frees the arrays of a result of sm_modes_compute() and zeroes it; accepts NULL and a zeroed
/// result.
SM_API void sm_modes_release(sm_modes* modes);

/// The stability limit of explicit integration, bounded at any positions. Symplectic Euler
/// (v += h a(x, v), then x += h v) applied to a mode of angular frequency omega and damping rate
/// gamma (m x'' + c x' + k x = 0: omega^2 = k/m, gamma = c/m) maps (x, v) by a matrix of
/// determinant 1 - h gamma and trace 2 - h gamma - h^2 omega^2, whose eigenvalues stay in the unit
/// circle while h <= 2 / (gamma/2 + sqrt(gamma^2/4 + omega^2)): 2/omega undamped, 2/gamma for
/// damping alone, and from 1.66/gamma (critical damping, zeta = gamma / (2 omega) = 1) up to
/// nearly 2/gamma for overdamped modes (zeta > 1; 1.89/gamma at zeta = 2). The bound
/// takes the largest omega^2 and gamma of any mode at once, from Gershgorin row sums: a spring's
/// stiffness and damping blocks are at most ks I and kd I at any positions (ks u u^T +
/// ks (1 - l0/L) (I - u u^T) with 1 - l0/L < 1; kd u u^T), so over the free particles
/// omega_max^2 <= max_i sum ks (1/m_i + 1/sqrt(m_i m_j)) and gamma <= alpha + max_i sum kd (1/m_i +
/// 1/sqrt(m_i m_j)) (the second terms where j is free too). With proportional damping each mode's
/// step limit is then at least `step`; with other damping it is an estimate.
typedef struct sm_explicit_limit {
	double omega_max;     ///< upper bound on the highest angular frequency [rad/s]
	double damping_rate;  ///< upper bound on the damping rate of any mode [1/s]
	double step;          ///< the largest stable step of symplectic Euler they give [s]; INFINITY for none
} sm_explicit_limit;

/// The bounds of sm_explicit_limit for a model (disabled springs left out);
/// SM_ERROR_INVALID_ARGUMENT for NULL arguments, SM_ERROR_OUT_OF_MEMORY.
SM_API sm_status sm_model_explicit_limit(const sm_model* model, sm_explicit_limit* limit);

/// The largest stable step [s] of symplectic Euler for angular frequency omega [rad/s] and damping
/// rate gamma [1/s] (sm_explicit_limit); INFINITY when both are 0, 0 for a negative gamma (no step
/// is stable) or an infinite one, NaN if either is NaN.
SM_API double sm_symplectic_euler_step(double omega, double gamma);

#ifdef __cplusplus
}
#endif

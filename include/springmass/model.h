// springmass: the model in memory (particles, springs, global forces) and its evaluation:
// forces, energies, dissipated power and analytic Jacobians.
//
// Conventions used by every function here:
// - Particles are numbered 0..n-1 in the order they were added; springs likewise.
// - Arrays of per-particle vectors are particle-major: x[3*i + 0..2] is particle i's x, y, z.
// - "Free" particles move under the forces; "fixed" ones stay where they are; "driven" ones
//   follow a motion the caller prescribes (the simulation and the FMU's motion ports use them).
//   Fixed and driven particles are "constrained": the forces reported for them are the forces
//   the model exerts on them, which whatever holds them must balance (their reaction is minus
//   that force).
#pragma once

#include "springmass/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// How a particle moves.
typedef enum sm_particle_motion {
	SM_PARTICLE_FREE = 0,  ///< moves under the forces
	SM_PARTICLE_FIXED,     ///< stays at its position, velocity zero
	/// Position and velocity prescribed by the caller over time (sm_simulation_set_driven); until
	/// then it moves from its initial position at its initial velocity, x0 + v0 t.
	SM_PARTICLE_DRIVEN,
} sm_particle_motion;

/// Masses must be at least this, DBL_MIN = 2^-1022 = 2.2250738585072014e-308 [kg]: below it,
/// 1 / mass, which the accelerations need, overflows.
#define SM_MIN_MASS 2.2250738585072014e-308

/// Definition of a particle; get one from sm_default_particle_def().
typedef struct sm_particle_def {
	double mass;         ///< mass, finite and >= SM_MIN_MASS [kg]; default 1
	double position[3];  ///< initial position [m]; default (0, 0, 0)
	double velocity[3];  ///< initial velocity [m/s]; default (0, 0, 0); must be finite; a fixed particle's is
	                     ///< zero whatever is given
	sm_particle_motion motion;  ///< default SM_PARTICLE_FREE
	/// Load: a constant external force on the particle [N], in every evaluation of the forces as
	/// gravity is (on a held particle it goes to the reaction); its potential -load . x is part of
	/// the gravitational energy. Must be finite; default (0, 0, 0).
	double load[3];
} sm_particle_def;

/// Force law of a spring.
typedef enum sm_spring_kind {
	/// f_a = ks (L - l0) u with L = |x_b - x_a|, u = (x_b - x_a) / L.
	SM_SPRING_REST_LENGTH = 0,
	/// f_a = ks (x_b - x_a): an ideal spring of zero rest length, linear in the positions.
	SM_SPRING_ZERO_LENGTH,
} sm_spring_kind;

/// How a spring constant is given.
typedef enum sm_scaling {
	/// The constant is the spring's own: stiffness ks [N/m], damping kd [N s/m].
	SM_ABSOLUTE = 0,
	/// The constant is per unit strain: stiffness E [N] with ks = E / l0, damping c [N s] with
	/// kd = c / l0. A structure discretised more finely, with shorter springs in series, then
	/// keeps the same overall stiffness (a rope). Requires l0 > 0.
	SM_PER_STRAIN,
	/// The constant is per unit strain and per unit of the cross-section the spring stands for:
	/// ks = stiffness section / l0, kd = damping section / l0, with the spring's `section` a
	/// width [m] in a sheet or a mesh (stiffness [N/m], damping [N s/m]) or an area [m^2] in a
	/// block (stiffness [N/m^2], damping [N s/m^2]). Springs side by side then share a sheet's or
	/// a block's stiffness, which a finer grid keeps: with per-strain constants alone a sheet of
	/// twice the rows is twice as stiff. The sheet, block and mesh builders give each spring its
	/// section (structures.h). Requires l0 > 0 and section > 0.
	SM_PER_SECTION,
} sm_scaling;

/// Rest length meaning "the distance between the two particles when the spring is added".
#define SM_REST_LENGTH_INITIAL (-1.0)

/// Break strains must exceed this, 2^-53 = 1.1102230246251565e-16 [1]: at or below it,
/// l0 (1 + break_strain) rounds to l0, and a spring at rest (strain 0) would count as at its limit
/// and break at once.
#define SM_MIN_BREAK_STRAIN 1.1102230246251565e-16

/// Definition of a spring between particles a and b; get one from sm_default_spring_def().
///
/// Spring damping acts along the spring: f_a = kd (u . (v_b - v_a)) u, f_b = -f_a. It only
/// resists the rate of change of the spring's length, so it never slows down a rigid motion
/// (translation or rotation) of the particles. Compare the model's mass damping.
typedef struct sm_spring_def {
	int32_t a;            ///< first particle index
	int32_t b;            ///< second particle index, != a
	sm_spring_kind kind;  ///< default SM_SPRING_REST_LENGTH
	double rest_length;   ///< l0 >= 0 [m], or SM_REST_LENGTH_INITIAL (default); zero-length springs use 0
	double stiffness;     ///< >= 0: ks [N/m] or, per strain, E [N]; default 0
	sm_scaling stiffness_scaling;  ///< default SM_ABSOLUTE
	double damping;                ///< >= 0: kd [N s/m] or, per strain, c [N s]; default 0
	sm_scaling damping_scaling;    ///< default SM_ABSOLUTE
	/// The cross-section the spring stands for [m or m^2], > 0, for SM_PER_SECTION constants
	/// (ignored otherwise); default 1.
	double section;
	/// Strain (L - l0) / l0 [1] at which the spring breaks (the simulation detects the crossing
	/// as an event, also one within a single solver step, or breaks it at once if it is already at
	/// or beyond when an advance begins); its elastic energy then counts as dissipated.
	/// > SM_MIN_BREAK_STRAIN (2^-53 = 1.1102230246251565e-16), or INFINITY (default) for a spring
	/// that never breaks. Requires l0 > 0.
	double break_strain;
} sm_spring_def;

/// Global settings of a model; get one from sm_default_model_def().
///
/// Mass-proportional damping f = -alpha m v acts on each particle's absolute velocity: unlike
/// spring damping it also slows down rigid motion of the whole structure (like air drag).
typedef struct sm_model_def {
	double gravity[3];          ///< gravitational acceleration [m/s^2]; default (0, 0, -9.81)
	double mass_damping;        ///< alpha >= 0 [1/s]; default 0
	int32_t particle_capacity;  ///< expected particle count, a hint for allocation; default 0
	int32_t spring_capacity;    ///< expected spring count, a hint for allocation; default 0
} sm_model_def;

/// Jacobian variant.
typedef enum sm_jacobian_variant {
	/// The exact derivatives of the forces, including the position-derivative of spring damping.
	SM_JACOBIAN_EXACT = 0,
	/// Definiteness-preserving: the geometric factor (1 - l0/L) is clamped at zero for
	/// compressed springs and the position-derivative of spring damping is left out, so
	/// df/dx is symmetric negative semi-definite (df/dv always is). Implicit cloth solvers use it
	/// because it keeps Newton's matrix M - h D - h^2 K positive definite.
	SM_JACOBIAN_DEFINITE,
} sm_jacobian_variant;

/// Name of a Jacobian variant ("exact", "definite"; "unknown" for another value) and the reverse
/// lookup: SM_OK, or SM_ERROR_INVALID_ARGUMENT for an unknown name or a NULL name or variant,
/// *variant then unchanged.
SM_API const char* sm_jacobian_variant_name(sm_jacobian_variant variant);
SM_API sm_status sm_jacobian_variant_from_name(const char* name, sm_jacobian_variant* variant);

/// Energies of a configuration.
typedef struct sm_energies {
	double kinetic;  ///< sum of m |v|^2 / 2 over all particles [J]
	double elastic;  ///< sum of ks (L - l0)^2 / 2 (rest-length) or ks L^2 / 2 (zero-length) [J]
	double gravity;  ///< potential of the constant forces, -sum (m g + load) . x (zero at the origin) [J]
} sm_energies;

/// Opaque model: owns its particles and springs. Not thread-safe for concurrent modification;
/// concurrent const use (evaluation) is safe. Separate models are fully independent.
typedef struct sm_model sm_model;

/// Definitions with the defaults documented in their structs.
SM_API sm_particle_def sm_default_particle_def(void);
SM_API sm_spring_def sm_default_spring_def(void);
SM_API sm_model_def sm_default_model_def(void);

/// Creates an empty model. Returns NULL if def is NULL (start from sm_default_model_def()) or
/// invalid (non-finite gravity, negative or non-finite mass damping, a negative capacity or one
/// above 2^29 - 1 = 536870911, the most particles or springs a model holds) or memory runs out;
/// err says which (may be NULL).
SM_API sm_model* sm_model_create(const sm_model_def* def, sm_error* err);

/// Destroys a model; accepts NULL.
SM_API void sm_model_destroy(sm_model* model);

/// Deep copy of a model (NULL if memory runs out).
SM_API sm_model* sm_model_clone(const sm_model* model);

/// Message of the last failed call that modifies this model (sm_model_add_*, sm_model_set_*, the
/// builders of structures.h), naming the particle or spring and the rule it broke; "" after a
/// successful one, and in a clone. Functions that take a const sm_model* never write it (they may
/// run concurrently): their status alone says what went wrong. Valid until the next call that
/// modifies the model.
SM_API const char* sm_model_last_error(const sm_model* model);

/// Adds a particle. On success writes its index to *index (may be NULL), on error -1. On error
/// the model is unchanged and the status says which rule the definition broke.
SM_API sm_status sm_model_add_particle(sm_model* model, const sm_particle_def* def, int32_t* index);

/// Adds a spring. A rest length of SM_REST_LENGTH_INITIAL is resolved to the current distance
/// between the particles, which must be 0 or from sqrt(DBL_MIN) = 1.5e-154 m to sqrt(DBL_MAX) =
/// 1.3e154 m (its square a normal double; else SM_ERROR_INVALID_ARGUMENT or
/// SM_ERROR_NOT_FINITE). The particles of a spring of either kind, whatever its rest length, must
/// be less than 1.3e154 m apart (SM_ERROR_NOT_FINITE). Writes the spring's index to *index (may be
/// NULL), -1 on error. On error the model is unchanged.
SM_API sm_status sm_model_add_spring(sm_model* model, const sm_spring_def* def, int32_t* index);

/// Numbers of particles and springs (disabled springs included); 0 for a NULL model.
SM_API int32_t sm_model_particle_count(const sm_model* model);
SM_API int32_t sm_model_spring_count(const sm_model* model);

/// The particle's definition as stored (current initial position and velocity); all zero on
/// an error (an index out of range).
SM_API sm_status sm_model_get_particle(const sm_model* model, int32_t index, sm_particle_def* def);

/// Replaces a particle's definition (same validation as adding). Rest lengths of springs
/// already added are not changed.
SM_API sm_status sm_model_set_particle(sm_model* model, int32_t index, const sm_particle_def* def);

/// Changes only how a particle moves. A fixed particle is at rest: making one fixed sets its stored
/// velocity to 0 (as sm_model_set_particle does), and making it free or driven again leaves it 0.
/// A change of motion (here, in sm_model_set_particle or sm_set_motion_at) numbers the free
/// particles again, a pass over all of them: to change many, give them to sm_set_motion_of or
/// sm_set_motion_in_box (structures.h), one pass for all (one call per particle of a 256 x 256
/// cloth took 2 s, growing with the square of the count).
SM_API sm_status sm_model_set_particle_motion(sm_model* model, int32_t index, sm_particle_motion motion);

/// The spring's definition as stored, with rest_length resolved to metres; all zero on an error
/// (an index out of range).
SM_API sm_status sm_model_get_spring(const sm_model* model, int32_t index, sm_spring_def* def);

/// Replaces a spring's definition (same validation as adding; a rest length of
/// SM_REST_LENGTH_INITIAL keeps the current one).
SM_API sm_status sm_model_set_spring(sm_model* model, int32_t index, const sm_spring_def* def);

/// The constants the force law uses: rest length l0 [m], stiffness ks [N/m], damping kd [N s/m].
/// A disabled spring gives those of its definition, which it takes up again when enabled, though
/// it exerts no force meanwhile. Any output may be NULL; each is 0 on an error (an index out of
/// range).
SM_API sm_status sm_model_spring_constants(const sm_model* model, int32_t index, double* rest_length,
                                           double* stiffness, double* damping);

/// A disabled spring exerts no force and contributes nothing to energies or Jacobians (a broken
/// spring). The sparsity pattern of an sm_sparse_jacobian is unaffected.
SM_API sm_status sm_model_set_spring_enabled(sm_model* model, int32_t index, bool enabled);
/// Whether a spring is enabled (false also for an index out of range).
SM_API bool sm_model_spring_enabled(const sm_model* model, int32_t index);

/// Gravity [m/s^2] and mass damping [1/s] as stored.
SM_API sm_model_def sm_model_get_def(const sm_model* model);
/// Changes gravity [m/s^2] and mass damping [1/s] (validated like sm_model_create).
SM_API sm_status sm_model_set_def(sm_model* model, const sm_model_def* def);

/// Copies every particle's initial position [m] and velocity [m/s] into x and v (3 per particle;
/// either may be NULL).
SM_API void sm_model_initial_state(const sm_model* model, double* x, double* v);

/// Total mass of all particles [kg].
SM_API double sm_model_total_mass(const sm_model* model);

/// Number of free particles, and the free index of a particle (its position among the free
/// particles in particle order, or -1 if it is constrained or out of range). Free indices number the unknowns
/// of the sparse Jacobian (degrees of freedom 3*free_index + 0..2).
SM_API int32_t sm_model_free_count(const sm_model* model);
SM_API int32_t sm_model_free_index(const sm_model* model, int32_t particle);

// ---------------------------------------------------------------------------------------------
// Evaluation. x [m] and v [m/s] hold 3 values per particle (all particles, constrained ones
// included); the model's stored initial state is not used. v may be NULL for zero velocities
// (no damping forces, no kinetic energy, no dissipated power). These functions do not modify the
// model and may run concurrently on the same model; given a NULL model or a NULL required array
// they do nothing (or return 0). sm_model_energies and sm_model_dissipated_power take a NULL x
// too, and leave out what needs positions (elastic and gravitational energy; spring damping).
// Outputs must not overlap inputs (but for the external forces of sm_model_forces, which may be
// its output): the Jacobian-vector products refuse an output that is one of their inputs.
// ---------------------------------------------------------------------------------------------

/// Total force [N] on every particle: springs, spring damping, mass damping, gravity, the
/// particles' loads and the optional external forces f_external [N] (3 per particle, NULL for
/// none), written to f. f_external may be f itself: the total then replaces the external forces
/// in place. f must not overlap x or v.
/// For constrained particles f is the force the model exerts on them (their reaction is -f).
///
/// At the singular point of a rest-length spring, L < SM_DEGENERATE_LENGTH_RATIO * l0 (the two
/// particles coincide), the direction u is undefined: the spring then exerts no force and its
/// damping none either; its Jacobian blocks are df/dx = ks I (as if zero-length), df/dv = 0.
/// A zero-length spring's elastic force is defined everywhere; its damping is zero at L = 0.
/// The results are finite for finite inputs unless a product overflows (particles about 1e154 m
/// apart, where L^2 overflows; ks (L - l0) or kd u.(v_b - v_a) beyond about 1.8e308 N): such
/// forces come out infinite or NaN, which the simulation and the analyses report as non-finite.
SM_API void sm_model_forces(const sm_model* model, const double* x, const double* v, const double* f_external,
                            double* f);

/// Relative length below which a rest-length spring is treated as degenerate [1].
#define SM_DEGENERATE_LENGTH_RATIO 1e-12

/// Kinetic, elastic and gravitational energies [J] of a configuration.
SM_API sm_energies sm_model_energies(const sm_model* model, const double* x, const double* v);

/// Power dissipated by spring damping and mass damping [W], >= 0.
SM_API double sm_model_dissipated_power(const sm_model* model, const double* x, const double* v);

/// Each spring's state, one value per spring in spring order, into each of the arrays that is
/// not NULL: its length L [m]; its strain (L - l0) / l0 [1], NAN for a spring with l0 = 0 (every
/// zero-length spring); and its tension [N], the force with which it pulls its two particles
/// towards each other, ks (L - l0) + kd u . (v_b - v_a) (elastic and damping; negative in
/// compression): f_a = tension u. The tension is 0 for a disabled spring and at the singular
/// point above, where the spring exerts no force; a length that is not finite (a position NaN or
/// infinite, or particles so far apart that L^2 overflows, about 1e154 m) gives a tension that is
/// not finite either, not 0: inf when L^2 overflows (ks > 0), NaN when a position is NaN or
/// infinite (the direction u is then NaN too) or ks = 0 (0 x inf).
SM_API void sm_model_spring_states(const sm_model* model, const double* x, const double* v, double* length,
                                   double* strain, double* tension);

/// Per-spring 3x3 blocks (row-major): K = d f_a / d x_b [N/m] and D = d f_a / d v_b [N s/m].
/// Since f depends on x_b - x_a and v_b - v_a and f_b = -f_a: d f_a/d x_a = -K,
/// d f_b/d x_b = -K, d f_b/d x_a = K, and likewise for D. Disabled springs give zero blocks, and
/// so does an error (an index out of range, a NULL model or x, an unknown variant). Either
/// output may be NULL.
SM_API sm_status sm_model_spring_jacobian(const sm_model* model, int32_t spring, const double* x,
                                          const double* v, sm_jacobian_variant variant, double K[9],
                                          double D[9]);

/// Dense Jacobians over all particles, row-major 3n x 3n: dfdx [N/m] and dfdv [N s/m] (mass
/// damping included in dfdv). Either may be NULL. For small models and tests.
/// SM_ERROR_INVALID_ARGUMENT, with nothing written, for a NULL model or x or an unknown variant.
SM_API sm_status sm_model_jacobian_dense(const sm_model* model, const double* x, const double* v,
                                         sm_jacobian_variant variant, double* dfdx, double* dfdv);

/// Jacobian-vector product without assembling: out = df/dx dx + df/dv dv [N] over all particles
/// (3 per particle). dx [m] or dv [m/s] may be NULL (treated as zero). out must not overlap x, v,
/// dx or dv: the product is not formed in place.
/// SM_ERROR_INVALID_ARGUMENT, with nothing written, for a NULL model, x or out, an out that is x,
/// v, dx or dv, or an unknown variant.
SM_API sm_status sm_model_jacobian_product(const sm_model* model, const double* x, const double* v,
                                           sm_jacobian_variant variant, const double* dx, const double* dv,
                                           double* out);

// ---------------------------------------------------------------------------------------------
// Sparse Jacobian over the free particles' degrees of freedom.
//
// The pattern is built once from the model's springs (constrained particles excluded) in
// compressed sparse row form with 64-bit indices, rows sorted by column, diagonal blocks always
// present: exactly the layout of a SUNDIALS SUNMatrix_Sparse of type CSR_MAT with 64-bit
// sunindextype, so the arrays can serve as its index arrays and the values be filled in place.
// Because df/dx and df/dv have the same pattern, one pattern serves both.
// ---------------------------------------------------------------------------------------------

typedef struct sm_sparse_jacobian sm_sparse_jacobian;

/// Builds the pattern for the model's current springs and free particles (NULL on OOM).
/// The pattern stays valid while the particles' motions and the springs' endpoints are
/// unchanged (enabling or disabling springs, changing constants are fine).
SM_API sm_sparse_jacobian* sm_sparse_jacobian_create(const sm_model* model);
SM_API void sm_sparse_jacobian_destroy(sm_sparse_jacobian* jacobian);

/// Dimension (3 * free particles) and number of stored entries.
SM_API int64_t sm_sparse_jacobian_dimension(const sm_sparse_jacobian* jacobian);
SM_API int64_t sm_sparse_jacobian_nonzeros(const sm_sparse_jacobian* jacobian);
/// Row pointers (dimension + 1 entries) and column indices (nonzeros entries), owned by the
/// jacobian.
SM_API const int64_t* sm_sparse_jacobian_row_pointers(const sm_sparse_jacobian* jacobian);
SM_API const int64_t* sm_sparse_jacobian_column_indices(const sm_sparse_jacobian* jacobian);

/// Fills the values (nonzeros entries each, in pattern order) of df/dx [N/m] and df/dv [N s/m]
/// (mass damping included) at (x, v). Either may be NULL. Fails with SM_ERROR_TOPOLOGY if the
/// model no longer matches the pattern, SM_ERROR_OUT_OF_MEMORY if the call's scratch (64 bytes
/// per spring, 24 per particle; freed before returning) cannot be allocated; the values are then
/// untouched. Concurrent fills with the same pattern into different arrays are independent.
/// Equivalent to sm_model_forces_and_jacobians followed by sm_sparse_jacobian_fill_from_springs,
/// which a caller that needs the forces too should use instead.
SM_API sm_status sm_sparse_jacobian_fill(const sm_sparse_jacobian* jacobian, const sm_model* model,
                                         const double* x, const double* v, sm_jacobian_variant variant,
                                         double* dfdx, double* dfdv);

// ---------------------------------------------------------------------------------------------
// Forces and per-spring Jacobians in one pass.
//
// An implicit step needs the forces and their Jacobians at the same state. Evaluating both in
// one pass over the springs computes each spring's geometry once, and storing each spring's
// Jacobian in a compact factored form (8 numbers per spring, written in spring order) costs a
// fraction of writing the assembled matrices (two 3x3 blocks per spring and matrix, and their
// diagonal sums). For every spring, with u its unit direction:
//
//   K = d f_a / d x_b = u z^T + beta I    [N/m]      D = d f_a / d v_b = kd u u^T    [N s/m]
//
// which holds for both variants, both spring kinds and the degenerate point (u = 0, K = ks I);
// the derivation of z and beta is in lib/forces.c. From this data the Jacobian-vector product
// and the assembled sparse matrices follow without evaluating the geometry again.
// ---------------------------------------------------------------------------------------------

/// Storage for every spring's factored Jacobian (64 bytes per spring), owned by the caller and
/// reused across evaluations.
typedef struct sm_spring_jacobians sm_spring_jacobians;

/// Storage sized for the model's current springs (NULL on OOM or a NULL model). It serves the
/// model while its particle and spring counts stay the same. The stored data describes the
/// state and constants of the last evaluation: apply it to the model as it was evaluated (the
/// functions below check the counts, and the sparse fill the whole pattern).
SM_API sm_spring_jacobians* sm_spring_jacobians_create(const sm_model* model);
SM_API void sm_spring_jacobians_destroy(sm_spring_jacobians* jacobians);

/// Forces [N] exactly as sm_model_forces computes them (the same numbers, bit for bit) and, in
/// the same pass, every spring's Jacobian for the variant at (x, v) into `jacobians`. v may be
/// NULL (zero velocities), f_external too, or f itself, as there. Disabled springs store zero
/// blocks. Errors:
/// SM_ERROR_INVALID_ARGUMENT (NULL model, x, f or jacobians, unknown variant),
/// SM_ERROR_TOPOLOGY (storage made for a model with other particles or springs); f and
/// jacobians are then untouched.
SM_API sm_status sm_model_forces_and_jacobians(const sm_model* model, const double* x, const double* v,
                                               const double* f_external, sm_jacobian_variant variant,
                                               double* f, sm_spring_jacobians* jacobians);

/// The blocks K = d f_a / d x_b [N/m] and D = d f_a / d v_b [N s/m] (row-major) of one spring
/// from the stored data; equal to sm_model_spring_jacobian at the evaluated state to rounding.
/// Either output may be NULL. SM_ERROR_SPRING_INDEX for an index out of range,
/// SM_ERROR_INVALID_ARGUMENT if nothing was evaluated yet.
SM_API sm_status sm_spring_jacobians_block(const sm_spring_jacobians* jacobians, int32_t spring, double K[9],
                                           double D[9]);

/// Jacobian-vector product from the stored data: out = df/dx dx + df/dv dv [N] over all
/// particles (3 per particle), mass damping -alpha m dv included from the model. dx [m] or
/// dv [m/s] may be NULL (zero). The same numbers as sm_model_jacobian_product at the evaluated
/// state, to rounding. out must not overlap dx or dv. SM_ERROR_TOPOLOGY if the model no longer
/// matches the storage, SM_ERROR_INVALID_ARGUMENT if nothing was evaluated yet or out is dx or dv,
/// with nothing written.
SM_API sm_status sm_spring_jacobians_product(const sm_spring_jacobians* jacobians, const sm_model* model,
                                             const double* dx, const double* dv, double* out);

/// The product with the Jacobian scaled two ways, out = (scale_k df/dx + scale_d df/dv) p [N]
/// over all particles (3 per particle; p in m, with scale_k in 1 and scale_d in 1/s, or any
/// consistent units), mass damping included. An implicit step of the second-order system needs
/// it with scale_k = gamma^2, scale_d = gamma [s^2, s]: the same numbers as
/// sm_spring_jacobians_product(gamma^2 p, gamma p) to rounding, without scaling p twice. p and
/// out must not overlap. Errors as sm_spring_jacobians_product (and NULL p, or out = p).
SM_API sm_status sm_spring_jacobians_combined_product(const sm_spring_jacobians* jacobians,
                                                      const sm_model* model, double scale_k, double scale_d,
                                                      const double* p, double* out);

/// Fills the sparse df/dx [N/m] and df/dv [N s/m] (mass damping from the model) from the stored
/// data, without evaluating any spring again: the same values as sm_sparse_jacobian_fill at the
/// evaluated state and variant (which works this way). Either output may be NULL. SM_ERROR_TOPOLOGY if
/// the model no longer matches the pattern or the storage, SM_ERROR_INVALID_ARGUMENT if nothing
/// was evaluated yet.
SM_API sm_status sm_sparse_jacobian_fill_from_springs(const sm_sparse_jacobian* jacobian,
                                                      const sm_model* model,
                                                      const sm_spring_jacobians* jacobians, double* dfdx,
                                                      double* dfdv);

#ifdef __cplusplus
}
#endif

// springmass: time integration of a model with SUNDIALS CVODE.
//
// The state is the positions and velocities of the free particles; fixed particles stay put and
// driven particles follow the motion the caller prescribes. Each simulation owns a copy of the
// model, its own SUNDIALS context and all solver memory: separate simulations are independent
// and may run in separate threads.
//
// Inputs between calls. sm_simulation_set_driven and sm_simulation_set_external_force (and their
// forms that change along a step: _accelerating, _ramp) change what the right-hand side sees from
// the current time on. A restart of CVODE (as a state set with sm_simulation_set_state, a spring
// break, a model update, a reset or a failure make) starts BDF again at first order, which costs
// about rtol of the motion each time, so by default (restart_on_input_change) a changed input
// restarts it only where BDF's history cannot carry the change (docs/simulation.md, "Inputs between
// calls"). An input set to what it was (the same force, a motion on its path, which then stays the
// path it was) or a force on a held particle, which moves nothing, keeps the history. So does one
// that turns (a force at the value its ramp reached with a new rate, a drive at the position and
// velocity its path reached with a new acceleration): the right-hand side stays continuous (an
// anchor driven through samples every 1 ms, a new acceleration at each, restarted at each: the bob
// 2.8e-4 m off after 2 s at rtol 1e-6; kept, 2.6e-8 m). So does a force that jumps by little: the
// advance restarts only if its interval (or max_step) times |jump| / m exceeds the velocity's
// tolerance rtol |v| + atol_velocity at some particle (an undamped oscillator under a sine force
// held over each 1 ms, restarted at every jump, was 4.5e-3 m off after 10 s; kept, 2.2e-6 m). So
// does a drive that jumps by little, by the same measure applied to the jump of its springs' forces
// at the free particles around it, and by its interval times the jump of the inputs' or the
// dissipated power, summed over the drives that jump before the advance, against the energies'
// tolerance rtol |E| + atol_velocity (a damped base excitation sampled every 1 ms jumps by much and
// restarts: its steady-state amplitude 2e-5 off, 9e-4 with the history kept, the steps that
// straddle the changes carrying an error CVODE's error test does not see; tests/test_simulation.c,
// test_base_excitation_sampled_at_every_step). An
// input set to another value and back before the next advance (a master that tries a value and
// reads the outputs it gives) changes nothing: once every input changed since the last advance is
// back on the path or ramp it had there, those are its values again, to the bit (the inputs' work
// included). A cut, a new state or a model update in
// between keeps the restart it asks for, and an input set back after it is a change (its jump's
// work counted), yet onto the path or ramp it had at the last advance, to the bit; a reset or a
// restore forgets those paths. restart_on_input_change = false keeps the history over every change:
// faster where inputs jump by much at every call (on the 8 x 8 benchmark cloth with a sine force
// changed every 10 ms the rule restarted 93 times in the 100 changes and took 2.25 times the
// steps of keeping the history; every 1 ms, 25 times in 1000 changes, 1.24 times the steps;
// bench_cloth with RESTART_EVERY, bench/README.md), less accurate there. A jump the error control
// cannot absorb then (a step force large against the model's, a driven particle moved far) makes
// CVODE fail; the advance restarts at the jump and tries once more, so the caller sees a restart
// in the statistics rather than an error.
//
// Reproducibility. On one machine the same model, options and calls give the same trajectory
// bit for bit, also in concurrent threads, with one exception: the CHOLMOD factorisations (the reduced
// Cholesky solver, and the coarse system of conjugate gradients on large models) use BLAS for large matrices,
// whose sums may depend on the number of BLAS threads (a process-wide setting, e.g. OPENBLAS_NUM_THREADS);
// keep it fixed to reproduce a run to the last bit. Across machines, OpenBLAS chooses its kernels by
// processor (OPENBLAS_CORETYPE overrides the choice), so the same large model may take another step sequence
// within the tolerances: over 0.3 s the 128 x 128 benchmark cloth took 1794 steps with OpenBLAS's AVX-512
// kernels and 1842 with its Haswell ones, the free corner within 1e-6 m of each other. springmass's own
// arithmetic is the same on every x86-64 processor: the force loop takes four springs at a time where the
// processor has AVX and two or one elsewhere, with the same IEEE operations in the same order (no fused
// multiply-add), so the forces and Jacobians are the same bits either way.
//
// Threads. The library starts threads of its own only when asked (sm_simulation_def.threads > 1,
// for the pcg solver on models of 4000 free particles or more; they end with the simulation),
// but OpenBLAS, which CHOLMOD calls, may start others, as its process-wide settings allow (see above): a
// program that runs simulations in threads of its own and wants no others sets OPENBLAS_NUM_THREADS=1 in
// the environment before the first call. It costs no time where CHOLMOD's blocks are small: a program
// solving the sparse statics of a 40 x 40 cloth took 3.5 - 3.9 s with one BLAS thread and 3.3 - 4.3 s with
// OpenBLAS's default of one per core on 2 cores, which spent twice the processor time (3 s of it waiting in
// the kernel) and, with the test suite running beside it, took 42 s against 4.2 s in one run. CHOLMOD's
// supernodal factorisation (where CHOLMOD's analysis picks it: the reduced Cholesky solver and the sparse
// statics on sheets and blocks from about 2000 unknowns on; the coarse system of conjugate gradients on large
// models; the sparse path of sm_modes_compute) would run
// its loops in an OpenMP team of 4 threads whatever OMP_NUM_THREADS says; springmass keeps them to the
// calling thread (the sparse statics of a 40 x 40 cloth ran 5 times faster so on 2 cores:
// lib/cholmod_factorize.c), and leaves the thread's OpenMP settings as they were.
#pragma once

#include <float.h>

#include "springmass/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Smallest absolute tolerance accepted [m], [m/s]. CVODE's error norm sums
/// (error / (rtol |y| + atol))^2 over the N components of the state, which overflows to infinity
/// when the errors reach 1.3e154 atol / sqrt(N) where |y| = 0: at this bound 1.3e4 / sqrt(N) m or
/// m/s (21 for the 393 206 components of a 256 x 256 cloth), beyond any step's error, while at
/// 3e-308 m/s the first steps of the bundled oscillator overflowed it and every step failed.
#define SM_MIN_ABSOLUTE_TOLERANCE 1e-150

/// Smallest relative tolerance accepted [1]: the machine epsilon, 2.2e-16. A smaller one asks
/// for local errors below the rounding of the state itself, which CVODE 6.4.1 cannot meet: before
/// every step it fails with CV_TOO_MUCH_ACC ("too much accuracy requested") when DBL_EPSILON
/// times the root mean square of |y| / (rtol |y| + atol) over the state exceeds 1. With rtol at
/// least DBL_EPSILON every term is below 1 / DBL_EPSILON, so that only the rounding of the norm
/// could make the test fire; below it, it fires once the state's components exceed
/// atol / (DBL_EPSILON - rtol) (the bundled oscillator at rtol 1e-17 and atol 1e-150 failed at
/// t = 0; at rtol = DBL_EPSILON it runs). CVODE's guide advises keeping rtol well above the unit
/// roundoff; this bound only refuses what cannot work.
#define SM_MIN_RELATIVE_TOLERANCE DBL_EPSILON

/// A limit on the internal step (max_step) must lie above this [s], 1 / DBL_MAX = 5.6e-309 s:
/// CVODE caps a step h at max_step as h / (|h| (1 / max_step)), and at or below it 1 / max_step
/// is beyond the largest double (it made every step 0 s, and the advance failed saying that the
/// accelerations were too large to measure).
#define SM_MAX_STEP_FLOOR (1.0 / DBL_MAX)

/// Linear multistep method.
typedef enum sm_method {
	SM_METHOD_BDF = 0,  ///< backward differentiation formulas with Newton iteration (stiff; default)
	SM_METHOD_ADAMS,    ///< Adams-Moulton with fixed-point iteration (non-stiff)
} sm_method;

/// Linear solver for Newton's method (BDF only).
typedef enum sm_linear_solver {
	/// Dense up to 2 free particles, reduced conjugate gradients above (bench/README.md).
	SM_SOLVER_AUTO = 0,
	/// Dense LU of the full 6n system with the analytic Jacobian, the Newton matrix formed at every
	/// step (small models).
	SM_SOLVER_DENSE,
	/// Sparse direct LU (KLU) of the full 6n system with the analytic sparse Jacobian, the Newton
	/// matrix kept over several steps as CVODE keeps it by default, which fails where a stiff
	/// spring turns fast (a pendulum on a stiff rod: tests/test_large_motions.c).
	SM_SOLVER_KLU,
	/// Second-order reduction to the 3n system (M - gamma D - gamma^2 K) dv = M bv + gamma K bx,
	/// symmetric positive definite with the definiteness-preserving Jacobian (always used by the
	/// reduced solvers), solved by conjugate gradients with a 3x3 block-Jacobi preconditioner
	/// (from 100 free particles on, plus a coarse correction over aggregates of neighbouring
	/// particles, solved exactly or, from 40 000 free particles on, by a multilevel cycle). The
	/// Jacobian is evaluated afresh at every step, and products with the matrix are formed from
	/// the springs' factored Jacobian blocks without assembling it. What AUTO picks above tiny
	/// models.
	SM_SOLVER_REDUCED_PCG,
	/// The same reduced system, by conjugate gradients preconditioned with a CHOLMOD Cholesky
	/// factorisation of the Newton matrix of an earlier step (symbolic analysis once; a new
	/// numeric factorisation when the extra iterations have cost as much as one). Fewer
	/// iterations than block Jacobi, each dearer; more robust for badly conditioned models.
	SM_SOLVER_REDUCED_CHOLMOD,
	SM_SOLVER_COUNT
} sm_linear_solver;

/// Integration options; get them from sm_default_simulation_def().
typedef struct sm_simulation_def {
	sm_method method;              ///< default SM_METHOD_BDF
	sm_linear_solver solver;       ///< default SM_SOLVER_AUTO
	sm_jacobian_variant jacobian;  ///< default SM_JACOBIAN_EXACT
	double relative_tolerance;     ///< in [SM_MIN_RELATIVE_TOLERANCE, 1) [1]; default 1e-6
	/// >= SM_MIN_ABSOLUTE_TOLERANCE [m]; default 1e-8, for models of centimetres and more: a
	/// smaller model's motion lies below it and needs it scaled down (docs/simulation.md)
	double absolute_tolerance_position;
	/// >= SM_MIN_ABSOLUTE_TOLERANCE [m/s], also for the dissipated energy and the inputs' work [J]; default
	/// 1e-6
	double absolute_tolerance_velocity;
	/// largest internal step [s], above SM_MAX_STEP_FLOOR = 5.6e-309 s, or 0 (default) = unlimited
	double max_step;
	int32_t max_steps;  ///< internal steps allowed per sm_simulation_advance, breaks included; default 100000
	/// Re-initialise CVODE where sm_simulation_set_driven or sm_simulation_set_external_force
	/// changes an input by more than its history can carry (default true; false keeps CVODE's
	/// history over every change: faster, less accurate where inputs jump by much at every call;
	/// see "Inputs between calls" above). Model files: "input_changes", "restart" or "keep".
	bool restart_on_input_change;
	/// BDF only: let CVODE lower the order where orders 3 to 5 turn unstable at the step its error
	/// test allows (CVODE's stability limit detection, CVodeSetStabLimDet). Lightly damped stiff
	/// modes, the fast vibrations of springs, lie near the imaginary axis, where those orders are
	/// not stable; without it such a mode's round-off grows until the error test cuts the step, and
	/// the steps stay short long after the motion has settled (docs/simulation.md, "Stability
	/// limit detection"). Default true. Model files: "stability_limit_detection", true or false.
	bool stability_limit_detection;
	/// Threads for the pcg solver's loops on models of 4000 free particles or more, the caller's
	/// included, >= 1 (default 1; at most 4 are used, and no more than the processors the process
	/// may run on).
	/// The results are the same bits with any count.
	int32_t threads;
	/// Called after every internal step of sm_simulation_advance with the time it reached [s]
	/// and `on_step_context` (default NULL: not called), e.g. to show progress during a long
	/// advance or to bound its wall time. The steps and results are the same with or without it.
	/// Returning false stops the advance at that step, with SM_ERROR_STEP_LIMIT (advancing again
	/// continues). It must not call back into the simulation.
	bool (*on_step)(void* context, double time);
	void* on_step_context;
} sm_simulation_def;

/// Counters since creation or the last reset.
typedef struct sm_statistics {
	int64_t steps;
	int64_t rhs_evaluations;
	int64_t jacobian_evaluations;
	int64_t linear_iterations;  ///< conjugate-gradient iterations, or one per solve for direct solvers
	int64_t error_test_failures;
	int64_t convergence_failures;
	int64_t restarts;  ///< solver re-initialisations (events, state changes, jumps in inputs)
	/// wall time in force evaluation for the right-hand side [s]. The pcg and cholmod solvers
	/// evaluate the forces of a right-hand side at a new time together with the springs'
	/// Jacobian blocks, in one pass timed as Jacobian evaluation: with them this is about 0.
	double force_seconds;
	/// wall time in Jacobian evaluation: the springs' derivatives (for pcg and cholmod with the
	/// forces of the same pass, above), and their assembly into the matrices of the dense, klu
	/// and cholmod solvers [s]
	double jacobian_seconds;
	/// wall time in linear solves, apart from the above: factorisations (dense and klu LU,
	/// cholmod's Cholesky), preconditioners and iterations [s]
	double linear_solve_seconds;
	/// Numeric factorisations of a Newton matrix: the set-ups of the dense and KLU solvers,
	/// CHOLMOD's factorisations for the reduced Cholesky solver, none for conjugate gradients.
	int64_t factorizations;
} sm_statistics;

/// A spring that broke.
typedef struct sm_break_event {
	double time;     ///< when its strain first reached the break strain [s]
	int32_t spring;  ///< spring index
} sm_break_event;

typedef struct sm_simulation sm_simulation;

/// The default options (the values documented in sm_simulation_def).
SM_API sm_simulation_def sm_default_simulation_def(void);

/// Fraction of a model's own scales (sm_motion_scales) above which both absolute tolerances
/// count as coarse [1]: CVODE then holds the model's motion to no better than this fraction of
/// its scales (docs/simulation.md, "Tolerances").
#define SM_COARSE_TOLERANCE 1e-4

/// The scales of a model's motion against which its absolute tolerances are judged.
typedef struct sm_motion_scales {
	/// The shortest enabled spring with a free end (one between fixed or driven particles is not
	/// integrated) and a stiffness or a damping (one of neither exerts no force): its rest length,
	/// or its initial length for one of rest length 0 [m]; INFINITY when no such spring has a
	/// length (springs between coincident particles, or none with a free end).
	double length;
	/// length times the Gershgorin bound of the highest angular frequency (sm_explicit_limit's
	/// omega_max) [m/s]: the speed of a motion of that size at that frequency; INFINITY when
	/// length is.
	double speed;
} sm_motion_scales;

/// The motion scales of a model (disabled springs left out). SM_ERROR_INVALID_ARGUMENT for NULL
/// arguments, SM_ERROR_OUT_OF_MEMORY.
SM_API sm_status sm_model_motion_scales(const sm_model* model, sm_motion_scales* scales);

/// Whether both absolute tolerances of def are above SM_COARSE_TOLERANCE times the scales; false
/// when either scale is 0 or not finite (nothing to judge by). The defaults, 1e-8 m and 1e-6 m/s,
/// suit models of centimetres and more; a micromechanical model's motion lies below them.
SM_API bool sm_tolerances_coarse(const sm_simulation_def* def, const sm_motion_scales* scales);

/// Fraction of a spring's round-off velocity (sm_round_off) below which the velocities' absolute
/// tolerance counts as too tight [1]: CVODE's error and convergence tests see about this fraction
/// of the noise the rounding of a stiff spring's force puts into its ends' velocities, and below
/// it fail over and over (docs/simulation.md, "Tolerances").
#define SM_TIGHT_TOLERANCE 0.1

/// The spring whose force's rounding puts the largest noise into its ends' velocities.
typedef struct sm_round_off {
	/// The enabled spring with a free end of the largest velocity below; -1 when there is none
	int32_t spring;
	double stiffness;  ///< its stiffness [N/m]
	/// DBL_EPSILON |x| sqrt(k / m) / 2, with |x| the largest magnitude of its ends' coordinates at
	/// the initial state, k its stiffness and m the mass of its lighter free end: the largest
	/// change of velocity the rounding of its force, about k DBL_EPSILON |x|, makes in one step
	/// (motion_scales.c) [m/s]; 0 when spring is -1
	double velocity;
} sm_round_off;

/// The round-off of a model's forces at its initial state (disabled springs, and springs between
/// held particles, left out). SM_ERROR_INVALID_ARGUMENT for NULL arguments, SM_ERROR_OUT_OF_MEMORY.
SM_API sm_status sm_model_round_off(const sm_model* model, sm_round_off* round_off);

/// Whether the velocities' absolute tolerance of def is below SM_TIGHT_TOLERANCE times the
/// round-off velocity: a particle at rest, or a velocity component passing through 0, is then
/// held to less than the noise of its force, and CVODE's steps fail their error or convergence test
/// over and over (and may stop at max_steps). False for NULL arguments or a round-off velocity that is 0 or
/// not finite (nothing to judge by).
SM_API bool sm_tolerances_tight(const sm_simulation_def* def, const sm_round_off* round_off);

/// Name of a linear solver ("auto", "dense", "klu", "pcg", "cholmod"; "unknown" for another
/// value) and the reverse lookup: SM_OK, or SM_ERROR_INVALID_ARGUMENT for an unknown name or
/// NULL, *solver then unchanged.
SM_API const char* sm_linear_solver_name(sm_linear_solver solver);
SM_API sm_status sm_linear_solver_from_name(const char* name, sm_linear_solver* solver);

/// Name of a method ("bdf", "adams"; "unknown" for another value) and the reverse lookup: SM_OK,
/// or SM_ERROR_INVALID_ARGUMENT for an unknown name, a NULL name or a NULL method, *method then
/// unchanged.
SM_API const char* sm_method_name(sm_method method);
SM_API sm_status sm_method_from_name(const char* name, sm_method* method);

/// Name of what an input that changes does (restart_on_input_change): "restart" for true,
/// "keep" (the history) for false, as model files and the FMU's solver.input_changes write
/// them; and the reverse lookup: SM_OK, or SM_ERROR_INVALID_ARGUMENT for another name, a NULL
/// name or a NULL restart, *restart then unchanged.
SM_API const char* sm_input_changes_name(bool restart);
SM_API sm_status sm_input_changes_from_name(const char* name, bool* restart);

/// Creates a simulation of a copy of the model, starting at time 0 from the model's initial
/// state; def NULL means the defaults. Returns NULL with err filled on invalid options or
/// solver set-up failure.
SM_API sm_simulation* sm_simulation_create(const sm_model* model, const sm_simulation_def* def,
                                           sm_error* err);

/// Destroys the simulation and everything it owns; accepts NULL.
SM_API void sm_simulation_destroy(sm_simulation* sim);

/// Integrates to exactly t_end [s] (never past it), handling spring breaks on the way; t_end
/// equal to the current time t does nothing. CVODE integrates on a time axis that starts at its
/// last (re)initialisation (set_state, restore_state, reset, a break, a changed input), so a state
/// set at a large time (1e9 s, 1e14 s) steps as precisely as at 0; the times the simulation
/// reports are doubles all the same, resolving eps |t| (a break at 1e14 s is recorded to 0.016 s,
/// and an advance to 1e14 s plus an ulp integrates 0.016 s). An interval below the resolution of
/// CVODE's axis, 4 eps max(1 s, |t - the last initialisation's t|) (about 9e-16 s in the first
/// second), too short for CVODE, is one explicit Euler step (exact to round-off). CVODE sizes its
/// first step after a (re)initialisation from the interval ahead, up to 1e9 s of it: an end far
/// beyond (1e300 s, "until it settles") is reached by steps that grow as the motion allows: a
/// damped bob settling on its spring reaches 1e300 s in about 400 steps with the dense, pcg and
/// cholmod solvers, a damped hanging rope of 10 segments in about 5000, and a damped 8 x 8 cloth
/// hanging from two corners with dense, klu and cholmod (629 to 669 steps); klu stopped at its
/// step limit near 5e61 s on the bob hanging under gravity and near 5e55 s on the rope, and pcg
/// near 1.2e257 s on the cloth (docs/simulation.md, "Advancing until it settles").
/// SM_ERROR_INVALID_ARGUMENT, with nothing changed, for a t_end that is not finite or lies before
/// t.
/// When the advance used its max_steps internal steps, or on_step returned false, before t_end:
/// SM_ERROR_STEP_LIMIT, the state valid at the last step (sm_simulation_time()), and advancing
/// again continues as if uninterrupted. On failure returns SM_ERROR_SOLVER
/// (SM_ERROR_OUT_OF_MEMORY when a spring break cannot be recorded) with the message in
/// sm_simulation_last_error(), which names a lack of memory as the cause where there was one; the
/// state is then the last one the solver reached (sm_simulation_time() tells when) and the
/// simulation remains usable (advance again, set a state, or reset).
SM_API sm_status sm_simulation_advance(sm_simulation* sim, double t_end);

/// Advances to t_end [s] as sm_simulation_advance does, but lets CVODE step past t_end, up to
/// t_stop [s] (never past it), and interpolates the state at t_end from its last step (CVODE's
/// interpolating polynomial, of the step's order: within the tolerances, as a step is). For
/// outputs at fixed times from a run whose inputs do not change before t_stop: CVODE then
/// takes the steps of one advance to t_stop, whatever the output times, where advancing to
/// each output time ends a step at each (the bundled cloth with 0.01 s outputs: 671 steps
/// instead of 1075). The trajectory at t_stop, and the spring breaks on the way, are then those
/// of one advance to t_stop, bit for bit, for a t_stop up to 1e9 s ahead; a farther t_stop (a
/// master's 1e28 s for "no end") sizes CVODE's first steps as one 1e9 s ahead would (CVODE's
/// first step is at least 100 eps of the interval it is sized for: 2e14 s for 1e28 s, which no
/// model converges at). A break that CVODE finds past t_end happens in the next advance that
/// reaches its time.
/// What is past the simulation's time is dropped, and CVODE restarts there, when an input
/// changes (sm_simulation_set_driven, sm_simulation_set_external_force; whatever
/// restart_on_input_change says), or the state or the model does. An advance whose inputs
/// changed since the previous advance began ends its last step at t_end, as
/// sm_simulation_advance does: inputs that change at one output time tend to change at the next
/// (a co-simulation master's), where steps past it would be dropped, and restarts from
/// interpolated states add up their errors (docs/fmu.md measures it). A later sm_simulation_advance
/// to a time CVODE has already passed interpolates too. SM_ERROR_INVALID_ARGUMENT, with nothing
/// changed, for a t_end that sm_simulation_advance refuses or a t_stop that is not finite or lies
/// before t_end; failures as for sm_simulation_advance.
SM_API sm_status sm_simulation_advance_interpolated(sm_simulation* sim, double t_end, double t_stop);

/// Current time [s]; NaN for a NULL simulation.
SM_API double sm_simulation_time(const sm_simulation* sim);

/// Positions [m] and velocities [m/s] of all particles (3 per particle) at the current time.
/// The pointer stays valid until the simulation is destroyed; its contents change with every
/// call that changes the state: advance (either form), set_driven (either form; the driven
/// particle), set_state, restore_state, reset and update_model. NULL for a NULL simulation.
SM_API const double* sm_simulation_positions(const sm_simulation* sim);
SM_API const double* sm_simulation_velocities(const sm_simulation* sim);

/// Forces [N] on all particles at the current state (external forces included); for
/// constrained particles, the force the model exerts on them.
SM_API void sm_simulation_forces(const sm_simulation* sim, double* f);

/// Kinetic, elastic and gravitational energy at the current state [J] (each NaN for a NULL
/// simulation).
SM_API sm_energies sm_simulation_energies(const sm_simulation* sim);
/// Energy dissipated since the start [J]: by damping (integrated with the state) and by broken
/// springs (the elastic energy each held when it broke), so that kinetic + elastic +
/// gravitational + dissipated energy is constant without external forces or driven particles,
/// and kinetic + elastic + gravitational + dissipated - input work (sm_simulation_input_work)
/// with them. NaN for a NULL simulation.
SM_API double sm_simulation_dissipated_energy(const sm_simulation* sim);

/// Work the inputs have done on the model since the start [J] (negative when they took energy
/// out): external forces on free particles, integrated with the state as f_ext . v; and what
/// drives each driven particle along its prescribed motion, the force m a - f_model its path
/// needs beyond the model's forces (springs, damping, gravity, its load; an external force on it
/// goes to whatever drives it), times its velocity, plus the energy a motion that jumps (a new position
/// or velocity, sm_simulation_set_driven) adds at once. Fixed particles do none. NaN for a NULL
/// simulation.
SM_API double sm_simulation_input_work(const sm_simulation* sim);

/// Power the inputs deliver at the current state [W]: the rate of sm_simulation_input_work
/// between jumps. Evaluates the forces into the simulation's work arrays: not at the same time
/// as another call on the same simulation. NAN for a NULL simulation.
SM_API double sm_simulation_input_power(sm_simulation* sim);

/// Prescribes a driven particle's motion from the current time t0 on: x(t) = position +
/// velocity (t - t0) [m, m/s]. Error if the particle is not driven. The same velocity with a
/// position on the current path, each to within round-off (16 units of it, of the velocities, and
/// of the largest of the positions and the distance travelled since the motion was last set),
/// continues the motion: it is no input change (restart_on_input_change,
/// sm_simulation_advance_interpolated).
SM_API sm_status sm_simulation_set_driven(sm_simulation* sim, int32_t particle, const double position[3],
                                          const double velocity[3]);

/// Prescribes a driven particle's motion with a constant acceleration from the current time t0
/// on: x(t) = position + velocity s + acceleration s^2 / 2, x'(t) = velocity + acceleration s,
/// s = t - t0 [m, m/s, m/s^2] (a co-simulation master's extrapolation of a motion input and its
/// derivative over a step). sm_simulation_set_driven is this with no acceleration. The same
/// acceleration with a position and a velocity on the current path, to within round-off as there
/// (of the largest of the positions and the terms v s and a s^2 / 2 however they cancel; of the
/// velocities and a s), continues the motion.
SM_API sm_status sm_simulation_set_driven_accelerating(sm_simulation* sim, int32_t particle,
                                                       const double position[3], const double velocity[3],
                                                       const double acceleration[3]);

/// Sets the external force [N] on a particle, held constant until changed. On a fixed or driven
/// particle it moves nothing, and changing it is no input change.
SM_API sm_status sm_simulation_set_external_force(sm_simulation* sim, int32_t particle,
                                                  const double force[3]);

/// Sets an external force that changes linearly from the current time t0 on until changed:
/// f(t) = force + rate (t - t0) [N, N/s] (a co-simulation master's extrapolation of a force input
/// and its derivative over a step). sm_simulation_set_external_force is this with rate 0. The
/// same rate with a force on the current ramp, to within round-off as in
/// sm_simulation_set_driven (with rate 0: of the forces), is no input change.
SM_API sm_status sm_simulation_set_external_force_ramp(sm_simulation* sim, int32_t particle,
                                                       const double force[3], const double rate[3]);

/// Replaces the time [s] and the state: positions [m] and velocities [m/s] of all particles
/// (3 each; the entries of fixed and driven particles are ignored: they stay at their
/// positions or follow their prescribed motion, see sm_simulation_set_driven). Re-initialises
/// the solver. SM_ERROR_NOT_FINITE, with nothing changed, for a non-finite time or free entry,
/// or a time at which a driven particle's prescribed position or a ramped external force is not
/// finite.
/// Only the particles' state changes: the dissipated energy, the inputs' work, the break events
/// recorded so far and the springs that broke stay as they are (setting an earlier time undoes no
/// break), so the energy balance of sm_simulation_dissipated_energy holds across the call only if
/// the caller accounts for the energy the new state adds. sm_simulation_reset restores broken
/// springs and clears the dissipated energy and the inputs' work.
SM_API sm_status sm_simulation_set_state(sm_simulation* sim, double time, const double* x, const double* v);

/// Breaks a spring now, as if its strain had just crossed its break strain (a cut, or a tear the
/// caller models itself): it is disabled, recorded as a break event at the current time
/// (sm_simulation_break), its elastic energy counts as dissipated, and a reset restores it.
/// Re-initialises the solver (once, at the next advance: cutting many springs between two advances
/// costs one restart, and each cut takes a time independent of the model's size). A spring already
/// broken or disabled is left as it is (SM_OK, no event); SM_ERROR_SPRING_INDEX, with nothing
/// changed, for an index out of range.
SM_API sm_status sm_simulation_break_spring(sm_simulation* sim, int32_t spring);

/// A snapshot of a simulation's state (sm_simulation_save_state): its time, the particles'
/// positions and velocities, the dissipated energy, the inputs' work, the inputs (external forces, driven
/// motions), the springs broken and the break events recorded so far. Not its statistics, which count the
/// work done, nor CVODE's history.
typedef struct sm_simulation_state sm_simulation_state;

/// Saves the simulation's current state in a new snapshot (NULL for a NULL simulation or when
/// memory runs out); free it with sm_simulation_state_destroy. The simulation is unchanged.
SM_API sm_simulation_state* sm_simulation_save_state(const sm_simulation* sim);

/// Puts the simulation back into a saved state, e.g. to repeat a step with other inputs (a
/// co-simulation master's rollback) or to branch from a checkpoint: everything the snapshot holds,
/// so that the energy balance, the break events and the broken springs are those of the save
/// (springs that the simulation's own model disables stay disabled).
/// Re-initialises the solver as new: the run goes on as a restart from that state would (within
/// the tolerances of the run that went on from it without a restart), and the same calls after
/// it give the same trajectory bit for bit in any simulation of the model that restores that
/// snapshot, whatever each did before (a rollback repeats a step exactly). The snapshot may come from
/// another simulation whose model has the same particles, motions and springs
/// (sm_simulation_update_model's rule); SM_ERROR_TOPOLOGY otherwise, SM_ERROR_NOT_FINITE when a
/// driven particle's position or an external force at the snapshot's time is not finite (a snapshot
/// read back from bytes whose motion or ramp overflows there; no advance gets there), SM_ERROR_OUT_OF_MEMORY
/// when the break events cannot be held, all with nothing changed. The snapshot stays valid.
SM_API sm_status sm_simulation_restore_state(sm_simulation* sim, const sm_simulation_state* state);

SM_API void sm_simulation_state_destroy(sm_simulation_state* state);

/// A snapshot as bytes, to store or send (an FMI master's serialised FMU state): its size
/// [bytes] (0 for NULL), the bytes written into buffer (SM_ERROR_INVALID_ARGUMENT if it holds
/// fewer than that size), and a snapshot read back from them (at any address; NULL with err for
/// bytes of another layout version, of the wrong length, damaged (a 64-bit checksum), holding
/// non-finite values or spring indices out of range, or listing a spring as broken twice).
/// sm_simulation_restore_state then checks the snapshot against the simulation. Numbers are in the machine's
/// byte order: read them on a machine of the same kind. A snapshot read back restores as the one saved does.
SM_API size_t sm_simulation_state_size(const sm_simulation_state* state);
SM_API sm_status sm_simulation_state_serialize(const sm_simulation_state* state, void* buffer, size_t size);
SM_API sm_simulation_state* sm_simulation_state_deserialize(const void* buffer, size_t size, sm_error* err);

/// Back to time 0 and the model's initial state (driven particles at their initial position
/// and velocity again), no external forces, springs as at the start (those that broke restored;
/// springs disabled in the model stay disabled, see sm_simulation_update_model), dissipated
/// energy, inputs' work, statistics and break events cleared. The model is the simulation's own: the one it
/// was created from, or the last one sm_simulation_update_model gave it (its constants and initial state).
/// The solver starts as new: the same calls as after creation from that model repeat that run bit for bit.
SM_API sm_status sm_simulation_reset(sm_simulation* sim);

/// Takes new constants (stiffness, damping, rest lengths, masses, loads, gravity, mass damping) from a
/// model of the same topology (same particle count and motions, same spring endpoints and kinds);
/// keeps the state of the free particles and broken springs, the dissipated energy and the inputs'
/// work (the energies change with the constants: the energy balance holds across the call only
/// if the caller accounts for that); re-initialises the solver.
/// SM_ERROR_TOPOLOGY otherwise. Fixed particles take the new model's positions (a fixed particle
/// moved that way jumps, as a driven one set elsewhere does); driven ones keep their motion.
/// Springs disabled in the new model are disabled from the start (a reset keeps them so),
/// except those that broke in this simulation: a copy of sm_simulation_model() has them
/// disabled, and a reset still restores them. External forces stay as set. Refused for lack of
/// memory (SM_ERROR_OUT_OF_MEMORY, or SM_ERROR_SOLVER when CVODE's own allocation failed), the
/// simulation keeps its model and state, and the next advance restarts CVODE there.
SM_API sm_status sm_simulation_update_model(sm_simulation* sim, const sm_model* model);

/// The simulation's own model (springs that broke are disabled in it). The pointer stays valid
/// until the next successful sm_simulation_update_model, which replaces the model, or
/// sm_simulation_destroy; a reset keeps it (and restores its springs). The simulation changes
/// this model in sm_simulation_advance (springs that break), sm_simulation_reset and
/// sm_simulation_update_model: another thread must not read it during those calls.
SM_API const sm_model* sm_simulation_model(const sm_simulation* sim);

/// Solver statistics since creation or the last reset (sm_statistics).
SM_API sm_statistics sm_simulation_statistics(const sm_simulation* sim);
/// Springs broken so far, and the index-th of them in the order they broke ({NaN, -1} for an
/// index out of range).
SM_API int32_t sm_simulation_break_count(const sm_simulation* sim);
SM_API sm_break_event sm_simulation_break(const sm_simulation* sim, int32_t index);

/// Linear solver actually in use (AUTO resolved). With SM_METHOD_ADAMS, which uses none, the
/// one the options name, resolved as for BDF. SM_SOLVER_COUNT for a NULL simulation.
SM_API sm_linear_solver sm_simulation_solver(const sm_simulation* sim);

/// Message of the last failed call that modifies the simulation (advance, set_driven,
/// set_external_force, set_state, break_spring, restore_state, reset, update_model), "" after a
/// successful one.
SM_API const char* sm_simulation_last_error(const sm_simulation* sim);

#ifdef __cplusplus
}
#endif

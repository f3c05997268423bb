// Internal layout of sm_simulation, shared by simulation.c, simulation_create.c,
// simulation_callbacks.c, simulation_events.c, simulation_state.c and the linear solvers
// (linear_solver_*.c).
//
// The CVODE state vector holds the free particles only, followed by two energies: the dissipated
// energy e and the work w the inputs did, less the driven particles' kinetic energy K_d,
//   y = [x_free (3 nf) ; v_free (3 nf) ; e ; w - K_d],
//   y' = [v ; M^-1 f(x, v) ; P_dissipated ; P_input - sum m a . v over the driven particles]
// (the inputs' work is w - K_d + K_d, the latter from the paths: sm_simulation_input_work).
// Constrained particles take their positions from the simulation's own arrays: fixed ones
// from the model, driven ones from x(t) = drive_position + drive_velocity s + drive_acceleration
// s^2 / 2, s = t - drive_time.
#pragma once

#include "springmass/simulation.h"
#include "sundials_compat.h"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

// Components of CVODE's state after the particles' 6 nf: the dissipated energy and the inputs' work.
#define SM_ENERGY_COMPONENTS 2

// A particle's input as it was before its first change since the last advance (input_origins.c):
// a driven particle's path (position [m], velocity [m/s], acceleration [m/s^2] from `time` [s]), or
// a free particle's external force (force [N], rate [N/s] from `time`; acceleration unused).
typedef struct sm_input_origin {
	int32_t particle;
	double value[3];
	double rate[3];
	double acceleration[3];
	double time;
} sm_input_origin;

// What the inputs' jumps since the last advance leave to CVODE's history, which the advance
// restarts if its interval times the rate this makes exceeds 1 (note_input_change in simulation.c):
// the largest velocity change per second a jump makes at a free particle (|jump| / m), over that
// velocity's error tolerance [1/s], and the jumps of the inputs' power and of the dissipated power
// that the drives make, summed over every drive that jumped, as they jump the energies' rates
// together [W].
typedef struct sm_input_jumps {
	double rate;              // [1/s]
	double input_power;       // [W]
	double dissipated_power;  // [W]
} sm_input_jumps;

// The flags an input change sets, as they were before the first change since the last advance.
typedef struct sm_input_flags {
	bool need_restart;
	bool input_jumped;
	bool input_changed;
	double jump_work;  // [J]
	sm_input_jumps jumps;
} sm_input_flags;

struct sm_simulation {
	sm_simulation_def def;
	sm_linear_solver solver;  // resolved (never AUTO)
	SUNContext context;
	void* cvode;
	N_Vector y;           // state at `time`
	N_Vector y_saved;     // state before the last CVode call (restored if a failure spoils y)
	N_Vector tolerances;  // absolute tolerance per component
	SUNMatrix matrix;     // NULL for the matrix-embedded solvers
	SUNLinearSolver linear_solver;
	SUNNonlinearSolver fixed_point;  // Adams only
	bool need_restart;               // something requires CVodeReInit before the next step
	bool forget_factor;              // that restart also drops the cholmod solver's factor (after a restore)
	bool input_jumped;               // an input jumped since CVODE's last (re)initialisation
	bool input_changed;              // an input jumped since the last advance began
	// CVODE found a spring break at break_time, past the time the last advance interpolated
	// (roots_found tells which); the next advance breaks it there.
	bool break_pending;
	bool stopped;       // the caller's on_step returned false during this CVode call
	double break_time;  // CVODE's time [s]

	sm_model* model;           // own copy; broken springs disabled in it
	uint8_t* initial_enabled;  // per spring: enabled in the model given to create/update
	uint64_t topology;         // sm_simulation_topology_hash of the model, which update_model keeps
	int32_t particle_count;
	int32_t spring_count;
	int32_t free_count;
	int64_t dofs;             // 3 * free_count
	int32_t* free_particles;  // particle index of each free particle
	int32_t constrained_count;
	int32_t* constrained;  // particle indices of fixed and driven particles
	double* inverse_mass;  // per free particle [1/kg]
	double* mass_dof;      // per free degree of freedom [kg]

	double time;  // [s]
	// CVODE integrates on its own time axis, t - time_origin, with the origin at its last
	// (re)initialisation: its steps then keep their precision however large the simulation's time
	// (a state set at t = 1e14 s, where a double resolves only 0.016 s). Every time CVODE sees or
	// gives ("CVODE's time" below) is on that axis.
	double time_origin;  // [s]
	double* position;    // all particles at `time` [m]
	double* velocity;    // [m/s]
	// Inputs. A particle's external force is external_force + force_rate (t - force_time); a driven
	// particle's position drive_position + drive_velocity s + drive_acceleration s^2 / 2 at
	// s = t - drive_time (3 per particle, times 1 per particle).
	double* external_force;    // [N]
	double* force_rate;        // [N/s]
	double* force_time;        // [s]
	int32_t ramping_forces;    // particles whose force_rate is not 0
	int32_t forced_particles;  // free particles whose external force or force_rate is not 0
	int32_t driven_count;      // driven particles
	// The springs at each driven particle, whose energy a jump of the particle changes: those of
	// particle i are driven_springs[driven_spring_start[i] .. driven_spring_start[i + 1] - 1]
	// (none for the other particles).
	int32_t* driven_spring_start;  // particle_count + 1
	int32_t* driven_springs;
	double* drive_position;      // [m]
	double* drive_velocity;      // [m/s]
	double* drive_acceleration;  // [m/s^2]
	double* drive_time;          // [s]
	// The inputs changed since the last advance, as they were before (input_origins.c): an input
	// set back to its origin before the next advance is no change, and once every one is back the
	// flags are as before the first.
	int32_t* origin_slot;  // per particle: its entry in origins, or -1
	sm_input_origin* origins;
	int32_t origin_count;
	int32_t origin_capacity;
	bool origins_lost;  // a change could not be recorded (out of memory): none counts as undone
	// A new state, a model update or a cut came after the records were made: an input set back
	// takes its recorded values, but counts as a change (the restart it asked for stays).
	bool origins_spanned;
	sm_input_flags flags_before;

	// Work arrays of the right-hand side and the Jacobian (all particles).
	double* work_position;
	double* work_velocity;
	double* work_force;
	double* work_external;  // the external forces at one time, when some ramp [N]
	// The inputs' work at jumps of driven particles (the energy each jump added beyond their
	// kinetic energy), and at changes of time or mass of the driven particles (what keeps the work
	// as it was while their kinetic energy changes), kept beside CVODE's state; after a restore, the
	// snapshot's work (sm_simulation_start_input_work) [J].
	double jump_work;
	sm_input_jumps jumps;  // the inputs' jumps since the last advance

	// Breakable springs: one root function each.
	int32_t root_count;
	int32_t* root_spring;
	double* root_limit;   // l0 (1 + break_strain) [m]
	double* root_values;  // the root functions at one time (work) [m]
	int* roots_found;     // per breakable spring: > 0 when it breaks at the next event
	// The search of each step for strain excursions between its ends (simulation_events.c).
	double* crossing_time;    // per breakable spring: its first crossing in the step searched [s]
	double* taylor_position;  // (max order + 1) x 3 per particle: positions' scaled derivatives [m]
	double* reach;            // per particle: a bound of its distance from where the step began [m]
	N_Vector interpolated;    // a derivative of CVODE's polynomial at one time (work)
	double searched_until;    // CVODE time up to which its last step has been searched [s]

	sm_break_event* breaks;
	int32_t break_count;
	int32_t break_capacity;

	// Sparse Jacobian over the free degrees of freedom (dense, KLU and cholmod solvers; pcg uses
	// the springs' factored blocks only).
	sm_sparse_jacobian* pattern;
	double* dfdx;               // values in the pattern's order [N/m]
	double* dfdv;               // [N s/m]
	int64_t* klu_row_pointers;  // pattern of the (6nf + 2) KLU matrix, copied into it on every fill
	int64_t* klu_column_indices;
	// The springs' Jacobian blocks, from which the dense and KLU solvers' fills assemble dfdx and
	// dfdv (the reduced solvers keep their own).
	sm_spring_jacobians* jacobian_records;

	// Counters; CVODE's own counters restart with every CVodeReInit, so what they had reached
	// is folded into `base` first.
	sm_statistics base;
	int64_t rhs_evaluations;
	int64_t jacobian_evaluations;
	int64_t linear_iterations;
	int64_t factorizations;

	char last_error[SM_ERROR_MESSAGE_CAPACITY];
	char solver_message[SM_ERROR_MESSAGE_CAPACITY];  // CVODE's last error text
	// The last Jacobian evaluation ran out of memory: CVODE reports only that the linear
	// solver's set-up failed.
	bool jacobian_out_of_memory;
};

// Seconds on a monotonic clock [s].
double sm_simulation_clock(void);

// Fills x and v for all particles from a CVODE state y at CVODE's time t.
void sm_simulation_unpack(sm_simulation* sim, double t, const double* y, double* x, double* v);
// The external forces on all particles at CVODE's time t [N]: sim->external_force itself when
// none ramps, else sim->work_external filled.
const double* sm_simulation_external_forces(sm_simulation* sim, double t);

// CVODE's time of the simulation's time t [s].
static inline double sm_simulation_cvode_time(const sm_simulation* sim, double t)
{
	return t - sim->time_origin;
}

// Length of CVODE's state vector, and the places of the dissipated energy and the inputs' work in it.
static inline int64_t sm_simulation_state_length(const sm_simulation* sim)
{
	return 2 * sim->dofs + SM_ENERGY_COMPONENTS;
}
static inline int64_t sm_simulation_dissipated_index(const sm_simulation* sim)
{
	return 2 * sim->dofs;
}
static inline int64_t sm_simulation_work_index(const sm_simulation* sim)
{
	return 2 * sim->dofs + 1;
}

// Whether the linear solver is the reduced one (linear_solver_reduced.c). Adams' fixed-point
// iteration has none, whatever the options name.
static inline bool sm_simulation_has_reduced_solver(const sm_simulation* sim)
{
	return sim->linear_solver != NULL &&
	       (sim->solver == SM_SOLVER_REDUCED_PCG || sim->solver == SM_SOLVER_REDUCED_CHOLMOD);
}

// Helpers of simulation.c that creation (simulation_create.c) and the snapshots
// (simulation_state.c) use too.
// Writes the free particles' entries of x and v into y (the energies e and w untouched).
void sm_simulation_pack(const sm_simulation* sim, const double* x, const double* v, double* y);
// Writes the formatted message into sim->last_error; returns status.
sm_status sm_simulation_fail(sm_simulation* sim, sm_status status, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
// Sets sim->position and sim->velocity (all particles) from the CVODE state y at sim->time.
void sm_simulation_refresh_outputs(sm_simulation* sim);
// Enables each spring as the model given to create or update_model does (broken ones restored).
void sm_simulation_restore_springs(sm_simulation* sim);
// The first driven particle whose position or velocity at time t is not finite under the given
// motions, or -1.
int32_t sm_simulation_overflowing_driven_particle(const sm_simulation* sim, double t, const double* position,
                                                  const double* velocity, const double* acceleration,
                                                  const double* start);
// The first particle whose external force at time t is not finite under the given ramps, or -1.
int32_t sm_simulation_overflowing_force(const sm_simulation* sim, double t, const double* force,
                                        const double* rate, const double* start);

// Steps of creation (simulation_create.c) that a reset and a model update repeat.
// Masses of the free particles (inverse_mass, mass_dof), from the simulation's model.
void sm_simulation_refresh_masses(sm_simulation* sim);
// Everything from the model's stored initial state: positions, velocities, driven motion, no
// external forces, e = w = 0, at time 0.
void sm_simulation_load_initial_state(sm_simulation* sim);
// Makes the inputs' work read `work` [J] exactly at the current state (its outputs refreshed):
// CVODE's part minus the driven particles' kinetic energy (+0 at rest, or when that energy
// overflows), the rest in jump_work.
void sm_simulation_start_input_work(sm_simulation* sim, double work);

// The functions CVODE calls, given to it at creation (simulation_callbacks.c); user data: the
// simulation.
// CVODE's right-hand side y' = [v; M^-1 f; P_dissipated; P_input - m a . v] at CVODE's time t, also the
// explicit step of an advance too short for CVODE: 0, or 1 (recoverable) where the state or its
// derivative is not finite.
int sm_simulation_rhs(sunrealtype t, N_Vector yv, N_Vector ydotv, void* user_data);
// The power the inputs deliver [W] at the velocities v and forces f of all particles (external
// forces included) and the external forces `external`; the part of it CVODE integrates, without
// the rate m a . v of the driven particles' kinetic energy; and that energy [J].
double sm_simulation_input_power_at(const sm_simulation* sim, const double* v, const double* f,
                                    const double* external);
double sm_simulation_driving_power_at(const sm_simulation* sim, const double* v, const double* f,
                                      const double* external);
double sm_simulation_driven_kinetic_energy(const sm_simulation* sim, const double* v);
// The Jacobian of the dense solver's matrix and of the KLU solver's CSR matrix (whose pattern
// sm_simulation_build_klu_pattern builds first, SM_ERROR_OUT_OF_MEMORY if it cannot): 0, or -1.
int sm_simulation_jacobian_dense(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
                                 N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
sm_status sm_simulation_build_klu_pattern(sm_simulation* sim);
int sm_simulation_jacobian_sparse(sunrealtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void* user_data,
                                  N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
// CVODE's error handler: its message into sim->solver_message, with the function's name and the
// times on the simulation's axis. SUNDIALS 7 calls the handlers of the context (for CVODE and the
// modules it uses), 6 the one of the CVODE memory.
#if SUNDIALS_VERSION_MAJOR >= 7
void sm_simulation_error_handler(int line, const char* function, const char* file, const char* msg,
                                 SUNErrCode code, void* user_data, SUNContext context);
#else
void sm_simulation_error_handler(int error_code, const char* module, const char* function, char* msg,
                                 void* user_data);
#endif

// Input changes undone before the next advance (input_origins.c).
// Forgets the recorded origins: after an advance, a reset or a restore, from which the inputs'
// earlier values are no longer "as they were".
void sm_input_origins_forget(sm_simulation* sim);
// Keeps the recorded origins over a new state, a model update or a cut, which restart CVODE but
// leave the inputs as they are: an input set back to its origin then takes the origin's values, to
// the bit, and is a change still (sm_input_origins_settle returns false once for them).
void sm_input_origins_span(sm_simulation* sim);
// Records the particle's input as it is now, before its first change since the origins were
// forgotten (nothing if it is recorded already), and with the first one the flags as they are.
void sm_input_origins_note(sm_simulation* sim, int32_t particle, bool driven);
// The particle's recorded origin, or NULL.
const sm_input_origin* sm_input_origins_find(const sm_simulation* sim, int32_t particle);
// Drops the particle's origin, its input being back there; when no other remains and none was
// lost or spanned, puts the flags back as they were before the first change and returns true.
bool sm_input_origins_settle(sm_simulation* sim, int32_t particle);

// Snapshots (simulation_state.c).
// What sm_simulation_update_model requires to match, as one hash: the counts, each particle's
// motion, each spring's ends and kind. A simulation takes it of its model once, at creation.
uint64_t sm_simulation_topology_hash(const sm_model* m);

// Spring breaks (simulation_events.c).
// The root functions for the model's breakable springs, given to CVODE (recomputed when the model
// changes). The new arrays are made before the old ones go: out of memory for them, the simulation
// keeps the old ones and CVODE the root functions it was given for them.
sm_status sm_simulation_build_events(sm_simulation* sim);
// Records a break of a spring at time t [s] and disables it in the simulation's model;
// SM_ERROR_OUT_OF_MEMORY, with nothing changed, when the event cannot be held.
sm_status sm_simulation_record_break(sm_simulation* sim, double t, int32_t spring);
// Breaks, at the current time, the intact springs marked in roots_found (> 0), their elastic
// energy counted as dissipated; CVODE restarts at the next step.
sm_status sm_simulation_break_springs(sm_simulation* sim);
// CVODE's root functions see a strain rise through a spring's limit; a spring already beyond it
// when an advance begins (placed there by the model's start, a new state, a moved driven particle
// or a lowered break strain) breaks at once.
sm_status sm_simulation_break_overstretched_springs(sm_simulation* sim);
// After each CVode call in one-step mode that returned flag at *reached (the end of its step, a
// stop time, or a root CVODE found, with the state there in y; new_step: the call took a step):
// searches CVODE's polynomial over the part of the step not yet searched for a strain that rises
// through its break strain, also where it falls back before the step ends. The first crossing
// there, or CVODE's root if none comes before it, is the next event: returns CV_ROOT_RETURN with
// *reached and y at it and roots_found marking the springs that break there (every intact one at
// or beyond its limit). Otherwise returns flag unchanged; also when flag < 0 or the model has no
// breakable spring. A negative CVODE flag if its polynomial cannot be read.
int sm_simulation_search_step(sm_simulation* sim, int flag, bool new_step, double* reached);
// The first s in [0, 1] at which the polynomial of Bernstein coefficients b[0..n] (finite, n at most
// 24) is >= 0 after being < 0, located to `resolution` (of s): the right end of the first interval
// of that width over which it rises from below 0 to 0 or above (0 if it is >= 0 at s = 0); -1 if
// it stays below 0. The search of sm_simulation_search_step, for one spring.
double sm_simulation_first_rise(const double* b, int n, double resolution);
// Frees what sm_simulation_build_events allocated.
void sm_simulation_free_events(sm_simulation* sim);

// Fills sim->dfdx and sim->dfdv at the CVODE state y (time t) with the given variant
// (simulation_callbacks.c).
int sm_simulation_fill_jacobian(sm_simulation* sim, double t, const double* y, sm_jacobian_variant variant);

// The reduced second-order linear solver (linear_solver_reduced.c): a SUNLinearSolver that
// solves (M - gamma D - gamma^2 K) dv = M bv + gamma K bx by conjugate gradients, preconditioned
// by block Jacobi and its coarse correction (use_cholmod false) or by the Cholesky factor of an
// earlier Newton matrix (true).
SUNLinearSolver sm_reduced_solver_create(sm_simulation* sim, bool use_cholmod);
// Its set-up, given to CVodeSetPreconditioner (user data: the simulation) without a
// preconditioner solve, which the solver does itself: evaluates the Jacobian afresh (always,
// whatever CVODE allows).
int sm_reduced_pset(sunrealtype t, N_Vector y, N_Vector fy, sunbooleantype jok, sunbooleantype* jcur,
                    sunrealtype gamma, void* user_data);
// Forgets the Jacobian the reduced solver holds, so that it evaluates one at its next solve
// (after a re-initialisation: a new state may come with the same CVODE time). With
// `forget_factor` also the Cholesky factor of an earlier Newton matrix (the cholmod solver's
// preconditioner), so that a reset simulation repeats its first run bit for bit; after other
// restarts the earlier factor stays a good preconditioner.
void sm_reduced_solver_invalidate(SUNLinearSolver ls, bool forget_factor);
// After the simulation's model changed its constants (sm_simulation_update_model): builds again
// what was built from the constants at creation (the multilevel path's aggregates follow the
// strong springs), so that the solver is the one a simulation created from the new model would
// have. False, with the solver unchanged, when out of memory.
bool sm_reduced_solver_rebuild(SUNLinearSolver ls);
// For the tests: q = A p with A = M (1 + gamma alpha) - gamma D - gamma^2 K of the reduced
// solver, the Jacobian (definite variant) evaluated at the simulation's current state, formed
// as the solver forms it in its conjugate gradients; p and q over all particles (3 each, p zero
// and q set to zero at constrained particles). Returns 0, or -1 if the Jacobian cannot be
// evaluated. The next solve evaluates its Jacobian afresh.
int sm_reduced_solver_product(SUNLinearSolver ls, double gamma, const double* p, double* q);
// The right-hand side's share in the Jacobian evaluation: whether the solver wants the Jacobian's
// records from the right-hand side at time t (false: it holds the Jacobian of the step at t);
// if so, sm_reduced_rhs_forces evaluates the forces at x, v (unpacked from CVODE's state y) into f
// and the records with them, as sm_model_forces_power_and_jacobians does (split into the solver's
// chunks for a large model), and returns the dissipated power [W].
bool sm_reduced_rhs_wants_records(SUNLinearSolver ls, double t);
double sm_reduced_rhs_forces(SUNLinearSolver ls, double t, const double* y, const double* x, const double* v,
                             const double* f_external, double* f);

// Replaces the arithmetic operations in a serial N_Vector's table of operations (vector_ops.c)
// by loops compiled with the project's flags: Debian's SUNDIALS is built without optimisation.
// Clones copy the table, so install before CVodeInit clones the state vector. A vector of
// another kind is left as it is.
void sm_vector_ops_install(N_Vector v);

// Wraps a matrix-based SUNLinearSolver so that its setup and solve are timed into the
// simulation's statistics; takes ownership of inner (simulation_callbacks.c).
SUNLinearSolver sm_timed_solver_create(sm_simulation* sim, SUNLinearSolver inner);

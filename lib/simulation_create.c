// Simulation: creation and destruction. The definition: its defaults, the names of its methods and
// linear solvers, and its check. A simulation: its arrays, its initial state from the model, and
// CVODE set up with its tolerances, root functions and linear solver (the one SM_SOLVER_AUTO
// chooses; dense LU, KLU or the reduced solver for BDF, Adams' fixed-point iteration without one).
// The functions CVODE is given: simulation_callbacks.c.
#include "model_internal.h"
#include "simulation_internal.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

// Free degrees of freedom up to which SM_SOLVER_AUTO picks the dense solver; above, it picks
// the reduced conjugate-gradient solver. Measured with `springmass run` on ropes, small sheets,
// a block, a mesh and anchored sheets of 1 to 9 free particles (bench/README.md, "The linear
// solver auto picks"): SUNDIALS' dense LU (Debian's archives are built without optimisation)
// costs about what the reduced solver does with 1 or 2 free particles, 1.5 - 2.6 times as much
// from 3 to 5 and 3 - 5 times from 6 on. On the benchmark cloth from n = 8 to 64
// block-Jacobi conjugate gradients beat the CHOLMOD-preconditioned ones by 1.3 to 1.7 times and
// KLU on the full system by more.
#define AUTO_DENSE_MAX_DOFS 6

sm_simulation_def sm_default_simulation_def(void)
{
	sm_simulation_def def;
	memset(&def, 0, sizeof def);
	def.method = SM_METHOD_BDF;
	def.solver = SM_SOLVER_AUTO;
	def.jacobian = SM_JACOBIAN_EXACT;
	def.relative_tolerance = 1e-6;
	def.absolute_tolerance_position = 1e-8;
	def.absolute_tolerance_velocity = 1e-6;
	def.max_step = 0.0;
	def.max_steps = 100000;
	def.restart_on_input_change = true;
	def.stability_limit_detection = true;
	def.threads = 1;
	return def;
}

static const char* const solver_names[SM_SOLVER_COUNT] = {"auto", "dense", "klu", "pcg", "cholmod"};

const char* sm_linear_solver_name(sm_linear_solver solver)
{
	if ((int)solver < 0 || solver >= SM_SOLVER_COUNT)
		return "unknown";
	return solver_names[solver];
}

const char* sm_method_name(sm_method method)
{
	switch (method) {
	case SM_METHOD_BDF: return "bdf";
	case SM_METHOD_ADAMS: return "adams";
	}
	return "unknown";
}

sm_status sm_method_from_name(const char* name, sm_method* method)
{
	if (name == NULL || method == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (strcmp(name, "bdf") == 0)
		*method = SM_METHOD_BDF;
	else if (strcmp(name, "adams") == 0)
		*method = SM_METHOD_ADAMS;
	else
		return SM_ERROR_INVALID_ARGUMENT;
	return SM_OK;
}

const char* sm_input_changes_name(bool restart)
{
	return restart ? "restart" : "keep";
}

sm_status sm_input_changes_from_name(const char* name, bool* restart)
{
	if (name == NULL || restart == NULL)
		return SM_ERROR_INVALID_ARGUMENT;
	if (strcmp(name, "restart") == 0)
		*restart = true;
	else if (strcmp(name, "keep") == 0)
		*restart = false;
	else
		return SM_ERROR_INVALID_ARGUMENT;
	return SM_OK;
}

sm_status sm_linear_solver_from_name(const char* name, sm_linear_solver* solver)
{
	for (int i = 0; name != NULL && solver != NULL && i < SM_SOLVER_COUNT; i++)
		if (strcmp(name, solver_names[i]) == 0) {
			*solver = (sm_linear_solver)i;
			return SM_OK;
		}
	return SM_ERROR_INVALID_ARGUMENT;
}

// ---------------------------------------------------------------------------------------------
// Creation
// ---------------------------------------------------------------------------------------------

static sm_status check_def(const sm_simulation_def* def, sm_error* err)
{
	if ((int)def->method < 0 || def->method > SM_METHOD_ADAMS)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown method %d",
		                    (int)def->method);
	if ((int)def->solver < 0 || def->solver >= SM_SOLVER_COUNT)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown linear solver %d",
		                    (int)def->solver);
	if ((int)def->jacobian < 0 || def->jacobian > SM_JACOBIAN_DEFINITE)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: unknown Jacobian variant %d",
		                    (int)def->jacobian);
	const struct {
		const char* name;
		double value;
	} positive[] = {{"relative_tolerance", def->relative_tolerance},
	                {"absolute_tolerance_position", def->absolute_tolerance_position},
	                {"absolute_tolerance_velocity", def->absolute_tolerance_velocity}};
	for (size_t i = 0; i < sizeof positive / sizeof positive[0]; i++)
		if (!(isfinite(positive[i].value) && positive[i].value > 0.0))
			return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: %s = %g must be finite and > 0",
			                    positive[i].name, positive[i].value);
	// Below SM_MIN_ABSOLUTE_TOLERANCE CVODE's error norm overflows (simulation.h).
	// Both numbers in the digits that read back: 9.9999999999e-151 is not 1e-150.
	const bool position_ok = def->absolute_tolerance_position >= SM_MIN_ABSOLUTE_TOLERANCE;
	if (!position_ok || !(def->absolute_tolerance_velocity >= SM_MIN_ABSOLUTE_TOLERANCE)) {
		char value[SM_NUMBER_TEXT_CAPACITY], floor[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(position_ok ? def->absolute_tolerance_velocity : def->absolute_tolerance_position,
		                 value);
		sm_format_number(SM_MIN_ABSOLUTE_TOLERANCE, floor);
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: absolute_tolerance_%s = %s must be at least %s: CVODE's error norm "
		                    "sums (error / atol)^2, which overflows for smaller tolerances",
		                    position_ok ? "velocity" : "position", value, floor);
	}
	if (!(def->relative_tolerance < 1.0))
		return sm_error_set(
		    err, SM_ERROR_INVALID_ARGUMENT,
		    "simulation: relative_tolerance = %g must be < 1 (a relative error of 100 %% or more)",
		    def->relative_tolerance);
	// Below the machine epsilon CVODE cannot meet it (SM_MIN_RELATIVE_TOLERANCE, simulation.h).
	// Both in their shortest exact digits: a value an ulp below the floor reads as below it.
	if (!(def->relative_tolerance >= SM_MIN_RELATIVE_TOLERANCE)) {
		char value[SM_NUMBER_TEXT_CAPACITY], floor[SM_NUMBER_TEXT_CAPACITY];
		sm_format_number(def->relative_tolerance, value);
		sm_format_number(SM_MIN_RELATIVE_TOLERANCE, floor);
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: relative_tolerance = %s must be at least %s, the machine epsilon: "
		                    "CVODE cannot hold errors below the rounding of the state",
		                    value, floor);
	}
	if (!(isfinite(def->max_step) && def->max_step >= 0.0))
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: max_step = %g must be finite and >= 0", def->max_step);
	if (def->max_step > 0.0 && def->max_step <= SM_MAX_STEP_FLOOR)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT,
		                    "simulation: max_step = %g s is too small for CVODE, whose 1 / max_step would be "
		                    "beyond the largest double; give 0 for no limit or a step above %g s",
		                    def->max_step, SM_MAX_STEP_FLOOR);
	if (def->max_steps <= 0)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: max_steps = %d must be > 0",
		                    (int)def->max_steps);
	if (def->threads < 1)
		return sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: threads = %d must be >= 1",
		                    (int)def->threads);
	return SM_OK;
}

static sm_linear_solver resolve_solver(const sm_simulation_def* def, int64_t dofs)
{
	if (def->solver != SM_SOLVER_AUTO)
		return def->solver;
	if (dofs <= AUTO_DENSE_MAX_DOFS)
		return SM_SOLVER_DENSE;
	return SM_SOLVER_REDUCED_PCG;
}

// Masses of the free particles, from the simulation's model.
void sm_simulation_refresh_masses(sm_simulation* sim)
{
	for (int32_t k = 0; k < sim->free_count; k++) {
		const double m = sim->model->mass[sim->free_particles[k]];
		sim->inverse_mass[k] = 1.0 / m;
		sim->mass_dof[3 * k] = sim->mass_dof[3 * k + 1] = sim->mass_dof[3 * k + 2] = m;
	}
}

// The springs at each driven particle (driven_spring_start, driven_springs): counted, then listed.
static sm_status build_driven_springs(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	int32_t* start = calloc((size_t)m->particle_count + 2, sizeof(int32_t));
	if (start == NULL)
		return SM_ERROR_OUT_OF_MEMORY;
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t ends[2] = {m->spring_a[s], m->spring_b[s]};
		for (int e = 0; e < 2; e++)
			start[ends[e] + 2] += m->motion[ends[e]] == SM_PARTICLE_DRIVEN;
	}
	for (int32_t i = 0; i < m->particle_count; i++)
		start[i + 2] += start[i + 1];
	int32_t* springs = malloc(((size_t)start[m->particle_count + 1] + 1) * sizeof(int32_t));
	if (springs == NULL) {
		free(start);
		return SM_ERROR_OUT_OF_MEMORY;
	}
	// start[i + 1] is the next place of particle i's springs, and ends as the end of them.
	for (int32_t s = 0; s < m->spring_count; s++) {
		const int32_t ends[2] = {m->spring_a[s], m->spring_b[s]};
		for (int e = 0; e < 2; e++)
			if (m->motion[ends[e]] == SM_PARTICLE_DRIVEN)
				springs[start[ends[e] + 1]++] = s;
	}
	sim->driven_spring_start = start;
	sim->driven_springs = springs;
	return SM_OK;
}

// Everything from the model's stored initial state: positions, velocities, driven motion,
// no external forces, e = w = 0.
void sm_simulation_load_initial_state(sm_simulation* sim)
{
	const sm_model* m = sim->model;
	const size_t n3 = 3 * (size_t)sim->particle_count;
	if (n3 > 0) {  // a model without particles has no arrays to copy from
		memcpy(sim->drive_position, m->position, n3 * sizeof(double));
		memcpy(sim->drive_velocity, m->velocity, n3 * sizeof(double));
	}
	for (int32_t i = 0; i < sim->particle_count; i++)
		sim->drive_time[i] = sim->force_time[i] = 0.0;
	memset(sim->drive_acceleration, 0, n3 * sizeof(double));
	memset(sim->external_force, 0, n3 * sizeof(double));
	memset(sim->force_rate, 0, n3 * sizeof(double));
	sim->ramping_forces = 0;
	sim->forced_particles = 0;
	double* y = N_VGetArrayPointer(sim->y);
	sm_simulation_pack(sim, m->position, m->velocity, y);
	y[sm_simulation_dissipated_index(sim)] = 0.0;
	y[sm_simulation_work_index(sim)] = 0.0;
	sim->jump_work = 0.0;
	sim->jumps = (sm_input_jumps){0.0, 0.0, 0.0};
	sim->time = 0.0;
	sim->time_origin = 0.0;
	sm_simulation_refresh_outputs(sim);
	sm_simulation_start_input_work(sim, 0.0);  // no work yet
}

// CVODE's part of the work is less the driven particles' kinetic energy, which
// sm_simulation_input_work adds back before jump_work: -K + K is +0 exactly, and the work reads
// as given, to the bit.
void sm_simulation_start_input_work(sm_simulation* sim, double work)
{
	const double driven_kinetic = sm_simulation_driven_kinetic_energy(sim, sim->velocity);
	N_VGetArrayPointer(sim->y)[sm_simulation_work_index(sim)] =
	    isfinite(driven_kinetic) && driven_kinetic > 0.0 ? -driven_kinetic : 0.0;
	sim->jump_work = work;
}

static sm_status attach_linear_solver(sm_simulation* sim)
{
	if (sim->def.method == SM_METHOD_ADAMS) {
		SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(sim->y, 0, sim->context);
		if (!nls)
			return SM_ERROR_OUT_OF_MEMORY;
		// CVODE does not take ownership of the nonlinear solver: the simulation frees it.
		int flag = CVodeSetNonlinearSolver(sim->cvode, nls);
		if (flag != CV_SUCCESS) {
			SUNNonlinSolFree(nls);
			return SM_ERROR_SOLVER;
		}
		sim->fixed_point = nls;
		return SM_OK;
	}
	const int64_t n = sm_simulation_state_length(sim);
	switch (sim->solver) {
	case SM_SOLVER_DENSE: {
		sim->matrix = SUNDenseMatrix(n, n, sim->context);
		// SUNDIALS 7 built without its error checks returns the matrix without its entries when
		// their allocation fails.
		if (!sim->matrix || !SUNDenseMatrix_Data(sim->matrix))
			return SM_ERROR_OUT_OF_MEMORY;
		sim->linear_solver = sm_timed_solver_create(sim, SUNLinSol_Dense(sim->y, sim->matrix, sim->context));
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		// A Newton matrix at every step, as the reduced solvers have: one kept over several steps
		// (CVODE's default) no longer fits where a stiff spring turns, and Newton's iteration then
		// fails again and again and ends on inaccurate iterates. A pendulum on a rod of 1e8 N/m
		// at 120 degrees, default tolerances, eight periods: 14 585 steps, 2334 convergence
		// failures and its passages 2.4e-2 of a period off their time with the kept matrix (auto
		// picks dense for it); with a fresh one 12 798 steps, 106 failures and 9.1e-4 of a period
		// (tests/test_large_motions.c). The price is a Newton iteration more in about half of the
		// steps (each set-up resets CVODE's estimate of the convergence rate): the bundled
		// oscillator takes 812 right-hand sides over 5 s instead of 542, each with a 14 x 14 LU.
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, sim->matrix) != CVLS_SUCCESS ||
		    CVodeSetJacFn(sim->cvode, sm_simulation_jacobian_dense) != CVLS_SUCCESS ||
		    CVodeSetLSetupFrequency(sim->cvode, 1) != CV_SUCCESS ||
		    CVodeSetJacEvalFrequency(sim->cvode, 1) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_KLU: {
		if (sm_simulation_build_klu_pattern(sim) != SM_OK)
			return SM_ERROR_OUT_OF_MEMORY;
		sim->matrix = SUNSparseMatrix(n, n, sim->klu_row_pointers[n], CSR_MAT, sim->context);
		if (!sim->matrix || !SUNSparseMatrix_Data(sim->matrix) || !SUNSparseMatrix_IndexValues(sim->matrix) ||
		    !SUNSparseMatrix_IndexPointers(sim->matrix))  // as the dense matrix's entries
			return SM_ERROR_OUT_OF_MEMORY;
		sim->linear_solver = sm_timed_solver_create(sim, SUNLinSol_KLU(sim->y, sim->matrix, sim->context));
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, sim->matrix) != CVLS_SUCCESS ||
		    CVodeSetJacFn(sim->cvode, sm_simulation_jacobian_sparse) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_REDUCED_PCG:
	case SM_SOLVER_REDUCED_CHOLMOD: {
		sim->linear_solver = sm_reduced_solver_create(sim, sim->solver == SM_SOLVER_REDUCED_CHOLMOD);
		if (!sim->linear_solver)
			return SM_ERROR_OUT_OF_MEMORY;
		if (CVodeSetLinearSolver(sim->cvode, sim->linear_solver, NULL) != CVLS_SUCCESS ||
		    CVodeSetPreconditioner(sim->cvode, sm_reduced_pset, NULL) != CVLS_SUCCESS)
			return SM_ERROR_SOLVER;
		return SM_OK;
	}
	case SM_SOLVER_AUTO:
	case SM_SOLVER_COUNT: break;
	}
	return SM_ERROR_INVALID_ARGUMENT;
}

// CVODE's error weights w_i = 1 / (rtol |y_i| + atol_i), computed as CVodeSVtolerances' own
// function computes them (the same bits), from the simulation's absolute tolerances. Given to
// CVodeWFtolerances because CVodeSVtolerances clones the tolerance vector and SUNDIALS 6.4.1 then
// writes into the clone without checking that it was made: out of memory, that crashes.
static int error_weights(N_Vector yv, N_Vector wv, void* user_data)
{
	const sm_simulation* sim = user_data;
	const double* y = N_VGetArrayPointer(yv);
	const double* atol = N_VGetArrayPointer(sim->tolerances);
	double* w = N_VGetArrayPointer(wv);
	const double rtol = sim->def.relative_tolerance;
	const sunindextype n = N_VGetLength(yv);
	for (sunindextype i = 0; i < n; i++) {
		const double t = rtol * fabs(y[i]) + atol[i];
		if (t <= 0.0)
			return -1;  // as CVODE: a zero or negative weight is an error
		w[i] = 1.0 / t;
	}
	return 0;
}

// CVODE's errors go to sm_simulation_error_handler, which keeps their text for the simulation's
// error, and are not printed. SUNDIALS 7 has the handlers in the context, which starts with one
// that prints to stderr: the simulation's own context has its handler instead. SUNDIALS 6 has it
// in the CVODE memory.
static int capture_errors(sm_simulation* sim)
{
#if SUNDIALS_VERSION_MAJOR >= 7
	if (SUNContext_ClearErrHandlers(sim->context) != SUN_SUCCESS ||
	    SUNContext_PushErrHandler(sim->context, sm_simulation_error_handler, sim) != SUN_SUCCESS)
		return CV_MEM_FAIL;
	return CV_SUCCESS;
#else
	return CVodeSetErrHandlerFn(sim->cvode, sm_simulation_error_handler, sim);
#endif
}

static sm_status setup_cvode(sm_simulation* sim)
{
	const int64_t nd = sim->dofs;
	double* tol = N_VGetArrayPointer(sim->tolerances);
	for (int64_t i = 0; i < nd; i++) {
		tol[i] = sim->def.absolute_tolerance_position;
		tol[nd + i] = sim->def.absolute_tolerance_velocity;
	}
	// The energies [J] share the velocities' absolute tolerance.
	tol[sm_simulation_dissipated_index(sim)] = sim->def.absolute_tolerance_velocity;
	tol[sm_simulation_work_index(sim)] = sim->def.absolute_tolerance_velocity;
	sim->cvode = CVodeCreate(sim->def.method == SM_METHOD_ADAMS ? CV_ADAMS : CV_BDF, sim->context);
	if (!sim->cvode)
		return SM_ERROR_OUT_OF_MEMORY;
	if (capture_errors(sim) != CV_SUCCESS ||
	    CVodeInit(sim->cvode, sm_simulation_rhs, sm_simulation_cvode_time(sim, sim->time), sim->y) !=
	        CV_SUCCESS ||
	    CVodeWFtolerances(sim->cvode, error_weights) != CV_SUCCESS ||
	    CVodeSetUserData(sim->cvode, sim) != CV_SUCCESS ||
	    CVodeSetMaxNumSteps(sim->cvode, sim->def.max_steps) != CV_SUCCESS ||
	    CVodeSetMaxStep(sim->cvode, sim->def.max_step) != CV_SUCCESS ||
	    (sim->def.method == SM_METHOD_BDF &&
	     CVodeSetStabLimDet(sim->cvode, sim->def.stability_limit_detection) != CV_SUCCESS))
		return SM_ERROR_SOLVER;
	// CVODE's warnings that t + h rounds to t are not printed (its time axis starts at every
	// (re)initialisation, so they would come only after a long run without one).
	CVodeSetMaxHnilWarns(sim->cvode, -1);
	sm_status st = sm_simulation_build_events(sim);
	if (st != SM_OK)
		return st;
	return attach_linear_solver(sim);
}

sm_simulation* sm_simulation_create(const sm_model* model, const sm_simulation_def* def, sm_error* err)
{
	sm_error_clear(err);
	if (model == NULL) {
		sm_error_set(err, SM_ERROR_INVALID_ARGUMENT, "simulation: model is NULL");
		return NULL;
	}
	sm_simulation_def d = def ? *def : sm_default_simulation_def();
	if (check_def(&d, err) != SM_OK)
		return NULL;
	sm_simulation* sim = calloc(1, sizeof *sim);
	if (!sim) {
		sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "simulation: out of memory");
		return NULL;
	}
	sim->def = d;
	sim->model = sm_model_clone(model);
	if (!sim->model)
		goto out_of_memory;
	const sm_model* m = sim->model;
	const int32_t n = m->particle_count;
	// Unchanged for the simulation's life: update_model refuses another topology, and the model's
	// own changes (breaks) only disable springs.
	sim->topology = sm_simulation_topology_hash(m);
	sim->particle_count = n;
	sim->spring_count = m->spring_count;
	sim->free_count = m->free_count;
	sim->dofs = 3 * (int64_t)m->free_count;
	sim->constrained_count = n - m->free_count;
	sim->solver = resolve_solver(&d, sim->dofs);
	const size_t n3 = 3 * (size_t)n + 1;
	sim->initial_enabled = malloc((size_t)m->spring_count + 1);
	sim->free_particles = malloc(((size_t)sim->free_count + 1) * sizeof(int32_t));
	sim->constrained = malloc(((size_t)sim->constrained_count + 1) * sizeof(int32_t));
	sim->inverse_mass = malloc(((size_t)sim->free_count + 1) * sizeof(double));
	sim->mass_dof = malloc(((size_t)sim->dofs + 1) * sizeof(double));
	sim->origin_slot = malloc(((size_t)n + 1) * sizeof(int32_t));
	double** arrays[] = {&sim->position,       &sim->velocity,           &sim->external_force,
	                     &sim->force_rate,     &sim->force_time,         &sim->drive_position,
	                     &sim->drive_velocity, &sim->drive_acceleration, &sim->drive_time,
	                     &sim->work_position,  &sim->work_velocity,      &sim->work_force,
	                     &sim->work_external};
	for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
		if (!(*arrays[i] = calloc(n3, sizeof(double))))
			goto out_of_memory;
	if (!sim->initial_enabled || !sim->free_particles || !sim->constrained || !sim->inverse_mass ||
	    !sim->mass_dof || !sim->origin_slot)
		goto out_of_memory;
	for (int32_t i = 0; i < n; i++)
		sim->origin_slot[i] = -1;
	if (m->spring_count > 0)  // no array to copy from in a model without springs
		memcpy(sim->initial_enabled, m->enabled, (size_t)m->spring_count);
	for (int32_t i = 0, kf = 0, kc = 0; i < n; i++) {
		if (m->motion[i] == SM_PARTICLE_FREE)
			sim->free_particles[kf++] = i;
		else
			sim->constrained[kc++] = i;
		sim->driven_count += m->motion[i] == SM_PARTICLE_DRIVEN;
	}
	sm_simulation_refresh_masses(sim);
	if (build_driven_springs(sim) != SM_OK)
		goto out_of_memory;
	// The assembled sparse Jacobian (conjugate gradients use the springs' factored blocks only;
	// Adams, with fixed-point iteration, no Jacobian at all).
	const bool newton = sim->def.method != SM_METHOD_ADAMS;
	if (newton && (sim->solver == SM_SOLVER_DENSE || sim->solver == SM_SOLVER_KLU ||
	               sim->solver == SM_SOLVER_REDUCED_CHOLMOD)) {
		sim->pattern = sm_sparse_jacobian_create(m);
		if (!sim->pattern)
			goto out_of_memory;
		const size_t nnz = (size_t)sm_sparse_jacobian_nonzeros(sim->pattern) + 1;
		sim->dfdx = malloc(nnz * sizeof(double));
		sim->dfdv = malloc(nnz * sizeof(double));
		if (!sim->dfdx || !sim->dfdv)
			goto out_of_memory;
	}
	if (newton && (sim->solver == SM_SOLVER_DENSE || sim->solver == SM_SOLVER_KLU)) {
		sim->jacobian_records = sm_spring_jacobians_create(m);
		if (!sim->jacobian_records)
			goto out_of_memory;
	}
	if (SUNContext_Create(SM_SUNDIALS_COMM_NULL, &sim->context) != 0) {
		sim->context = NULL;
		goto out_of_memory;
	}
	sim->y = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	sim->y_saved = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	sim->tolerances = N_VNew_Serial(sm_simulation_state_length(sim), sim->context);
	// As the dense matrix's entries (attach_linear_solver), those of a vector: SUNDIALS 7 without
	// its error checks leaves them NULL when their allocation fails.
	if (!sim->y || !sim->y_saved || !sim->tolerances || !N_VGetArrayPointer(sim->y) ||
	    !N_VGetArrayPointer(sim->y_saved) || !N_VGetArrayPointer(sim->tolerances))
		goto out_of_memory;
	// Before CVodeInit: every vector CVODE and the solvers clone from y inherits the operations.
	sm_vector_ops_install(sim->y);
	sm_vector_ops_install(sim->y_saved);
	sm_vector_ops_install(sim->tolerances);
	sm_simulation_load_initial_state(sim);
	sm_status st = setup_cvode(sim);
	if (st != SM_OK) {
		sm_error_set(err, st, "simulation: cannot set up CVODE with the %s linear solver%s%s",
		             sm_linear_solver_name(sim->solver), sim->solver_message[0] ? ": " : "",
		             sim->solver_message);
		sm_simulation_destroy(sim);
		return NULL;
	}
	return sim;

out_of_memory:
	sm_error_set(err, SM_ERROR_OUT_OF_MEMORY, "simulation: out of memory for a model of %d particles",
	             (int)model->particle_count);
	sm_simulation_destroy(sim);
	return NULL;
}

void sm_simulation_destroy(sm_simulation* sim)
{
	if (sim == NULL)
		return;
	if (sim->cvode)
		CVodeFree(&sim->cvode);
	SUNLinSolFree(sim->linear_solver);
	if (sim->fixed_point)
		SUNNonlinSolFree(sim->fixed_point);
	SUNMatDestroy(sim->matrix);
	N_VDestroy(sim->y);
	N_VDestroy(sim->y_saved);
	N_VDestroy(sim->tolerances);
	sm_simulation_free_events(sim);  // before the context its vector belongs to
	if (sim->context)
		SUNContext_Free(&sim->context);
	sm_model_destroy(sim->model);
	sm_sparse_jacobian_destroy(sim->pattern);
	free(sim->dfdx);
	free(sim->dfdv);
	free(sim->klu_row_pointers);
	free(sim->klu_column_indices);
	sm_spring_jacobians_destroy(sim->jacobian_records);
	free(sim->initial_enabled);
	free(sim->free_particles);
	free(sim->constrained);
	free(sim->inverse_mass);
	free(sim->mass_dof);
	free(sim->position);
	free(sim->velocity);
	free(sim->external_force);
	free(sim->drive_position);
	free(sim->drive_velocity);
	free(sim->drive_acceleration);
	free(sim->drive_time);
	free(sim->origin_slot);
	free(sim->origins);
	free(sim->force_rate);
	free(sim->force_time);
	free(sim->work_external);
	free(sim->driven_spring_start);
	free(sim->driven_springs);
	free(sim->work_position);
	free(sim->work_velocity);
	free(sim->work_force);
	free(sim->breaks);
	free(sim);
}
